"""Chapter 03, the ground plane image (GPI): eq. 22's corners moved by hand, how far the GPI reaches, and how many
GPI rows one front-face pixel spreads over as the floor recedes."""

from __future__ import annotations

import ipywidgets as widgets
import matplotlib.pyplot as plt
import numpy as np

from gpo.book.figures import draw_floor_image
from gpo.book.panels import int_slider, slider
from gpo.floor_image.analytic import analytic_table, route_difference
from gpo.floor_image.cubemap import Cubemap
from gpo.floor_image.gpi import apply_homography, front_face_corners, ground_plane_image
from gpo.floor_image.image import GroundImageError

GPI_CORNER_NAMES = ("near-right", "far-right", "far-left", "near-left")
"""The four corners of eq. 22 in the order of ``gpo.floor_image.gpi.front_face_corners``."""


def gpi_corners_panel(fisheye_image, camera, placement, mount=None) -> widgets.VBox:
    """Move the four corners of eq. 22 by hand in the front face and see the GPI they give, redrawn on release.

    The sliders (front-face pixels) start at the corners found automatically (``gpo.floor_image.gpi.front_face_corners``
    for the board lying at ``placement``). Left: the front face with the corners found (circles) and those used
    (the outline); right: the GPI made the paper's way. With ``mount``, the camera's true mount (the simulator
    knows it), it also prints how far the GPI's front-face part puts the floor from where it truly is.
    """
    cubemap = Cubemap(camera)
    found = front_face_corners(fisheye_image, cubemap, placement)
    front = cubemap.face_image(fisheye_image, "front")
    controls = {}
    for index, (name, (u, v)) in enumerate(zip(GPI_CORNER_NAMES, found, strict=True)):
        controls[f"u{index}"] = slider(f"{name} u", float(u), round(u) - 20.0, round(u) + 20.0, 0.1)
        controls[f"v{index}"] = slider(f"{name} v", float(v), round(v) - 20.0, round(v) + 20.0, 0.1)

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
    base_link (``gpo.book.figures.draw_floor_image``; the camera marked at ``mount`` when given). Too far ahead, the
    front face resolves the floor no more, and the panel prints the package's error, which says what fits.
    """
    corners = front_face_corners(fisheye_image, Cubemap(camera), placement)
    default = ground_plane_image(fisheye_image, camera, placement, corners=corners, cache=False)
    ahead = slider("ahead [m]", 0.30, 0.05, 1.00, 0.01)
    rows = int_slider("bottom rows", default.bottom_rows, 1, default.cubemap.face_size)

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


def rows_per_face_pixel(gpi, reach_m: float, samples: int = 400) -> tuple[np.ndarray, np.ndarray]:
    """How many GPI rows one front-face pixel spreads over, along the GPI's middle column, against the distance
    ahead of the seam (the front face's bottom edge), from 0 to ``reach_m`` metres: the GPI's rows continued ahead by
    eq. 22's homography (``gpi``, a ``GroundPlaneImage``). Returns (distance [m], rows per face pixel); NaN past the
    horizon."""
    ahead = np.linspace(0.0, reach_m, samples)
    rows = gpi.front_rows - 0.5 - ahead / gpi.floor.metres_per_pixel  # image up is forward
    column = np.column_stack([np.full(samples, (gpi.size[0] - 1) / 2.0), rows])
    to_face = np.linalg.inv(gpi.homography)
    next_row = apply_homography(to_face, column + np.array([0.0, 1.0]))
    step = np.linalg.norm(next_row - apply_homography(to_face, column), axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        return ahead, 1.0 / step
