"""Chapter 00, the overview: the rig's view of the floor, how far it reaches, the tracking camera's drift over seeds,
one frame along the method, and a browser over a simulated recording."""

from __future__ import annotations

import ipywidgets as widgets
import matplotlib.pyplot as plt
import numpy as np

from gpo.cameras.rig import Rig, floor_points, rays_in_base
from gpo.floor_image.analytic import analytic_table
from gpo.floor_image.cubemap import Cubemap
from gpo.floor_image.image import FloorImage
from gpo.io.bag import Recording
from gpo.io.trajectory import base_from_sensor_odometry
from gpo.sim.drift import tracking_odometry
from gpo.sim.record import START_NS, preset


def floor_seen(rig: Rig, max_range: float = np.inf, step: int = 1) -> np.ndarray:
    """The floor points (N, 2), metres in ``base_link``, of the rig's pixels on a grid every ``step`` pixels whose
    ray meets the floor within ``max_range`` metres (horizontally) of the camera."""
    pixels = rig.camera.pixel_grid()[::step, ::step]
    rays, valid = rays_in_base(rig, pixels)
    points, hits = floor_points(rig, rays)
    with np.errstate(invalid="ignore"):
        seen = valid & hits & (np.linalg.norm(points - rig.mount.position[:2], axis=-1) <= max_range)
    return points[seen]


def floor_extent_text(rig: Rig, max_range: float = np.inf) -> str:
    """One line: the box (``base_link``, metres) around the floor that the rig's camera sees within ``max_range``."""
    points = floor_seen(rig, max_range)
    (x_min, y_min), (x_max, y_max) = points.min(axis=0), points.max(axis=0)
    within = "" if np.isinf(max_range) else f" (within {max_range:.1f} m)"
    return (
        f"{rig.name}: floor seen{within} from x = {x_min:.2f} to {x_max:.2f} m and y = {y_min:.2f} to {y_max:.2f} m, "
        f"a box {x_max - x_min:.2f} m long and {y_max - y_min:.2f} m wide"
    )


def draw_rig_footprint(rig: Rig, ax=None, max_range: float = 1.5, step: int = 8, color: str = "tab:blue") -> plt.Axes:
    """Top view (``base_link``, metres) of the floor the rig's camera sees within ``max_range`` metres.

    Each dot is the floor point of one pixel of a grid every ``step`` pixels; pixels whose ray misses
    the floor, or meets it further than ``max_range`` from the camera, are left out.
    """
    if ax is None:
        _, ax = plt.subplots(figsize=(5, 5))
    points = floor_seen(rig, max_range, step)
    ax.plot(points[:, 0], points[:, 1], ".", ms=1, color=color, label=f"floor seen by {rig.name}")
    ax.plot(*rig.mount.position[:2], "^", ms=9, color="k", label="camera")
    ax.set_aspect("equal")
    ax.set_xlabel("x forward [m]")
    ax.set_ylabel("y left [m]")
    return ax


def drift_by_seed(name: str = "sample", seeds=range(1, 13)) -> dict[int, float]:
    """The tracking camera's final position error (metres, in the floor plane, its odometry expressed as base_link's
    path) on preset ``name``'s path for each seed, as the preset's recording with that seed would hold it; no image is
    rendered. Returns seed -> error."""
    setup = preset(name).setup()
    plan, mount = setup.plan, setup.rig.mount
    truth = plan.ground_truth(120.0, START_NS)
    start = (truth.rotations[0], truth.positions[0])
    errors = {}
    for seed in seeds:
        odometry = tracking_odometry(plan, mount, 200.0, setup.drift, seed, START_NS)
        path = base_from_sensor_odometry(odometry, (mount.body_rotation, mount.position), start)
        errors[seed] = float(np.linalg.norm(path.positions[-1, :2] - truth.positions[-1, :2]))
    return errors


def draw_method_preview(image: np.ndarray, rig: Rig, axes=None) -> np.ndarray:
    """One fisheye frame along the method: the frame, its cubemap (chapter 02) and the top view of the floor patch
    the method tracks (chapters 03-04; here from the calibration and the mount). Returns the three axes."""
    if axes is None:
        _, axes = plt.subplots(
            1, 3, figsize=(13, 4.4), gridspec_kw={"width_ratios": [1.06, 1.0, 0.8]}, layout="constrained"
        )
    floor = FloorImage.top_view()
    top_view = analytic_table(rig.camera, rig.mount, floor, cache=False).apply(image)
    x_near, x_far, y_right, y_left = floor.extent
    ticks = np.arange(-0.1, 1.0, 0.05)
    shown = (
        (image, "the fisheye's frame (chapter 01)", None),
        (Cubemap(rig.camera).cross(image), "its cubemap (chapter 02)", None),
        (top_view, "the floor ahead, from above (03-04)", (y_left, y_right, x_near, x_far)),
    )
    for ax, (picture, title, extent) in zip(axes, shown, strict=True):
        ax.imshow(picture, cmap="gray", vmin=0, vmax=255, extent=extent)
        ax.set_title(title, fontsize="medium")
        if extent is None:
            ax.axis("off")
        else:
            ax.set_xticks(ticks[(ticks >= y_right - 1e-9) & (ticks <= y_left + 1e-9)])
            ax.set_yticks(ticks[(ticks >= x_near - 1e-9) & (ticks <= x_far + 1e-9)])
            ax.set_xlabel("y, left [m]")
            ax.set_ylabel("x, ahead [m]")
    return axes


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
