"""Chapter 05, a glossy floor: the tracks' two layers (the floor's grain, the mirrored lamps) in one frame, the
whole-view check's shift beside them (``gpo.motion.overview``), and what it buys each fisheye method over a run."""

from __future__ import annotations

import dataclasses

import matplotlib.pyplot as plt
import numpy as np

from gpo.experiments.runs import ROUTE_NAMES, floor_run
from gpo.io.bag import Recording
from gpo.metrics import FinalError, final_error
from gpo.motion.klt import FloorFlow, FlowFrame
from gpo.motion.layers import floor_layer
from gpo.motion.overview import Overview
from gpo.odometry.kinematics import between
from gpo.pipeline.config import OdometryConfig, load_config
from gpo.pipeline.odometer import FloorOdometer
from gpo.sim.record import GROUND_TRUTH_TOPIC, recording

GLOSSY_METHODS = ("gpo-exact", "gpo-rigid", "gpo")  # the suite's two with the check, the paper's as printed
ON_FLOOR_PX = 2.0  # a track this close to the truth's shift moves with the floor (a frame's turn spreads them ~1 px)


def with_check(config: OdometryConfig, check: bool) -> OdometryConfig:
    """``config`` with the whole-view check on (the shipped ``overview_scale``) or off (0)."""
    scale = load_config().klt.overview_scale if check else 0.0
    return config.replace(klt=dataclasses.replace(config.klt, overview_scale=scale))


def whole_view_errors(name: str = "glossy") -> dict[tuple[str, bool], FinalError]:
    """The final error of each of ``GLOSSY_METHODS`` on the recording ``name``, with the tracks alone (False) and with
    the whole-view check (True); the floor runs are kept in the cache (``gpo.experiments.runs.floor_run``)."""
    bag = recording(name, progress=False)
    with Recording(bag) as recorded:
        truth = recorded.trajectory(GROUND_TRUTH_TOPIC)
    base = load_config()
    return {
        (method, check): final_error(floor_run(bag, with_check(base.replace(method=method), check)).trajectory, truth)
        for method in GLOSSY_METHODS
        for check in (False, True)
    }


def whole_view_text(errors: dict[tuple[str, bool], FinalError]) -> str:
    """One line a method: its final error (% of the distance) and heading error with the tracks alone and with the
    whole-view check."""
    lines = [f"{'method':10s} {'tracks alone':>22s} {'with the check':>22s}"]
    for method in dict.fromkeys(m for m, _ in errors):
        cells = [f"{errors[method, c].percent:7.2f} % {np.degrees(errors[method, c].heading_rad):+7.1f} deg"
                 for c in (False, True)]
        lines.append(f"{method:10s} {cells[0]:>22s} {cells[1]:>22s}")
    lines.append(f"final position error in % of the distance, final heading error; on the shipped route's floor image "
                 f"({ROUTE_NAMES[load_config().route]})")
    return "\n".join(lines)


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


def two_layers(name: str = "glossy", frames: int = 120) -> TwoLayers:
    """Of the first ``frames`` frames of the recording ``name``, the one where the tracks' median lies furthest from
    the truth while the whole-view check's shift lies within a pixel of it (see ``TwoLayers``)."""
    config = with_check(load_config().replace(method="gpo-exact"), True)
    odometer = FloorOdometer(config)
    flow = FloorFlow(dataclasses.replace(config.klt, overview_scale=0.0), mask=odometer.table.valid)
    nadir = odometer.estimator.geometry.nadir_px
    correlator, best, previous_pose = None, None, None
    with Recording(recording(name, progress=False)) as recorded:
        truth = recorded.trajectory(GROUND_TRUTH_TOPIC)
        poses = {s: (p[0], p[1], y) for s, p, y in zip(truth.stamps_ns, truth.positions, truth.yaw, strict=True)}
        for index, frame in zip(range(frames), recorded.frames(progress=False), strict=False):
            prepared = odometer.prepare(frame.image)
            correlator = correlator or Overview(config.klt.overview_scale, prepared.overview.shape[::-1])
            found = correlator.observe(prepared.overview)
            measurement = flow.track(FlowFrame(prepared.image, prepared.texture))
            pose = np.array(poses[frame.stamp_ns])
            if measurement is not None and measurement.flag is None and found is not None:
                shift = _true_shift(config, between(previous_pose, pose))
                pulled = np.hypot(*(measurement.median - shift))
                if np.hypot(*(found.shift_px - shift)) < 1.0 and (best is None or pulled > best[0]):
                    on_floor = np.hypot(*(measurement.vectors - shift).T) < ON_FLOOR_PX
                    kept = floor_layer(measurement.start, measurement.end, nadir)
                    best = (pulled, TwoLayers(index, prepared.image, measurement.start, measurement.end, on_floor,
                                              kept, measurement.median, found.shift_px, shift))
            previous_pose = pose
    return best[1]


def _true_shift(config: OdometryConfig, increment: np.ndarray) -> np.ndarray:
    """How far the floor under the floor image's middle moves in the image (pixels) when base_link moves by
    ``increment`` (dx, dy, dtheta in its own frame): a floor point p of base_link is then at R(-dtheta) (p - t)."""
    floor = config.floor
    middle = np.array([(floor.width - 1) / 2, (floor.height - 1) / 2])
    point = floor.pixel_to_base(middle)
    c, s = np.cos(increment[2]), np.sin(increment[2])
    moved = np.array([[c, s], [-s, c]]) @ (point - increment[:2])
    return floor.base_to_pixel(moved) - middle


def draw_two_layers(frame: TwoLayers) -> plt.Figure:
    """Left: the floor image with the tracks alone, those moving with the floor in green, the rest (on the
    reflections) in red. Right: their vectors, with their median, the whole-view check's shift and the truth's."""
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.6))
    left.imshow(frame.image, cmap="gray")
    for mask, colour, label in ((~frame.on_floor, "tab:red", "on the reflections"),
                                (frame.on_floor, "tab:green", "on the floor")):
        start, end = frame.start[mask], frame.end[mask]
        left.plot(*np.stack([start, end], axis=1).transpose(2, 1, 0), color=colour, lw=1)
        left.scatter(*start.T, s=8, color=colour, label=f"{label} ({mask.sum()})")
    left.set_title(f"frame {frame.index}: the tracks alone")
    left.legend(fontsize="small", loc="lower right")
    left.axis("off")
    vectors = frame.end - frame.start
    right.scatter(*vectors[~frame.on_floor].T, s=10, color="tab:red")
    right.scatter(*vectors[frame.on_floor].T, s=10, color="tab:green")
    for point, marker, label in ((frame.median, "s", "the tracks' median"), (frame.overview, "D", "the whole view's"),
                                 (frame.truth, "*", "truth")):
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
    return "\n".join([
        f"frame {frame.index} ({ROUTE_NAMES[load_config().route]} floor image): {frame.on_floor.sum()} of "
        f"{len(frame.on_floor)} tracks on the floor, "
        f"{(~frame.on_floor).sum()} on the reflections; floor_layer keeps {frame.kept.sum()} as the floor's",
        f"the tracks' median {cell(frame.median)}, the whole view's shift {cell(frame.overview)}, "
        f"the truth {cell(frame.truth)}",
    ])


if __name__ == "__main__":  # `python -m gpo.book.ch05_glossy`: the floor runs the chapter reads, made and kept
    print(whole_view_text(whole_view_errors()))
