"""What every camera model shares: the `CameraModel` base, and the checks and shapes each model's
constructor and projection use.

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
"""

from __future__ import annotations

import math
from typing import ClassVar

import numpy as np


def shaped(values, width: int, what: str) -> np.ndarray:
    """``values`` as a float64 array whose last axis has length ``width``, else ValueError."""
    array = np.asarray(values, dtype=np.float64)
    if array.ndim == 0 or array.shape[-1] != width:
        raise ValueError(f"{what} must have shape (..., {width}), got shape {array.shape}")
    return array


def finite(name: str, value: float) -> float:
    value = float(value)
    if not math.isfinite(value):
        raise ValueError(f"{name} must be a finite number, got {value}")
    return value


def positive(name: str, value: float) -> float:
    value = finite(name, value)
    if value <= 0:
        raise ValueError(f"{name} must be > 0, got {value}")
    return value


def check_intrinsics(camera) -> None:
    """Check what every model shares: the image size, focal lengths and principal point."""
    check_image_size(camera)
    positive("fx", camera.fx)
    positive("fy", camera.fy)
    finite("cx", camera.cx)
    finite("cy", camera.cy)


def check_image_size(camera) -> None:
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


class CameraModel:
    """What every camera model is: a frozen dataclass of its intrinsics (the first four ``fx, fy, cx, cy``) and its
    image's ``width`` and ``height``, which projects points of the optical frame to pixels and back.

    A model implements ``project(points) -> (pixels, valid)`` and ``unproject(pixels) -> (rays, valid)`` (the module
    docstring's shapes and validity), ``params`` and ``from_params`` (its parameter vector, named by
    ``PARAMETER_NAMES``) and, to be fitted by least squares, ``project_jacobians`` with ``BOUNDS`` and ``START_SHAPE``.
    The class attributes below say how calibration files name it (``gpo.cameras.files``) and how a fit starts
    (``gpo.cameras.fit``); ``NAME`` is its name in ``gpo.cameras.MODELS``, configs and the command line.
    """

    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float

    NAME: ClassVar[str]
    PARAMETER_NAMES: ClassVar[tuple[str, ...]] = ()
    KALIBR_MODEL: ClassVar[str | None] = None  # Kalibr's camera_model (None: not written to Kalibr files)
    KALIBR_DISTORTIONS: ClassVar[tuple[str, ...]] = ("none",)  # the distortion_model names it reads
    KALIBR_INTRINSICS: ClassVar[int] = 0  # how many intrinsics a Kalibr entry of it lists
    CAMERA_INFO: ClassVar[str] = ""  # the camera_info distortion models it reads, as an error message lists them
    BASALT_TYPE: ClassVar[str | None] = None  # Basalt's camera_type (None: not in Basalt files)
    BOUNDS: ClassVar[dict[str, tuple[float, float]] | None] = None  # least squares: shape parameters' bounds
    START_SHAPE: ClassVar[tuple[float, ...]] = ()  # the shape parameters a fit starts from
    START_FOCAL_SCALE: ClassVar[float] = 1.0  # a fit's start focal length over the local focal length

    @classmethod
    def from_kalibr(cls, intrinsics: list[float], distortion: str, coeffs: list[float], width: int, height: int,
                    where: str) -> CameraModel:
        """The camera of a Kalibr entry of this model (its ``KALIBR_MODEL``, one of its ``KALIBR_DISTORTIONS``)."""
        raise TypeError(f"{where}: {cls.__name__} is not read from Kalibr files")

    def kalibr(self, name: str) -> tuple[list[float], str, list[float]]:
        """(intrinsics, distortion model, distortion coefficients) of its Kalibr entry; ``name`` names it in errors."""
        raise TypeError(f"{name}: cannot write a {type(self).__name__} as a Kalibr camera")

    @classmethod
    def from_camera_info(cls, model: str, d: list[float], fx: float, fy: float, cx: float, cy: float, width: int,
                         height: int) -> CameraModel | None:
        """The camera of a ROS camera_info of ``distortion_model`` ``model`` and coefficients ``d``, or None when this
        model does not read it."""
        return None

    def camera_info_distortion(self) -> tuple[str, list[float]]:
        """The camera_info ``distortion_model`` and D of this camera."""
        raise TypeError(f"a {type(self).__name__} has no camera_info distortion model")

    def in_image(self, uv) -> np.ndarray:
        """True where pixel coordinates ``uv (..., 2)`` fall inside the image.

        The image spans [-0.5, width - 0.5) x [-0.5, height - 0.5): pixel centres are integers.
        """
        uv = shaped(uv, 2, "pixels")
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


def round_trip_valid(camera, rays: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """True where ``rays (..., 3)`` project validly back onto the pixels ``uv (..., 2)`` within 1e-6 px."""
    back, valid = camera.project(rays)
    with np.errstate(invalid="ignore"):
        return valid & np.all(np.abs(back - uv) <= 1e-6, axis=-1)


def flat_from_params(cls, names: tuple[str, ...], params, width: int, height: int):
    params = np.asarray(params, dtype=np.float64)
    if params.shape != (len(names),):
        raise ValueError(f"{cls.__name__} parameters must be ({', '.join(names)}), got shape {params.shape}")
    return cls(*params.tolist(), width, height)
