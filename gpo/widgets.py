"""ipywidgets panels for the notebooks. Each panel redraws its own figure when a slider is released."""

from __future__ import annotations

import dataclasses

import ipywidgets as widgets
import matplotlib.pyplot as plt

from gpo.camera import EUCM, T265_LIKE
from gpo.plots import draw_room_in_image, field_of_view_text


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
