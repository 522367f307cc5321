"""ipywidgets panels for the notebooks. Each panel redraws its own figure when a slider is released."""

from __future__ import annotations

import dataclasses

import ipywidgets as widgets
import matplotlib.pyplot as plt
import numpy as np

from gpo.bag import Recording
from gpo.calibrate import CalibrationError, calibrate_corners
from gpo.camera import EUCM, T265_LIKE
from gpo.cubemap import Cubemap, default_face_size
from gpo.plots import draw_residuals, draw_room_in_image, draw_view_errors, field_of_view_text


def _slider(description: str, value: float, low: float, high: float, step: float) -> widgets.FloatSlider:
    return widgets.FloatSlider(
        value=value,
        min=low,
        max=high,
        step=step,
        description=description,
        continuous_update=False,
        readout_format=".2f",
        style={"description_width": "initial"},
    )


def eucm_panel(camera: EUCM = T265_LIKE, camera_height: float = 0.12) -> widgets.VBox:
    """Sliders for alpha, beta and the focal length f (fx = fy = f, pixels) of ``camera``.

    Each change redraws where a grid on the floor and the walls of a room lands in the image of
    a camera ``camera_height`` metres above the floor, and prints the field of view.
    """
    alpha = _slider("alpha", camera.alpha, 0.0, 1.0, 0.01)
    beta = _slider("beta", camera.beta, 0.1, 3.0, 0.05)
    focal = _slider("f [px]", camera.fx, 80.0, 800.0, 2.0)

    def redraw(alpha: float, beta: float, focal: float) -> None:
        shown = dataclasses.replace(camera, fx=focal, fy=focal, alpha=alpha, beta=beta)
        plt.close("all")
        _, ax = plt.subplots(figsize=(6.4, 6.4 * shown.height / shown.width))
        draw_room_in_image(shown, ax=ax, height=camera_height)
        ax.set_title(f"alpha={alpha:.2f}  beta={beta:.2f}  f={focal:.0f} px")
        print(field_of_view_text(shown))
        plt.show()

    output = widgets.interactive_output(redraw, {"alpha": alpha, "beta": beta, "focal": focal})
    panel = widgets.VBox([widgets.HBox([alpha, beta, focal]), output])
    return panel


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


def calibration_panel(corners: list, board, image_size: tuple[int, int]) -> widgets.VBox:
    """Drop views and switch the model, then see the calibration again: residuals, per-view errors, summary.

    ``corners``: one (N, 2) pixel array per view in the order of ``board.inner_corners()`` (as
    ``CalibrationResult.corners`` holds them); ``image_size`` = (width, height) pixels.
    """
    names = [f"view {index}" for index in range(len(corners))]
    model = widgets.ToggleButtons(options=["eucm", "pinhole"], value="eucm", description="model")
    dropped = widgets.SelectMultiple(options=names, rows=6, description="drop views")

    def redraw(model: str, dropped: tuple[str, ...]) -> None:
        kept = [None if name in dropped else view for name, view in zip(names, corners, strict=True)]
        plt.close("all")
        try:
            result = calibrate_corners(kept, board, image_size, model)
        except CalibrationError as error:
            print(f"no calibration: {error}")
            return
        _, (left, right) = plt.subplots(1, 2, figsize=(12, 4.6), gridspec_kw={"width_ratios": [1, 1.3]})
        draw_residuals(result, ax=left)
        draw_view_errors(result, ax=right)
        print(result.summary())
        plt.show()

    output = widgets.interactive_output(redraw, {"model": model, "dropped": dropped})
    return widgets.VBox([widgets.HBox([model, dropped]), output])


def cubemap_panel(fisheye_image, camera: EUCM) -> widgets.VBox:
    """A face-size slider over the cubemap of ``fisheye_image``: the cross of the five faces, redrawn on release.

    The default face size (``gpo.cubemap.default_face_size``) keeps the fisheye's pixel density at the
    front face's centre; smaller faces throw detail away, larger ones only interpolate.
    """
    default = default_face_size(camera)
    size = widgets.IntSlider(
        value=default, min=64, max=2 * default, step=2, description="face [px]", continuous_update=False
    )

    def redraw(face_size: int) -> None:
        cubemap = Cubemap(camera, face_size)
        plt.close("all")
        _, ax = plt.subplots(figsize=(7, 7))
        ax.imshow(cubemap.cross(fisheye_image), cmap="gray", vmin=0, vmax=255)
        ax.set_title(f"five faces of {face_size} x {face_size} px, f = {face_size / 2:.0f} px")
        ax.axis("off")
        plt.show()

    return widgets.VBox([size, widgets.interactive_output(redraw, {"face_size": size})])
