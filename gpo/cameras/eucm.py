"""The extended unified camera model (EUCM) of the first paper's eqs. 1-7.

B. Khomutenko, G. Garcia, P. Martinet, "An Enhanced Unified Camera Model", IEEE Robotics and Automation
Letters 1(1), 2016; written as in the first paper's eqs. 1-7 and as Basalt implements it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from gpo.cameras.base import CameraModel, check_intrinsics, finite, positive, shaped

EUCM_PARAMETER_NAMES = ("fx", "fy", "cx", "cy", "alpha", "beta")


@dataclass(frozen=True)
class EUCM(CameraModel):
    """Extended unified camera model.

    A point p = (x, y, z) is projected as (the first paper's eqs. 1-7: its rho is d here, eqs. 4-5 give
    (x_P, y_P), eq. 6 puts them on the plane z = 1 and eq. 7 multiplies by K)::

        d = sqrt(beta * (x^2 + y^2) + z^2)
        u = fx * x / (alpha * d + (1 - alpha) * z) + cx
        v = fy * y / (alpha * d + (1 - alpha) * z) + cy

    valid where ``z > -w * d`` with ``w = alpha / (1 - alpha)`` for alpha <= 0.5 and
    ``w = (1 - alpha) / alpha`` otherwise (Khomutenko et al.; the paper gives no validity region). A pixel
    is unprojected (Khomutenko et al.'s closed form; the paper has no equation for it) as::

        mx = (u - cx) / fx,  my = (v - cy) / fy,  r^2 = mx^2 + my^2
        mz = (1 - beta * alpha^2 * r^2) / (alpha * sqrt(1 - (2 alpha - 1) * beta * r^2) + 1 - alpha)

    and the ray (mx, my, mz) normalised, valid where alpha <= 0.5 or
    ``r^2 <= 1 / (beta * (2 alpha - 1))``.

    Parameters: ``fx, fy`` focal lengths and ``cx, cy`` principal point in pixels, ``alpha`` in
    [0, 1] (0 is a pinhole), ``beta`` > 0 (1 is the unified model of Mei), ``width, height``
    the image size in pixels.
    """

    fx: float
    fy: float
    cx: float
    cy: float
    alpha: float
    beta: float
    width: int
    height: int

    PARAMETER_NAMES = EUCM_PARAMETER_NAMES
    NAME = "eucm"
    KALIBR_MODEL, KALIBR_INTRINSICS = "eucm", 6  # intrinsics [alpha, beta, fu, fv, pu, pv]
    CAMERA_INFO = "eucm (alpha, beta)"
    BASALT_TYPE = "eucm"
    BOUNDS: ClassVar[dict[str, tuple[float, float]]] = {"alpha": (0.0, 1.0), "beta": (1e-6, np.inf)}
    START_SHAPE = (0.5, 1.0)  # a stereographic lens

    @classmethod
    def from_kalibr(cls, intrinsics, distortion, coeffs, width, height, where) -> EUCM:
        alpha, beta, fx, fy, cx, cy = intrinsics
        return cls(fx, fy, cx, cy, alpha, beta, width, height)

    def kalibr(self, name: str) -> tuple[list[float], str, list[float]]:
        return [self.alpha, self.beta, self.fx, self.fy, self.cx, self.cy], "none", []

    @classmethod
    def from_camera_info(cls, model, d, fx, fy, cx, cy, width, height) -> EUCM | None:
        return cls(fx, fy, cx, cy, d[0], d[1], width, height) if model == "eucm" and len(d) == 2 else None

    def camera_info_distortion(self) -> tuple[str, list[float]]:
        return "eucm", [self.alpha, self.beta]

    def __post_init__(self):
        check_intrinsics(self)
        if not 0.0 <= finite("alpha", self.alpha) <= 1.0:
            raise ValueError(f"alpha must lie in [0, 1], got {self.alpha}")
        positive("beta", self.beta)

    @classmethod
    def from_params(cls, params, width: int, height: int) -> EUCM:
        """Build from the parameter vector (fx, fy, cx, cy, alpha, beta), the order of ``params``."""
        params = np.asarray(params, dtype=np.float64)
        if params.shape != (6,):
            raise ValueError(f"EUCM parameters must be (fx, fy, cx, cy, alpha, beta), got shape {params.shape}")
        return cls(*params.tolist(), width, height)

    @property
    def params(self) -> np.ndarray:
        """The parameter vector (fx, fy, cx, cy, alpha, beta)."""
        return np.array([self.fx, self.fy, self.cx, self.cy, self.alpha, self.beta])

    @property
    def _w(self) -> float:
        alpha = self.alpha
        return alpha / (1.0 - alpha) if alpha <= 0.5 else (1.0 - alpha) / alpha

    def project(self, points) -> tuple[np.ndarray, np.ndarray]:
        """Pixels ``(..., 2)`` and validity mask ``(...)`` of camera-frame points ``(..., 3)``."""
        points = shaped(points, 3, "points")
        x, y, z = np.moveaxis(points, -1, 0)
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            d = np.sqrt(self.beta * (x * x + y * y) + z * z)
            denominator = self.alpha * d + (1.0 - self.alpha) * z
            valid = np.isfinite(d) & (z > -self._w * d) & (denominator > 0)
            uv = np.stack([self.fx * x / denominator + self.cx, self.fy * y / denominator + self.cy], axis=-1)
        uv[~valid] = np.nan
        return uv, valid

    def project_jacobians(self, points) -> tuple[np.ndarray, np.ndarray]:
        """Jacobians of ``project`` at ``points (..., 3)``.

        Returns ``d(u, v)/d(x, y, z)`` of shape ``(..., 2, 3)`` and
        ``d(u, v)/d(fx, fy, cx, cy, alpha, beta)`` of shape ``(..., 2, 6)``; NaN where the
        projection is invalid.
        """
        points = shaped(points, 3, "points")
        _, valid = self.project(points)
        x, y, z = np.moveaxis(points, -1, 0)
        a, b = self.alpha, self.beta
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            d = np.sqrt(b * (x * x + y * y) + z * z)
            den = a * d + (1.0 - a) * z
            mx, my = x / den, y / den
            # derivatives of the denominator with respect to x, y, z, alpha and beta
            dden = np.stack([a * b * x / d, a * b * y / d, a * z / d + (1.0 - a)], axis=-1)
            dden_dalpha = d - z
            dden_dbeta = a * (x * x + y * y) / (2.0 * d)

            j_point = np.zeros((*points.shape[:-1], 2, 3))
            j_point[..., 0, :] = -self.fx * (mx / den)[..., None] * dden
            j_point[..., 1, :] = -self.fy * (my / den)[..., None] * dden
            j_point[..., 0, 0] += self.fx / den
            j_point[..., 1, 1] += self.fy / den

            j_params = np.zeros((*points.shape[:-1], 2, 6))
            j_params[..., 0, 0] = mx
            j_params[..., 1, 1] = my
            j_params[..., 0, 2] = 1.0
            j_params[..., 1, 3] = 1.0
            j_params[..., 0, 4] = -self.fx * mx / den * dden_dalpha
            j_params[..., 1, 4] = -self.fy * my / den * dden_dalpha
            j_params[..., 0, 5] = -self.fx * mx / den * dden_dbeta
            j_params[..., 1, 5] = -self.fy * my / den * dden_dbeta
        j_point[~valid] = np.nan
        j_params[~valid] = np.nan
        return j_point, j_params

    def unproject(self, uv) -> tuple[np.ndarray, np.ndarray]:
        """Unit rays ``(..., 3)`` in the camera frame and validity mask ``(...)`` of pixels ``(..., 2)``."""
        uv = shaped(uv, 2, "pixels")
        a, b = self.alpha, self.beta
        mx = (uv[..., 0] - self.cx) / self.fx
        my = (uv[..., 1] - self.cy) / self.fy
        r2 = mx * mx + my * my
        valid = np.isfinite(r2)
        if a > 0.5:
            with np.errstate(invalid="ignore"):
                valid &= r2 <= 1.0 / (b * (2.0 * a - 1.0))
        with np.errstate(invalid="ignore", divide="ignore"):
            mz = (1.0 - b * a * a * r2) / (a * np.sqrt(1.0 - (2.0 * a - 1.0) * b * r2) + 1.0 - a)
            rays = np.stack([mx, my, mz], axis=-1) / np.sqrt(r2 + mz * mz)[..., None]
        rays[~valid] = np.nan
        return rays, valid


T265_LIKE = EUCM(fx=286.0, fy=286.0, cx=424.0, cy=400.0, alpha=0.6, beta=1.1, width=848, height=800)
"""An EUCM like the Intel RealSense T265's fisheye (848 x 800 pixels), the default of the examples."""
