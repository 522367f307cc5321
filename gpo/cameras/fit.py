"""One camera model fitted to another over the image: a KB4 calibration as an EUCM, a DS as a KB4, ...

The fit samples the source camera's image on a regular grid of pixels, takes the source's ray through
each (``unproject``) and finds the target model's parameters theta that project those rays back onto
the same pixels, by ``scipy.optimize.least_squares`` with the target's analytic Jacobian
(``project_jacobians``)::

    minimise over theta   sum_i | pi_theta(ray_i) - (u_i, v_i) |^2

Pixels where the source has no ray are left out; a ray the target cannot project counts as a residual of
``INVALID_RESIDUAL_PX`` in each coordinate, so the fit is pushed to cover the whole image. The result
says how well the target holds the source: the RMS (per coordinate) and the worst pixel distance.

Models are named as on the command line (``gpo.cameras.MODELS``). A model is a fit's target when it has ``BOUNDS``
and ``project_jacobians`` (``fittable``): not the pinhole, which cannot hold a fisheye's field of view.
Units: pixels; frames as in `gpo.cameras`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gpo.cameras import MODELS

INVALID_RESIDUAL_PX = 100.0


def fittable() -> tuple[str, ...]:
    """The models a least-squares fit can target: those with ``BOUNDS`` (and so ``project_jacobians``)."""
    return tuple(name for name, cls in MODELS.items() if cls.BOUNDS is not None)


def model_name(camera) -> str:
    """The name of ``camera``'s model in ``MODELS``."""
    for name, cls in MODELS.items():
        if type(camera) is cls:
            return name
    raise TypeError(f"not a camera model of gpo.cameras: {type(camera).__name__}")


def _check_fittable(model: str) -> type:
    if model not in fittable():
        raise ValueError(f"cannot fit the camera model '{model}'; choose one of {', '.join(fittable())}")
    return MODELS[model]


def parameter_bounds(model: str) -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper bounds of ``model``'s parameter vector (its ``PARAMETER_NAMES``), for least squares: fx, fy at
    least 1 px, the shape parameters within the model's ``BOUNDS``."""
    cls = _check_fittable(model)
    names = cls.PARAMETER_NAMES
    lower, upper = np.full(len(names), -np.inf), np.full(len(names), np.inf)
    lower[:2] = 1.0  # fx, fy
    for name, (low, high) in cls.BOUNDS.items():
        lower[names.index(name)], upper[names.index(name)] = low, high
    return lower, upper


def initial_camera(model: str, focal: float, cx: float, cy: float, width: int, height: int):
    """A start for ``model`` that images a small field around the axis with the focal length ``focal``
    (pixels per radian there): the model's ``START_SHAPE`` (EUCM alpha = 0.5, beta = 1; DS xi = 0, alpha = 0.5; KB4
    equidistant, k = 0; omni xi = 1 without distortion, whose focal length is twice the local one:
    ``START_FOCAL_SCALE``)."""
    cls = _check_fittable(model)
    scale = cls.START_FOCAL_SCALE
    return cls.from_params([scale * focal, scale * focal, cx, cy, *cls.START_SHAPE], width, height)


def local_focal(camera) -> float:
    """Pixels per radian at the principal point: the mean over u and v of 1 px over the angle of its ray."""
    rays, valid = camera.unproject([[camera.cx + 1.0, camera.cy], [camera.cx, camera.cy + 1.0]])
    if not valid.all():
        raise ValueError("the camera has no ray next to its principal point")
    return float(np.mean(1.0 / np.tan(np.arccos(np.clip(rays[:, 2], -1.0, 1.0)))))


@dataclass(frozen=True)
class ModelFit:
    """A fitted camera and how well it reproduces the source: RMS per coordinate and worst distance (px)
    over ``samples`` pixels, ``uncovered`` of which the fitted model cannot project."""

    camera: object
    source_model: str
    rms_px: float
    worst_px: float
    samples: int
    uncovered: int

    def summary(self) -> str:
        text = (
            f"{self.source_model} -> {model_name(self.camera)} over {self.samples} pixels: "
            f"RMS {self.rms_px:.4f} px, worst {self.worst_px:.4f} px"
        )
        if self.uncovered:
            text += f"; {self.uncovered} pixels the {model_name(self.camera)} model cannot see"
        return text


def fit_model(source, model: str, step_px: float = 16.0, max_angle_deg: float | None = None, start=None) -> ModelFit:
    """Fit the camera model named ``model`` to the camera ``source`` over its image.

    ``step_px`` is the spacing of the sampled pixel grid; ``max_angle_deg`` leaves out the pixels whose rays lie
    farther off the optical axis (where a lens's image circle ends inside the image, its calibration there
    is an extrapolation that another model need not follow); ``start`` a camera of that model to start
    from (by default ``initial_camera`` with ``source``'s principal point and ``local_focal``).
    """
    cls = _check_fittable(model)
    width, height = source.width, source.height
    u, v = np.meshgrid(np.arange(0.0, width, step_px), np.arange(0.0, height, step_px))
    pixels = np.column_stack([u.ravel(), v.ravel()])
    rays, valid = source.unproject(pixels)
    if max_angle_deg is not None:
        with np.errstate(invalid="ignore"):
            valid &= rays[:, 2] >= np.cos(np.radians(max_angle_deg))
    if not valid.any():
        raise ValueError("the source camera has no valid pixel to fit")
    pixels, rays = pixels[valid], rays[valid]
    if start is None:
        start = initial_camera(model, local_focal(source), source.cx, source.cy, width, height)

    def residuals(params):
        projected, ok = cls.from_params(params, width, height).project(rays)
        errors = projected - pixels
        errors[~ok] = INVALID_RESIDUAL_PX
        return errors.ravel()

    def jacobian(params):
        _, j_params = cls.from_params(params, width, height).project_jacobians(rays)
        return np.nan_to_num(j_params, nan=0.0).reshape(-1, len(params))

    from scipy.optimize import least_squares  # imported by what fits, not by every command

    solution = least_squares(
        residuals, start.params, jac=jacobian, bounds=parameter_bounds(model), x_scale="jac", ftol=1e-10, xtol=1e-10
    )
    camera = cls.from_params(solution.x, width, height)
    projected, ok = camera.project(rays)
    distance = np.linalg.norm(projected[ok] - pixels[ok], axis=-1)
    return ModelFit(
        camera,
        model_name(source),
        float(np.sqrt(np.mean(distance**2) / 2.0)),
        float(distance.max()),
        len(pixels),
        int((~ok).sum()),
    )
