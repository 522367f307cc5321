"""What every chapter's panel is built from: sliders that redraw their panel's figure only when released."""

from __future__ import annotations

import ipywidgets as widgets


def slider(description: str, value: float, low: float, high: float, step: float) -> widgets.FloatSlider:
    """A slider over [``low``, ``high``] in steps of ``step``, two decimals shown, that reports only when released."""
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


def int_slider(description: str, value: int, low: int, high: int, step: int = 1) -> widgets.IntSlider:
    """A whole-number slider over [``low``, ``high``] that reports only when released."""
    return widgets.IntSlider(
        value=value,
        min=low,
        max=high,
        step=step,
        description=description,
        continuous_update=False,
        style={"description_width": "initial"},
    )
