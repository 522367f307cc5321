"""Chapter 01, calibrating the EUCM: the residuals, each view's error, and a panel to drop views and switch the
model."""

from __future__ import annotations

import ipywidgets as widgets
import matplotlib.pyplot as plt
import numpy as np

from gpo.cameras.calibrate import CalibrationError, calibrate_corners


def draw_residuals(result, ax=None, scale: float | None = None) -> plt.Axes:
    """Residual vectors of a ``gpo.cameras.calibrate.CalibrationResult`` over its image, magnified ``scale`` times
    (by default so that an RMS-sized residual is drawn 10 px long)."""
    if ax is None:
        _, ax = plt.subplots(figsize=(6.4, 6.0))
    if scale is None:
        scale = float(10 ** np.round(np.log10(10.0 / max(result.rms_px, 1e-6))))
    corners = np.concatenate([result.corners[i] for i in result.used])
    residuals = np.concatenate([result.residuals[i] for i in result.used])
    ax.quiver(
        corners[:, 0],
        corners[:, 1],
        residuals[:, 0],
        residuals[:, 1],
        angles="xy",
        scale_units="xy",
        scale=1.0 / scale,
        width=0.003,
        color="tab:red",
    )
    ax.plot(corners[:, 0], corners[:, 1], ".", ms=1.5, color="0.4")
    ax.set_xlim(-0.5, result.camera.width - 0.5)
    ax.set_ylim(result.camera.height - 0.5, -0.5)
    ax.set_aspect("equal")
    ax.set_xlabel("u [px]")
    ax.set_ylabel("v [px]")
    ax.set_title(f"{result.model}: residuals x{scale:.0f}, RMS {result.rms_px:.3f} px")
    return ax


def draw_view_errors(result, ax=None) -> plt.Axes:
    """RMS reprojection error of every view of a ``CalibrationResult``; views left out are marked."""
    if ax is None:
        _, ax = plt.subplots(figsize=(7, 3))
    views = sorted(result.view_rms_px)
    colours = ["tab:blue" if i in result.used else "tab:gray" for i in views]
    ax.bar([str(i) for i in views], [result.view_rms_px[i] for i in views], color=colours)
    for i in sorted(result.dropped):
        ax.annotate("left out", (str(i), 0), rotation=90, ha="center", va="bottom", fontsize="x-small")
    ax.set_xlabel("view")
    ax.set_ylabel("RMS [px]")
    return ax


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
