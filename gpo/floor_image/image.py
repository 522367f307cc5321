"""A floor image and the one remap table that makes it from a camera frame.

The first paper turns a fisheye frame into a top view of the floor in front of the robot in three stages
(chapters 02-04), each a fixed per-pixel map: fisheye -> cubemap (``gpo.floor_image.cubemap``, eqs. 8-18) ->
GPI (``gpo.floor_image.gpi``, eq. 22) -> ortho-GPI (``gpo.floor_image.ortho``). Because every stage is a fixed
map, the chain collapses into **one table**: for each floor-image pixel, the camera pixel it shows
(``RemapTable``: one ``cv2.remap`` per frame, one resampling instead of three). The analytic rectifier
(``gpo.floor_image.analytic``) builds the same kind of table with no chessboard at all.

Frames and units
----------------
``base_link`` (REP-103/105): x forward, y left, z up, origin at the rear-axle centre on the floor z = 0;
lengths in metres, angles in radians. Pixels (u, v): u right, v down, the centre of the top-left pixel at
(0, 0), as ``gpo.cameras`` and OpenCV. A floor image is a top view: image up is the robot's forward (+x) and
image right the robot's right (-y). ``FloorImage`` holds its size and the affine map between its pixels and
floor points (x, y) in base_link.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Callable
from dataclasses import dataclass

import cv2
import numpy as np

import gpo.io.cache
from gpo.cameras import CameraModel
from gpo.cameras.rig import CameraMount

TABLE_FORMAT = 1  # bump when the tables' meaning changes, so that old cached files are not read


OUTSIDE = -16.0  # remap coordinate of a masked pixel: far enough outside that only the border value is read


class GroundImageError(ValueError):
    """A floor image cannot be made from this input; the message says what to change."""


# The default floor patch, where an odometry config leaves it unset (the shipped gpo/configs/sim_t265.yaml writes the
# same values): 0.20 x 0.20 m from 0.70 m ahead of the rear axle, base_link metres, at 1 mm per pixel. 1 mm pixels
# track better than 0.5 mm (a floor point's error per track 0.11 mm against 0.15 mm with a 21-pixel window: the
# window then spans twice the floor) and take a quarter of the time.
# The one default: ``FloorImage.top_view()`` and a run config read these; the stages (``analytic_table``,
# ``ortho_rectify``, ``chessboard_route``) take the floor image they are given and have none of their own.
FLOOR_X_RANGE_M = (0.70, 0.90)
FLOOR_Y_RANGE_M = (-0.10, 0.10)
FLOOR_METRES_PER_PIXEL = 1e-3
MAX_FLOOR_PIXELS = 16_000_000
"""The largest floor image, pixels (4000 x 4000; its remap table alone is 128 MB): the KLT tracks a few hundred
pixels a side, and a wider extent or finer pixel is a mistake that would otherwise ask for terabytes."""


@dataclass(frozen=True, eq=False)
class FloorImage:
    """A floor image's size and where it lies on the floor of ``base_link``.

    ``width`` x ``height`` pixels; ``affine`` (2, 3): pixel (u, v, 1) -> floor point (x, y), metres in
    base_link, so that (x, y) = affine[:, :2] (u, v) + affine[:, 2]. ``metric``: True when the map holds
    exactly (the ortho-GPI, the analytic route); False for the plain GPI, where it is exact only up to the
    four corners' accuracy on the front face's part and approximate on the bottom face's rows.
    """

    width: int
    height: int
    affine: np.ndarray
    metric: bool = True

    def __post_init__(self):
        affine = np.array(self.affine, dtype=np.float64)
        if affine.shape != (2, 3) or not np.isfinite(affine).all() or abs(np.linalg.det(affine[:, :2])) < 1e-18:
            raise GroundImageError(
                f"a floor image's affine map must be a finite, invertible (2, 3) matrix, got {affine}"
            )
        if min(self.width, self.height) < 2:
            raise GroundImageError(f"a floor image needs at least 2 x 2 pixels, got {self.width} x {self.height}")
        affine.flags.writeable = False
        object.__setattr__(self, "affine", affine)
        object.__setattr__(self, "width", int(self.width))
        object.__setattr__(self, "height", int(self.height))

    @classmethod
    def top_view(
        cls, x_range=FLOOR_X_RANGE_M, y_range=FLOOR_Y_RANGE_M, metres_per_pixel: float = FLOOR_METRES_PER_PIXEL
    ) -> FloorImage:
        """The floor from x_range = (near, far) ahead to y_range = (right, left) sideways (base_link, metres).

        Image up = +x (forward), image right = -y (the robot's right); the ranges are the outer edges of the
        border pixels, rounded to whole pixels keeping the far-left corner.
        """
        (near, far), (right, left) = x_range, y_range
        step = float(metres_per_pixel)
        if not (math.isfinite(step) and step > 0):
            raise GroundImageError(f"metres_per_pixel must be a positive number, got {metres_per_pixel!r}")
        if not (far > near and left > right):
            raise GroundImageError(
                f"x_range must be (near, far) with far > near and y_range (right, left) with left > right, "
                f"got x_range={x_range}, y_range={y_range}"
            )
        width, height = round((left - right) / step), round((far - near) / step)
        if width * height > MAX_FLOOR_PIXELS:
            raise GroundImageError(
                f"x_range {list(x_range)} m and y_range {list(y_range)} m at {step:g} metres_per_pixel make a floor "
                f"image of {width} x {height} pixels, over the {MAX_FLOOR_PIXELS} allowed: give a larger "
                "metres_per_pixel or a smaller extent"
            )
        affine = [[0.0, -step, far - 0.5 * step], [-step, 0.0, left - 0.5 * step]]
        return cls(width, height, np.array(affine))

    def widened(self, scale: float) -> FloorImage:
        """The floor image ``scale`` times as wide and long about the same centre, on as many pixels: each pixel
        ``scale`` times the side, the same orientation, the centre pixel on the same floor point."""
        if not (math.isfinite(scale) and scale > 0):
            raise GroundImageError(f"a floor image is widened by a positive scale, got {scale!r}")
        centre = np.array([(self.width - 1) / 2, (self.height - 1) / 2])
        linear = self.affine[:, :2]
        offset = self.affine[:, 2] + (1.0 - scale) * linear @ centre
        return FloorImage(self.width, self.height, np.column_stack([scale * linear, offset]), self.metric)

    @property
    def metres_per_pixel(self) -> float:
        """Side of a pixel on the floor, metres (the square root of the affine map's area scale)."""
        return math.sqrt(abs(np.linalg.det(self.affine[:, :2])))

    @property
    def extent(self) -> tuple[float, float, float, float]:
        """(x_min, x_max, y_min, y_max) metres in base_link covered by the image's pixels (outer edges)."""
        right, bottom = self.width - 0.5, self.height - 0.5
        xy = self.pixel_to_base([[-0.5, -0.5], [right, -0.5], [-0.5, bottom], [right, bottom]])
        return float(xy[:, 0].min()), float(xy[:, 0].max()), float(xy[:, 1].min()), float(xy[:, 1].max())

    def pixel_to_base(self, uv) -> np.ndarray:
        """Floor points (..., 2) (x, y) metres in base_link of pixels ``uv`` (..., 2)."""
        return as_points(uv) @ self.affine[:, :2].T + self.affine[:, 2]

    def base_to_pixel(self, xy) -> np.ndarray:
        """Pixels (..., 2) (u, v) of floor points ``xy`` (..., 2), metres in base_link."""
        return (as_points(xy) - self.affine[:, 2]) @ np.linalg.inv(self.affine[:, :2]).T

    def pixel_centres(self) -> np.ndarray:
        """The centre of every pixel, (height, width, 2) as (u, v)."""
        u, v = np.meshgrid(np.arange(self.width, dtype=np.float64), np.arange(self.height, dtype=np.float64))
        return np.stack([u, v], axis=-1)

    def description(self) -> dict:
        """Plain numbers for a cache key."""
        return {"width": self.width, "height": self.height, "affine": self.affine.tolist(), "metric": self.metric}


@dataclass(frozen=True, eq=False)
class RemapTable:
    """One ``cv2.remap`` from a fisheye image to a floor image.

    ``map_x``, ``map_y`` (height, width) float32: the fisheye pixel (u, v) shown at each pixel centre of
    ``floor``, NaN where ``valid`` (bool) is False (the floor point is not seen). ``source_size``: the fisheye
    image's (width, height). ``key``: the hash of the calibration and parameters the table was built from.
    """

    map_x: np.ndarray
    map_y: np.ndarray
    valid: np.ndarray
    floor: FloorImage
    source_size: tuple[int, int]
    key: str

    @classmethod
    def from_points(cls, fisheye_uv: np.ndarray, valid: np.ndarray, floor: FloorImage, camera: CameraModel, key: str):
        """The table of fisheye pixels ``fisheye_uv`` (height, width, 2), valid where ``valid`` (height, width)."""
        uv = np.where(valid[..., None], fisheye_uv, np.nan).astype(np.float32)
        return cls(uv[..., 0].copy(), uv[..., 1].copy(), valid.copy(), floor, (camera.width, camera.height), key)

    @property
    def outside_fraction(self) -> float:
        """Fraction of the floor image's pixels that no fisheye pixel shows."""
        return float(1.0 - self.valid.mean())

    @functools.cached_property
    def remap_maps(self) -> tuple[np.ndarray, np.ndarray]:
        """float32 maps for ``cv2.remap``: valid pixels clamped onto the fisheye's pixel centres, masked ones
        far outside (so that they read only the border value)."""
        width, height = self.source_size
        remap_x = np.where(self.valid, np.clip(self.map_x, 0.0, width - 1.0), OUTSIDE).astype(np.float32)
        remap_y = np.where(self.valid, np.clip(self.map_y, 0.0, height - 1.0), OUTSIDE).astype(np.float32)
        return remap_x, remap_y

    @functools.cached_property
    def fixed_point(self) -> tuple[np.ndarray, np.ndarray]:
        """The maps in OpenCV's fixed-point form (``cv2.convertMaps`` to CV_16SC2: the integer pixel and a
        1/32-pixel interpolation index; 6 bytes a pixel instead of 8). Whether it remaps faster than the float
        maps depends on the OpenCV build: ``benchmarks/ground_speed.py`` times both."""
        return cv2.convertMaps(*self.remap_maps, cv2.CV_16SC2)

    def apply(self, fisheye_image: np.ndarray, fixed: bool = False, border_value: int = 0) -> np.ndarray:
        """The floor image of a fisheye frame (bilinear); pixels not seen are ``border_value``.

        ``fixed``: remap with the fixed-point maps (coordinates rounded to 1/32 pixel).
        """
        check_frame_size(fisheye_image, self.source_size)
        maps = self.fixed_point if fixed else self.remap_maps
        return cv2.remap(
            fisheye_image, *maps, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT, borderValue=border_value
        )


def table_key(description: dict) -> str:
    """The cache key of a table: a hash of everything it is built from (``description``: plain numbers)."""
    return gpo.io.cache.key({"format": TABLE_FORMAT, **description})


def cached_table(description: dict, floor: FloorImage, camera, build: Callable, keep: bool) -> RemapTable:
    """The table of ``description``: read from the disk cache (``gpo.io.cache``, ``tables``) when there, else
    ``build()`` -> (fisheye uv, valid) and, with ``keep``, kept there (on a full disk, used without being kept)."""
    key = table_key({**description, "floor": floor.description(), "camera": _camera_description(camera)})
    path = gpo.io.cache.path("tables", "table", key, ".npz")
    if keep and gpo.io.cache.intact(path):
        with np.load(path) as stored:
            return RemapTable(
                stored["map_x"], stored["map_y"], stored["valid"], floor, (camera.width, camera.height), key
            )
    table = RemapTable.from_points(*build(), floor, camera, key)
    if keep:
        arrays = {"map_x": table.map_x, "map_y": table.map_y, "valid": table.valid}
        gpo.io.cache.keep(path, lambda partial: np.savez(partial, **arrays))
    return table


def _camera_description(camera: CameraModel) -> dict:
    """The camera model's name and every parameter, for a cache key."""
    return {"model": type(camera).__name__, **dataclasses.asdict(camera)}


def as_points(values) -> np.ndarray:
    """``values`` as a float64 array of 2-D points (..., 2), else a GroundImageError."""
    points = np.asarray(values, dtype=np.float64)
    if points.ndim == 0 or points.shape[-1] != 2:
        raise GroundImageError(f"points must have shape (..., 2), got shape {points.shape}")
    return points


def as_mount(mount) -> CameraMount:
    """A CameraMount, or (height, pitch, roll) as ``CameraMount.forward`` above base_link's origin."""
    if isinstance(mount, CameraMount):
        return mount
    values = np.asarray(mount, dtype=np.float64)
    if values.shape != (3,) or not np.isfinite(values).all():
        raise GroundImageError(f"mount must be a CameraMount or (height m, pitch rad, roll rad), got {mount!r}")
    return CameraMount.forward(0.0, 0.0, *values.tolist())


def check_frame_size(image: np.ndarray, size: tuple[int, int]) -> None:
    """A GroundImageError unless ``image`` is a (height, width[, channels]) image of ``size`` = (width, height)."""
    image = np.asarray(image)
    if image.ndim not in (2, 3):
        raise GroundImageError(
            f"a fisheye image must be (height, width) or (height, width, channels), got {image.shape}"
        )
    if (image.shape[1], image.shape[0]) != tuple(size):
        raise GroundImageError(
            f"the fisheye image is {image.shape[1]} x {image.shape[0]} pixels but the calibration is for "
            f"{size[0]} x {size[1]} (width x height): use this camera's calibration, or images of the camera it "
            "calibrates"
        )


def positive_whole(name: str, value) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
        raise GroundImageError(f"{name} must be a whole number of pixels >= 1, got {value!r}")
    return int(value)


def check_extent(table: RemapTable, what: str, max_outside: float) -> None:
    """A GroundImageError when more than ``max_outside`` of ``table``'s floor image lies outside ``what``; it gives
    the fraction and a smaller extent that lies inside."""
    outside = table.outside_fraction
    if outside <= max_outside:
        return
    x_min, x_max, y_min, y_max = table.floor.extent
    message = f"{outside:.1%} of the floor image (x {x_min:.3f}..{x_max:.3f} m, y {y_min:.3f}..{y_max:.3f} m) lies "
    message += f"outside {what}: "
    rectangle = _valid_rectangle(table.valid)
    if rectangle is None:
        raise GroundImageError(message + "none of it is seen; move the extent to where the camera looks")
    top, bottom, left, right = rectangle  # less a pixel all round, so that rounding cannot bring in an unseen one
    (x_a, y_a), (x_b, y_b) = table.floor.pixel_to_base([[left + 0.5, top + 0.5], [right - 1.5, bottom - 1.5]])
    x_range, y_range = _inward(x_a, x_b), _inward(y_a, y_b)
    raise GroundImageError(
        message + f"choose a smaller extent, e.g. x_range=({x_range[0]:.4f}, {x_range[1]:.4f}), "
        f"y_range=({y_range[0]:.4f}, {y_range[1]:.4f}) m, or allow max_outside={math.ceil(outside * 100) / 100:.2f} "
        "(the pixels not seen are masked)"
    )


def _inward(a: float, b: float) -> tuple[float, float]:
    """The interval between ``a`` and ``b`` with its ends rounded inwards to 0.1 mm."""
    low, high = min(a, b), max(a, b)
    return math.ceil(low * 1e4) / 1e4, math.floor(high * 1e4) / 1e4


def _valid_rectangle(valid: np.ndarray) -> tuple[int, int, int, int] | None:
    """(top, bottom, left, right), the bounds of a rectangle of ``valid`` pixels: the image shrunk side by side,
    always dropping the border line with the largest share of invalid pixels; None when nothing is valid."""
    top, bottom, left, right = 0, valid.shape[0], 0, valid.shape[1]
    while top < bottom and left < right:
        window = valid[top:bottom, left:right]
        if window.all():
            return top, bottom, left, right
        misses = [(~window[0]).mean(), (~window[-1]).mean(), (~window[:, 0]).mean(), (~window[:, -1]).mean()]
        side = int(np.argmax(misses))
        top, bottom = top + (side == 0), bottom - (side == 1)
        left, right = left + (side == 2), right - (side == 3)
    return None
