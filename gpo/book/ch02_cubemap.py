"""Chapter 02, the cubemap: its face size on a slider."""

from __future__ import annotations

import ipywidgets as widgets
import matplotlib.pyplot as plt

from gpo.cameras import EUCM
from gpo.floor_image.cubemap import Cubemap, default_face_size


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
