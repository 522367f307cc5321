"""The Kannala-Brandt camera model with four coefficients (KB4).

J. Kannala, S. S. Brandt, "A Generic Camera Model and Calibration Method for Conventional, Wide-Angle, and
Fish-Eye Lenses", IEEE TPAMI 28(8), 2006, with four coefficients as OpenCV's ``cv2.fisheye``, Kalibr's
``pinhole-equi``, Basalt's ``kb4`` and ROS camera_info's ``equidistant``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from gpo.cameras.base import CameraModel, check_intrinsics, finite, flat_from_params, round_trip_valid, shaped

KB4_PARAMETER_NAMES = ("fx", "fy", "cx", "cy", "k1", "k2", "k3", "k4")


@dataclass(frozen=True)
class KB4(CameraModel):
    """Kannala-Brandt model with four coefficients (OpenCV's fisheye model).

    A point p = (x, y, z) at the angle theta = atan2(r, z) off the optical axis, r = sqrt(x^2 + y^2),
    lands at the distorted angle::

        theta_d = theta (1 + k1 theta^2 + k2 theta^4 + k3 theta^6 + k4 theta^8)
        u = fx theta_d x / r + cx,  v = fy theta_d y / r + cy

    (on the axis, r = 0: (u, v) = (cx, cy)). A projection is valid where theta_d still grows with theta,
    up to ``max_theta`` (at most pi, straight back); beyond it two rays would share a pixel. A pixel is
    unprojected by solving theta_d(theta) = |(mx, my)|, mx = (u - cx) / fx, my = (v - cy) / fy, by
    Newton's method; the ray is (sin(theta) mx / theta_d, sin(theta) my / theta_d, cos(theta)), valid
    where it projects back onto the pixel within 1e-6 px.

    Parameters: ``fx, fy`` focal lengths and ``cx, cy`` principal point in pixels; ``k1 .. k4``
    dimensionless (theta in radians); ``width, height`` the image size in pixels.
    """

    fx: float
    fy: float
    cx: float
    cy: float
    k1: float
    k2: float
    k3: float
    k4: float
    width: int
    height: int

    PARAMETER_NAMES = KB4_PARAMETER_NAMES
    NAME = "kb4"
    KALIBR_MODEL, KALIBR_DISTORTIONS, KALIBR_INTRINSICS = "pinhole", ("equidistant",), 4  # + coeffs [k1, k2, k3, k4]
    CAMERA_INFO = "equidistant (k1, k2, k3, k4)"
    BASALT_TYPE = "kb4"
    BOUNDS: ClassVar[dict[str, tuple[float, float]]] = {}
    START_SHAPE = (0.0,) * 4  # equidistant

    @classmethod
    def from_kalibr(cls, intrinsics, distortion, coeffs, width, height, where) -> KB4:
        if len(coeffs) != 4:
            raise ValueError(f"{where}: equidistant needs 4 distortion_coeffs [k1, k2, k3, k4], got {len(coeffs)}")
        return cls(*intrinsics, *coeffs, width, height)

    def kalibr(self, name: str) -> tuple[list[float], str, list[float]]:
        return [self.fx, self.fy, self.cx, self.cy], "equidistant", list(self.dist)

    @classmethod
    def from_camera_info(cls, model, d, fx, fy, cx, cy, width, height) -> KB4 | None:
        if model == "equidistant" and (len(d) == 4 or (len(d) == 5 and d[4] == 0.0)):
            return cls(fx, fy, cx, cy, *d[:4], width, height)
        return None

    def camera_info_distortion(self) -> tuple[str, list[float]]:
        return "equidistant", list(self.dist)

    def __post_init__(self):
        check_intrinsics(self)
        for name in ("k1", "k2", "k3", "k4"):
            object.__setattr__(self, name, finite(name, getattr(self, name)))

    @classmethod
    def from_params(cls, params, width: int, height: int) -> KB4:
        """Build from the parameter vector (fx, fy, cx, cy, k1, k2, k3, k4)."""
        return flat_from_params(cls, KB4_PARAMETER_NAMES, params, width, height)

    @property
    def params(self) -> np.ndarray:
        """The parameter vector (fx, fy, cx, cy, k1, k2, k3, k4)."""
        return np.array([self.fx, self.fy, self.cx, self.cy, self.k1, self.k2, self.k3, self.k4])

    @property
    def dist(self) -> tuple[float, float, float, float]:
        """(k1, k2, k3, k4), OpenCV's ``cv2.fisheye`` D."""
        return self.k1, self.k2, self.k3, self.k4

    @property
    def max_theta(self) -> float:
        """Largest angle off the optical axis (radians, at most pi) up to which theta_d grows with theta:
        the smallest positive root s = theta^2 of 1 + 3 k1 s + 5 k2 s^2 + 7 k3 s^3 + 9 k4 s^4, else pi."""
        roots = np.roots(np.trim_zeros([9.0 * self.k4, 7.0 * self.k3, 5.0 * self.k2, 3.0 * self.k1, 1.0], "f"))
        positive = [s.real for s in roots if abs(s.imag) < 1e-12 and s.real > 0]
        return min([math.pi, *(math.sqrt(s) for s in positive)])

    def _theta_d(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """theta_d(theta) and its derivative d theta_d / d theta."""
        t2 = theta * theta
        poly = 1.0 + t2 * (self.k1 + t2 * (self.k2 + t2 * (self.k3 + t2 * self.k4)))
        slope = 1.0 + t2 * (3.0 * self.k1 + t2 * (5.0 * self.k2 + t2 * (7.0 * self.k3 + t2 * 9.0 * self.k4)))
        return theta * poly, slope

    def _angles(self, points: np.ndarray):
        """r, theta, theta_d / r (theta_d / r -> 1 / z on the axis) and the validity mask."""
        x, y, z = np.moveaxis(points, -1, 0)
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            r = np.hypot(x, y)
            theta = np.arctan2(r, z)
            theta_d, _ = self._theta_d(theta)
            on_axis = r <= 1e-12 * np.abs(z)
            scale = np.where(on_axis, 1.0 / z, theta_d / np.where(on_axis, 1.0, r))
            valid = np.isfinite(points).all(axis=-1) & np.isfinite(scale) & (theta <= self.max_theta)
            valid &= ~(on_axis & (z <= 0))
        return x, y, z, r, theta, scale, valid

    def project(self, points) -> tuple[np.ndarray, np.ndarray]:
        """Pixels ``(..., 2)`` and validity mask ``(...)`` of camera-frame points ``(..., 3)``."""
        points = shaped(points, 3, "points")
        x, y, _, _, _, scale, valid = self._angles(points)
        with np.errstate(invalid="ignore", over="ignore"):
            uv = np.stack([self.fx * scale * x + self.cx, self.fy * scale * y + self.cy], axis=-1)
        uv[~valid] = np.nan
        return uv, valid

    def project_jacobians(self, points) -> tuple[np.ndarray, np.ndarray]:
        """Jacobians of ``project`` at ``points (..., 3)``: ``d(u, v)/d(x, y, z)`` of shape ``(..., 2, 3)`` and
        ``d(u, v)/d(fx, fy, cx, cy, k1, k2, k3, k4)`` of shape ``(..., 2, 8)``; NaN where invalid."""
        points = shaped(points, 3, "points")
        x, y, z, r, theta, scale, valid = self._angles(points)
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            _, slope = self._theta_d(theta)
            rho2 = r * r + z * z
            on_axis = r <= 1e-12 * np.abs(z)
            r_safe = np.where(on_axis, 1.0, r)
            # d(scale * x)/dp with scale = theta_d / r and theta = atan2(r, z)
            radial = np.where(on_axis, 0.0, slope * z / (r_safe * r_safe * rho2) - scale / (r_safe * r_safe))
            d_scale_dz = np.where(on_axis, -1.0 / (z * z), -slope / rho2)
            j_point = np.zeros((*points.shape[:-1], 2, 3))
            for row, (f, c) in enumerate(((self.fx, x), (self.fy, y))):
                j_point[..., row, 0] = f * radial * c * x
                j_point[..., row, 1] = f * radial * c * y
                j_point[..., row, row] += f * scale
                j_point[..., row, 2] = f * d_scale_dz * c
            j_params = np.zeros((*points.shape[:-1], 2, 8))
            j_params[..., 0, 0] = scale * x
            j_params[..., 1, 1] = scale * y
            j_params[..., 0, 2] = 1.0
            j_params[..., 1, 3] = 1.0
            # d theta_d / d k_i = theta^(2i + 1); on the axis theta / r -> 1 / z
            theta_over_r = np.where(on_axis, 1.0 / z, theta / r_safe)
            for i in range(4):
                power = theta_over_r * theta ** (2 * i + 2)
                j_params[..., 0, 4 + i] = self.fx * power * x
                j_params[..., 1, 4 + i] = self.fy * power * y
        j_point[~valid] = np.nan
        j_params[~valid] = np.nan
        return j_point, j_params

    def unproject(self, uv, iterations: int = 20) -> tuple[np.ndarray, np.ndarray]:
        """Unit rays ``(..., 3)`` in the camera frame and validity mask ``(...)`` of pixels ``(..., 2)``."""
        uv = shaped(uv, 2, "pixels")
        mx = (uv[..., 0] - self.cx) / self.fx
        my = (uv[..., 1] - self.cy) / self.fy
        radius = np.hypot(mx, my)
        theta = np.minimum(radius, self.max_theta)
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            for _ in range(iterations):
                theta_d, slope = self._theta_d(theta)
                step = (theta_d - radius) / slope
                theta = np.clip(theta - step, 0.0, self.max_theta)
                if not np.any(np.abs(step) > 1e-15):
                    break
            sin_over_radius = np.where(radius > 0, np.sin(theta) / np.where(radius > 0, radius, 1.0), 1.0)
            rays = np.stack([sin_over_radius * mx, sin_over_radius * my, np.cos(theta)], axis=-1)
        valid = round_trip_valid(self, rays, uv)
        rays[~valid] = np.nan
        return rays, valid
