"""Chapter 04, the ortho-rectified GPI and the analytic route: the chessboard route's images, Table 1 read from a
figure, the ortho-GPI's extent and the analytic route's mount on sliders, and the analytic route on a real car's
fisheyes (Kalibr's sample): its ground images and the road's lines fitted in them. The chapter's Table 1 is
``gpo.experiments.table1``."""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import ipywidgets as widgets
import matplotlib.pyplot as plt
import numpy as np

from gpo.book.figures import draw_floor_image
from gpo.book.panels import slider
from gpo.cameras.mount import floor_angles
from gpo.cameras.rig import CameraMount
from gpo.experiments.table1 import (
    CALIBRATION_ERRORS,
    PAPER_TABLE1_ERRORS,
    PICK_ERROR_PX,
    paper_table1,
    table1_placements,
)
from gpo.floor_image.analytic import analytic_table, route_difference
from gpo.floor_image.gpi import ground_plane_image
from gpo.floor_image.image import FloorImage, GroundImageError
from gpo.floor_image.ortho import board_corners, ortho_rectify

MAX_PANEL_PIXELS = 2_000_000  # floor images larger than this are not redrawn by a panel: too slow to be interactive


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
        "near": slider("near x [m]", 0.70, 0.55, 1.00, 0.01),
        "far": slider("far x [m]", 0.90, 0.60, 1.10, 0.01),
        "half_width": slider("half width [m]", 0.10, 0.02, 0.30, 0.01),
        "millimetres": slider("mm per pixel", 0.50, 0.20, 2.00, 0.05),
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
        "height_mm": slider("height [mm]", height_mm, 0.5 * height_mm, 1.5 * height_mm, 0.5),
        "pitch_deg": slider("pitch [deg]", math.degrees(pitch), -5.0, 25.0, 0.1),
        "roll_deg": slider("roll [deg]", math.degrees(roll), -10.0, 10.0, 0.1),
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


def draw_ortho_gpi(gpi_image, ortho, ortho_image, truth_px, fitted_px, mount) -> plt.Figure:
    """The chessboard route's result in three panels: the GPI with the 2 x 4 block's 15 corners found in it; the
    ortho-GPI (``ortho``, a ``gpo.floor_image.OrthoGPI``, and its image) with the block's outline where it truly lies
    (``truth_px``, its 15 corners in ortho-GPI pixels in ``gpo.floor_image.ortho.block_corner_indices`` order) and
    the corners as
    the second homography H_o maps them (``fitted_px``); and the ortho-GPI where it lies in base_link, the camera at
    ``mount``."""
    fig, axes = plt.subplots(1, 3, figsize=(14, 6), gridspec_kw={"width_ratios": [0.56, 1, 0.7]})
    axes[0].imshow(gpi_image, cmap="gray", vmin=0, vmax=255)
    axes[0].plot(*ortho.block_gpi_px.T, "r.", ms=4)
    axes[0].set_title("GPI: the block's 15 corners found")
    axes[1].imshow(ortho_image, cmap="gray", vmin=0, vmax=255)
    outline = truth_px[[0, 4, 14, 10, 0]]
    axes[1].plot(*outline.T, "-", color="tab:cyan", lw=1, label="40 x 80 mm, where it truly lies")
    axes[1].plot(*fitted_px.T, "r.", ms=4, label="the corners after H_o")
    axes[1].legend(loc="lower right", fontsize="small")
    axes[1].set_title(f"ortho-GPI, {ortho.floor.width} x {ortho.floor.height} px")
    for ax in axes[:2]:
        ax.axis("off")
    draw_floor_image(ortho_image, ortho.floor, ax=axes[2], mount=mount)
    axes[2].set_title("where it lies in base_link")
    return fig


CAR_FLOORS = {  # the Kalibr car's camera -> the floor its ground image covers, 1 cm per pixel
    "left": FloorImage.top_view(x_range=(-2.0, 6.0), y_range=(1.0, 6.0), metres_per_pixel=0.01),
    "front": FloorImage.top_view(x_range=(3.8, 10.0), y_range=(-4.0, 4.0), metres_per_pixel=0.01),
}
ROAD_LINES = {  # a line of the road -> the columns of the left ground image searched, and whether by its edge
    "lane marking": ((270, 350), False),  # y from 3.3 to 2.5 m: the brightest pixel of each row
    "road edge": ((110, 180), True),  # y from 4.9 to 4.2 m: the strongest change across each row
}


@dataclass(frozen=True)
class RoadLine:
    """A line of the road found in a ground image: one point a row (``xy``, (N, 2) metres in base_link) and the
    straight line y = ``slope`` x + ``offset`` fitted to them, with the points' RMS distance across it (metres)."""

    xy: np.ndarray
    slope: float
    offset: float
    rms_m: float


def car_ground_images(car_images: dict, cars: dict) -> dict[str, np.ndarray]:
    """The analytic route's ground image (``CAR_FLOORS``) of the Kalibr car's left and front fisheyes: camera name
    -> grey image. ``car_images`` and ``cars``: ``gpo.io.datasets.kalibr_car_images()`` and
    ``gpo.io.kalibr_car.kalibr_car_cameras()``."""
    return {
        name: analytic_table(cars[name].camera, cars[name].mount, floor, max_outside=1.0, cache=False).apply(
            car_images[name]
        )
        for name, floor in CAR_FLOORS.items()
    }


def fit_road_lines(ground_image, floor: FloorImage = CAR_FLOORS["left"]) -> dict[str, RoadLine]:
    """Each line of ``ROAD_LINES`` found row by row in ``ground_image`` (of ``floor``, smoothed by a 2-pixel
    Gaussian) and fitted with a straight line in base_link."""
    smooth = cv2.GaussianBlur(ground_image.astype(np.float32), (0, 0), 2.0)
    values = {False: smooth, True: np.abs(cv2.Sobel(smooth, cv2.CV_32F, 1, 0, ksize=5))}
    rows = np.arange(floor.height)
    lines = {}
    for what, ((first, last), by_edge) in ROAD_LINES.items():
        columns = first + np.argmax(values[by_edge][:, first:last], axis=1)
        xy = floor.pixel_to_base(np.column_stack([columns, rows]))
        slope, offset = np.polyfit(xy[:, 0], xy[:, 1], 1)
        off_line = xy[:, 1] - (slope * xy[:, 0] + offset)
        lines[what] = RoadLine(xy, float(slope), float(offset), float(np.sqrt(np.mean(off_line**2))))
    return lines


def draw_car_ground_images(car_images: dict, cars: dict, views: dict, lines: dict[str, RoadLine]) -> plt.Figure:
    """The Kalibr car's left fisheye, its ground image with the road's ``lines`` (``fit_road_lines``) drawn dashed,
    and the front camera's ground image with the left camera's lane marking drawn dashed over it, and the sun's
    smear (a bright column of the front fisheye, bent by the ground map) named; ``views``: ``car_ground_images``."""
    fig, axes = plt.subplots(1, 3, figsize=(15, 6.5), gridspec_kw={"width_ratios": [1.6, 1, 1.1]})
    axes[0].imshow(car_images["left"], cmap="gray")
    axes[0].set_title("the left fisheye (1280 x 800)")
    axes[0].axis("off")
    draw_floor_image(views["left"], CAR_FLOORS["left"], ax=axes[1], mount=cars["left"].mount, axes_length=1.0)
    for what, line in lines.items():
        ends = np.array([line.xy[0, 0], line.xy[-1, 0]])
        colour = "tab:cyan" if what == "road edge" else "tab:red"
        axes[1].plot(line.slope * ends + line.offset, ends, "--", lw=1, color=colour)
    axes[1].set_title("its ground image, lines fitted")
    draw_floor_image(views["front"], CAR_FLOORS["front"], ax=axes[2], axes_length=1.0)
    lane = lines["lane marking"]
    ahead = np.array(CAR_FLOORS["front"].extent[:2])
    axes[2].plot(lane.slope * ahead + lane.offset, ahead, "--", lw=1, color="tab:red")
    for text, (y, x), at, colour in (
        ("the left camera's\nlane marking", (2.9, 4.6), (4.0, 2.4), "tab:red"),
        ("the sun's smear", (-2.5, 5.6), (-1.2, 2.6), "tab:orange"),
    ):
        axes[2].annotate(
            text, (y, x), at, color=colour, fontsize="small", arrowprops={"arrowstyle": "->", "color": colour}
        )
    axes[2].set_title("the front camera's ground image")
    return fig


def fisheye_pixel_on_floor(camera, mount: CameraMount, xy, step_m: float = 1e-4) -> tuple[float, float]:
    """How much floor one fisheye pixel covers at the floor point ``xy`` of base_link, (across, along) millimetres:
    a step of ``step_m`` across (y) and along (x) the floor, projected by ``camera`` from its ``mount``, over the
    pixels it moves in the fisheye."""
    x, y = xy
    points = np.array([[x, y, 0.0], [x, y + step_m, 0.0], [x + step_m, y, 0.0]])
    pixels, _ = camera.project(mount.to_camera(points))
    across, along = np.linalg.norm(pixels[1:] - pixels[0], axis=1)
    return 1e3 * step_m / float(across), 1e3 * step_m / float(along)


def table1_errors_panel(seed: int = 0) -> widgets.VBox:
    """Table 1's effect against the size of the calibration's errors: ``CALIBRATION_ERRORS`` times a factor and the
    hand-picked corners' scatter (px, one sigma) on sliders; on release, ``paper_table1`` (one frame per placement,
    no mean) redrawn as each image's errors on the fitted and on the second placement, the paper's beside them."""
    controls = {
        "factor": slider("calibration errors x", 1.0, 0.0, 3.0, 0.25),
        "pick_px": slider("corner pick sigma [px]", PICK_ERROR_PX, 0.0, 4.0, 0.5),
    }
    paper = PAPER_TABLE1_ERRORS  # as the paper prints them

    def redraw(factor: float, pick_px: float) -> None:
        errors = {name: factor * value for name, value in CALIBRATION_ERRORS.items()}
        plt.close("all")
        try:
            truth, rows = paper_table1(calibration_errors=errors, pick_error_px=pick_px, mean_over=0, seed=seed)
        except GroundImageError as error:
            print(f"no Table 1 with these errors: {error}")
            return
        _, axes = plt.subplots(1, 2, figsize=(12, 3.8))
        for ax, columns, unit in ((axes[0], (0, 1), "mm"), (axes[1], (2,), "mm^2")):
            labels = [f"{row.image}, {row.where}" for row in rows] + ["GPI, the paper", "ortho-GPI, the paper"]
            for k, column in enumerate(columns):
                measured = [abs((row.long_mm, row.short_mm, row.area_mm2)[column] - truth[column]) for row in rows]
                values = [*measured, paper["GPI"][column], paper["ortho-GPI"][column]]
                offsets = np.arange(len(values)) + 0.4 * k - 0.2 * (len(columns) - 1)
                ax.barh(offsets, values, height=0.8 / len(columns), label=("(a+c)/2", "(b+d)/2", "S")[column])
            ax.set_yticks(np.arange(len(labels)), labels)
            ax.set_xscale("log")
            ax.set_xlabel(f"error [{unit}], log scale")
            ax.legend(loc="lower right")
        axes[0].set_title("the block's sides")
        axes[1].set_title("its area")
        plt.tight_layout()
        for row in rows:
            print(
                f"{row.image:>9}, {row.where:<6}: sides off {abs(row.long_mm - truth[0]):6.3f} and "
                f"{abs(row.short_mm - truth[1]):6.3f} mm, area {abs(row.area_mm2 - truth[2]):7.2f} mm^2"
            )
        plt.show()

    sliders = widgets.HBox(list(controls.values()), layout={"flex_flow": "row wrap"})
    return widgets.VBox([sliders, widgets.interactive_output(redraw, controls)])


TABLE1_COLOURS = {"GPI": "tab:orange", "ortho-GPI": "tab:blue", "analytic": "tab:gray"}
SUITE_PLACEMENTS = table1_placements()  # the placements reproduce_table1 measures by default
TABLE1_FLOOR = 1e-3  # errors below this (a thousandth of a mm or mm^2) are drawn at it, on the log scale


def draw_table1(truth, paper_rows, suite_rows, paper=PAPER_TABLE1_ERRORS) -> plt.Figure:
    """Table 1 read from a figure: each measurement's error ((a + c) / 2, (b + d) / 2 in mm, S in mm^2) as bars on a
    log scale, one group of bars per way of measuring it, each image in its colour: the paper's (``paper``, as it
    prints them), the suite's under the paper's definitions (``truth`` and ``paper_rows`` from
    ``gpo.experiments.table1.paper_table1``: the fitted placement, a second one, the mean over placements) and the
    suite's own measure (``suite_rows`` from ``reproduce_table1``: the mean over its placements with the exact
    calibration, then one placement's RMS error). Errors below ``TABLE1_FLOOR`` are drawn at it."""
    groups = [("the paper, one frame", {image: paper[image] for image in ("GPI", "ortho-GPI")})]
    titles = {"fitted": "fitted placement, one frame", "second": "second placement, one frame", "mean": "mean of 8"}
    for where, title in titles.items():
        values = {row.image: (row.long_mm, row.short_mm, row.area_mm2) for row in paper_rows if row.where == where}
        groups.append((title, {image: np.abs(np.subtract(v, truth)) for image, v in values.items()}))
    errors = {row.image: (row.long_error_mm, row.short_error_mm, row.area_error_mm2) for row in suite_rows}
    groups.append((f"mean of {len(SUITE_PLACEMENTS)}, exact calibration", {k: np.abs(v) for k, v in errors.items()}))
    singles = {
        row.image: (row.single_side_rms_mm, row.single_side_rms_mm, row.single_area_rms_mm2) for row in suite_rows
    }
    groups.append(("one placement (RMS)", singles))
    fig, axes = plt.subplots(1, 3, figsize=(14, 5.2), sharey=True)
    for column, (ax, name) in enumerate(zip(axes, ("(a+c)/2 [mm]", "(b+d)/2 [mm]", "S [mm^2]"), strict=True)):
        position, ticks = 0.0, []
        for title, values in groups:
            start = position
            for image, measured in values.items():
                ax.barh(position, max(measured[column], TABLE1_FLOOR), color=TABLE1_COLOURS[image], height=0.8)
                position += 1
            ticks.append(((start + position - 1) / 2, title))
            position += 0.8
        ax.set_xscale("log")
        ax.set_xlim(TABLE1_FLOOR, None)
        ax.set_xlabel(f"error of {name}, log scale")
        ax.set_yticks([at for at, _ in ticks], [title for _, title in ticks])
        ax.invert_yaxis()
    handles = [plt.Rectangle((0, 0), 1, 1, color=colour) for colour in TABLE1_COLOURS.values()]
    axes[-1].legend(handles, list(TABLE1_COLOURS), loc="lower right", fontsize="small")
    fig.tight_layout()
    return fig
