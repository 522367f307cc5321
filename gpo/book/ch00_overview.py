"""Chapter 00, the overview: the rig's view of the floor and a browser over a simulated recording."""

from __future__ import annotations

import ipywidgets as widgets
import matplotlib.pyplot as plt
import numpy as np

from gpo.bag import Recording
from gpo.rig import Rig, floor_points, rays_in_base


def draw_rig_footprint(rig: Rig, ax=None, max_range: float = 1.5, step: int = 8, color: str = "tab:blue") -> plt.Axes:
    """Top view (``base_link``, metres) of the floor the rig's camera sees within ``max_range`` metres.

    Each dot is the floor point of one pixel of a grid every ``step`` pixels; pixels whose ray misses
    the floor, or meets it further than ``max_range`` from the camera, are left out.
    """
    if ax is None:
        _, ax = plt.subplots(figsize=(5, 5))
    pixels = rig.camera.pixel_grid()[::step, ::step]
    rays, valid = rays_in_base(rig, pixels)
    points, hits = floor_points(rig, rays)
    with np.errstate(invalid="ignore"):
        seen = valid & hits & (np.linalg.norm(points - rig.mount.position[:2], axis=-1) <= max_range)
    ax.plot(points[seen, 0], points[seen, 1], ".", ms=1, color=color, label=f"floor seen by {rig.name}")
    ax.plot(*rig.mount.position[:2], "^", ms=9, color="k", label="camera")
    ax.set_aspect("equal")
    ax.set_xlabel("x forward [m]")
    ax.set_ylabel("y left [m]")
    return ax


def recording_browser(path, topic: str | None = None, ground_truth_topic: str = "/mocap/base_link") -> widgets.VBox:
    """A time slider over a recording: the camera frame at that time beside the ground-truth path.

    Only the one frame shown is read from the bag; ``topic`` is the image topic (found when None).
    """
    with Recording(path) as bag:
        image_topic = bag.image_topic(topic)
        truth = bag.trajectory(ground_truth_topic)
        start_ns, duration_s = bag.start_ns, bag.duration_s
    time = widgets.FloatSlider(
        value=0.0, min=0.0, max=round(duration_s, 2), step=0.1, description="t [s]", continuous_update=False
    )

    def redraw(time_s: float) -> None:
        stamp_ns = start_ns + round(time_s * 1e9)
        with Recording(path) as bag:
            frame = next(bag.frames(image_topic, start_ns=stamp_ns, progress=False), None)
        plt.close("all")
        _, (left, right) = plt.subplots(1, 2, figsize=(11, 4.6), gridspec_kw={"width_ratios": [1.1, 1]})
        if frame is not None:
            left.imshow(frame.image, cmap="gray", vmin=0, vmax=255)
            left.set_title(f"{image_topic} at {(frame.stamp_ns - start_ns) * 1e-9:.2f} s")
        left.axis("off")
        here = min(np.searchsorted(truth.stamps_ns, stamp_ns), len(truth) - 1)
        right.plot(truth.positions[:, 0], truth.positions[:, 1], color="0.6", lw=1)
        right.plot(*truth.positions[here, :2], "o", color="tab:red")
        right.set_aspect("equal")
        right.set_xlabel("x [m]")
        right.set_ylabel("y [m]")
        right.set_title("ground truth of base_link")
        plt.show()

    return widgets.VBox([time, widgets.interactive_output(redraw, {"time_s": time})])
