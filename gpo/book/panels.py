"""ipywidgets panels for the notebooks. Each panel redraws its own figure when a slider is released."""

from __future__ import annotations

import dataclasses
import math
import time

import ipywidgets as widgets
import matplotlib.pyplot as plt
import numpy as np

from gpo.bag import Recording
from gpo.calibrate import CalibrationError, calibrate_corners
from gpo.camera import EUCM, T265_LIKE
from gpo.cubemap import Cubemap, default_face_size
from gpo.features import DETECTORS, FeatureParameters, FeatureTracker, detect
from gpo.flow import FloorFlow, KLTParameters
from gpo.fusion import FilterDiverged, FusionSettings, fuse
from gpo.ground import (
    FloorImage,
    GroundImageError,
    analytic_table,
    board_corners,
    front_face_corners,
    ground_plane_image,
    ortho_rectify,
    route_difference,
)
from gpo.kinematics import (
    PaperBicycle,
    arc_increment,
    between,
    exact_velocities,
    integrate,
    paper_heading_rate_ratio,
)
from gpo.metrics import Alignment, evaluate, final_error
from gpo.mount import floor_angles
from gpo.plots import (
    draw_evaluated_paths,
    draw_evaluation_errors,
    draw_feature_matches,
    draw_floor_image,
    draw_flow_scatter,
    draw_flow_vectors,
    draw_heading_rate_ratio,
    draw_invariance_loops,
    draw_match_histogram,
    draw_paths_on_truth,
    draw_position_errors,
    draw_residuals,
    draw_room_in_image,
    draw_view_errors,
    field_of_view_text,
)
from gpo.rig import CameraMount


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


def _int_slider(description: str, value: int, low: int, high: int, step: int = 1) -> widgets.IntSlider:
    return widgets.IntSlider(
        value=value,
        min=low,
        max=high,
        step=step,
        description=description,
        continuous_update=False,
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


GPI_CORNER_NAMES = ("near-right", "far-right", "far-left", "near-left")
"""The four corners of eq. 22 in the order of ``gpo.ground.front_face_corners``."""
MAX_PANEL_PIXELS = 2_000_000  # floor images larger than this are not redrawn by a panel: too slow to be interactive


def gpi_corners_panel(fisheye_image, camera, placement, mount=None) -> widgets.VBox:
    """Move the four corners of eq. 22 by hand in the front face and see the GPI they give, redrawn on release.

    The sliders (front-face pixels) start at the corners found automatically (``gpo.ground.front_face_corners``
    for the board lying at ``placement``). Left: the front face with the corners found (circles) and those used
    (the outline); right: the GPI made the paper's way. With ``mount``, the camera's true mount (the simulator
    knows it), it also prints how far the GPI's front-face part puts the floor from where it truly is.
    """
    cubemap = Cubemap(camera)
    found = front_face_corners(fisheye_image, cubemap, placement)
    front = cubemap.face_image(fisheye_image, "front")
    controls = {}
    for index, (name, (u, v)) in enumerate(zip(GPI_CORNER_NAMES, found, strict=True)):
        controls[f"u{index}"] = _slider(f"{name} u", float(u), round(u) - 20.0, round(u) + 20.0, 0.1)
        controls[f"v{index}"] = _slider(f"{name} v", float(v), round(v) - 20.0, round(v) + 20.0, 0.1)

    def redraw(**values: float) -> None:
        corners = np.array([[values[f"u{index}"], values[f"v{index}"]] for index in range(4)])
        plt.close("all")
        try:
            gpi = ground_plane_image(fisheye_image, camera, placement, corners=corners, cache=False)
        except GroundImageError as error:
            print(f"no GPI: {error}")
            return
        _, (left, right) = plt.subplots(1, 2, figsize=(11, 5.5))
        left.imshow(front, cmap="gray", vmin=0, vmax=255)
        left.plot(*found.T, "o", mfc="none", color="tab:blue", label="found")
        left.plot(*np.vstack([corners, corners[:1]]).T, "-", color="tab:red", lw=1, label="used")
        (u_min, v_min), (u_max, v_max) = corners.min(axis=0) - 60, corners.max(axis=0) + 60
        left.set(xlim=(u_min, u_max), ylim=(v_max, v_min), title="front face (zoomed on the board)")
        left.legend(fontsize="small")
        right.imshow(gpi.staged(fisheye_image), cmap="gray", vmin=0, vmax=255)
        right.axhline(gpi.front_rows - 0.5, color="tab:orange", lw=0.8)
        right.set_title("GPI: warped front face above, bottom face below")
        moved = np.linalg.norm(corners - found, axis=1).max()
        print(f"corners up to {moved:.1f} px from those found; GPI {gpi.size[0]} x {gpi.size[1]} px")
        if mount is not None:
            truth = analytic_table(camera, mount, gpi.floor, max_outside=1.0, cache=False)
            error_mm = route_difference(gpi.table, truth).floor_mm[: gpi.front_rows]
            mean, worst = np.nanmean(error_mm), np.nanmax(error_mm)
            print(f"front-face part against the truth: mean {mean:.1f} mm, worst {worst:.1f} mm")
        plt.show()

    rows = [widgets.HBox([controls[f"u{index}"], controls[f"v{index}"]]) for index in range(4)]
    return widgets.VBox([*rows, widgets.interactive_output(redraw, controls)])


def gpi_extent_panel(fisheye_image, camera, placement, mount=None) -> widgets.VBox:
    """How far ahead the GPI reaches (``ahead_m``) and how many bottom-face rows it keeps, redrawn on release.

    The corners are found once (``front_face_corners``). Left: the GPI, the seam marked; right: where it lies in
    base_link (``gpo.plots.draw_floor_image``; the camera marked at ``mount`` when given). Too far ahead, the front
    face resolves the floor no more, and the panel prints the package's error, which says what fits.
    """
    corners = front_face_corners(fisheye_image, Cubemap(camera), placement)
    default = ground_plane_image(fisheye_image, camera, placement, corners=corners, cache=False)
    ahead = _slider("ahead [m]", 0.30, 0.05, 1.00, 0.01)
    rows = _int_slider("bottom rows", default.bottom_rows, 1, default.cubemap.face_size)

    def redraw(ahead_m: float, bottom_rows: int) -> None:
        plt.close("all")
        try:
            gpi = ground_plane_image(
                fisheye_image, camera, placement, corners, ahead_m=ahead_m, bottom_rows=bottom_rows, cache=False
            )
        except GroundImageError as error:
            print(f"no GPI: {error}")
            return
        image = gpi.staged(fisheye_image)
        _, (left, right) = plt.subplots(1, 2, figsize=(11, 5.5))
        left.imshow(image, cmap="gray", vmin=0, vmax=255)
        left.axhline(gpi.front_rows - 0.5, color="tab:orange", lw=0.8)
        left.set_title(f"GPI {gpi.size[0]} x {gpi.size[1]} px: {gpi.front_rows} rows of front face above the seam")
        draw_floor_image(image, gpi.floor, ax=right, mount=mount)
        x_min, x_max, y_min, y_max = gpi.floor.extent
        print(
            f"the GPI covers x {x_min:.3f}..{x_max:.3f} m, y {y_min:.3f}..{y_max:.3f} m of base_link at about "
            f"{gpi.floor.metres_per_pixel * 1e3:.2f} mm per pixel (nominal: the plain GPI is not exactly metric)"
        )
        plt.show()

    output = widgets.interactive_output(redraw, {"ahead_m": ahead, "bottom_rows": rows})
    return widgets.VBox([widgets.HBox([ahead, rows]), output])


def ortho_extent_panel(fisheye_image, camera, placement, mount=None) -> widgets.VBox:
    """The ortho-GPI's extent (near and far x, half width in y, metres in base_link) and millimetres per pixel.

    The GPI and the board's block in it are found once; each release fits the second homography to the new
    ``FloorImage.top_view`` and redraws the ortho-GPI, left in its pixels and right where it lies in base_link.
    An extent the GPI does not show prints the package's error with one that fits; floor images of more than
    ``MAX_PANEL_PIXELS`` pixels are not drawn.
    """
    gpi = ground_plane_image(fisheye_image, camera, placement, cache=False)
    gpi_image = gpi.table.apply(fisheye_image)
    corners = board_corners(gpi_image, gpi.floor, placement)
    controls = {
        "near": _slider("near x [m]", 0.70, 0.55, 1.00, 0.01),
        "far": _slider("far x [m]", 0.90, 0.60, 1.10, 0.01),
        "half_width": _slider("half width [m]", 0.10, 0.02, 0.30, 0.01),
        "millimetres": _slider("mm per pixel", 0.50, 0.20, 2.00, 0.05),
    }

    def redraw(near: float, far: float, half_width: float, millimetres: float) -> None:
        plt.close("all")
        try:
            floor = FloorImage.top_view((near, far), (-half_width, half_width), millimetres * 1e-3)
            if floor.width * floor.height > MAX_PANEL_PIXELS:
                print(f"{floor.width} x {floor.height} px is too many to redraw here: more mm per pixel or less floor")
                return
            ortho = ortho_rectify(gpi, gpi_image, placement, floor, corners=corners)
        except GroundImageError as error:
            print(f"no ortho-GPI: {error}")
            return
        image = ortho.table.apply(fisheye_image)
        _, (left, right) = plt.subplots(1, 2, figsize=(11, 5.5))
        left.imshow(image, cmap="gray", vmin=0, vmax=255)
        left.set_title(f"ortho-GPI {floor.width} x {floor.height} px, {millimetres:.2f} mm per pixel")
        draw_floor_image(image, floor, ax=right, mount=mount)
        approximate = ortho.through_bottom_face().mean()
        print(f"{approximate:.0%} of it is seen through the GPI's bottom-face rows (only approximately metric there)")
        plt.show()

    sliders = widgets.HBox(list(controls.values()), layout={"flex_flow": "row wrap"})
    return widgets.VBox([sliders, widgets.interactive_output(redraw, controls)])


def analytic_mount_panel(fisheye_image, camera, mount: CameraMount, reference, placement=None) -> widgets.VBox:
    """The analytic route's camera height, pitch and roll: its floor image redrawn on release, and how far it lies
    from ``reference`` (a ``RemapTable``, e.g. the chessboard route's ortho-GPI), in millimetres on the floor.

    The sliders start at ``mount``'s values (a forward mount, no yaw: ``CameraMount.forward`` at the mount's x and
    y); the image covers ``reference.floor``. With ``placement``, the board's true inner corners are marked: a
    wrong height scales the image about the point below the camera, a wrong pitch stretches it, a wrong roll skews it.
    """
    pitch, roll = floor_angles(mount.rotation.inv().apply([0.0, 0.0, 1.0]))
    x, y = mount.position[:2]
    height_mm = 1e3 * mount.height
    controls = {
        "height_mm": _slider("height [mm]", height_mm, 0.5 * height_mm, 1.5 * height_mm, 0.5),
        "pitch_deg": _slider("pitch [deg]", math.degrees(pitch), -5.0, 25.0, 0.1),
        "roll_deg": _slider("roll [deg]", math.degrees(roll), -10.0, 10.0, 0.1),
    }
    floor = reference.floor

    def redraw(height_mm: float, pitch_deg: float, roll_deg: float) -> None:
        guess = CameraMount.forward(x, y, height_mm * 1e-3, math.radians(pitch_deg), math.radians(roll_deg))
        table = analytic_table(camera, guess, floor, max_outside=1.0, cache=False)
        difference = route_difference(reference, table)
        plt.close("all")
        _, ax = plt.subplots(figsize=(6, 6))
        ax.imshow(table.apply(fisheye_image), cmap="gray", vmin=0, vmax=255)
        if placement is not None:
            ax.plot(*floor.base_to_pixel(placement.corners_world()[:, :2]).T, "+", color="tab:red", ms=6)
        ax.set_title(f"analytic: height {height_mm:.1f} mm, pitch {pitch_deg:.1f} deg, roll {roll_deg:.1f} deg")
        ax.axis("off")
        print(
            f"from the reference: mean {difference.mean_mm:.2f} mm, worst {difference.max_mm:.2f} mm on the floor "
            f"({difference.mean_px:.2f} px, {difference.max_px:.2f} px in the fisheye); {table.outside_fraction:.0%} "
            "of the image not seen"
        )
        plt.show()

    return widgets.VBox([widgets.HBox(list(controls.values())), widgets.interactive_output(redraw, controls)])


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
        "window_px": _int_slider("window [px]", base.window_px, 5, 51, step=2),
        "pyramid_levels": _int_slider("pyramid levels", base.pyramid_levels, 0, 6),
        "max_corners": _int_slider("max corners", base.max_corners, 5, 400, step=5),
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


def constant_steering_paths(
    wheelbase_m: float,
    rear_to_reference_m: float,
    speed_mps: float,
    steering_rad: float,
    duration_s: float,
    rate_hz: float = 30.0,
) -> tuple[np.ndarray, np.ndarray]:
    """base_link's poses (N + 1, 3) over ``duration_s`` of a drive whose virtual front wheel (L ahead of the rear
    axle) moves at ``speed_mps`` in the constant direction ``steering_rad`` in base_link: the exact motion (circular
    arcs, ``gpo.kinematics.exact_velocities`` and ``arc_increment``) and what the first paper's model
    (``PaperBicycle(wheelbase_m, rear_to_reference_m)``, eqs. 25-34) makes of it, fed each frame (``rate_hz``) with
    the front wheel's displacement as the floor image shows it."""
    dt = 1.0 / rate_hz
    frames = max(1, round(duration_s * rate_hz))
    v, omega = exact_velocities(speed_mps, steering_rad, wheelbase_m)
    increment = arc_increment(v, omega, dt)
    exact = integrate(np.tile(increment, (frames, 1)))
    seen_at = between(increment, [wheelbase_m, 0.0, 0.0])[:2]  # the floor point under the wheel, at the frame's end
    displacement = np.array([wheelbase_m, 0.0]) - seen_at
    model = PaperBicycle(wheelbase_m, rear_to_reference_m)
    paper = [np.zeros(3)]
    for _ in range(frames):
        paper.append(model.step(paper[-1], displacement, dt))
    return exact, np.array(paper)


def bicycle_panel(wheelbase_m: float = 0.8, rear_to_reference_m: float = 0.8, rate_hz: float = 30.0) -> widgets.VBox:
    """The first paper's bicycle model against the exact kinematics: the wheelbase L, the reference point l_r, a
    constant steering angle delta, the front wheel's speed V and how long it drives.

    Left: eq. 30's heading rate over the true one against delta for this L and l_r (``draw_heading_rate_ratio``),
    the chosen delta marked. Right: the path of base_link under constant steering, exact and as the paper's model
    integrates it frame by frame at ``rate_hz`` (``constant_steering_paths``). One line says how far apart they end.
    """
    style = {"description_width": "initial"}
    length = _slider("L [m]", wheelbase_m, 0.2, 2.0, 0.05)
    lever = _slider("l_r [m]", rear_to_reference_m, 0.0, wheelbase_m, 0.01)
    controls = {
        "wheelbase_m": length,
        "rear_to_reference_m": lever,
        "steering_deg": _slider("delta [deg]", 20.0, 0.0, 60.0, 1.0),
        "speed_mps": _slider("V [m/s]", 0.5, 0.05, 2.0, 0.05),
        "duration_s": _slider("time [s]", 5.0, 0.5, 20.0, 0.5),
    }
    for control in controls.values():
        control.style = style
    controls["steering_deg"].readout_format = ".0f"

    def follow_wheelbase(change) -> None:  # l_r lies between the rear axle and the front wheel
        lever.max = change["new"]

    length.observe(follow_wheelbase, names="value")  # before interactive_output's own observer: l_r is clamped first

    def redraw(wheelbase_m, rear_to_reference_m, steering_deg, speed_mps, duration_s) -> None:
        rear_to_reference_m = min(rear_to_reference_m, wheelbase_m)
        steering = math.radians(steering_deg)
        exact, paper = constant_steering_paths(
            wheelbase_m, rear_to_reference_m, speed_mps, steering, duration_s, rate_hz
        )
        ratio = float(paper_heading_rate_ratio(steering, wheelbase_m, rear_to_reference_m))
        plt.close("all")
        _, (left, right) = plt.subplots(1, 2, figsize=(12, 4.8), gridspec_kw={"width_ratios": [1, 1.1]})
        draw_heading_rate_ratio(wheelbase_m, rear_to_reference_m, ax=left)
        left.plot(steering_deg, ratio, "o", color="tab:red")
        left.set_title(f"L = {wheelbase_m:.2f} m, l_r = {rear_to_reference_m:.2f} m")
        for name, poses, line in (("exact", exact, "-"), ("the paper's model", paper, "--")):
            right.plot(poses[:, 0], poses[:, 1], line, label=name)
            right.plot(*poses[-1, :2], "o", color=right.lines[-1].get_color())
        right.plot(0.0, 0.0, "go", label="start")
        right.set_aspect("equal", adjustable="datalim")
        right.set_xlabel("x [m]")
        right.set_ylabel("y [m]")
        right.grid(True, alpha=0.3)
        right.legend(fontsize="small")
        right.set_title(f"base_link over {duration_s:.1f} s, delta = {steering_deg:.0f} deg, V = {speed_mps:.2f} m/s")
        apart = float(np.hypot(*(paper[-1, :2] - exact[-1, :2])))
        turned = math.degrees(paper[-1, 2] - exact[-1, 2])
        chord = -speed_mps * math.cos(steering) / rate_hz / (2.0 * wheelbase_m)
        print(
            f"eq. 30 turns {ratio:.3f}x as fast as the robot, eq. 26's chord {100 * chord:+.2f} % a frame at "
            f"{rate_hz:.0f} Hz; the paper's model ends {apart:.3f} m from the exact path, heading {turned:+.2f} deg"
        )
        plt.show()

    sliders = widgets.HBox(list(controls.values()), layout={"flex_flow": "row wrap"})
    return widgets.VBox([sliders, widgets.interactive_output(redraw, controls)])


FUSION_SLIDERS = {  # FusionSettings field -> (slider label, log10 of its lowest and highest value)
    "floor_speed_sigma_mps": ("floor sigma v [m/s]", -4.0, 0.0),
    "floor_turn_sigma_radps": ("floor sigma omega [rad/s]", -4.0, 0.0),
    "tracking_position_walk_m_per_sqrt_s": ("camera position walk [m/sqrt(s)]", -4.0, 0.0),
    "tracking_yaw_walk_rad_per_sqrt_s": ("camera yaw walk [rad/sqrt(s)]", -5.0, -1.0),
    "accel_mps2": ("accel [m/s^2/sqrt(Hz)]", -2.0, 2.0),
    "angular_accel_radps2": ("angular accel [rad/s^2/sqrt(Hz)]", -2.0, 2.0),
}


def fusion_panel(floor, tracking, truth, settings: FusionSettings | None = None, drifted=None) -> widgets.VBox:
    """The EKF's noise parameters on log-scale sliders (``FUSION_SLIDERS``): the sigmas of the floor's (v, omega), the
    tracking camera's random walks and the process noise; a floor outage (its start and length, seconds: the floor's
    steps inside it not fused); and, when ``drifted`` is given, the tracking camera's drift (scale error %, yaw bias
    mrad/s). On each release ``gpo.fusion.fuse`` runs again.

    ``floor``: the floor odometry with its flow's inlier counts (a ``gpo.sim.table4.FloorRun``, or anything with its
    ``trajectory``, ``inliers`` and ``spread_px``); ``tracking``: the tracking camera's path of base_link;
    ``truth``: the true path; ``settings``: the ``FusionSettings`` the sliders start from (default: the package's);
    ``drifted(scale_error, yaw_bias_radps)``: the tracking camera's path with that drift (then ``tracking`` is unused).
    Left, the three paths placed on the truth at their first pose; right, their position error along the way. One
    line reads out the fused path's final error (``gpo.metrics.final_error``), the camera's biases as the filter
    estimated them, and how many measurements the NIS gate refused.
    """
    base = settings or FusionSettings()
    style = {"description_width": "initial"}
    controls = {
        name: widgets.FloatLogSlider(
            value=getattr(base, name),
            base=10,
            min=low,
            max=high,
            step=0.1,
            description=label,
            readout_format=".2g",
            continuous_update=False,
            style=style,
        )
        for name, (label, low, high) in FUSION_SLIDERS.items()
    }
    seconds = floor.trajectory.times - floor.trajectory.times[0]
    controls["outage_start"] = _slider("outage from [s]", 0.0, 0.0, float(seconds[-1]), 0.5)
    controls["outage_length"] = _slider("outage length [s]", 0.0, 0.0, 5.0, 0.5)
    if drifted is not None:
        controls["scale_percent"] = _slider("camera scale error [%]", 2.0, -5.0, 5.0, 0.5)
        controls["yaw_bias_mradps"] = _slider("camera yaw bias [mrad/s]", 1.0, -5.0, 5.0, 0.5)
    styles = {"tracking camera": {"color": "tab:orange"}, "floor": {"color": "tab:blue"}, "fused": {"color": "tab:red"}}
    spread = getattr(floor, "spread_px", None)

    def redraw(outage_start, outage_length, scale_percent=None, yaw_bias_mradps=None, **sigmas: float) -> None:
        chosen = dataclasses.replace(base, **sigmas)
        camera = tracking if drifted is None else drifted(scale_percent / 100, yaw_bias_mradps / 1e3)
        inliers = np.where((seconds >= outage_start) & (seconds < outage_start + outage_length), 0, floor.inliers)
        plt.close("all")
        try:
            fused = fuse(floor.trajectory, inliers, camera, chosen, spread)
        except FilterDiverged as error:
            print(f"no fused path: {error}")
            return
        paths = {"tracking camera": camera, "floor": floor.trajectory, "fused": fused.trajectory}
        _, (left, right) = plt.subplots(1, 2, figsize=(13, 4.8), gridspec_kw={"width_ratios": [1, 1.2]})
        draw_paths_on_truth(paths, truth, ax=left, styles=styles)
        left.set_title("the paths, each placed on the truth at its start")
        draw_position_errors(paths, truth, ax=right, styles=styles)
        gap = f" (no floor {outage_start:.1f}-{outage_start + outage_length:.1f} s)" if outage_length > 0 else ""
        right.set_title(f"how far from the truth, along the way{gap}")
        error = final_error(fused.trajectory, truth)
        scale, yaw_bias = fused.biases[-1]
        print(
            f"fused: final error {1e3 * error.position_m:.1f} mm ({error.percent:.2f} % of {error.distance_m:.2f} m), "
            f"heading {math.degrees(error.heading_rad):+.2f} deg; camera scale {100 * scale:+.2f} %, yaw bias "
            f"{1e3 * yaw_bias:+.2f} mrad/s as estimated; the NIS gate refused {fused.refused} measurement(s)"
        )
        plt.show()

    sliders = widgets.HBox(list(controls.values()), layout={"flex_flow": "row wrap"})
    return widgets.VBox([sliders, widgets.interactive_output(redraw, controls)])


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
        "invariance_threshold": _slider("t", base.invariance_threshold, 0.5, 1.0, 0.01),
        "cardinality": widgets.Dropdown(  # 0 stands for None, "auto": a Dropdown's None is no choice at all
            options=[("auto", 0), *((str(size), size) for size in sizes)],
            value=base.cardinality or 0,
            description="C",
            style=style,
        ),
        "orientation_bins": _int_slider("orientation bins", base.orientation_bins, 10, 360),
        "length_bins": _int_slider("length bins", base.length_bins, 10, 320),
        "ratio": _slider("ratio test", base.ratio, 0.5, 1.0, 0.01),
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
    """One line about a ``gpo.features.FeatureMatches``: the matches left after each stage that ran, the flag if
    any, and each stage's wall time in milliseconds."""
    counts = [f"{len(matches.pairs)} matches"]
    if matches.histogram is not None:
        counts.append(f"{int(matches.histogram_kept.sum())} after the histogram filter")
    if matches.invariance is not None:
        counts.append(f"{int(matches.kept.sum())} after the invariance check")
    flag = f"; flagged: {matches.flag}" if matches.flag is not None else ""
    times = ", ".join(f"{stage} {1e3 * seconds:.1f} ms" for stage, seconds in matches.seconds.items())
    return f"{', '.join(counts)}{flag} ({times})"


def evaluation_panel(table, shown: tuple | None = None) -> widgets.VBox:
    """Every row of a Table 4 (``gpo.sim.table4.Table4``) on one path, under the alignment chosen.

    ``table.evaluations[row][path]`` holds each row's estimate placed on the truth at its first pose (``origin``,
    shown as it is); for ``se2``, ``se3`` or ``posyaw`` the panel aligns it again (``gpo.metrics.evaluate``, once
    per row, path and alignment; an alignment that moves the whole path is the same from either start) and draws
    the paths over the truth and their position errors along the distance travelled. ``shown``: the rows selected
    at first (default: the table's first three). One line a row reads out its APE RMSE and maximum, final position
    error in mm and % of the distance, and heading RMSE.
    """
    labels = {row.label: row for row in table.rows}
    style = {"description_width": "initial"}
    controls = {
        "path": widgets.Dropdown(options=table.paths, value=table.paths[0], description="path", style=style),
        "alignment": widgets.Dropdown(
            options=[mode.value for mode in Alignment if mode is not Alignment.NONE],
            value=Alignment.ORIGIN.value,
            description="alignment",
            style=style,
        ),
        "chosen": widgets.SelectMultiple(
            options=list(labels),
            value=[row.label for row in (shown or table.rows[:3])],
            rows=min(len(labels), 8),
            description="rows",
            layout={"width": "34em"},
            style=style,
        ),
    }

    aligned = {}  # (label, path, alignment) -> Evaluation, each computed once

    def evaluated(label: str, path: str, alignment: str):
        placed = table.evaluations[labels[label]][path]
        if alignment == Alignment.ORIGIN:
            return placed
        if (label, path, alignment) not in aligned:
            aligned[label, path, alignment] = evaluate(placed.estimate, placed.truth, alignment)
        return aligned[label, path, alignment]

    def redraw(path: str, alignment: str, chosen: tuple[str, ...]) -> None:
        plt.close("all")
        if not chosen:
            print("choose at least one row")
            return
        evaluations = {label: evaluated(label, path, alignment) for label in chosen}
        _, (left, right) = plt.subplots(1, 2, figsize=(13, 4.8), gridspec_kw={"width_ratios": [1, 1.2]})
        draw_evaluated_paths(evaluations, ax=left)
        left.set_title(f"{path}, aligned by {alignment}")
        draw_evaluation_errors(evaluations, ax=right)
        right.set_title("how far from the truth, along the way")
        for label, evaluation in evaluations.items():
            final = evaluation.final
            print(
                f"{label:<38} APE RMSE {1e3 * evaluation.ape_m.rmse:6.1f} mm, max {1e3 * evaluation.ape_m.max:6.1f} mm;"
                f" final {1e3 * final.position_m:6.1f} mm ({final.percent:.2f} %); heading RMSE"
                f" {evaluation.heading_rmse_deg:.2f} deg"
            )
        plt.show()

    return widgets.VBox([widgets.HBox(list(controls.values())), widgets.interactive_output(redraw, controls)])
