"""Chapter 02, the cubemap: where each face's pixels come from in the fisheye image, and its face size on a slider."""

from __future__ import annotations

import ipywidgets as widgets
import matplotlib.pyplot as plt
import numpy as np

from gpo.cameras import EUCM
from gpo.floor_image.cubemap import FACE_NAMES, Cubemap, default_face_size

FACE_COLOURS = {
    "front": "tab:red",
    "left": "tab:blue",
    "right": "tab:green",
    "bottom": "tab:orange",
    "top": "tab:purple",
}


def draw_faces_on_fisheye(cubemap: Cubemap, fisheye_image, ax=None, lines: int = 9) -> plt.Axes:
    """The fisheye image with each face's grid drawn where the face's pixels read it (the look-up tables of eqs.
    13-18): ``lines`` rows and as many columns per face, from edge to edge, broken where the face sees nothing."""
    if ax is None:
        _, ax = plt.subplots(figsize=(6.4, 6.4 * fisheye_image.shape[0] / fisheye_image.shape[1]))
    ax.imshow(fisheye_image, cmap="gray", vmin=0, vmax=255)
    size = cubemap.face_size
    along = np.linspace(-0.5, size - 0.5, 4 * size)
    for name in FACE_NAMES:
        for index, at in enumerate(np.linspace(-0.5, size - 0.5, lines)):
            for row in (True, False):
                uv = np.stack([along, np.full_like(along, at)] if row else [np.full_like(along, at), along], axis=-1)
                fisheye_uv, _ = cubemap.face_to_fisheye(name, uv)
                label = name if index == 0 and row else None
                ax.plot(*fisheye_uv.T, color=FACE_COLOURS[name], lw=0.8, label=label)
    ax.set_xlim(-0.5, fisheye_image.shape[1] - 0.5)
    ax.set_ylim(fisheye_image.shape[0] - 0.5, -0.5)
    ax.legend(fontsize="small", loc="upper right", framealpha=0.9)
    ax.axis("off")
    return ax


def cubemap_panel(fisheye_image, camera: EUCM) -> widgets.VBox:
    """A face-size slider over the cubemap of ``fisheye_image``: the cross of the five faces, redrawn on release.

    The default face size (``gpo.floor_image.cubemap.default_face_size``) keeps the fisheye's pixel density at the
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
