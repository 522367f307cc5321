"""The pinhole camera with OpenCV's radial-tangential distortion, and that distortion on its own
(`RadialTangential`), which the unified model (`gpo.cameras.omni`) shares.

OpenCV's ``projectPoints`` model with (k1, k2, p1, p2[, k3]).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from gpo.cameras.base import CameraModel, check_intrinsics, finite, round_trip_valid, shaped

RADTAN_NAMES = ("k1", "k2", "p1", "p2", "k3")


def check_radtan(dist, lengths: tuple[int, ...]) -> tuple[float, ...]:
    """``dist`` as a tuple of finite floats (k1, k2, p1, p2[, k3]) of one of the ``lengths``, else ValueError."""
    dist = tuple(float(c) for c in np.ravel(dist))
    if len(dist) not in lengths:
        forms = " or ".join(f"({', '.join(RADTAN_NAMES[:length])})" for length in lengths)
        raise ValueError(f"dist must be {forms}, got {len(dist)} values")
    for name, value in zip(RADTAN_NAMES, dist, strict=False):
        finite(name, value)
    return dist


def radtan_coeffs(distortion: str, coeffs: list[float], where: str) -> tuple[float, ...]:
    """(k1, k2, p1, p2) of a Kalibr entry's ``radtan`` distortion, zeros for ``none``; ``where`` names the entry."""
    if distortion == "none":
        return (0.0, 0.0, 0.0, 0.0)
    if len(coeffs) != 4:
        raise ValueError(f"{where}: radtan needs 4 distortion_coeffs [k1, k2, r1, r2], got {len(coeffs)}")
    return tuple(coeffs)


@functools.lru_cache(maxsize=256)
def _max_radius(coefficients: tuple[float, float, float, float, float]) -> float:
    """``RadialTangential.max_radius`` of (k1, k2, p1, p2, k3), found once for each lens (a camera asks at every
    projection)."""
    k1, k2, _, _, k3 = coefficients
    roots = np.roots(np.trim_zeros([7.0 * k3, 5.0 * k2, 3.0 * k1, 1.0], "f"))
    positive = [s.real for s in roots if abs(s.imag) < 1e-12 and s.real > 0]
    return math.sqrt(min(positive)) if positive else math.inf


class RadialTangential:
    """OpenCV's radial-tangential distortion on the normalised image plane, shared by `Pinhole` and `Omni`.

    ``dist`` holds (k1, k2, p1, p2) or (k1, k2, p1, p2, k3), OpenCV's order (k3 = 0 when absent). A point
    (xn, yn) of the normalised plane (dimensionless) with r^2 = xn^2 + yn^2 is distorted to::

        xd = xn (1 + k1 r^2 + k2 r^4 + k3 r^6) + 2 p1 xn yn + p2 (r^2 + 2 xn^2)
        yd = yn (1 + k1 r^2 + k2 r^4 + k3 r^6) + p1 (r^2 + 2 yn^2) + 2 p2 xn yn
    """

    dist: tuple[float, ...]

    @property
    def _coefficients(self) -> tuple[float, float, float, float, float]:
        """(k1, k2, p1, p2, k3), k3 = 0 when ``dist`` has four values."""
        return (*self.dist, 0.0)[:5]

    @property
    def max_radius(self) -> float:
        """Largest undistorted radius r = |(xn, yn)| on the normalised plane up to which the radial distortion
        grows with r.

        The radial map r -> r (1 + k1 r^2 + k2 r^4 + k3 r^6) stops growing at the smallest
        positive root s = r^2 of 1 + 3 k1 s + 5 k2 s^2 + 7 k3 s^3; infinite when there is none.
        """
        return _max_radius(self._coefficients)

    def _distort(self, xn: np.ndarray, yn: np.ndarray):
        """Distorted normalised coordinates (xd, yd) of (xn, yn), and their Jacobian.

        The Jacobian d(xd, yd)/d(xn, yn) is symmetric; it is returned as its entries (j_xx, j_xy, j_yy).
        """
        k1, k2, p1, p2, k3 = self._coefficients
        r2 = xn * xn + yn * yn
        radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3))
        dradial = k1 + r2 * (2.0 * k2 + r2 * 3.0 * k3)  # d radial / d r^2
        xd = xn * radial + 2.0 * p1 * xn * yn + p2 * (r2 + 2.0 * xn * xn)
        yd = yn * radial + p1 * (r2 + 2.0 * yn * yn) + 2.0 * p2 * xn * yn
        j_xx = radial + 2.0 * xn * xn * dradial + 2.0 * p1 * yn + 6.0 * p2 * xn
        j_xy = 2.0 * xn * yn * dradial + 2.0 * p1 * xn + 2.0 * p2 * yn
        j_yy = radial + 2.0 * yn * yn * dradial + 6.0 * p1 * yn + 2.0 * p2 * xn
        return xd, yd, (j_xx, j_xy, j_yy)

    def _undistort(self, target_x: np.ndarray, target_y: np.ndarray, iterations: int):
        """Undistorted normalised coordinates (xn, yn) of the distorted (target_x, target_y).

        Newton's method from the distorted point, at most ``iterations`` steps, stopping once every
        point distorts back within 1e-13. Callers check the result by projecting it again.
        """
        xn, yn = target_x.copy(), target_y.copy()
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            for _ in range(iterations):
                xd, yd, (j_xx, j_xy, j_yy) = self._distort(xn, yn)
                error_x, error_y = xd - target_x, yd - target_y
                if not (np.any(np.abs(error_x) > 1e-13) or np.any(np.abs(error_y) > 1e-13)):
                    break
                determinant = j_xx * j_yy - j_xy * j_xy
                xn -= (j_yy * error_x - j_xy * error_y) / determinant
                yn -= (j_xx * error_y - j_xy * error_x) / determinant
        return xn, yn


@dataclass(frozen=True)
class Pinhole(RadialTangential, CameraModel):
    """Pinhole camera with OpenCV's radial-tangential distortion.

    With (x', y') = (x / z, y / z) and r^2 = x'^2 + y'^2, the distorted normalised point is::

        x'' = x' (1 + k1 r^2 + k2 r^4 + k3 r^6) + 2 p1 x' y' + p2 (r^2 + 2 x'^2)
        y'' = y' (1 + k1 r^2 + k2 r^4 + k3 r^6) + p1 (r^2 + 2 y'^2) + 2 p2 x' y'

    and (u, v) = (fx x'' + cx, fy y'' + cy), as ``cv2.projectPoints``. A projection is valid
    where z > 0 and r lies where the radial polynomial still grows with r (beyond that radius
    distinct rays would land on the same pixel).

    ``dist`` is (k1, k2, p1, p2) or (k1, k2, p1, p2, k3), OpenCV's order; it is kept as five values, k3 = 0
    when not given.
    """

    fx: float
    fy: float
    cx: float
    cy: float
    dist: tuple[float, ...]
    width: int
    height: int

    def __post_init__(self):
        check_intrinsics(self)
        dist = check_radtan(self.dist, (4, 5))
        object.__setattr__(self, "dist", (*dist, 0.0)[:5])  # always (k1, k2, p1, p2, k3)

    NAME = "pinhole"
    KALIBR_MODEL, KALIBR_DISTORTIONS, KALIBR_INTRINSICS = "pinhole", ("radtan", "none"), 4  # + [k1, k2, r1, r2]
    CAMERA_INFO = "plumb_bob (k1, k2, p1, p2[, k3]), rational_polynomial with k4 = k5 = k6 = 0"

    @classmethod
    def from_kalibr(cls, intrinsics, distortion, coeffs, width, height, where) -> Pinhole:
        return cls(*intrinsics, radtan_coeffs(distortion, coeffs, where), width, height)

    def kalibr(self, name: str) -> tuple[list[float], str, list[float]]:
        k1, k2, p1, p2, *rest = self.dist
        if rest and rest[0] != 0.0:
            raise ValueError(f"{name}: Kalibr's radtan has no k3, but this camera has k3 = {rest[0]}")
        return [self.fx, self.fy, self.cx, self.cy], "radtan", [k1, k2, p1, p2]

    @classmethod
    def from_camera_info(cls, model, d, fx, fy, cx, cy, width, height) -> Pinhole | None:
        if model == "rational_polynomial" and len(d) == 8 and not any(d[5:]):
            d = d[:5]
        if model in ("plumb_bob", "rational_polynomial") and len(d) in (0, 4, 5):
            return cls(fx, fy, cx, cy, d or (0.0,) * 5, width, height)
        return None

    def camera_info_distortion(self) -> tuple[str, list[float]]:
        return "plumb_bob", list(self.dist)

    @property
    def camera_matrix(self) -> np.ndarray:
        """The 3x3 intrinsic matrix K."""
        return np.array([[self.fx, 0.0, self.cx], [0.0, self.fy, self.cy], [0.0, 0.0, 1.0]])

    def project(self, points) -> tuple[np.ndarray, np.ndarray]:
        """Pixels ``(..., 2)`` and validity mask ``(...)`` of camera-frame points ``(..., 3)``."""
        points = shaped(points, 3, "points")
        x, y, z = np.moveaxis(points, -1, 0)
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            xn, yn = x / z, y / z
            r2 = xn * xn + yn * yn
            valid = np.isfinite(r2) & (z > 0) & (r2 <= self.max_radius**2)
            xd, yd, _ = self._distort(xn, yn)
            uv = np.stack([self.fx * xd + self.cx, self.fy * yd + self.cy], axis=-1)
        uv[~valid] = np.nan
        return uv, valid

    def unproject(self, uv, iterations: int = 20) -> tuple[np.ndarray, np.ndarray]:
        """Unit rays ``(..., 3)`` and validity mask ``(...)`` of pixels ``(..., 2)``.

        The distortion is inverted by Newton's method from the distorted point; a pixel is valid
        where the ray found lies inside the monotonic radius and projects back onto the pixel
        within 1e-6 px.
        """
        uv = shaped(uv, 2, "pixels")
        xn, yn = self._undistort((uv[..., 0] - self.cx) / self.fx, (uv[..., 1] - self.cy) / self.fy, iterations)
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            rays = np.stack([xn, yn, np.ones_like(xn)], axis=-1)
            rays /= np.linalg.norm(rays, axis=-1, keepdims=True)
        valid = round_trip_valid(self, rays, uv)
        rays[~valid] = np.nan
        return rays, valid
