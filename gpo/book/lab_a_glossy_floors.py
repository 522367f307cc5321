"""Lab chapter A, glossy floors and how the suite reads them: a glossy recording's frames read three ways (the tracks'
median, the whole-view check's shift, the truth's shift; ``gpo.motion.layers``, ``gpo.motion.overview``), one frame's
two layers of tracks (the floor's grain, the mirrored lamps), and the floor runs of each fisheye method with the tracks
alone, with the whole-view check, and with the check never wary, kept in the cache (``gpo.experiments.runs.floor_run``).

    python -m gpo.book.lab_a_glossy_floors

makes and keeps every floor run the chapter reads (``make tables`` runs it before the tests) and prints their final
errors.
"""

from __future__ import annotations

import dataclasses

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.colors import ListedColormap
from matplotlib.patches import Patch

from gpo.book.figures import draw_placed_paths
from gpo.experiments.runs import ROUTE_NAMES, floor_run
from gpo.io.bag import Recording
from gpo.metrics import FinalError, final_error, place_on_truth
from gpo.motion.klt import FloorFlow, FlowFrame
from gpo.motion.layers import floor_layer, slower_layer
from gpo.motion.overview import Overview
from gpo.odometry.kinematics import between
from gpo.pipeline.config import OdometryConfig, load_config
from gpo.pipeline.odometer import FloorOdometer, Status
from gpo.sim.record import GROUND_TRUTH_TOPIC, recording

GLOSSY_METHODS = ("gpo-exact", "gpo-rigid", "gpo")  # the suite's two with the check, the paper's as printed
CHECKED_METHODS = ("gpo-exact", "gpo-rigid")  # the estimators that take the whole-view check
VARIANTS = ("tracks alone", "with the check", "never wary")  # the check off, on (as shipped), on but never wary
RECORDINGS = ("glossy", "short1")  # the glossy screed, and the matte floor with sheets dragged across it
ON_FLOOR_PX = 2.0  # a track this close to the truth's shift moves with the floor (a frame's turn spreads them ~1 px)
FIRST_FRAMES = 120  # the two-layer frame is chosen among the recording's first frames (its first four seconds)


def with_check(config: OdometryConfig, variant: str) -> OdometryConfig:
    """``config`` with the whole-view check off (``"tracks alone"``), as shipped (``"with the check"``) or on but
    never wary (``"never wary"``: ``overview_wary_share`` 0, the tolerance fixed)."""
    shipped = load_config().klt
    scale = 0.0 if variant == "tracks alone" else shipped.overview_scale
    wary = 0.0 if variant == "never wary" else shipped.overview_wary_share
    return config.replace(klt=dataclasses.replace(config.klt, overview_scale=scale, overview_wary_share=wary))


def glossy_runs(name: str = "glossy") -> tuple[dict, object]:
    """The floor runs (``gpo.pipeline.run.FloorRun``, kept in the cache) of the recording ``name`` by
    (method, variant): each of ``GLOSSY_METHODS`` with the tracks alone and with the check, and each of
    ``CHECKED_METHODS`` with the check never wary; and the recording's ground truth (a ``Trajectory``)."""
    bag = recording(name, progress=False)
    with Recording(bag) as recorded:
        truth = recorded.trajectory(GROUND_TRUTH_TOPIC)
    base = load_config()
    runs = {}
    for method in GLOSSY_METHODS:
        for variant in VARIANTS if method in CHECKED_METHODS else VARIANTS[:2]:
            runs[method, variant] = floor_run(bag, with_check(base.replace(method=method), variant))
    return runs, truth


def whole_view_errors(runs: dict, truth) -> dict[tuple[str, str], FinalError]:
    """The final error of each of ``runs`` (``glossy_runs``) against ``truth``."""
    return {key: final_error(run.trajectory, truth) for key, run in runs.items()}


def whole_view_text(errors: dict[tuple[str, str], FinalError]) -> str:
    """One line a method: its final position error (% of the distance) and heading error under each variant."""
    variants = [v for v in VARIANTS if any(key[1] == v for key in errors)]
    lines = [f"{'method':10s}" + "".join(f"{variant:>22s}" for variant in variants)]
    for method in dict.fromkeys(m for m, _ in errors):
        cells = [
            f"{errors[method, v].percent:7.2f} % {np.degrees(errors[method, v].heading_rad):+7.1f} deg"
            if (method, v) in errors
            else "-"
            for v in variants
        ]
        lines.append(f"{method:10s}" + "".join(f"{cell:>22s}" for cell in cells))
    lines.append(
        "final position error in % of the distance, final heading error; on the shipped route's floor image "
        f"({ROUTE_NAMES[load_config().route]})"
    )
    return "\n".join(lines)


def draw_runs(runs: dict, truth, methods=GLOSSY_METHODS) -> plt.Figure:
    """The paths of ``methods`` (``glossy_runs``), their first pose placed on the truth's: with the tracks alone
    (left) and with the check (right)."""
    fig, axes = plt.subplots(1, 2, figsize=(13, 5))
    for ax, variant in zip(axes, VARIANTS[:2], strict=True):
        placed = {m: place_on_truth(runs[m, variant].trajectory, truth)[0].positions[:, :2] for m in methods}
        draw_placed_paths(placed, truth, ax=ax, truth_end=True)
        ax.set_title(variant)
    fig.tight_layout()
    return fig


@dataclasses.dataclass(frozen=True)
class TwoLayers:
    """One frame of a glossy recording: its floor image (``image``), the tracks alone (``start``, ``end``, (N, 2)
    pixels), which of them move with the floor (``on_floor``: within ``ON_FLOOR_PX`` of the truth's shift) and which
    ``gpo.motion.layers.floor_layer`` keeps as the floor's own (``kept``), both (N,) bool; their median, the
    whole-view check's shift and the truth's shift of the floor image's middle, all (2,) pixels."""

    index: int
    image: np.ndarray
    start: np.ndarray
    end: np.ndarray
    on_floor: np.ndarray
    kept: np.ndarray
    median: np.ndarray
    overview: np.ndarray
    truth: np.ndarray


@dataclasses.dataclass(frozen=True)
class GlossyFrames:
    """Every measured frame of a recording read with the tracks alone: its ``index`` (N,), the tracks' ``median``,
    the whole-view check's ``overview`` shift and the ``truth``'s shift of the floor image's middle (N, 2) pixels,
    the correlation's ``peak`` (N,), and the kept vectors (``kept``, N) and those in a slower layer (``slower``, N);
    the frames read (``read``) and the tracks' flags by reason (``flags``: the flag's words before its colon)."""

    index: np.ndarray
    median: np.ndarray
    overview: np.ndarray
    truth: np.ndarray
    peak: np.ndarray
    kept: np.ndarray
    slower: np.ndarray
    read: int
    flags: dict[str, int]


def read_frames(name: str = "glossy") -> tuple[GlossyFrames, TwoLayers]:
    """Every frame of the recording ``name`` tracked with the tracks alone beside the whole-view check's shift and the
    truth (``GlossyFrames``, the frames the tracks measured and the check read); and of its first ``FIRST_FRAMES``,
    the one where the tracks' median lies furthest from the truth while the check's shift lies within a pixel of it
    (``TwoLayers``)."""
    config = with_check(load_config().replace(method="gpo-exact"), "with the check")
    odometer = FloorOdometer(config)
    flow = FloorFlow(dataclasses.replace(config.klt, overview_scale=0.0), mask=odometer.table.valid)
    nadir = odometer.estimator.geometry.nadir_px
    correlator, best, previous_pose, rows, flags, read = None, None, None, [], {}, 0
    with Recording(recording(name, progress=False)) as recorded:
        truth = recorded.trajectory(GROUND_TRUTH_TOPIC)
        poses = {s: (p[0], p[1], y) for s, p, y in zip(truth.stamps_ns, truth.positions, truth.yaw, strict=True)}
        for index, frame in enumerate(recorded.frames(progress=False)):
            prepared = odometer.prepare(frame.image)
            correlator = correlator or Overview(config.klt.overview_scale, prepared.overview.shape[::-1])
            found = correlator.observe(prepared.overview)
            measurement = flow.track(FlowFrame(prepared.image, prepared.texture))
            pose, read = np.array(poses[frame.stamp_ns]), read + 1
            if measurement is not None and measurement.flag is not None:
                reason = measurement.flag.split(":")[0].split(" (")[0]
                flags[reason] = flags.get(reason, 0) + 1
            if measurement is not None and measurement.flag is None and found is not None:
                shift = _true_shift(config, between(previous_pose, pose))
                q = measurement.quality
                rows.append((index, measurement.median, found.shift_px, shift, found.peak, q.kept, q.slower))
                pulled = np.hypot(*(measurement.median - shift))
                close = np.hypot(*(found.shift_px - shift)) < 1.0
                if index < FIRST_FRAMES and close and (best is None or pulled > best[0]):
                    on_floor = np.hypot(*(measurement.vectors - shift).T) < ON_FLOOR_PX
                    kept = floor_layer(measurement.start, measurement.end, nadir)
                    layers = TwoLayers(
                        index,
                        prepared.image,
                        measurement.start,
                        measurement.end,
                        on_floor,
                        kept,
                        measurement.median,
                        found.shift_px,
                        shift,
                    )
                    best = (pulled, layers)
            previous_pose = pose
    columns = [np.array(column) for column in zip(*rows, strict=True)]
    return GlossyFrames(*columns, read, flags), best[1]


def _true_shift(config: OdometryConfig, increment: np.ndarray) -> np.ndarray:
    """How far the floor under the floor image's middle moves in the image (pixels) when base_link moves by
    ``increment`` (dx, dy, dtheta in its own frame): a floor point p of base_link is then at R(-dtheta) (p - t)."""
    floor = config.floor
    middle = np.array([(floor.width - 1) / 2, (floor.height - 1) / 2])
    point = floor.pixel_to_base(middle)
    c, s = np.cos(increment[2]), np.sin(increment[2])
    moved = np.array([[c, s], [-s, c]]) @ (point - increment[:2])
    return floor.base_to_pixel(moved) - middle


def draw_frames(frames: GlossyFrames) -> plt.Figure:
    """Frame by frame: how far the floor moved (the truth), and the tracks' median and the whole-view check's shift
    (top, lengths in pixels); how far each lies from the truth (middle, log scale); the share of the kept vectors in a
    slower layer (bottom)."""
    fig, (top, middle, bottom) = plt.subplots(3, 1, figsize=(12, 7.5), sharex=True, height_ratios=[1.2, 1, 0.7])
    index = np.arange(frames.index.max() + 1)  # every frame, NaN where the tracks measured none: gaps stay gaps

    def spread(values):
        full = np.full(len(index), np.nan)
        full[frames.index] = values
        return full

    lengths = {name: spread(np.hypot(*getattr(frames, name).T)) for name in ("truth", "median", "overview")}
    styles = {"truth": ("k", 3, 0.3), "median": ("tab:red", 1, 1.0), "overview": ("tab:blue", 1, 1.0)}
    labels = {"truth": "the truth", "median": "the tracks' median", "overview": "the whole view's shift"}
    for name, (colour, width, alpha) in styles.items():
        top.plot(index, lengths[name], color=colour, lw=width, alpha=alpha, label=labels[name])
        if name != "truth":
            off = np.hypot(*(getattr(frames, name) - frames.truth).T)
            middle.semilogy(index, spread(np.maximum(off, 1e-3)), color=colour, lw=1, label=labels[name])
    top.set(ylabel="motion [px]", title="how far the floor moved from the frame before, read three ways")
    top.legend(fontsize="small", loc="upper left")
    middle.set(ylabel="off the truth [px]")
    bottom.plot(index, spread(frames.slower / np.maximum(frames.kept, 1)), color="tab:purple", lw=1)
    bottom.set(xlabel="frame", ylabel="slower share", ylim=(0, 1))
    for ax in (top, middle, bottom):
        ax.grid(True, alpha=0.3)
    fig.tight_layout()
    return fig


STEP_KINDS = {  # what measured each step of a run, and its colour
    "the tracks": "0.75",
    "the tracks, in doubt": "tab:orange",
    "the whole view": "tab:blue",
    "not measured": "tab:red",
}


def draw_steps(records) -> plt.Axes:
    """Each step of a run (``gpo.pipeline.odometer.FrameRecord``, the first frame left out) as a strip of colour: what
    measured it (``STEP_KINDS``); below it, the steps whose kept vectors held a slower layer."""
    steps = records[1:]
    kinds = list(STEP_KINDS)

    def kind(record) -> int:
        if record.status is not Status.MEASURED:
            return kinds.index("not measured")
        if record.overview:
            return kinds.index("the whole view")
        return kinds.index("the tracks, in doubt" if record.disagreed else "the tracks")

    strip = np.array([[kind(r) for r in steps]])
    slower = np.array([[r.kept > 0 and slower_layer(r.slower, r.kept) for r in steps]])
    _, (upper, lower) = plt.subplots(2, 1, figsize=(12, 1.9), sharex=True, height_ratios=[2, 1])
    colours = ListedColormap(list(STEP_KINDS.values()))
    upper.imshow(strip, aspect="auto", cmap=colours, vmin=-0.5, vmax=len(kinds) - 0.5, interpolation="nearest")
    lower.imshow(slower, aspect="auto", cmap=ListedColormap(["white", "tab:purple"]), vmin=0, vmax=1)
    upper.set_yticks([0], ["measured by"])
    lower.set_yticks([0], ["slower layer"])
    lower.set_xlabel("step (frame)")
    handles = [Patch(color=colour, label=name) for name, colour in STEP_KINDS.items()]
    upper.legend(handles=handles, ncols=4, fontsize="small", loc="lower left", bbox_to_anchor=(0, 1.02))
    return upper


def draw_two_layers(frame: TwoLayers) -> plt.Figure:
    """Left: the floor image with the tracks alone, those moving with the floor in green, the rest (on the
    reflections) in red. Right: their vectors, with their median, the whole-view check's shift and the truth's."""
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.6))
    left.imshow(frame.image, cmap="gray")
    for mask, colour, label in (
        (~frame.on_floor, "tab:red", "on the reflections"),
        (frame.on_floor, "tab:green", "on the floor"),
    ):
        start, end = frame.start[mask], frame.end[mask]
        left.plot(*np.stack([start, end], axis=1).transpose(2, 1, 0), color=colour, lw=1)
        left.scatter(*start.T, s=8, color=colour, label=f"{label} ({mask.sum()})")
    left.set_title(f"frame {frame.index}: the tracks alone")
    left.legend(fontsize="small", loc="lower right")
    left.axis("off")
    vectors = frame.end - frame.start
    right.scatter(*vectors[~frame.on_floor].T, s=10, color="tab:red")
    right.scatter(*vectors[frame.on_floor].T, s=10, color="tab:green")
    for point, marker, label in (
        (frame.median, "s", "the tracks' median"),
        (frame.overview, "D", "the whole view's"),
        (frame.truth, "*", "truth"),
    ):
        right.scatter(*point, marker=marker, s=120, edgecolors="k", label=label, zorder=3)
    right.set_xlabel("u [px]")
    right.set_ylabel("v [px]")
    right.invert_yaxis()
    right.set_aspect("equal", adjustable="datalim")
    right.legend(fontsize="small")
    right.set_title("the vectors, floor-image pixels")
    fig.tight_layout()
    return fig


def two_layers_text(frame: TwoLayers) -> str:
    """The frame's tracks by layer, what ``floor_layer`` keeps, and the three shifts."""

    def cell(v):
        return f"({v[0]:+.2f}, {v[1]:+.2f}) px"

    return "\n".join(
        [
            f"frame {frame.index} ({ROUTE_NAMES[load_config().route]} floor image): {frame.on_floor.sum()} of "
            f"{len(frame.on_floor)} tracks on the floor, "
            f"{(~frame.on_floor).sum()} on the reflections; floor_layer keeps {frame.kept.sum()} as the floor's",
            f"the tracks' median {cell(frame.median)}, the whole view's shift {cell(frame.overview)}, "
            f"the truth {cell(frame.truth)}",
        ]
    )


if __name__ == "__main__":  # `python -m gpo.book.lab_a_glossy_floors`: the floor runs the chapter reads, made and kept
    for name in RECORDINGS:
        print(name)
        print(whole_view_text(whole_view_errors(*glossy_runs(name))))
