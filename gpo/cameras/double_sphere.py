"""The double sphere camera model (DS).

V. Usenko, N. Demmel, D. Cremers, "The Double Sphere Camera Model", 3DV 2018, eqs. 40-47, as Basalt's and
Kalibr's ``ds``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from gpo.cameras.base import CameraModel, check_intrinsics, finite, flat_from_params, round_trip_valid, shaped

DS_PARAMETER_NAMES = ("fx", "fy", "cx", "cy", "xi", "alpha")


@dataclass(frozen=True)
class DoubleSphere(CameraModel):
    """Double sphere model of Usenko, Demmel and Cremers (2018).

    A point p = (x, y, z) is put on a first unit sphere, then on a second one shifted by ``xi`` along z,
    then projected by a pinhole shifted by alpha / (1 - alpha) (the paper's eqs. 40-42)::

        d1 = sqrt(x^2 + y^2 + z^2),  d2 = sqrt(x^2 + y^2 + (xi d1 + z)^2)
        u = fx x / (alpha d2 + (1 - alpha) (xi d1 + z)) + cx,  v likewise with fy, y, cy

    valid where ``z > -w2 d1`` with w1 = alpha / (1 - alpha) for alpha <= 0.5, (1 - alpha) / alpha
    otherwise, and w2 = (w1 + xi) / sqrt(2 w1 xi + xi^2 + 1) (eqs. 43-45). A pixel is unprojected
    (eqs. 46-47) with mx = (u - cx) / fx, my = (v - cy) / fy, r^2 = mx^2 + my^2::

        mz = (1 - alpha^2 r^2) / (alpha sqrt(1 - (2 alpha - 1) r^2) + 1 - alpha)
        ray = (mz xi + sqrt(mz^2 + (1 - xi^2) r^2)) / (mz^2 + r^2) (mx, my, mz) - (0, 0, xi)

    valid where alpha <= 0.5 or r^2 <= 1 / (2 alpha - 1), and the ray projects back onto the pixel
    within 1e-6 px. The ray is returned normalised.

    Parameters: ``fx, fy`` and ``cx, cy`` in pixels, ``xi`` (dimensionless, Basalt keeps it in [-1, 1]),
    ``alpha`` in [0, 1]; ``width, height`` the image size in pixels. With xi = 0 it is `EUCM` with beta = 1.
    At xi = 0 the parameters are degenerate to first order: scaling fx and fy by (1 + e) while adding e to
    xi and (2 alpha - 1) e to alpha changes no pixel, so a calibration near xi = 0 leaves f, xi and alpha with large
    standard deviations although its pixels are well determined.
    """

    fx: float
    fy: float
    cx: float
    cy: float
    xi: float
    alpha: float
    width: int
    height: int

    PARAMETER_NAMES = DS_PARAMETER_NAMES
    NAME = "ds"
    KALIBR_MODEL, KALIBR_INTRINSICS = "ds", 6  # intrinsics [xi, alpha, fu, fv, pu, pv]
    CAMERA_INFO = "ds (xi, alpha)"
    BASALT_TYPE = "ds"
    BOUNDS: ClassVar[dict[str, tuple[float, float]]] = {"xi": (-1.0, 1.0), "alpha": (0.0, 1.0)}
    START_SHAPE = (0.0, 0.5)

    @classmethod
    def from_kalibr(cls, intrinsics, distortion, coeffs, width, height, where) -> DoubleSphere:
        xi, alpha, fx, fy, cx, cy = intrinsics
        return cls(fx, fy, cx, cy, xi, alpha, width, height)

    def kalibr(self, name: str) -> tuple[list[float], str, list[float]]:
        return [self.xi, self.alpha, self.fx, self.fy, self.cx, self.cy], "none", []

    @classmethod
    def from_camera_info(cls, model, d, fx, fy, cx, cy, width, height) -> DoubleSphere | None:
        return cls(fx, fy, cx, cy, d[0], d[1], width, height) if model == "ds" and len(d) == 2 else None

    def camera_info_distortion(self) -> tuple[str, list[float]]:
        return "ds", [self.xi, self.alpha]

    def __post_init__(self):
        check_intrinsics(self)
        if not -1.0 <= finite("xi", self.xi) <= 1.0:
            raise ValueError(f"xi must lie in [-1, 1], got {self.xi}")
        if not 0.0 <= finite("alpha", self.alpha) <= 1.0:
            raise ValueError(f"alpha must lie in [0, 1], got {self.alpha}")

    @classmethod
    def from_params(cls, params, width: int, height: int) -> DoubleSphere:
        """Build from the parameter vector (fx, fy, cx, cy, xi, alpha), Basalt's order."""
        return flat_from_params(cls, DS_PARAMETER_NAMES, params, width, height)

    @property
    def params(self) -> np.ndarray:
        """The parameter vector (fx, fy, cx, cy, xi, alpha)."""
        return np.array([self.fx, self.fy, self.cx, self.cy, self.xi, self.alpha])

    @property
    def _w2(self) -> float:
        alpha, xi = self.alpha, self.xi
        w1 = alpha / (1.0 - alpha) if alpha <= 0.5 else (1.0 - alpha) / alpha
        return (w1 + xi) / math.sqrt(2.0 * w1 * xi + xi * xi + 1.0)

    def _terms(self, points: np.ndarray):
        """x, y, d1, m = xi d1 + z, d2, the denominator and the validity mask."""
        x, y, z = np.moveaxis(points, -1, 0)
        with np.errstate(invalid="ignore", over="ignore"):
            d1 = np.sqrt(x * x + y * y + z * z)
            m = self.xi * d1 + z
            d2 = np.sqrt(x * x + y * y + m * m)
            denominator = self.alpha * d2 + (1.0 - self.alpha) * m
            valid = np.isfinite(d2) & (z > -self._w2 * d1) & (denominator > 0)
        return x, y, d1, m, d2, denominator, valid

    def project(self, points) -> tuple[np.ndarray, np.ndarray]:
        """Pixels ``(..., 2)`` and validity mask ``(...)`` of camera-frame points ``(..., 3)``."""
        points = shaped(points, 3, "points")
        x, y, _, _, _, denominator, valid = self._terms(points)
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            uv = np.stack([self.fx * x / denominator + self.cx, self.fy * y / denominator + self.cy], axis=-1)
        uv[~valid] = np.nan
        return uv, valid

    def project_jacobians(self, points) -> tuple[np.ndarray, np.ndarray]:
        """Jacobians of ``project`` at ``points (..., 3)``: ``d(u, v)/d(x, y, z)`` of shape ``(..., 2, 3)`` and
        ``d(u, v)/d(fx, fy, cx, cy, xi, alpha)`` of shape ``(..., 2, 6)``; NaN where invalid."""
        points = shaped(points, 3, "points")
        x, y, d1, m, d2, den, valid = self._terms(points)
        a, xi = self.alpha, self.xi
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            dm = xi * points / d1[..., None]  # d m / d p
            dm[..., 2] += 1.0
            dd2 = (points * np.array([1.0, 1.0, 0.0]) + m[..., None] * dm) / d2[..., None]
            dden = a * dd2 + (1.0 - a) * dm
            dden_dxi = (a * m / d2 + 1.0 - a) * d1
            dden_dalpha = d2 - m
            j_point = np.zeros((*points.shape[:-1], 2, 3))
            j_params = np.zeros((*points.shape[:-1], 2, 6))
            for row, (f, c) in enumerate(((self.fx, x), (self.fy, y))):
                minus_f_c_over_den2 = -f * c / (den * den)
                j_point[..., row, :] = minus_f_c_over_den2[..., None] * dden
                j_point[..., row, row] += f / den
                j_params[..., row, row] = c / den
                j_params[..., row, 2 + row] = 1.0
                j_params[..., row, 4] = minus_f_c_over_den2 * dden_dxi
                j_params[..., row, 5] = minus_f_c_over_den2 * dden_dalpha
        j_point[~valid] = np.nan
        j_params[~valid] = np.nan
        return j_point, j_params

    def unproject(self, uv) -> tuple[np.ndarray, np.ndarray]:
        """Unit rays ``(..., 3)`` in the camera frame and validity mask ``(...)`` of pixels ``(..., 2)``."""
        uv = shaped(uv, 2, "pixels")
        a, xi = self.alpha, self.xi
        mx = (uv[..., 0] - self.cx) / self.fx
        my = (uv[..., 1] - self.cy) / self.fy
        r2 = mx * mx + my * my
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            mz = (1.0 - a * a * r2) / (a * np.sqrt(1.0 - (2.0 * a - 1.0) * r2) + 1.0 - a)
            scale = (mz * xi + np.sqrt(mz * mz + (1.0 - xi * xi) * r2)) / (mz * mz + r2)
            rays = np.stack([scale * mx, scale * my, scale * mz - xi], axis=-1)
            rays /= np.linalg.norm(rays, axis=-1, keepdims=True)
        valid = round_trip_valid(self, rays, uv)
        if a > 0.5:
            with np.errstate(invalid="ignore"):
                valid &= r2 <= 1.0 / (2.0 * a - 1.0)
        rays[~valid] = np.nan
        return rays, valid
