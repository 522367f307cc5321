"""Chapter 08, the second paper's floor feature odometer: a recording's frames, keypoints, matches by fate, the
histogram filter and the invariance check's loops, how the mu +- sigma bands select in a turn, the calibration's
errors, the tilt's cost over the image, heading errors along a path, what each stage is worth, Table 2's short form
on three floors beside the paper's rows, the keypoints each floor gives, and the odometer's panel on one frame pair.
The second paper's experiments and the ablation from its published method are lab C's
(``gpo.book.lab_c_second_paper``)."""

from __future__ import annotations

import dataclasses
import itertools
import time

import ipywidgets as widgets
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.collections import LineCollection, PatchCollection, PolyCollection
from matplotlib.patches import Circle

from gpo.book.panels import int_slider, slider
from gpo.io.bag import Recording
from gpo.motion.keypoints import DETECTORS, FeatureParameters, FeatureTracker, detect


def frames_of(bag, start: int = 0, stop: int | None = None) -> list[tuple[int, np.ndarray]]:
    """(stamp ns, grey image) of the camera frames ``start`` .. ``stop`` - 1 of the recording at ``bag``."""
    with Recording(bag) as recorded:
        chosen = itertools.islice(recorded.frames(gray=True, progress=False), start, stop)
        return [(frame.stamp_ns, frame.image) for frame in chosen]


def draw_floor_frames(images: dict, frame: int) -> plt.Figure:
    """One grey camera frame of each floor (name -> image (H, W)) side by side, each titled with its name and the
    frame's number ``frame``."""
    fig, axes = plt.subplots(1, len(images), figsize=(5 * len(images), 3.4))
    for ax, (kind, image) in zip(np.atleast_1d(axes), images.items(), strict=True):
        ax.imshow(image, cmap="gray", vmin=0, vmax=255)
        ax.set_title(f"{kind}, frame {frame}")
        ax.axis("off")
    fig.tight_layout()
    return fig


def _frame(image, ax=None) -> plt.Axes:
    """A grey 8-bit frame (H, W) on ``ax`` (a new figure when None), pixel centres at whole (u, v), no axes."""
    if ax is None:
        _, ax = plt.subplots(figsize=(7, 4.5))
    ax.imshow(image, cmap="gray", vmin=0, vmax=255)
    ax.set_xlim(-0.5, image.shape[1] - 0.5)
    ax.set_ylim(image.shape[0] - 0.5, -0.5)
    ax.set_axis_off()
    return ax


def draw_keypoints(image, keypoints, ax=None) -> plt.Axes:
    """A grey frame (H, W) with its keypoints (``gpo.motion.keypoints.Keypoints``, pixels of the full image), each a
    circle of its diameter ``size``."""
    ax = _frame(image, ax)
    circles = [Circle(point, size / 2) for point, size in zip(keypoints.points, keypoints.sizes, strict=True)]
    ax.add_collection(PatchCollection(circles, facecolor="none", edgecolor="yellow", lw=0.8))
    ax.set_title(f"{len(keypoints)} keypoints")
    return ax


MATCH_FATES = {  # a match's fate -> its colour
    "rejected by the histogram filter": "tab:red",
    "rejected by the invariance check": "tab:orange",
    "kept": "tab:green",
    "not filtered: frame flagged": "tab:gray",
}


def match_fates(matches) -> dict[str, np.ndarray]:
    """Which of the M matches of a ``gpo.motion.keypoints.FeatureMatches`` met each fate of ``MATCH_FATES`` (M,) bool. A
    frame flagged before any stage ran keeps none: its matches are all "not filtered: frame flagged"."""
    through_histogram = matches.histogram_kept
    unfiltered = matches.flag is not None and matches.histogram is None and matches.invariance is None
    return {
        "rejected by the histogram filter": ~through_histogram,
        "rejected by the invariance check": through_histogram & ~matches.kept,
        "kept": matches.kept & (not unfiltered),
        "not filtered: frame flagged": matches.kept & unfiltered,
    }


def draw_feature_matches(image, matches, ax=None) -> plt.Axes:
    """The current grey frame (H, W) with every match of a ``gpo.motion.keypoints.FeatureMatches``: a line from its
    start
    (previous frame) to its end (this frame), pixels of the full image, with a dot at the end, coloured by its fate
    (``MATCH_FATES``, the flagged frame's only when it has some); the legend counts each fate."""
    ax = _frame(image, ax)
    start, end = matches.matched
    fates = match_fates(matches)
    for fate, chosen in fates.items():
        if chosen.any() or fate != "not filtered: frame flagged":
            segments = np.stack([start[chosen], end[chosen]], axis=1)
            colour = MATCH_FATES[fate]
            ax.add_collection(LineCollection(segments, colors=colour, lw=1, label=f"{chosen.sum()} {fate}"))
            ax.plot(*end[chosen].T, ".", ms=3, color=colour)
    ax.legend(loc="lower right", fontsize="small", framealpha=0.8)
    ax.set_title(f"{fates['kept'].sum()} of {len(matches.pairs)} matches kept")
    return ax


def draw_match_histogram(stage, ax=None, label: str = "orientation (deg)") -> plt.Axes:
    """One histogram of the filter (a ``gpo.motion.keypoints.HistogramStage``) as bars over ``label``, the values' unit
    (degrees for the orientation, pixels for the length), with lines at its mean mu and at mu +- sigma and that band
    shaded; the filter keeps a band never narrower than the keypoints' localisation, so it may keep a little more.
    An empty histogram (mean NaN) is drawn without the lines."""
    if ax is None:
        _, ax = plt.subplots(figsize=(6, 3.5))
    ax.stairs(stage.counts, stage.edges, fill=True, color="tab:blue")
    if np.isfinite(stage.mean):
        mean, sigma = stage.mean, stage.sigma
        ax.axvspan(mean - sigma, mean + sigma, color="tab:green", alpha=0.15)
        ax.axvline(mean, color="tab:green", lw=1.2, label=f"mu = {mean:.2f}")
        ax.axvline(mean - sigma, color="tab:green", lw=0.8, ls="--", label=f"mu +- sigma, sigma = {sigma:.2f}")
        ax.axvline(mean + sigma, color="tab:green", lw=0.8, ls="--")
        ax.legend(loc="upper right", fontsize="small")
    ax.set_xlabel(label)
    ax.set_ylabel("matches")
    ax.set_title(f"{int(stage.kept.sum())} of {len(stage.values)} kept")
    return ax


def draw_invariance_loops(image, matches, ax=None, max_loops: int = 60) -> plt.Axes:
    """The loops of the invariance check (the second paper's Algorithm 1, its Figs. 7-8) of a
    ``gpo.motion.keypoints.FeatureMatches`` on the previous grey frame (H, W): each a closed polygon through its
    matches'
    start points, pixels of the full image, kept loops green and rejected ones red (drawn thicker), at most
    ``max_loops`` of each (the first tried). When the check did not run, only the frame."""
    ax = _frame(image, ax)
    check = matches.invariance
    if check is None:
        ax.set_title("the invariance check did not run")
        return ax
    start = matches.matched[0][np.flatnonzero(matches.histogram_kept)]  # the check's input, which its loops index
    loops = np.array(check.loops, dtype=int).reshape(-1, check.cardinality)
    for kept, colour, name, width in ((True, "tab:green", "kept", 0.8), (False, "tab:red", "rejected", 2.0)):
        shown = loops[check.kept_loops == kept][:max_loops]
        polygons = PolyCollection(start[shown], closed=True, facecolors="none", edgecolors=colour, lw=width)
        polygons.set_label(f"{len(shown)} {name} loops shown")
        ax.add_collection(polygons)
    ax.legend(loc="lower right", fontsize="small", framealpha=0.8)
    ax.set_title(f"{int(check.kept_loops.sum())} of {len(loops)} loops kept, C = {check.cardinality}")
    return ax


def draw_band_selection(start, end, kept, right, band: tuple[float, float], ax=None) -> plt.Axes:
    """How the length band of the histogram filter selects in a turn: each match's vector length (px) against where
    it starts across the motion (its start (M, 2) projected on the normal of the kept vectors' mean direction: its u
    for a motion down the image), the right matches kept by the filters (``kept`` (M,) bool) green, the right ones
    dropped grey, the wrong ones (``right`` (M,) False) red; the band (low, high) of lengths shaded, and a least-squares
    line through the right matches and one through the kept, each labelled with its slope (px of length per px
    across: about the turn, in radians)."""
    if ax is None:
        _, ax = plt.subplots(figsize=(9, 4))
    start, end = np.asarray(start, dtype=float), np.asarray(end, dtype=float)
    vectors = end - start
    mean = vectors[kept].mean(axis=0)
    normal = np.array([mean[1], -mean[0]]) / np.hypot(*mean)
    across, length = start @ normal, np.hypot(*vectors.T)
    ax.axhspan(*band, color="tab:green", alpha=0.1, label="the length band")
    groups = (
        (right & ~kept, "0.55", "right, dropped"),
        (right & kept, "tab:green", "right, kept"),
        (~right, "tab:red", "wrong"),
    )
    for chosen, colour, name in groups:
        ax.plot(across[chosen], length[chosen], ".", color=colour, ms=6, label=f"{chosen.sum()} {name}")
    reach = np.array([across[right].min(), across[right].max()])
    for chosen, colour, name in ((right, "k", "the right ones"), (right & kept, "tab:green", "the kept")):
        slope, offset = np.polyfit(across[chosen], length[chosen], 1)
        ax.plot(reach, slope * reach + offset, color=colour, lw=1.2, label=f"least squares, {name}: slope {slope:.4f}")
    low, high = np.percentile(length[right], [0, 100])
    ax.set_ylim(low - 0.3 * (high - low), high + 0.15 * (high - low))
    ax.set_xlabel("where the match starts, across the motion [px]")
    ax.set_ylabel("length of the match vector [px]")
    ax.legend(fontsize="small", loc="lower right", ncols=2)
    return ax


def draw_calibration_errors(errors: dict, ax=None) -> plt.Axes:
    """Each fitted parameter's error (parameter name -> error / its standard deviation) as a bar, with the bands
    of one and two standard deviations shaded: where a calibration's errors should lie."""
    if ax is None:
        _, ax = plt.subplots(figsize=(7, 3))
    names = list(errors)
    ax.axhspan(-2, 2, color="tab:green", alpha=0.08, label="within 2 standard deviations")
    ax.axhspan(-1, 1, color="tab:green", alpha=0.15, label="within 1")
    ax.bar(names, [errors[name] for name in names], color="tab:blue")
    ax.axhline(0, color="k", lw=0.8)
    ax.set_ylim(-3, 3)
    ax.set_ylabel("error / standard deviation")
    ax.legend(loc="upper right", fontsize="small")
    return ax


def draw_step_lengths(pixels, lengths_mm, size: tuple[int, int], ax=None) -> plt.Axes:
    """A floor step measured at pixels (N, 2) all over a ``size`` (width, height) image, each dot coloured by the
    length read there (mm), with a colour bar."""
    if ax is None:
        _, ax = plt.subplots(figsize=(8.5, 4.5))
    dots = ax.scatter(*np.asarray(pixels).T, c=lengths_mm, cmap="coolwarm", s=60)
    ax.set_xlim(0, size[0])
    ax.set_ylim(size[1], 0)
    ax.set_aspect("equal")
    ax.set_xlabel("u [px]")
    ax.set_ylabel("v [px]")
    ax.figure.colorbar(dots, ax=ax, label="the step read [mm]")
    return ax


def heading_error_deg(trajectory, truth) -> np.ndarray:
    """The heading error (degrees, unwrapped) of ``trajectory`` at each of its poses against ``truth`` at the nearest
    stamp not before it, both counted from their first pose."""
    true_yaw = np.unwrap(truth.yaw)
    index = np.minimum(np.searchsorted(truth.stamps_ns, trajectory.stamps_ns), len(true_yaw) - 1)
    yaw = np.unwrap(trajectory.yaw)
    return np.degrees((yaw - yaw[0]) - (true_yaw[index] - true_yaw[0]))


def draw_heading_errors(paths: dict, truth, ax=None) -> plt.Axes:
    """The heading error (degrees) against time (seconds from the start) of each trajectory of ``paths`` (label ->
    ``gpo.io.trajectory.Trajectory``) against ``truth``."""
    if ax is None:
        _, ax = plt.subplots(figsize=(10, 3.6))
    for label, trajectory in paths.items():
        ax.plot(trajectory.times - trajectory.times[0], heading_error_deg(trajectory, truth), label=label)
    ax.axhline(0, color="k", lw=0.6)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("heading error [deg]")
    ax.legend(fontsize="small")
    return ax


def draw_stage_worth(measures: dict, axes=None) -> np.ndarray:
    """What each variant of the odometer (label -> ``gpo.metrics.Evaluation.measures()``) ends at: its final error
    (mm) and its heading RMSE (degrees) as horizontal bars on log scales, the first variant at the top."""
    if axes is None:
        _, axes = plt.subplots(1, 2, figsize=(12, 3.4), sharey=True)
    labels = list(measures)[::-1]
    columns = (("final_error_mm", "final error [mm]"), ("heading_rmse_deg", "heading RMSE [deg]"))
    for ax, (key, label) in zip(axes, columns, strict=True):
        ax.barh(labels, [measures[name][key] for name in labels], color="tab:blue")
        ax.set_xscale("log")
        ax.set_xlabel(label)
        ax.grid(True, axis="x", which="both", alpha=0.3)
    return axes



STAGES = {  # a frame's stages as the trackers time them (``FeatureMatches.seconds``), in the order they run
    "detect": "SIFT: find (and describe)", "describe": "describe (a failed search)", "match": "match descriptors",
    "follow": "Lucas-Kanade: follow", "histogram": "histogram filter", "invariance": "invariance check",
}


def stage_milliseconds(seconds: list[dict]) -> dict[str, float]:
    """The mean time a frame (ms) of each stage of ``STAGES`` that ran in any of a run's frames, from each frame's
    ``FeatureMatches.seconds`` (``seconds``: one dict a frame; a frame where a stage did not run counts 0 for it)."""
    ran = set().union(*seconds)
    mean = {stage: float(np.mean([frame.get(stage, 0.0) for frame in seconds])) for stage in STAGES if stage in ran}
    return {stage: 1e3 * value for stage, value in mean.items()}


def draw_stage_times(stage_ms: dict, ax=None) -> plt.Axes:
    """Each way of tracking (label -> ``stage_milliseconds``) as one horizontal bar, its stages' mean times a frame
    (ms) stacked in the order they run, the first way at the top."""
    if ax is None:
        _, ax = plt.subplots(figsize=(10, 2.8))
    labels = list(stage_ms)[::-1]
    colours = dict(zip(STAGES, plt.rcParams["axes.prop_cycle"].by_key()["color"], strict=False))
    left = np.zeros(len(labels))
    for stage, name in STAGES.items():
        widths = np.array([stage_ms[label].get(stage, 0.0) for label in labels])
        if widths.any():
            ax.barh(labels, widths, left=left, color=colours[stage], label=name)
            left += widths
    ax.set_xlabel("time a frame [ms]")
    ax.legend(fontsize="small", ncols=3, loc="upper center", bbox_to_anchor=(0.5, -0.3))
    return ax

PAPER_FLOORS = {"wood": ("I", "II"), "raised": ("III",), "industrial": ("IV", "V", "VI", "VII", "VIII", "IX")}
"""The second paper's experiments on each kind of floor (its Table 1)."""


def paper_value(row, key: str) -> float:
    """A column ``key`` of one of the paper's rows of Table 2 (a ``gpo.metrics.PaperTable2``), the final error in %
    (``final_error_percent``) computed from its own columns, 100 e_N / distance: the paper's printed % is that only
    for its IV."""
    if key == "final_error_percent":
        return row.final_error_mm / row.distance_m / 10.0
    return getattr(row, key)


def draw_table2_floors(rows: dict, paper: dict, axes=None, label: str = "the suite") -> np.ndarray:
    """Table 2's final error (% of the distance) and heading RMSE (degrees) of the suite's run on each floor
    (floor -> ``gpo.metrics.PaperTable2``), a bar per floor, beside the paper's own rows for the experiments on
    that floor (number -> ``PaperTable2``, ``PAPER_FLOORS``; the final error as ``paper_value`` computes it), each a
    labelled black dot; log scales. ``label`` names the suite's bars."""
    if axes is None:
        _, axes = plt.subplots(1, 2, figsize=(12, 3.8))
    columns = (("final_error_percent", "final error [% of the distance]"), ("heading_rmse_deg", "heading RMSE [deg]"))
    for ax, (key, name) in zip(axes, columns, strict=True):
        floors = list(rows)
        ax.bar(floors, [getattr(rows[floor], key) for floor in floors], color="tab:blue", label=label)
        shown = False
        for place, floor in enumerate(floors):
            numbers = [n for n in PAPER_FLOORS[floor] if np.isfinite(paper_value(paper[n], key))]
            for offset, number in zip(np.linspace(-0.35, 0.35, max(len(numbers), 1)), numbers, strict=False):
                value = paper_value(paper[number], key)
                dots = "the paper's Table 2 (final error: e_N / distance)"
                ax.plot(place + offset, value, "ko", ms=5, label=None if shown else dots)
                ax.annotate(number, (place + offset, value), xytext=(3, 3), textcoords="offset points", fontsize=8)
                shown = True
        ax.set_yscale("log")
        bottom, top = ax.get_ylim()
        ax.set_ylim(bottom, top * 4)  # room above the dots for their labels and the legend
        ax.set_ylabel(name)
    axes[0].legend(fontsize="small", loc="upper center")
    return axes


def draw_keypoint_counts(counts: dict, ax=None) -> plt.Axes:
    """Keypoints found in one frame of each floor at each contrast threshold ((floor, threshold) -> count), grouped
    by floor."""
    if ax is None:
        _, ax = plt.subplots(figsize=(6, 3.4))
    floors = list(dict.fromkeys(floor for floor, _ in counts))
    thresholds = list(dict.fromkeys(threshold for _, threshold in counts))
    width = 0.8 / len(thresholds)
    for k, threshold in enumerate(thresholds):
        places = np.arange(len(floors)) + (k - (len(thresholds) - 1) / 2) * width
        ax.bar(places, [counts[floor, threshold] for floor in floors], width, label=f"contrast threshold {threshold}")
    ax.set_xticks(range(len(floors)), floors)
    ax.set_ylabel("keypoints in the frame")
    ax.legend(fontsize="small")
    return ax


def feature_panel(previous_image, current_image, parameters: FeatureParameters | None = None) -> widgets.VBox:
    """The second paper's floor feature odometer on one frame pair: the detector, the invariance check's threshold t
    and cardinality C, the histograms' bins and Lowe's ratio test (1.0: off).

    ``previous_image`` and ``current_image``: consecutive grey frames (H, W) uint8; ``parameters``: the
    ``FeatureParameters`` the controls start from (default: SIFT) and the rest of the settings. Each detector's
    keypoints are found once and kept, so that the other controls only match and filter again
    (``FeatureTracker.matches``). Top: the matches on the current frame by fate, and the orientation histogram;
    bottom: the length histogram, and the loops of the invariance check on the previous frame. One line reads out
    the counts after each stage, the flag and each stage's time (detection's is that of the current frame, once).
    """
    base = parameters or FeatureParameters(detector="sift")
    style = {"description_width": "initial"}
    sizes = sorted({3, 4, 5, 6, base.cardinality} - {None})
    controls = {
        "detector": widgets.Dropdown(options=DETECTORS, value=base.detector, description="detector", style=style),
        "invariance_threshold": slider("t", base.invariance_threshold, 0.5, 1.0, 0.01),
        "cardinality": widgets.Dropdown(  # 0 stands for None, "auto": a Dropdown's None is no choice at all
            options=[("auto", 0), *((str(size), size) for size in sizes)],
            value=base.cardinality or 0,
            description="C",
            style=style,
        ),
        "orientation_bins": int_slider("orientation bins", base.orientation_bins, 10, 360),
        "length_bins": int_slider("length bins", base.length_bins, 10, 320),
        "ratio": slider("ratio test", base.ratio, 0.5, 1.0, 0.01),
    }
    found = {}  # detector -> the previous and current frames' keypoints and the current frame's detection seconds

    def keypoints(detector: str):
        if detector not in found:
            chosen = dataclasses.replace(base, detector=detector)
            previous = detect(previous_image, chosen)
            started = time.perf_counter()
            current = detect(current_image, chosen)
            found[detector] = previous, current, time.perf_counter() - started
        return found[detector]

    def redraw(**values) -> None:
        chosen = dataclasses.replace(base, **(values | {"cardinality": values["cardinality"] or None}))
        previous, current, seconds = keypoints(chosen.detector)
        matches = FeatureTracker(chosen).matches(previous, current, {"detect": seconds})
        plt.close("all")
        _, axes = plt.subplots(2, 2, figsize=(12, 8), gridspec_kw={"hspace": 0.3})
        draw_feature_matches(current_image, matches, ax=axes[0, 0])
        stages = matches.histogram or (None, None)
        names = (("orientation", "deg"), ("length", "px"))
        for ax, stage, (name, unit) in zip((axes[0, 1], axes[1, 0]), stages, names, strict=True):
            if stage is None:
                ax.set_title(f"no {name} histogram")
                ax.set_axis_off()
            else:
                draw_match_histogram(stage, ax=ax, label=f"{name} ({unit})")
        draw_invariance_loops(previous_image, matches, ax=axes[1, 1])
        print(feature_matches_text(matches))
        plt.show()

    sliders = widgets.HBox(list(controls.values()), layout={"flex_flow": "row wrap"})
    return widgets.VBox([sliders, widgets.interactive_output(redraw, controls)])


def feature_matches_text(matches) -> str:
    """One line about a ``gpo.motion.keypoints.FeatureMatches``: the matches left after each stage that ran, the flag if
    any, and each stage's wall time in milliseconds."""
    counts = [f"{len(matches.pairs)} matches"]
    if matches.histogram is not None:
        counts.append(f"{int(matches.histogram_kept.sum())} after the histogram filter")
    if matches.invariance is not None:
        counts.append(f"{int(matches.kept.sum())} after the invariance check")
    flag = f"; flagged: {matches.flag}" if matches.flag is not None else ""
    times = ", ".join(f"{stage} {1e3 * seconds:.1f} ms" for stage, seconds in matches.seconds.items())
    return f"{', '.join(counts)}{flag} ({times})"
