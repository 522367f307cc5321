"""Chapter 04, the ortho-rectified GPI and the analytic route: the ortho-GPI's extent and the analytic route's
mount on sliders (the chapter's Table 1 is ``gpo.book.ch04_table1``)."""

from __future__ import annotations

import math

import ipywidgets as widgets
import matplotlib.pyplot as plt

from gpo.book.figures import draw_floor_image
from gpo.book.panels import slider
from gpo.ground import (
    FloorImage,
    GroundImageError,
    analytic_table,
    board_corners,
    ground_plane_image,
    ortho_rectify,
    route_difference,
)
from gpo.mount import floor_angles
from gpo.rig import CameraMount

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
