"""Mei's unified (omnidirectional) camera model with radial-tangential distortion.

C. Mei, P. Rives, "Single View Point Omnidirectional Camera Calibration from Planar Grids", ICRA 2007, with
radial-tangential distortion (k1, k2, p1, p2) as Kalibr's ``omni`` + ``radtan`` and OpenCV's ``cv2.omnidir``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from gpo.cameras.base import CameraModel, check_intrinsics, finite, round_trip_valid, shaped
from gpo.cameras.pinhole import RadialTangential, check_radtan, radtan_coeffs

OMNI_PARAMETER_NAMES = ("fx", "fy", "cx", "cy", "xi", "k1", "k2", "p1", "p2")


@dataclass(frozen=True)
class Omni(RadialTangential, CameraModel):
    """Unified camera model of Mei with radial-tangential distortion: Kalibr's ``omni`` + ``radtan``.

    A point p = (x, y, z) is put on the unit sphere and seen from a centre ``xi`` sphere radii behind
    the sphere's centre, on the normalised plane (Mei and Rives 2007, projection steps 1-5)::

        s = p / |p|
        (mx, my) = (s_x / (s_z + xi), s_y / (s_z + xi))

    then (mx, my) is distorted as in `Pinhole` (k1, k2, p1, p2; no k3) into (mx'', my'') and
    (u, v) = (fx mx'' + cx, fy my'' + cy); unlike Mei's K there is no skew, as in Kalibr.

    Valid region. A ray theta off the optical axis lands at the radius r = sin(theta) / (cos(theta) + xi),
    and dr/dtheta = (1 + xi cos(theta)) / (cos(theta) + xi)^2. The point must lie in front of the projection
    centre (s_z + xi > 0), and r must still grow with theta (s_z > -1/xi), else two rays share a pixel::

        s_z > -w,  w = xi for xi <= 1,  w = 1 / xi for xi > 1

    as Kalibr's ``OmniProjection`` and `EUCM` have it; and r must lie within ``max_radius``, where the radial
    distortion still grows.

    Unprojection: the distortion is inverted by Newton's method, then (mx, my) is lifted onto the sphere
    with Mei's closed form::

        r^2 = mx^2 + my^2
        eta = (xi + sqrt(1 + (1 - xi^2) r^2)) / (1 + r^2)
        s = (eta mx, eta my, eta - xi)

    which exists for r^2 <= 1 / (xi^2 - 1) when xi > 1, i.e. up to the fold s_z = -1/xi. A pixel is valid
    where its ray projects back onto it within 1e-6 px.

    Without distortion this is `EUCM` with alpha = xi / (1 + xi), beta = 1 and focal lengths f / (1 + xi);
    with xi = 0 it is `Pinhole`.

    Parameters: ``fx, fy`` (Kalibr's fu, fv) in pixels, ``cx, cy`` (Kalibr's pu, pv) the principal point in
    pixels, ``xi`` >= 0 (dimensionless), ``dist`` = (k1, k2, p1, p2), ``width, height`` the image size in
    pixels. Reference: C. Mei, P. Rives, "Single View Point Omnidirectional Camera Calibration from Planar
    Grids", ICRA 2007.
    """

    fx: float
    fy: float
    cx: float
    cy: float
    xi: float
    dist: tuple[float, ...]
    width: int
    height: int

    def __post_init__(self):
        check_intrinsics(self)
        if finite("xi", self.xi) < 0:
            raise ValueError(f"xi must be >= 0, got {self.xi}")
        object.__setattr__(self, "dist", check_radtan(self.dist, (4,)))

    PARAMETER_NAMES = OMNI_PARAMETER_NAMES
    NAME = "omni"
    KALIBR_MODEL, KALIBR_DISTORTIONS, KALIBR_INTRINSICS = "omni", ("radtan", "none"), 5  # [xi, fu, fv, pu, pv]
    BOUNDS: ClassVar[dict[str, tuple[float, float]]] = {"xi": (0.0, np.inf)}
    START_SHAPE = (1.0, 0.0, 0.0, 0.0, 0.0)  # xi = 1 without distortion
    START_FOCAL_SCALE = 2.0  # whose focal length is twice the local one

    @classmethod
    def from_kalibr(cls, intrinsics, distortion, coeffs, width, height, where) -> Omni:
        xi, fu, fv, pu, pv = intrinsics
        return cls(fu, fv, pu, pv, xi, radtan_coeffs(distortion, coeffs, where), width, height)

    def kalibr(self, name: str) -> tuple[list[float], str, list[float]]:
        return [self.xi, self.fx, self.fy, self.cx, self.cy], "radtan", list(self.dist)

    @classmethod
    def from_params(cls, params, width: int, height: int) -> Omni:
        """Build from the parameter vector (fx, fy, cx, cy, xi, k1, k2, p1, p2)."""
        params = np.asarray(params, dtype=np.float64)
        if params.shape != (9,):
            raise ValueError(f"Omni parameters must be ({', '.join(OMNI_PARAMETER_NAMES)}), got shape {params.shape}")
        return cls(*params[:5].tolist(), tuple(params[5:].tolist()), width, height)

    @property
    def params(self) -> np.ndarray:
        """The parameter vector (fx, fy, cx, cy, xi, k1, k2, p1, p2)."""
        return np.array([self.fx, self.fy, self.cx, self.cy, self.xi, *self.dist])

    @property
    def _w(self) -> float:
        """Valid points have s_z > -w on the unit sphere."""
        return self.xi if self.xi <= 1.0 else 1.0 / self.xi

    def project_jacobians(self, points) -> tuple[np.ndarray, np.ndarray]:
        """Jacobians of ``project`` at ``points (..., 3)``: ``d(u, v)/d(x, y, z)`` of shape ``(..., 2, 3)`` and
        ``d(u, v)/d(fx, fy, cx, cy, xi, k1, k2, p1, p2)`` of shape ``(..., 2, 9)``; NaN where invalid.

        By the chain rule through (mx, my) = (x, y) / (z + xi |p|) and the distortion's own Jacobian.
        """
        points = shaped(points, 3, "points")
        _, valid = self.project(points)
        x, y, z = np.moveaxis(points, -1, 0)
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            norm = np.sqrt(x * x + y * y + z * z)
            denominator = z + self.xi * norm
            mx, my = x / denominator, y / denominator
            xd, yd, (j_xx, j_xy, j_yy) = self._distort(mx, my)
            d_den = self.xi * points / norm[..., None]  # d denominator / d p
            d_den[..., 2] += 1.0
            d_m = -np.stack([mx, my], axis=-1)[..., :, None] * d_den[..., None, :] / denominator[..., None, None]
            d_m[..., 0, 0] += 1.0 / denominator
            d_m[..., 1, 1] += 1.0 / denominator
            d_m_dxi = -np.stack([mx, my], axis=-1) * (norm / denominator)[..., None]
            j_distort = np.stack([np.stack([j_xx, j_xy], axis=-1), np.stack([j_xy, j_yy], axis=-1)], axis=-2)
            focal = np.array([self.fx, self.fy])[:, None]
            j_point = focal * (j_distort @ d_m)
            r2 = mx * mx + my * my
            j_params = np.zeros((*points.shape[:-1], 2, 9))
            j_params[..., 0, 0] = xd
            j_params[..., 1, 1] = yd
            j_params[..., 0, 2] = 1.0
            j_params[..., 1, 3] = 1.0
            j_params[..., :, 4] = focal[:, 0] * (j_distort @ d_m_dxi[..., None])[..., 0]
            j_params[..., 0, 5:] = self.fx * np.stack([mx * r2, mx * r2 * r2, 2.0 * mx * my, r2 + 2.0 * mx * mx], -1)
            j_params[..., 1, 5:] = self.fy * np.stack([my * r2, my * r2 * r2, r2 + 2.0 * my * my, 2.0 * mx * my], -1)
        j_point[~valid] = np.nan
        j_params[~valid] = np.nan
        return j_point, j_params

    def project(self, points) -> tuple[np.ndarray, np.ndarray]:
        """Pixels ``(..., 2)`` and validity mask ``(...)`` of camera-frame points ``(..., 3)``."""
        points = shaped(points, 3, "points")
        x, y, z = np.moveaxis(points, -1, 0)
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            norm = np.sqrt(x * x + y * y + z * z)
            denominator = z + self.xi * norm  # |p| (s_z + xi)
            mx, my = x / denominator, y / denominator
            r2 = mx * mx + my * my
            valid = np.isfinite(r2) & (z > -self._w * norm) & (r2 <= self.max_radius**2)
            xd, yd, _ = self._distort(mx, my)
            uv = np.stack([self.fx * xd + self.cx, self.fy * yd + self.cy], axis=-1)
        uv[~valid] = np.nan
        return uv, valid

    def unproject(self, uv, iterations: int = 20) -> tuple[np.ndarray, np.ndarray]:
        """Unit rays ``(..., 3)`` in the camera frame and validity mask ``(...)`` of pixels ``(..., 2)``."""
        uv = shaped(uv, 2, "pixels")
        mx, my = self._undistort((uv[..., 0] - self.cx) / self.fx, (uv[..., 1] - self.cy) / self.fy, iterations)
        r2 = mx * mx + my * my
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            eta = (self.xi + np.sqrt(1.0 + (1.0 - self.xi * self.xi) * r2)) / (1.0 + r2)
            rays = np.stack([eta * mx, eta * my, eta - self.xi], axis=-1)
        valid = round_trip_valid(self, rays, uv)
        rays[~valid] = np.nan
        return rays, valid
