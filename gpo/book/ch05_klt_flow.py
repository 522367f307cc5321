"""Chapter 05, KLT flow on the floor image: a recording's floor images, the tracks and their motion vectors (the first
paper's Fig. 17), a frame's quality and its tracks against the truth in one line, and the chapter's figures:
Lucas-Kanade's Newton steps on one window, the tracks each pyramid depth keeps, the forward-backward check on a frame,
the median and the mean vector's error frame by frame, the first paper's Table 3 beside the suite's; and the tracker's
panel. The table itself (the mean and the median vector on the short paths) is ``gpo.experiments.table3``."""

from __future__ import annotations

import dataclasses

import ipywidgets as widgets
import matplotlib.pyplot as plt
import numpy as np

from gpo.book.panels import int_slider
from gpo.io.bag import Recording
from gpo.motion.klt import FloorFlow, KLTParameters
from gpo.sim.record import GROUND_TRUTH_TOPIC, recording

FLOW_COLOURS = {"inlier": "tab:green", "outlier": "tab:red", "median": "tab:blue", "mean": "tab:orange"}
RIGHT_PX = 1.0  # a track ending this close to where its floor point truly is counts as right in the figures


def draw_lk_steps(window, residuals, history, target) -> plt.Figure:
    """Lucas-Kanade on one window: the previous image's ``window`` (2h+1, 2h+1), the temporal difference I_t over it
    at the start (``residuals[0]``, at the first guess) and after the first, the second and the last Newton step
    (``residuals[k]`` taken at ``history[k - 1]``, the displacement (2,) pixels after step k), all on one grey scale;
    and how far each step's displacement lies from the truth's ``target`` (2,) pixels."""
    shown = [0, 1, 2, len(residuals) - 1]
    fig, axes = plt.subplots(1, 6, figsize=(16, 3.1), gridspec_kw={"width_ratios": [1, 1, 1, 1, 1, 1.6]})
    axes[0].imshow(window, cmap="gray")
    axes[0].set_title("the window in I")
    limit = float(np.abs(residuals[0]).max())
    for ax, k in zip(axes[1:5], shown, strict=True):
        ax.imshow(residuals[k], cmap="RdBu", vmin=-limit, vmax=limit)
        rms = float(np.sqrt(np.mean(residuals[k] ** 2)))
        ax.set_title(f"I_t {'at the guess' if k == 0 else f'after step {k}'}\nRMS {rms:.2f}", fontsize="medium")
    for ax in axes[:5]:
        ax.set_axis_off()
    off = [np.hypot(*(np.asarray(d) - target)) for d in history]
    axes[5].semilogy(range(1, len(off) + 1), off, "o-", color="tab:blue")
    axes[5].set(xlabel="Newton step", ylabel="|d - truth| [px]", title="the displacement's error")
    axes[5].grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    return fig


def _draw_tracks(ax, image, start, end, right) -> None:
    """``image`` with tracks from ``start`` to ``end`` (N, 2) drawn as arrows, the ``right`` ones (N,) bool green and
    the others red."""
    ax.imshow(image, cmap="gray", vmin=0, vmax=255)
    for chosen, colour in ((right, "tab:green"), (~right, "tab:red")):
        if chosen.any():
            vectors = end[chosen] - start[chosen]
            ax.quiver(*start[chosen].T, *vectors.T, angles="xy", scale_units="xy", scale=1.0, width=0.006, color=colour)
    ax.set_xlim(-0.5, image.shape[1] - 0.5)
    ax.set_ylim(image.shape[0] - 0.5, -0.5)
    ax.set_axis_off()


def draw_pyramid_levels(image, rows) -> plt.Figure:
    """One floor image per row of ``rows`` ((title, ``FlowMeasurement``, the kept tracks' true ends (N, 2) pixels)),
    side by side: the kept tracks as arrows, green where they end within ``RIGHT_PX`` of the truth, red elsewhere."""
    fig, axes = plt.subplots(1, len(rows), figsize=(3.3 * len(rows), 3.8))
    for ax, (title, measurement, true_end) in zip(axes, rows, strict=True):
        right = np.hypot(*(measurement.end - true_end).T) < RIGHT_PX
        _draw_tracks(ax, image, measurement.start, measurement.end, right)
        ax.set_title(f"{title}\n{len(right)} kept, {int(right.sum())} right", fontsize="medium")
    fig.tight_layout()
    return fig


def draw_forward_backward(image, start, end, error, true_error, threshold) -> plt.Figure:
    """The forward-backward check on one frame. Left: ``image`` with the tracks from ``start`` to ``end`` (N, 2)
    pixels, those whose forward-backward ``error`` (N,) pixels is under ``threshold`` (kept) in green, the rest
    (refused) in red. Right: the histogram of ``error`` on a log scale, split by the truth (``true_error`` (N,): how
    far each track ends from where its floor point truly is, right under ``RIGHT_PX``), with the threshold."""
    fig, (left, right) = plt.subplots(1, 2, figsize=(12, 4.6), gridspec_kw={"width_ratios": [1, 1.5]})
    kept = error < threshold
    _draw_tracks(left, image, start, end, kept)
    left.set_title(f"{int(kept.sum())} kept (green), {int((~kept).sum())} refused (red)")
    bins = np.logspace(-2, 2, 33)
    clipped = np.clip(error, bins[0], bins[-1])
    truly = true_error < RIGHT_PX
    right.hist(
        [clipped[truly], clipped[~truly]],
        bins=bins,
        stacked=True,
        color=["tab:green", "tab:red"],
        label=[f"ends within {RIGHT_PX:g} px of the truth", "ends further from it"],
    )
    right.axvline(threshold, color="k", ls="--", label=f"the check: {threshold:g} px")
    right.set_xscale("log")
    right.set(xlabel="forward-backward error [px]", ylabel="tracks", title="how far each track came back")
    right.legend(fontsize="small")
    fig.tight_layout()
    return fig


def draw_vector_errors(errors, outliers, frames) -> plt.Axes:
    """The median and the mean vector's error against the truth (``errors`` (N, 2) pixels: median, mean) at each of
    ``frames`` (N,), on a log scale, the frames where some kept vectors are outliers (``outliers`` (N,) bool) shaded."""
    _, ax = plt.subplots(figsize=(12, 3.4))
    for edge in np.flatnonzero(np.diff(np.r_[0, outliers.astype(int), 0])).reshape(-1, 2):
        ax.axvspan(frames[edge[0]] - 0.5, frames[edge[1] - 1] + 0.5, color="0.9", lw=0)
    ax.semilogy(frames, errors[:, 1], color=FLOW_COLOURS["mean"], lw=1, label="mean vector")
    ax.semilogy(frames, errors[:, 0], color=FLOW_COLOURS["median"], lw=1, label="median vector")
    ax.fill_between([], [], color="0.9", label="frames with tracks off the floor's motion")
    ax.set(xlabel="frame", ylabel="off the truth [px]")
    ax.grid(True, which="major", alpha=0.3)
    ax.legend(fontsize="small", loc="upper right", ncols=3)
    return ax


COASTING_COLOURS = {"coasted": "tab:orange", "held": "tab:red"}


def draw_coasting(times_s, driven_m, odometry_m, statuses) -> plt.Axes:
    """The distance driven against time, the truth's (``driven_m``) and the odometry's (``odometry_m``), metres, at
    ``times_s`` (N,), through frames that could not be measured: each run of frames whose status (``statuses``, N
    strings) is "coasted" or "held" shaded in its colour (``COASTING_COLOURS``)."""
    _, ax = plt.subplots(figsize=(10, 3.4))
    times_s, statuses = np.asarray(times_s), np.asarray(statuses)
    half = 0.5 * np.median(np.diff(times_s))
    for status, colour in COASTING_COLOURS.items():
        runs = np.flatnonzero(np.diff(np.r_[0, (statuses == status).astype(int), 0])).reshape(-1, 2)
        for first, end in runs:
            ax.axvspan(times_s[first] - half, times_s[end - 1] + half, color=colour, alpha=0.25, lw=0)
        ax.fill_between([], [], color=colour, alpha=0.25, label=f"frames {status}")
    ax.plot(times_s, driven_m, color="k", lw=4, alpha=0.25, label="truth")
    ax.plot(times_s, odometry_m, ".-", color=FLOW_COLOURS["median"], ms=4, lw=1, label="odometry")
    ax.set(xlabel="time [s]", ylabel="driven forward [m]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize="small", loc="upper left")
    return ax


def draw_table3(paper, ours, columns) -> plt.Figure:
    """The first paper's Table 3 beside the suite's: for each of ``columns`` (the tests, then their average), the
    average relative translation error with the mean and with the median vector as bars, the minimum to the maximum
    as a line; ``paper`` and ``ours``: ``gpo.experiments.table3.PaperTable3.values``' layout, metres; drawn in mm."""
    fig, axes = plt.subplots(1, 2, figsize=(13, 4))
    x = np.arange(len(columns))
    for ax, values, title in (
        (axes[0], paper, "the paper's Table 3: a real robot"),
        (axes[1], ours, "the suite: the simulated short paths"),
    ):
        for offset, vector in ((-0.2, "mean"), (0.2, "median")):
            average, low, high = (1e3 * np.array(values[vector, s]) for s in ("avg", "min", "max"))
            ax.bar(x + offset, average, 0.38, color=FLOW_COLOURS[vector], label=f"{vector} vector: average")
            ax.vlines(x + offset, low, high, color="k", lw=1.5)
        ax.vlines([], [], [], color="k", lw=1.5, label="minimum to maximum")
        ax.set_xticks(x, columns)
        ax.set_ylim(0, 1.3e3 * max(max(values[vector, "max"]) for vector in ("mean", "median")))
        ax.set(ylabel="relative translation error [mm]", title=title)
        ax.grid(True, axis="y", alpha=0.3)
    axes[0].legend(fontsize="small", ncols=3, loc="upper center")
    fig.tight_layout()
    return fig


def draw_flow_vectors(image, measurement, ax=None, scale: float = 1.0) -> plt.Axes:
    """A floor image with the kept tracks of a ``gpo.motion.klt.FlowMeasurement``: each an arrow from where it started,
    ``scale`` times its length; inliers (near the median vector) and outliers in two colours (``FLOW_COLOURS``)."""
    if ax is None:
        _, ax = plt.subplots(figsize=(5, 5))
    ax.imshow(image, cmap="gray", vmin=0, vmax=255)
    start, vectors = measurement.start, measurement.vectors
    for chosen, kind in ((measurement.inlier, "inlier"), (~measurement.inlier, "outlier")):
        if chosen.any():
            ax.quiver(
                start[chosen, 0],
                start[chosen, 1],
                vectors[chosen, 0],
                vectors[chosen, 1],
                angles="xy",
                scale_units="xy",
                scale=1.0 / scale,
                width=0.005,
                color=FLOW_COLOURS[kind],
                label=f"{int(chosen.sum())} {kind}{'s' if chosen.sum() != 1 else ''}",
            )
    if len(start):
        ax.legend(loc="lower right", fontsize="small", framealpha=0.8)
    ax.set_xlim(-0.5, image.shape[1] - 0.5)
    ax.set_ylim(image.shape[0] - 0.5, -0.5)
    ax.set_axis_off()
    return ax


def draw_flow_scatter(measurement, ax=None) -> plt.Axes:
    """The first paper's Fig. 17: every kept track's motion vector (du, dv) pixels as a point, inliers and outliers
    apart, with the median vector and the mean vector marked. v grows downwards, as in the image."""
    if ax is None:
        _, ax = plt.subplots(figsize=(5, 5))
    vectors = measurement.vectors
    for chosen, kind in ((measurement.inlier, "inlier"), (~measurement.inlier, "outlier")):
        if chosen.any():
            ax.plot(*vectors[chosen].T, ".", ms=5, color=FLOW_COLOURS[kind], label=f"{kind}s")
    if np.isfinite(measurement.median).all():
        for name, marker in (("median", "*"), ("mean", "X")):
            du, dv = getattr(measurement, name)
            ax.plot(du, dv, marker, ms=14, mec="k", color=FLOW_COLOURS[name], label=f"{name} ({du:+.2f}, {dv:+.2f})")
    ax.set_aspect("equal", adjustable="datalim")
    if not ax.yaxis_inverted():
        ax.invert_yaxis()
    ax.grid(True, alpha=0.3)
    ax.set_xlabel("du [px] (right)")
    ax.set_ylabel("dv [px] (down)")
    if len(vectors):
        ax.legend(fontsize="small")
    return ax


def klt_flow_panel(floor_images, mask=None, parameters: KLTParameters | None = None) -> widgets.VBox:
    """The KLT tracker's window size, pyramid levels, number of corners and quality level on a run of floor images.

    ``floor_images``: two or more consecutive floor images (H, W) uint8 of one size; ``mask``: their valid pixels
    (``FloorFlow``'s); ``parameters``: the ``KLTParameters`` the sliders start from (default: the package's). On
    each release a fresh ``FloorFlow`` tracks the images from the first up to the chosen frame, so that each search
    starts from the previous motion as in odometry, and the last pair is drawn: the earlier image, the later one
    with the kept motion vectors (inliers and outliers in two colours), and the vectors' (du, dv) scatter with the
    median and the mean (the first paper's Fig. 17); one line reads out the frame's quality record.
    """
    images = list(floor_images)
    if len(images) < 2:
        raise ValueError(f"klt_flow_panel needs two or more consecutive floor images, got {len(images)}")
    base = parameters or KLTParameters()
    style = {"description_width": "initial"}
    controls = {
        "window_px": int_slider("window [px]", base.window_px, 5, 51, step=2),
        "pyramid_levels": int_slider("pyramid levels", base.pyramid_levels, 0, 6),
        "max_corners": int_slider("max corners", base.max_corners, 5, 400, step=5),
        "quality_level": widgets.FloatLogSlider(
            value=base.quality_level,
            base=10,
            min=-3,
            max=-0.5,
            step=0.1,
            description="quality level",
            readout_format=".3f",
            continuous_update=False,
            style=style,
        ),
        "frame": widgets.IntSlider(
            value=len(images) - 1,
            min=1,
            max=len(images) - 1,
            description="frame",
            continuous_update=False,
            disabled=len(images) == 2,
            style=style,
        ),
    }

    def redraw(window_px: int, pyramid_levels: int, max_corners: int, quality_level: float, frame: int) -> None:
        chosen = dataclasses.replace(
            base,
            window_px=window_px,
            pyramid_levels=pyramid_levels,
            max_corners=max_corners,
            quality_level=quality_level,
        )
        flow = FloorFlow(chosen, mask)
        for image in images[: frame + 1]:
            measurement = flow.track(image)
        plt.close("all")
        _, (left, middle, right) = plt.subplots(1, 3, figsize=(14, 4.8), gridspec_kw={"width_ratios": [1, 1, 1.1]})
        left.imshow(images[frame - 1], cmap="gray", vmin=0, vmax=255)
        left.set_title(f"frame {frame - 1}")
        left.set_axis_off()
        draw_flow_vectors(images[frame], measurement, ax=middle)
        middle.set_title(f"frame {frame}: the kept tracks")
        draw_flow_scatter(measurement, ax=right)
        right.set_title("motion vectors (Fig. 17)")
        print(flow_quality_text(measurement, chosen))
        plt.show()

    sliders = widgets.HBox(list(controls.values()), layout={"flex_flow": "row wrap"})
    return widgets.VBox([sliders, widgets.interactive_output(redraw, controls)])


def flow_quality_text(measurement, parameters: KLTParameters | None = None) -> str:
    """One line about a ``FlowMeasurement``: its counts, its spread and its median and mean vectors, or its flag;
    with ``parameters``, also the pyramid's reach."""
    quality = measurement.quality
    reach = "" if parameters is None else f"; reach {parameters.reach_px:.0f} px"
    if not quality.ok:
        return f"flagged: {quality.flag} ({quality.tracked} tracked, {quality.kept} kept{reach})"
    (mu, mv), (au, av) = measurement.median, measurement.mean
    return (
        f"{quality.tracked} tracked, {quality.kept} kept, {quality.inliers} inliers ({quality.inlier_ratio:.0%}), "
        f"spread {quality.spread_px:.2f} px; median ({mu:+.2f}, {mv:+.2f}) px, mean ({au:+.2f}, {av:+.2f}) px{reach}"
    )


def recorded_floor_images(name: str, odometer, shown: int) -> tuple[list[np.ndarray], list[int], np.ndarray, object]:
    """Every frame of the simulated recording ``name`` (``gpo.sim.record.recording``, rendered on first use) as
    ``odometer``'s floor image (a ``gpo.pipeline.odometer.FloorOdometer``), with its stamp (ns); the fisheye frame
    number
    ``shown``; and the recording's ground truth of base_link (a ``Trajectory``)."""
    floors, stamps, fisheye = [], [], None
    with Recording(recording(name, progress=False)) as bag:
        for index, frame in enumerate(bag.frames(progress=False)):
            floors.append(odometer.floor_image(frame.image))
            stamps.append(frame.stamp_ns)
            if index == shown:
                fisheye = frame.image
        truth = bag.trajectory(GROUND_TRUTH_TOPIC)
    return floors, stamps, fisheye, truth


def tracks_text(measurement, true_end_px) -> str:
    """One line about a ``FlowMeasurement`` of a frame pair: its tracks kept of those tracked, its median vector (or
    "flagged") and how far the tracks end from ``true_end_px`` (N, 2), where their floor points truly are in the
    second frame, as an RMS in pixels."""
    quality = measurement.quality
    if len(measurement.start) == 0:
        return f"{quality.kept:3d} of {quality.tracked:3d} kept"
    error = np.linalg.norm(measurement.end - true_end_px, axis=1)
    vector = "flagged" if not quality.ok else "({:+6.2f}, {:+6.2f}) px".format(*measurement.median)
    rms = np.sqrt(np.mean(error**2))
    return f"{quality.kept:3d} of {quality.tracked:3d} kept, median {vector}, tracks off {rms:6.2f} px RMS"
