"""Camera models: the extended unified camera model (EUCM), the pinhole camera with OpenCV's
radial-tangential distortion, and Mei's unified (omnidirectional) model with that same distortion.
Kannala-Brandt (``KB4``) and the double sphere (``DoubleSphere``) live in `gpo.fisheye` and are
importable from here as well; `gpo.camera_fit` fits one model to another.

Frames and units
----------------
Points are in the camera optical frame (REP-103): x right, y down, z forward, in metres (the
models are scale free, so any consistent unit works). Pixels are (u, v) with u to the right and
v down; the centre of the top-left pixel is (0, 0), as in OpenCV.

Shapes and invalid input
------------------------
Every function is vectorised: points have shape ``(..., 3)`` and pixels ``(..., 2)``, so a
single point, a list of points and a whole image grid all work. Each projection and unprojection
returns its result together with a boolean mask of shape ``(...)``. Where the mask is false (the
point is behind the lens, outside the model's valid region, or holds NaN or inf) the result is
NaN, so an invalid point can never turn silently into a pixel. An array whose last axis has the
wrong length raises a ``ValueError`` that says which shape was expected.

References
----------
EUCM: B. Khomutenko, G. Garcia, P. Martinet, "An Enhanced Unified Camera Model", IEEE Robotics
and Automation Letters 1(1), 2016; written here as in the first paper's eqs. 1-7 and as Basalt
implements it. Pinhole: OpenCV's ``projectPoints`` model with (k1, k2, p1, p2[, k3]). Omni: C. Mei,
P. Rives, "Single View Point Omnidirectional Camera Calibration from Planar Grids", ICRA 2007, with
radial-tangential distortion (k1, k2, p1, p2) as Kalibr's ``omni`` + ``radtan`` and OpenCV's ``cv2.omnidir``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

EUCM_PARAMETER_NAMES = ("fx", "fy", "cx", "cy", "alpha", "beta")
OMNI_PARAMETER_NAMES = ("fx", "fy", "cx", "cy", "xi", "k1", "k2", "p1", "p2")


def _as_array(values, width: int, what: str) -> np.ndarray:
    """``values`` as a float64 array whose last axis has length ``width``, else ValueError."""
    array = np.asarray(values, dtype=np.float64)
    if array.ndim == 0 or array.shape[-1] != width:
        raise ValueError(f"{what} must have shape (..., {width}), got shape {array.shape}")
    return array


def _check_finite(name: str, value: float) -> float:
    value = float(value)
    if not math.isfinite(value):
        raise ValueError(f"{name} must be a finite number, got {value}")
    return value


def _check_positive(name: str, value: float) -> float:
    value = _check_finite(name, value)
    if value <= 0:
        raise ValueError(f"{name} must be > 0, got {value}")
    return value


def _check_intrinsics(camera) -> None:
    """Check what every model shares: the image size, focal lengths and principal point."""
    _check_image_size(camera)
    _check_positive("fx", camera.fx)
    _check_positive("fy", camera.fy)
    _check_finite("cx", camera.cx)
    _check_finite("cy", camera.cy)


def _check_image_size(camera) -> None:
    """Check ``camera.width`` and ``camera.height`` and store them as int."""
    for name in ("width", "height"):
        value = getattr(camera, name)
        if (
            isinstance(value, bool)
            or not isinstance(value, (int, float, np.integer, np.floating))
            or not (value > 0 and float(value).is_integer())
        ):
            raise ValueError(f"{name} must be a positive whole number of pixels, got {value!r}")
        object.__setattr__(camera, name, int(value))


class _Camera:
    """What every camera model shares: pixel helpers over its ``width`` x ``height`` image."""

    width: int
    height: int
    cx: float
    cy: float

    def in_image(self, uv) -> np.ndarray:
        """True where pixel coordinates ``uv (..., 2)`` fall inside the image.

        The image spans [-0.5, width - 0.5) x [-0.5, height - 0.5): pixel centres are integers.
        """
        uv = _as_array(uv, 2, "pixels")
        with np.errstate(invalid="ignore"):
            return (
                (uv[..., 0] >= -0.5)
                & (uv[..., 0] < self.width - 0.5)
                & (uv[..., 1] >= -0.5)
                & (uv[..., 1] < self.height - 0.5)
            )

    def pixel_grid(self) -> np.ndarray:
        """The centre of every pixel, shape (height, width, 2), as (u, v)."""
        u, v = np.meshgrid(np.arange(self.width, dtype=np.float64), np.arange(self.height, dtype=np.float64))
        return np.stack([u, v], axis=-1)

    def field_of_view(self) -> tuple[float, float, float]:
        """Horizontal, vertical and diagonal field of view in radians.

        Each is the sum of the angles from the optical axis of the rays through two opposite
        border pixel centres: the left and right edge on the principal point's row, the top and
        bottom edge on its column, and the top-left and bottom-right corners. A lens may see
        more than 180 degrees. NaN where such a pixel has no valid ray.
        """
        cx, cy = self.principal_point
        right, bottom = self.width - 1.0, self.height - 1.0
        pairs = np.array([[[0.0, cy], [right, cy]], [[cx, 0.0], [cx, bottom]], [[0.0, 0.0], [right, bottom]]])
        rays, _ = self.unproject(pairs)
        off_axis = np.arccos(np.clip(rays[..., 2], -1.0, 1.0))
        horizontal, vertical, diagonal = off_axis.sum(axis=-1)
        return float(horizontal), float(vertical), float(diagonal)

    @property
    def principal_point(self) -> tuple[float, float]:
        """(cx, cy) in pixels."""
        return self.cx, self.cy

    def unproject(self, uv) -> tuple[np.ndarray, np.ndarray]:
        raise NotImplementedError


@dataclass(frozen=True)
class EUCM(_Camera):
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

    def __post_init__(self):
        _check_intrinsics(self)
        if not 0.0 <= _check_finite("alpha", self.alpha) <= 1.0:
            raise ValueError(f"alpha must lie in [0, 1], got {self.alpha}")
        _check_positive("beta", self.beta)

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
        points = _as_array(points, 3, "points")
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
        points = _as_array(points, 3, "points")
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
        uv = _as_array(uv, 2, "pixels")
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


_RADTAN_NAMES = ("k1", "k2", "p1", "p2", "k3")


def _check_radtan(dist, lengths: tuple[int, ...]) -> tuple[float, ...]:
    """``dist`` as a tuple of finite floats (k1, k2, p1, p2[, k3]) of one of the ``lengths``, else ValueError."""
    dist = tuple(float(c) for c in np.ravel(dist))
    if len(dist) not in lengths:
        forms = " or ".join(f"({', '.join(_RADTAN_NAMES[:length])})" for length in lengths)
        raise ValueError(f"dist must be {forms}, got {len(dist)} values")
    for name, value in zip(_RADTAN_NAMES, dist, strict=False):
        _check_finite(name, value)
    return dist


class _RadialTangential:
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
        k1, k2, _, _, k3 = self._coefficients
        roots = np.roots(np.trim_zeros([7.0 * k3, 5.0 * k2, 3.0 * k1, 1.0], "f"))
        positive = [s.real for s in roots if abs(s.imag) < 1e-12 and s.real > 0]
        return math.sqrt(min(positive)) if positive else math.inf

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


def _round_trip_valid(camera, rays: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """True where ``rays (..., 3)`` project validly back onto the pixels ``uv (..., 2)`` within 1e-6 px."""
    back, valid = camera.project(rays)
    with np.errstate(invalid="ignore"):
        return valid & np.all(np.abs(back - uv) <= 1e-6, axis=-1)


@dataclass(frozen=True)
class Pinhole(_RadialTangential, _Camera):
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
        _check_intrinsics(self)
        dist = _check_radtan(self.dist, (4, 5))
        object.__setattr__(self, "dist", (*dist, 0.0)[:5])  # always (k1, k2, p1, p2, k3)

    @property
    def camera_matrix(self) -> np.ndarray:
        """The 3x3 intrinsic matrix K."""
        return np.array([[self.fx, 0.0, self.cx], [0.0, self.fy, self.cy], [0.0, 0.0, 1.0]])

    def project(self, points) -> tuple[np.ndarray, np.ndarray]:
        """Pixels ``(..., 2)`` and validity mask ``(...)`` of camera-frame points ``(..., 3)``."""
        points = _as_array(points, 3, "points")
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
        uv = _as_array(uv, 2, "pixels")
        xn, yn = self._undistort((uv[..., 0] - self.cx) / self.fx, (uv[..., 1] - self.cy) / self.fy, iterations)
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            rays = np.stack([xn, yn, np.ones_like(xn)], axis=-1)
            rays /= np.linalg.norm(rays, axis=-1, keepdims=True)
        valid = _round_trip_valid(self, rays, uv)
        rays[~valid] = np.nan
        return rays, valid


@dataclass(frozen=True)
class Omni(_RadialTangential, _Camera):
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
        _check_intrinsics(self)
        if _check_finite("xi", self.xi) < 0:
            raise ValueError(f"xi must be >= 0, got {self.xi}")
        object.__setattr__(self, "dist", _check_radtan(self.dist, (4,)))

    PARAMETER_NAMES = OMNI_PARAMETER_NAMES

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
        points = _as_array(points, 3, "points")
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
        points = _as_array(points, 3, "points")
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
        uv = _as_array(uv, 2, "pixels")
        mx, my = self._undistort((uv[..., 0] - self.cx) / self.fx, (uv[..., 1] - self.cy) / self.fy, iterations)
        r2 = mx * mx + my * my
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            eta = (self.xi + np.sqrt(1.0 + (1.0 - self.xi * self.xi) * r2)) / (1.0 + r2)
            rays = np.stack([eta * mx, eta * my, eta - self.xi], axis=-1)
        valid = _round_trip_valid(self, rays, uv)
        rays[~valid] = np.nan
        return rays, valid


T265_LIKE = EUCM(fx=286.0, fy=286.0, cx=424.0, cy=400.0, alpha=0.6, beta=1.1, width=848, height=800)
"""An EUCM like the Intel RealSense T265's fisheye (848 x 800 pixels), the default of the examples."""


def __getattr__(name: str):
    """`gpo.fisheye`'s models (Kannala-Brandt, double sphere) are read from here too: ``from gpo.camera import KB4``."""
    if name in ("KB4", "DoubleSphere", "KB4_PARAMETER_NAMES", "DS_PARAMETER_NAMES"):
        from gpo import fisheye

        return getattr(fisheye, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
