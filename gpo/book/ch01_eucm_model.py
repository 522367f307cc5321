"""Chapter 01, the EUCM camera model: a room's grid in the fisheye image, the projection curves, each pixel's ray
angle, the field of view, and the model's panel."""

from __future__ import annotations

import dataclasses

import ipywidgets as widgets
import matplotlib.pyplot as plt
import numpy as np

from gpo.book.panels import slider
from gpo.cameras import EUCM, T265_LIKE, CameraModel

SURFACE_COLOURS = {"floor": "tab:brown", "left wall": "tab:blue", "right wall": "tab:green", "front wall": "tab:purple"}


def room_grid_lines(
    height: float = 0.12, half_width: float = 2.0, depth: float = 4.0, wall_height: float = 2.0, spacing: float = 0.25
) -> dict[str, list[np.ndarray]]:
    """Grid lines on the floor and walls of a box-shaped room, in the camera optical frame.

    The camera stands ``height`` metres above the floor looking straight ahead along the floor
    (optical axis level); the room spans ``x`` in [-half_width, half_width] metres, ``z`` in
    [-depth, depth] (so the floor also continues behind the camera) and the walls rise
    ``wall_height`` metres above the floor. Lines are ``spacing`` metres apart and each is a
    (200, 3) polyline, so that its curved image can be drawn.

    Returns a dict surface name -> list of polylines, with the surfaces of ``SURFACE_COLOURS``.
    """
    t = np.linspace(0.0, 1.0, 200)[:, None]
    floor_y, ceiling_y = height, height - wall_height

    def segment(start, end):
        return np.asarray(start, dtype=float) + t * (np.asarray(end, dtype=float) - np.asarray(start, dtype=float))

    def ticks(low, high):
        return np.arange(np.ceil(low / spacing), np.floor(high / spacing) + 1) * spacing

    lines: dict[str, list[np.ndarray]] = {name: [] for name in SURFACE_COLOURS}
    for x in ticks(-half_width, half_width):
        lines["floor"].append(segment([x, floor_y, -depth], [x, floor_y, depth]))
        lines["front wall"].append(segment([x, floor_y, depth], [x, ceiling_y, depth]))
    for z in ticks(-depth, depth):
        lines["floor"].append(segment([-half_width, floor_y, z], [half_width, floor_y, z]))
    for side, x in (("left wall", -half_width), ("right wall", half_width)):
        for z in ticks(-depth, depth):
            lines[side].append(segment([x, floor_y, z], [x, ceiling_y, z]))
        for y in ticks(ceiling_y, floor_y):
            lines[side].append(segment([x, y, -depth], [x, y, depth]))
    for y in ticks(ceiling_y, floor_y):
        lines["front wall"].append(segment([-half_width, y, depth], [half_width, y, depth]))
    return lines


def draw_room_in_image(camera: CameraModel, ax=None, **room) -> plt.Axes:
    """Draw where ``room_grid_lines(**room)`` lands in ``camera``'s image, with the image border.

    Invalid projections (NaN) break the lines instead of joining them across the image.
    For an EUCM with alpha > 0.5, the dashed ellipse bounds the pixels that have a ray.
    """
    if ax is None:
        _, ax = plt.subplots(figsize=(6.4, 6.4 * camera.height / camera.width))
    for surface, polylines in room_grid_lines(**room).items():
        for index, polyline in enumerate(polylines):
            uv, _ = camera.project(polyline)
            ax.plot(uv[:, 0], uv[:, 1], color=SURFACE_COLOURS[surface], lw=0.7, label=surface if index == 0 else None)
    if isinstance(camera, EUCM) and camera.alpha > 0.5:
        r_max = 1.0 / np.sqrt(camera.beta * (2.0 * camera.alpha - 1.0))
        phi = np.linspace(0.0, 2.0 * np.pi, 361)
        ax.plot(
            camera.cx + camera.fx * r_max * np.cos(phi),
            camera.cy + camera.fy * r_max * np.sin(phi),
            "k--",
            lw=0.8,
            label="edge of the valid region",
        )
    ax.add_patch(plt.Rectangle((-0.5, -0.5), camera.width, camera.height, fill=False, color="k", lw=1.2))
    ax.set_xlim(-0.5, camera.width - 0.5)
    ax.set_ylim(camera.height - 0.5, -0.5)
    ax.set_aspect("equal")
    ax.set_xlabel("u [px]")
    ax.set_ylabel("v [px]")
    ax.legend(loc="lower right", fontsize="small", framealpha=0.9)
    return ax


def draw_projection_curves(cameras: dict[str, CameraModel], ax=None, max_angle_deg: float = 135.0) -> plt.Axes:
    """Image radius (pixels from the principal point) against the angle off the optical axis.

    Each camera is probed along its +x axis, so the curve is r(theta) = u(theta) - cx; the
    curve stops where the projection becomes invalid.
    """
    if ax is None:
        _, ax = plt.subplots(figsize=(6.4, 4.0))
    theta = np.radians(np.linspace(0.0, max_angle_deg, 541))
    rays = np.stack([np.sin(theta), np.zeros_like(theta), np.cos(theta)], axis=-1)
    for label, camera in cameras.items():
        uv, _ = camera.project(rays)
        ax.plot(np.degrees(theta), uv[:, 0] - camera.principal_point[0], label=label)
    ax.set_xlabel("angle off the optical axis [deg]")
    ax.set_ylabel("image radius [px]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize="small")
    return ax


def draw_ray_angles(camera: CameraModel, ax=None, levels=(30, 60, 90, 120)) -> plt.Axes:
    """Each pixel's ray (``camera.unproject``) as its angle off the optical axis, degrees, over the image, with
    contours at ``levels``; pixels without a ray are left white. For an EUCM with alpha > 0.5, the dashed ellipse
    bounds the pixels that have a ray (wherever it lies, in the image or beyond it)."""
    if ax is None:
        _, ax = plt.subplots(figsize=(6.4, 6.4 * camera.height / camera.width))
    rays, _ = camera.unproject(camera.pixel_grid())
    angle = np.degrees(np.arccos(np.clip(rays[..., 2], -1.0, 1.0)))
    extent = (-0.5, camera.width - 0.5, camera.height - 0.5, -0.5)
    shown = ax.imshow(angle, cmap="viridis", extent=extent, vmin=0.0, vmax=180.0)
    lines = ax.contour(
        angle,
        levels=list(levels),
        colors="w",
        linewidths=0.8,
        extent=(0, camera.width - 1, 0, camera.height - 1),
        origin="upper",
    )
    ax.clabel(lines, fmt="%d°", fontsize="small")
    if isinstance(camera, EUCM) and camera.alpha > 0.5:
        r_max = 1.0 / np.sqrt(camera.beta * (2.0 * camera.alpha - 1.0))
        phi = np.linspace(0.0, 2.0 * np.pi, 361)
        ax.plot(camera.cx + camera.fx * r_max * np.cos(phi), camera.cy + camera.fy * r_max * np.sin(phi), "k--", lw=0.8)
    ax.set_xlim(extent[0], extent[1])
    ax.set_ylim(extent[2], extent[3])
    ax.set_aspect("equal")
    ax.set_xlabel("u [px]")
    ax.set_ylabel("v [px]")
    plt.colorbar(shown, ax=ax, label="angle off the optical axis [deg]", shrink=0.8)
    return ax


def field_of_view_text(camera) -> str:
    """The camera's field of view as one line of text, in degrees."""
    angles = np.degrees(camera.field_of_view())
    parts = [
        f"{name} {angle:.1f} deg" if np.isfinite(angle) else f"{name} n/a (border outside the valid region)"
        for name, angle in zip(("horizontal", "vertical", "diagonal"), angles, strict=True)
    ]
    return "field of view: " + ", ".join(parts)


def eucm_panel(camera: EUCM = T265_LIKE, camera_height: float = 0.12) -> widgets.VBox:
    """Sliders for alpha, beta and the focal length f (fx = fy = f, pixels) of ``camera``.

    Each change redraws where a grid on the floor and the walls of a room lands in the image of
    a camera ``camera_height`` metres above the floor, and prints the field of view.
    """
    alpha = slider("alpha", camera.alpha, 0.0, 1.0, 0.01)
    beta = slider("beta", camera.beta, 0.1, 3.0, 0.05)
    focal = slider("f [px]", camera.fx, 80.0, 800.0, 2.0)

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
