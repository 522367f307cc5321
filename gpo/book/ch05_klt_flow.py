"""Chapter 05, KLT flow on the floor image: a recording's floor images, the tracks and their motion vectors (the first
paper's Fig. 17), a frame's quality and its tracks against the truth in one line, and the tracker's panel. The first
paper's Table 3 (the mean and the median vector on the short paths) is ``gpo.experiments.table3``."""

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
