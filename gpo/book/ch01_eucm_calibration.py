"""Chapter 01, calibrating the EUCM: the residuals, each view's error, each parameter's error in its standard
deviations, the models on real views, the gap between two models of one lens, and a panel to drop views and switch
the model."""

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


def draw_errors_in_sigmas(fits: dict, truth, ax=None) -> plt.Axes:
    """Each parameter's error against ``truth`` (a camera of the fits' model) in units of its standard deviation,
    one group of bars per fit of ``fits`` (label -> ``CalibrationResult``), with the band of one and two sigmas."""
    if ax is None:
        _, ax = plt.subplots(figsize=(7, 3.2))
    names = list(truth.PARAMETER_NAMES)
    true_values = dict(zip(names, truth.params, strict=True))
    width = 0.8 / len(fits)
    for k, (label, fit) in enumerate(fits.items()):
        errors = [(fit.params[name] - true_values[name]) / fit.std[name] for name in names]
        ax.bar(np.arange(len(names)) + (k - (len(fits) - 1) / 2) * width, errors, width, label=label)
    for sigmas, shade in ((1, 0.12), (2, 0.06)):
        ax.axhspan(-sigmas, sigmas, color="tab:green", alpha=shade, lw=0)
    ax.axhline(0.0, color="k", lw=0.8)
    ax.set_xticks(range(len(names)), names)
    ax.set_ylabel("error / standard deviation")
    ax.legend(fontsize="small")
    return ax


def draw_model_bars(fits: dict, views: int, ax=None) -> plt.Axes:
    """The RMS reprojection error of each fit of ``fits`` (model name -> ``CalibrationResult``) as a bar, labelled
    with how many of the ``views`` it kept; a fit that is not a good calibration is drawn grey and hatched."""
    if ax is None:
        _, ax = plt.subplots(figsize=(6, 3.2))
    for index, fit in enumerate(fits.values()):
        style = {"color": "tab:blue"} if fit.ok else {"color": "0.8", "hatch": "//", "edgecolor": "0.4"}
        ax.bar(index, fit.rms_px, **style)
        verdict = "" if fit.ok else "\nnot a calibration"
        ax.annotate(
            f"{len(fit.used)}/{views} views{verdict}",
            (index, fit.rms_px),
            ha="center",
            va="bottom",
            xytext=(0, 2),
            textcoords="offset points",
            fontsize="small",
        )
    ax.set_xticks(range(len(fits)), list(fits))
    ax.set_ylabel("RMS reprojection error [px]")
    ax.margins(y=0.3)
    return ax


def draw_model_gap(source, fitted, ax=None, max_angle_deg: float | None = None, step_px: int = 8) -> plt.Axes:
    """How far apart two models of one lens put the same ray: for pixels of ``source`` every ``step_px``, the
    distance (px) between the pixel and ``fitted``'s projection of its ray, against the ray's angle off the axis;
    a dotted line at ``max_angle_deg``, the angle the fit was made within."""
    if ax is None:
        _, ax = plt.subplots(figsize=(6.4, 3.4))
    pixels = source.pixel_grid()[::step_px, ::step_px].reshape(-1, 2)
    rays, valid = source.unproject(pixels)
    back, projected = fitted.project(rays)
    keep = valid & projected
    angle = np.degrees(np.arccos(np.clip(rays[keep, 2], -1.0, 1.0)))
    ax.plot(angle, np.linalg.norm(back[keep] - pixels[keep], axis=-1), ".", ms=2)
    if max_angle_deg is not None:
        ax.axvline(max_angle_deg, color="k", lw=0.8, ls=":", label=f"the fit's limit, {max_angle_deg:.0f} deg")
        ax.legend(fontsize="small")
    ax.set_xlabel("angle off the optical axis [deg]")
    ax.set_ylabel("gap between the models [px]")
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
