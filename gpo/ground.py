"""Floor images from the fisheye: the ground plane image (GPI), its ortho-rectification, one remap table.

One module for the three stages and the table that composes them (about 900 lines): they share ``FloorImage``,
``RemapTable`` and its cache key, and the pipeline uses only the composed table; a module per stage would part the
stages from the one table they must agree with.

The first paper turns a fisheye frame into a top view of the floor in front of the robot in three stages
(chapters 02-04), each a fixed per-pixel map:

1. fisheye -> cubemap: the front and bottom faces (``gpo.cubemap``, the paper's eqs. 8-18);
2. cubemap -> **GPI** (chapter 03, ``ground_plane_image``): the front face's floor trapezoid warped by the
   homography of eq. 22, found from four corners of a chessboard lying on the floor, to a rectangle; the
   bottom face cropped and concatenated below it (the paper's Fig. 9);
3. GPI -> **ortho-GPI** (chapter 04, ``ortho_rectify``): a second homography, from the corners of a 2 x 4-square
   block of the chessboard to a metric rectangle, so that the image has a known metres per pixel and a known
   place on the robot's floor.

Because every stage is a fixed map, the chain collapses into **one table**: for each ortho-GPI pixel, the
fisheye pixel it shows (``RemapTable``: one ``cv2.remap`` per frame, one resampling instead of three).
The **analytic rectifier** (``analytic_table``) builds the same kind of table with no chessboard at all:
each floor point of the ortho-GPI is projected straight through the calibrated camera model from the
camera's mount (height, pitch, roll). ``route_difference`` measures how far the two routes disagree, and
``reproduce_table1`` measures the chessboard block in both images, as the paper's Table 1.

Frames and units
----------------
``base_link`` (REP-103/105): x forward, y left, z up, origin at the rear-axle centre on the floor z = 0;
lengths in metres, angles in radians. Pixels (u, v): u right, v down, the centre of the top-left pixel at
(0, 0), as ``gpo.camera`` and OpenCV. A floor image is a top view: image up is the robot's forward (+x) and
image right the robot's right (-y). ``FloorImage`` holds its size and the affine map between its pixels and
floor points (x, y) in base_link.

The GPI's homography (eq. 22)
-----------------------------
The front face is a pinhole camera, so front-face pixels and floor points are related by a homography::

    (22)  lambda (u_g, v_g, 1)^T = H_g (u_f, v_f, 1)^T

H_g is found (``cv2.findHomography`` of four points: an exact solve, to 1e-4 px) from the board's four outer inner
corners in the front face (u_f, v_f) and a rectangle of the board's true proportions in the GPI (u_g, v_g).
The paper leaves the rectangle's scale and place to the reader; here they are chosen so that the bottom face
can be concatenated below: the front face's bottom edge, which is the bottom face's top edge, is mapped as
nearly as possible (least squares over the edge) onto the GPI's seam row with each face column kept. The
GPI's upper part is then a top view at that scale, as exact as the four corners are (for the simulated T265
rig 0.2 mm on average, 1 mm at its far corners, which the four-corner homography reaches by extrapolation); the
bottom face, a pinhole looking nearly straight down, continues it only approximately: its scale and the seam's
match are right only as far as the camera is level (the simulated camera is pitched 6 degrees and rolled 1.5:
the two halves meet up to 5 pixels off, and the bottom rows are 3 mm off on average, 9 mm at worst). The plain
GPI is therefore only approximately metric (``FloorImage.metric`` is False) - the paper's point, which the
ortho-rectification answers on the front face's part.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Callable
from dataclasses import dataclass

import cv2
import numpy as np

import gpo.cache
from gpo.camera import EUCM, Pinhole
from gpo.cubemap import Cubemap
from gpo.mount import MountError, detect_corners, estimate_mount
from gpo.rig import CameraMount
from gpo.targets import Chessboard, FloorBoard

TABLE_FORMAT = 1  # bump when the tables' meaning changes, so that old cached files are not read
OUTSIDE = -16.0  # remap coordinate of a masked pixel: far enough outside that only the border value is read
SEAM_SAMPLES = 33  # points along the front face's bottom edge fitted to the GPI's seam row
MIN_CORNER_SPACING_PX = 5.0  # four corners closer than this cannot fix a homography
MIN_CORNER_ANGLE = math.radians(5.0)  # nor corners of a quadrilateral this flat
MAX_MAGNIFICATION = 20.0  # GPI rows per front-face pixel beyond which the GPI shows nothing new, only blur
BLOCK_SQUARES = (4, 2)  # the 2 x 4-square block of the paper's Table 1: 4 squares along the board's x, 2 along y
DEFAULT_BLOCK = (2, 2)  # its first inner corner (i, j): the centre block of the 8 x 6-square board


class GroundImageError(ValueError):
    """A floor image cannot be made from this input; the message says what to change."""


# --------------------------------------------------------------------------------------------------------------
# What a floor image is, and its table


# The default floor patch, where an odometry config leaves it unset (the shipped gpo/configs/sim_t265.yaml writes the
# same values): 0.20 x 0.20 m from 0.70 m ahead of the rear axle, base_link metres, at 1 mm per pixel. 1 mm pixels
# track better than 0.5 mm (a floor point's error per track 0.11 mm against 0.15 mm with a 21-pixel window: the
# window then spans twice the floor) and take a quarter of the time.
FLOOR_X_RANGE_M = (0.70, 0.90)
FLOOR_Y_RANGE_M = (-0.10, 0.10)
FLOOR_METRES_PER_PIXEL = 1e-3


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
        affine = [[0.0, -step, far - 0.5 * step], [-step, 0.0, left - 0.5 * step]]
        return cls(width, height, np.array(affine))

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
        return _as_points(uv) @ self.affine[:, :2].T + self.affine[:, 2]

    def base_to_pixel(self, xy) -> np.ndarray:
        """Pixels (..., 2) (u, v) of floor points ``xy`` (..., 2), metres in base_link."""
        return (_as_points(xy) - self.affine[:, 2]) @ np.linalg.inv(self.affine[:, :2]).T

    def pixel_centres(self) -> np.ndarray:
        """The centre of every pixel, (height, width, 2) as (u, v)."""
        u, v = np.meshgrid(np.arange(self.width, dtype=np.float64), np.arange(self.height, dtype=np.float64))
        return np.stack([u, v], axis=-1)

    def description(self) -> dict:
        """Plain numbers for a cache key."""
        return {"width": self.width, "height": self.height, "affine": self.affine.tolist(), "metric": self.metric}


DEFAULT_FLOOR_IMAGE = FloorImage.top_view(metres_per_pixel=0.5e-3)
"""The chapters' and tests' floor image: the default patch at twice the odometry's resolution, 0.5 mm per pixel
(400 x 400 pixels), a finer picture of the same floor."""


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
    def from_points(
        cls, fisheye_uv: np.ndarray, valid: np.ndarray, floor: FloorImage, camera: EUCM | Pinhole, key: str
    ):
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
        _check_image_size(fisheye_image, self.source_size)
        maps = self.fixed_point if fixed else self.remap_maps
        return cv2.remap(
            fisheye_image, *maps, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT, borderValue=border_value
        )


def table_key(description: dict) -> str:
    """The cache key of a table: a hash of everything it is built from (``description``: plain numbers)."""
    return gpo.cache.key({"format": TABLE_FORMAT, **description})


def _cached_table(description: dict, floor: FloorImage, camera, build: Callable, keep: bool) -> RemapTable:
    """The table of ``description``: read from the disk cache (``gpo.cache``, ``tables``) when there, else
    ``build()`` -> (fisheye uv, valid) and, with ``keep``, kept there."""
    key = table_key({**description, "floor": floor.description(), "camera": _camera_description(camera)})
    path = gpo.cache.path("tables", "table", key, ".npz")
    if keep and path.exists():
        with np.load(path) as stored:
            return RemapTable(
                stored["map_x"], stored["map_y"], stored["valid"], floor, (camera.width, camera.height), key
            )
    table = RemapTable.from_points(*build(), floor, camera, key)
    if keep:
        arrays = {"map_x": table.map_x, "map_y": table.map_y, "valid": table.valid}
        gpo.cache.write(path, lambda partial: np.savez(partial, **arrays))
    return table


def _camera_description(camera: EUCM | Pinhole) -> dict:
    """The camera model's name and every parameter, for a cache key."""
    return {"model": type(camera).__name__, **dataclasses.asdict(camera)}


# --------------------------------------------------------------------------------------------------------------
# Chapter 03: the ground plane image


@dataclass(frozen=True, eq=False)
class GroundPlaneImage:
    """The paper's GPI (chapter 03): the front face warped by ``homography`` (eq. 22), the bottom face below.

    ``cubemap``: the faces. ``homography`` (3, 3): front-face pixel -> GPI pixel. Rows [0, ``front_rows``) of the
    GPI show the warped front face; rows [front_rows, front_rows + ``bottom_rows``) the bottom face's top
    ``bottom_rows`` rows, column for column. ``floor``: where the GPI lies in base_link (approximately:
    ``metric`` False, see the module docstring). ``face_corners`` (4, 2): the front-face pixels of the board's
    outer inner corners the homography was found from. ``cache``: keep the table on disk.
    """

    cubemap: Cubemap
    homography: np.ndarray
    front_rows: int
    bottom_rows: int
    floor: FloorImage
    face_corners: np.ndarray
    cache: bool = True

    @property
    def size(self) -> tuple[int, int]:
        """(width, height) pixels."""
        return self.floor.width, self.floor.height

    def to_faces(self, uv) -> tuple[np.ndarray, np.ndarray]:
        """Front-face and bottom-face pixels (..., 2) of GPI pixels ``uv`` (..., 2); each NaN where the point
        is not on that face's part of the GPI (or outside the GPI)."""
        uv = _as_points(uv)
        width, height = self.size
        with np.errstate(invalid="ignore"):
            inside = (uv[..., 0] >= -0.5) & (uv[..., 0] <= width - 0.5)
            inside &= (uv[..., 1] >= -0.5) & (uv[..., 1] <= height - 0.5)
            upper = inside & (uv[..., 1] < self.front_rows - 0.5)
        front = np.where(upper[..., None], _apply_homography(np.linalg.inv(self.homography), uv), np.nan)
        bottom = np.where((inside & ~upper)[..., None], uv - [0.0, self.front_rows], np.nan)
        return front, bottom

    def to_fisheye(self, uv) -> tuple[np.ndarray, np.ndarray]:
        """Fisheye pixels (..., 2) shown at GPI pixels ``uv`` (..., 2), and their validity (...); NaN where not."""
        front, bottom = self.to_faces(uv)
        fisheye = np.full(front.shape, np.nan)
        valid = np.zeros(front.shape[:-1], dtype=bool)
        for name, face_uv in (("front", front), ("bottom", bottom)):
            part = np.isfinite(face_uv).all(axis=-1)  # only the face's part of the GPI: the rest cannot be seen
            fisheye[part], valid[part] = self.cubemap.face_to_fisheye(name, face_uv[part])  # NaN where not seen
        return fisheye, valid

    @functools.cached_property
    def table(self) -> RemapTable:
        """The GPI as one table from the fisheye (eqs. 13-18 and 22 composed)."""
        description = {
            "route": "gpi",
            "face_size": self.cubemap.face_size,
            "homography": self.homography.tolist(),
            "rows": [self.front_rows, self.bottom_rows],
        }
        build = functools.partial(self.to_fisheye, self.floor.pixel_centres())
        return _cached_table(description, self.floor, self.cubemap.camera, build, self.cache)

    def resampled(self, floor: FloorImage, max_outside: float = 0.0) -> RemapTable:
        """The GPI resampled onto the grid of ``floor`` **by the GPI's own placement**: each of its pixels shows the
        GPI at the point ``self.floor`` (approximate) says is that floor point. So the image has ``floor``'s size
        and scale, and is exactly as metric as the plain GPI (``metric`` False): what a method sees when it takes
        the GPI's scale and place for true. Raises ``GroundImageError`` beyond ``max_outside`` unseen."""
        nominal = FloorImage(floor.width, floor.height, floor.affine, metric=False)
        description = {
            "route": "gpi-resampled",
            "face_size": self.cubemap.face_size,
            "homography": self.homography.tolist(),
            "rows": [self.front_rows, self.bottom_rows],
            "gpi_floor": self.floor.description(),
        }
        gpi_uv = self.floor.base_to_pixel(nominal.pixel_to_base(nominal.pixel_centres()))
        table = _cached_table(
            description, nominal, self.cubemap.camera, functools.partial(self.to_fisheye, gpi_uv), self.cache
        )
        _check_extent(table, "the GPI (the front face's floor ahead, the bottom face's crop)", max_outside)
        return table

    def staged(self, fisheye_image: np.ndarray) -> np.ndarray:
        """The GPI the paper's way: the faces remapped from the fisheye, the front face warped by
        ``cv2.warpPerspective`` (eq. 22), the bottom face's crop stacked below; two resamplings."""
        front = self.cubemap.face_image(fisheye_image, "front")
        upper = cv2.warpPerspective(
            front, self.homography, (self.size[0], self.front_rows), flags=cv2.INTER_LINEAR, borderValue=0
        )
        bottom = self.cubemap.face_image(fisheye_image, "bottom")[: self.bottom_rows]
        return np.vstack([upper, bottom])


def front_face_corners(fisheye_image: np.ndarray, cubemap: Cubemap, placement: FloorBoard) -> np.ndarray:
    """The floor board's four outer inner corners (4, 2) in the cubemap's front face, pixels, found automatically.

    ``gpo.mount.estimate_mount`` finds the board (``detect_corners``, sub-pixel) in the front face and puts its
    corners in the board's order; the four returned are the board frame's inner corners (1, 1), (nx-1, 1),
    (nx-1, ny-1), (1, ny-1) (for the board of ``FLOOR_BOARDS``: near-right, far-right, far-left, near-left).
    """
    _check_image_size(fisheye_image, (cubemap.camera.width, cubemap.camera.height))
    front = cubemap.face_image(fisheye_image, "front")
    try:
        estimate = estimate_mount(front, cubemap.face("front").pinhole, placement.board, placement)
    except MountError as error:
        raise GroundImageError(
            f"{error} in the cubemap's front face: lay the board flat in front of the robot, wholly inside the "
            "front face (90 degrees around the optical axis), or pass its four outer inner corners by hand "
            "(corners=)"
        ) from error
    return estimate.corners_px[outer_corner_indices(placement.board)]


def ground_plane_image(
    fisheye_image: np.ndarray,
    camera: EUCM | Pinhole,
    placement: FloorBoard,
    corners=None,
    face_size: int | None = None,
    ahead_m: float = 0.30,
    bottom_rows: int | None = None,
    cache: bool = True,
) -> GroundPlaneImage:
    """The paper's GPI (chapter 03) from a fisheye frame of the floor board lying at ``placement``.

    ``corners`` (4, 2): the board's outer inner corners in the front face, pixels, in the order of
    ``front_face_corners``, to set them by hand; found automatically when None. ``face_size``: the cubemap's
    (default ``gpo.cubemap.default_face_size``). ``ahead_m``: how far beyond the front face's bottom edge the
    GPI reaches on the floor, metres. ``bottom_rows``: rows of the bottom face kept below (default: those the
    fisheye sees across the whole width). ``placement`` (board and where it lies in base_link with the robot at
    rest) gives the rectangle's proportions and the GPI's place on the robot.
    """
    cubemap = Cubemap(camera, face_size)
    if corners is None:
        corners = front_face_corners(fisheye_image, cubemap, placement)
    else:
        _check_image_size(fisheye_image, (camera.width, camera.height))
    face_corners = _checked_quadrilateral(corners, cubemap.face_size)
    board_xy = placement.corners_world()[outer_corner_indices(placement.board), :2]
    face_to_floor = _homography(face_corners, board_xy)
    rows = _bottom_rows(cubemap) if bottom_rows is None else _positive_whole("bottom_rows", bottom_rows)
    floor = _gpi_floor(cubemap.face_size, face_to_floor, ahead_m, rows)
    homography = _homography(face_corners, floor.base_to_pixel(board_xy))  # eq. 22
    front_rows = floor.height - rows
    _check_magnification(homography, floor, front_rows, ahead_m)
    return GroundPlaneImage(cubemap, homography, front_rows, rows, floor, face_corners, cache)


def outer_corner_indices(board: Chessboard) -> np.ndarray:
    """Indices into ``board.inner_corners()`` of its inner corners (1, 1), (nx-1, 1), (nx-1, ny-1), (1, ny-1)."""
    across, along = board.pattern_size
    return np.array([0, across - 1, across * along - 1, (along - 1) * across])


def _gpi_floor(face_size: int, face_to_floor: np.ndarray, ahead_m: float, bottom_rows: int) -> FloorImage:
    """The GPI's place on the floor: the similarity (scale, turn, shift; image up = forward) that puts the front
    face's bottom edge, column for column, as nearly as possible onto the GPI's seam row (least squares)."""
    if not (math.isfinite(ahead_m) and ahead_m > 0):
        raise GroundImageError(f"ahead_m must be a positive distance in metres, got {ahead_m!r}")
    edge_u = np.linspace(-0.5, face_size - 0.5, SEAM_SAMPLES)
    edge_floor = _apply_homography(face_to_floor, np.column_stack([edge_u, np.full(SEAM_SAMPLES, face_size - 0.5)]))
    if not np.isfinite(edge_floor).all():
        raise GroundImageError(
            "the corners put the front face's bottom edge beyond the horizon: they are not four floor-board corners "
            "in the front face"
        )
    # (u, v) = [[a, -b], [b, a]] (-y, -x) + (t_u, t_v): image right = -y, image up = +x
    q = -edge_floor[:, ::-1]
    design = np.zeros((2 * SEAM_SAMPLES, 4))
    design[0::2] = np.column_stack([q[:, 0], -q[:, 1], np.ones(SEAM_SAMPLES), np.zeros(SEAM_SAMPLES)])
    design[1::2] = np.column_stack([q[:, 1], q[:, 0], np.zeros(SEAM_SAMPLES), np.ones(SEAM_SAMPLES)])
    target = np.column_stack([edge_u, np.zeros(SEAM_SAMPLES)]).ravel()
    a, b, t_u, t_v = np.linalg.lstsq(design, target, rcond=None)[0]
    front_rows = math.ceil(ahead_m * math.hypot(a, b))
    to_pixel = np.array([[a, -b], [b, a]]) @ np.array([[0.0, -1.0], [-1.0, 0.0]])
    shift = np.array([t_u, t_v + front_rows - 0.5])
    to_base = np.linalg.inv(to_pixel)
    return FloorImage(face_size, front_rows + bottom_rows, np.column_stack([to_base, -to_base @ shift]), metric=False)


def _bottom_rows(cubemap: Cubemap) -> int:
    """The bottom face's top rows that the fisheye sees across the whole width."""
    seen = cubemap.maps("bottom").valid.all(axis=1)
    return int(np.argmin(seen)) if not seen.all() else cubemap.face_size


def _check_magnification(homography: np.ndarray, floor: FloorImage, front_rows: int, ahead_m: float) -> None:
    """A GroundImageError when the GPI reaches floor that the front face sees only as a sliver: where, along the
    GPI's middle column, a GPI row moves less than 1 / ``MAX_MAGNIFICATION`` face pixel (or lies past the horizon)."""
    rows = np.arange(front_rows, dtype=np.float64)
    column = np.column_stack([np.full(front_rows, (floor.width - 1) / 2.0), rows])
    to_face = np.linalg.inv(homography)
    next_row = _apply_homography(to_face, column + np.array([0.0, 1.0]))
    step = np.linalg.norm(next_row - _apply_homography(to_face, column), axis=1)
    too_far = ~(step >= 1.0 / MAX_MAGNIFICATION)
    if too_far.any():
        allowed = math.floor((front_rows - 1 - rows[too_far].max()) * floor.metres_per_pixel * 100) / 100
        raise GroundImageError(
            f"ahead_m={ahead_m} m reaches floor the front face hardly resolves (one face pixel over more than "
            f"{MAX_MAGNIFICATION:.0f} GPI rows, or past the horizon): choose ahead_m <= {allowed:.2f}"
        )


# --------------------------------------------------------------------------------------------------------------
# Chapter 04: the ortho-rectified GPI, and the composed table


@dataclass(frozen=True, eq=False)
class OrthoRectification:
    """The ortho-rectified GPI (chapter 04): the GPI warped by a second homography onto a metric top view.

    ``homography`` (3, 3): GPI pixel -> ortho-GPI pixel, found from the corners of a 2 x 4-square block of the
    floor board (``block_gpi_px`` (15, 2), their GPI pixels). ``floor``: the ortho-GPI, metric and placed in
    base_link. ``table`` composes fisheye -> faces -> GPI -> ortho-GPI into one remap. ``cache``: keep it on disk.
    """

    gpi: GroundPlaneImage
    homography: np.ndarray
    floor: FloorImage
    block_gpi_px: np.ndarray
    cache: bool = True

    def to_gpi(self, uv) -> np.ndarray:
        """GPI pixels (..., 2) of ortho-GPI pixels ``uv`` (..., 2)."""
        return _apply_homography(np.linalg.inv(self.homography), uv)

    def to_fisheye(self, uv) -> tuple[np.ndarray, np.ndarray]:
        """Fisheye pixels (..., 2) shown at ortho-GPI pixels ``uv`` (..., 2) and their validity: the stages'
        point maps chained (ortho-GPI -> GPI -> face -> fisheye)."""
        return self.gpi.to_fisheye(self.to_gpi(uv))

    def through_bottom_face(self) -> np.ndarray:
        """(height, width) True where an ortho-GPI pixel is seen through the GPI's bottom-face rows, where the
        GPI, and so the ortho-GPI, is only approximately metric."""
        return np.isfinite(self.gpi.to_faces(self.to_gpi(self.floor.pixel_centres()))[1][..., 0])

    @functools.cached_property
    def table(self) -> RemapTable:
        """The one table: for each ortho-GPI pixel centre, the fisheye pixel it shows."""
        description = {
            "route": "ortho-gpi",
            "face_size": self.gpi.cubemap.face_size,
            "gpi_homography": self.gpi.homography.tolist(),
            "rows": [self.gpi.front_rows, self.gpi.bottom_rows],
            "homography": self.homography.tolist(),
        }
        build = functools.partial(self.to_fisheye, self.floor.pixel_centres())
        return _cached_table(description, self.floor, self.gpi.cubemap.camera, build, self.cache)

    def staged(self, fisheye_image: np.ndarray) -> np.ndarray:
        """The ortho-GPI the paper's way: the staged GPI warped by ``cv2.warpPerspective``; three resamplings."""
        return cv2.warpPerspective(
            self.gpi.staged(fisheye_image),
            self.homography,
            (self.floor.width, self.floor.height),
            flags=cv2.INTER_LINEAR,
            borderValue=0,
        )


def ortho_rectify(
    gpi: GroundPlaneImage,
    gpi_image: np.ndarray,
    placement: FloorBoard,
    floor: FloorImage = DEFAULT_FLOOR_IMAGE,
    block: tuple[int, int] = DEFAULT_BLOCK,
    max_outside: float = 0.0,
    corners: np.ndarray | None = None,
) -> OrthoRectification:
    """The ortho-rectified GPI (chapter 04) for the metric ``floor`` image.

    The board is found in ``gpi_image`` (the GPI of a frame of the board lying at ``placement``), and the
    homography GPI -> ortho-GPI fitted (``cv2.findHomography``, least squares) from the 3 x 5 inner corners of
    its 2 x 4-square block starting at inner corner ``block`` = (i, j) to where the block truly lies in
    ``floor`` (40 x 80 mm for 20 mm squares). ``corners``: the board's inner corners (N, 2) GPI pixels when
    already found in ``gpi_image`` (``board_corners``), e.g. to try several floor images without searching again.
    Raises ``GroundImageError`` when more than ``max_outside`` of ``floor`` lies outside what the GPI shows, with
    an extent that fits. The table is kept on disk when the GPI's is (``gpi.cache``).
    """
    index = block_corner_indices(placement.board, block)
    found = (board_corners(gpi_image, gpi.floor, placement) if corners is None else np.asarray(corners))[index]
    truth = floor.base_to_pixel(placement.corners_world()[index, :2])
    rectification = OrthoRectification(gpi, _homography(found, truth), floor, found, gpi.cache)
    _check_extent(rectification.table, "the GPI (the front face's floor ahead, the bottom face's crop)", max_outside)
    return rectification


def chessboard_route(
    fisheye_image: np.ndarray,
    camera: EUCM | Pinhole,
    placement: FloorBoard,
    floor: FloorImage = DEFAULT_FLOOR_IMAGE,
    max_outside: float = 0.0,
    cache: bool = True,
) -> OrthoRectification:
    """GPI and ortho-GPI from one fisheye frame of the floor board at ``placement``, with default parameters.

    The GPI image in which the block is found is made with the GPI's own table (one resampling).
    """
    gpi = ground_plane_image(fisheye_image, camera, placement, cache=cache)
    return ortho_rectify(gpi, gpi.table.apply(fisheye_image), placement, floor, max_outside=max_outside)


def block_corner_indices(board: Chessboard, block: tuple[int, int] = DEFAULT_BLOCK) -> np.ndarray:
    """Indices into ``board.inner_corners()`` of the 3 x 5 corners of the 2 x 4-square block whose first inner
    corner is ``block`` = (i, j) (``BLOCK_SQUARES``: 4 squares along the board's x, 2 along its y), row by row."""
    i0, j0 = block
    across, along = board.pattern_size
    di, dj = BLOCK_SQUARES
    if not (1 <= i0 <= across - di and 1 <= j0 <= along - dj):
        raise GroundImageError(
            f"block {block}: a {di} x {dj}-square block from inner corner (i, j) must have 1 <= i <= {across - di} "
            f"and 1 <= j <= {along - dj} on a board of {board.squares[0]} x {board.squares[1]} squares"
        )
    i, j = np.meshgrid(np.arange(i0, i0 + di + 1), np.arange(j0, j0 + dj + 1))
    return ((j - 1) * across + (i - 1)).ravel()


def board_corners(image: np.ndarray, floor: FloorImage, placement: FloorBoard) -> np.ndarray:
    """The board's inner corners (N, 2) in a floor image (GPI or ortho-GPI), pixels, in the board's order.

    Found by ``gpo.mount.detect_corners`` (sub-pixel) on the image; each is matched to where ``floor`` puts the
    board lying at ``placement``, within half a square.
    """
    height, width = image.shape[:2]
    if (width, height) != (floor.width, floor.height):
        raise GroundImageError(
            f"the floor image is {width} x {height} pixels but its description is {floor.width} x {floor.height}"
        )
    board = placement.board
    # detect_corners checks an image against a camera's size; a floor image has none, so a stand-in of its size
    frame = Pinhole(1.0, 1.0, 0.0, 0.0, (0.0, 0.0, 0.0, 0.0), width, height)
    try:
        found = detect_corners(image, frame, board, rectify=False)
    except MountError as error:
        raise GroundImageError(
            f"{error}: the whole board, with its white margin, must lie inside the floor image; choose a larger "
            "extent or move the board"
        ) from error
    expected = floor.base_to_pixel(placement.corners_world()[:, :2])
    distance = np.linalg.norm(expected[:, None, :] - found[None, :, :], axis=-1)
    nearest = np.argmin(distance, axis=1)
    tolerance = 0.5 * board.square / floor.metres_per_pixel
    if len(set(nearest.tolist())) != len(nearest) or distance.min(axis=1).max() > tolerance:
        raise GroundImageError(
            "the board found in the floor image does not lie where its placement puts it (off by "
            f"{distance.min(axis=1).max():.1f} px, more than half a square): check the placement and the calibration"
        )
    return found[nearest]


# --------------------------------------------------------------------------------------------------------------
# The analytic rectifier, and how far the routes differ


def analytic_points(
    camera: EUCM | Pinhole, mount: CameraMount | tuple[float, float, float], floor: FloorImage
) -> tuple[np.ndarray, np.ndarray]:
    """Fisheye pixels (height, width, 2) of every pixel centre of ``floor``, and their validity (height, width).

    Each floor point (x, y, 0) of base_link is turned into the camera's optical frame by ``mount`` (the optical
    frame's pose in base_link) and projected by ``camera.project``; valid where the projection is and the pixel
    lies in the image. ``mount`` may be (height m, pitch rad, roll rad): ``CameraMount.forward`` above
    base_link's origin (the floor image is then placed relative to the point below the camera).
    """
    mount = _as_mount(mount)
    xy = floor.pixel_to_base(floor.pixel_centres())
    uv, valid = camera.project(mount.to_camera(np.concatenate([xy, np.zeros((*xy.shape[:-1], 1))], axis=-1)))
    valid &= camera.in_image(uv)
    uv[~valid] = np.nan
    return uv, valid


def pixels_to_floor(
    camera: EUCM | Pinhole, mount: CameraMount | tuple[float, float, float], uv
) -> tuple[np.ndarray, np.ndarray]:
    """The floor points (..., 2) of base_link, metres, seen at camera pixels ``uv`` (..., 2), and their validity.

    The inverse of ``analytic_points`` for single points, and the second paper's keypoint correction (its §3.2):
    ``camera.unproject`` removes the lens distortion, ``mount`` (the optical frame's pose in base_link, e.g. from
    ``gpo.mount.estimate_mount`` on a chessboard lying on the floor) turns each ray so that the floor is level, and
    the ray meets the floor z = 0 at the mount's height. Invalid where the pixel does not unproject or its ray does
    not point down to the floor.
    """
    mount = _as_mount(mount)
    rays, valid = camera.unproject(_as_points(uv))
    down = mount.rotation.apply(rays.reshape(-1, 3)).reshape(rays.shape)
    with np.errstate(invalid="ignore", divide="ignore"):
        reach = -mount.position[2] / down[..., 2]
    valid &= np.isfinite(reach) & (reach > 0)
    xy = mount.position[:2] + reach[..., None] * down[..., :2]
    xy[~valid] = np.nan
    return xy, valid


def analytic_table(
    camera: EUCM | Pinhole,
    mount: CameraMount | tuple[float, float, float],
    floor: FloorImage = DEFAULT_FLOOR_IMAGE,
    max_outside: float = 0.0,
    cache: bool = True,
) -> RemapTable:
    """The floor image's table from the calibration and the mount alone (``analytic_points``), no chessboard.

    Raises ``GroundImageError`` when more than ``max_outside`` of ``floor`` lies outside the lens's view.
    """
    mount = _as_mount(mount)
    description = {
        "route": "analytic",
        "position": mount.position.tolist(),
        "rotation_xyzw": mount.rotation.as_quat().tolist(),
    }
    build = functools.partial(analytic_points, camera, mount, floor)
    table = _cached_table(description, floor, camera, build, cache)
    _check_extent(table, "the fisheye's image", max_outside)
    return table


@dataclass(frozen=True, eq=False)
class RouteDifference:
    """How far two tables of the same floor image disagree, over the pixels both see.

    ``pixels_px`` (height, width): the distance between their fisheye pixels; ``floor_mm``: the same difference
    as a distance on the floor, millimetres (through the reference table's local scale); NaN where not both
    valid. ``common_fraction``: the share of the floor image both see (less a rim where the reference's local
    scale cannot be differenced).
    """

    pixels_px: np.ndarray
    floor_mm: np.ndarray
    common_fraction: float

    @property
    def mean_px(self) -> float:
        return float(np.nanmean(self.pixels_px))

    @property
    def max_px(self) -> float:
        return float(np.nanmax(self.pixels_px))

    @property
    def mean_mm(self) -> float:
        return float(np.nanmean(self.floor_mm))

    @property
    def max_mm(self) -> float:
        return float(np.nanmax(self.floor_mm))


def route_difference(table: RemapTable, reference: RemapTable) -> RouteDifference:
    """How far ``table`` (e.g. the chessboard route's) lies from ``reference`` (e.g. the analytic route's).

    The fisheye-pixel difference at each floor-image pixel, and the floor distance it amounts to:
    d_floor = J^-1 d_fisheye, with J the reference's fisheye pixels per floor-image pixel (finite differences),
    times the metres per pixel.
    """
    if table.floor.description() != reference.floor.description() or table.source_size != reference.source_size:
        raise GroundImageError("the two tables describe different floor images or fisheye sizes: build both for one")
    difference = np.stack([table.map_x - reference.map_x, table.map_y - reference.map_y], axis=-1).astype(np.float64)
    reference_uv = np.stack([reference.map_x, reference.map_y], axis=-1).astype(np.float64)
    jacobian = np.stack([np.gradient(reference_uv, axis=1), np.gradient(reference_uv, axis=0)], axis=-1)
    common = table.valid & reference.valid & np.isfinite(jacobian).all(axis=(-2, -1))
    (a, b), (c, d) = np.moveaxis(jacobian[common], (-2, -1), (0, 1))
    du, dv = difference[common].T
    shift = np.full(difference.shape, np.nan)  # J^-1 d by Cramer's rule: numpy's batched solve is slower on 2 x 2
    shift[common] = np.column_stack([d * du - b * dv, a * dv - c * du]) / (a * d - b * c)[:, None]
    pixels = np.where(common, np.linalg.norm(difference, axis=-1), np.nan)
    floor_mm = np.linalg.norm(shift, axis=-1) * table.floor.metres_per_pixel * 1e3
    return RouteDifference(pixels, floor_mm, float(common.mean()))


# --------------------------------------------------------------------------------------------------------------
# Measuring a block of the board in a floor image (the paper's Table 1)


@dataclass(frozen=True)
class BlockMeasurement:
    """The four sides (a, b, c, d) metres and the area m^2 of a 2 x 4-square block measured in a floor image.

    a and c are the long sides (4 squares), b and d the short ones (2 squares), in turn around the block: the
    paper's labels (its Fig. 11 and Table 1, where (a + c) / 2 is 4 x 20.007 mm).
    """

    sides_m: tuple[float, float, float, float]
    area_m2: float

    @property
    def long_m(self) -> float:
        """(a + c) / 2, metres."""
        return 0.5 * (self.sides_m[0] + self.sides_m[2])

    @property
    def short_m(self) -> float:
        """(b + d) / 2, metres."""
        return 0.5 * (self.sides_m[1] + self.sides_m[3])


def measure_block(
    image: np.ndarray, floor: FloorImage, placement: FloorBoard, block: tuple[int, int] = DEFAULT_BLOCK
) -> BlockMeasurement:
    """The block from inner corner ``block`` of the board lying at ``placement``, measured in ``image``.

    Its four outer corners by ``board_corners`` (sub-pixel), lengths through ``floor``'s pixel -> floor map (for
    the plain GPI its nominal scale), the area by the shoelace formula.
    """
    grid = block_corner_indices(placement.board, block).reshape(BLOCK_SQUARES[1] + 1, BLOCK_SQUARES[0] + 1)
    outline = [grid[0, 0], grid[0, -1], grid[-1, -1], grid[-1, 0]]  # a long side first, then round the block
    corners = floor.pixel_to_base(board_corners(image, floor, placement)[outline])
    sides = np.linalg.norm(np.roll(corners, -1, axis=0) - corners, axis=1)
    x, y = corners[:, 0], corners[:, 1]
    area = 0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))
    return BlockMeasurement(tuple(sides.tolist()), float(area))


# --------------------------------------------------------------------------------------------------------------
# Helpers


def _as_points(values) -> np.ndarray:
    """``values`` as a float64 array of 2-D points (..., 2), else a GroundImageError."""
    points = np.asarray(values, dtype=np.float64)
    if points.ndim == 0 or points.shape[-1] != 2:
        raise GroundImageError(f"points must have shape (..., 2), got shape {points.shape}")
    return points


def _as_mount(mount) -> CameraMount:
    """A CameraMount, or (height, pitch, roll) as ``CameraMount.forward`` above base_link's origin."""
    if isinstance(mount, CameraMount):
        return mount
    values = np.asarray(mount, dtype=np.float64)
    if values.shape != (3,) or not np.isfinite(values).all():
        raise GroundImageError(f"mount must be a CameraMount or (height m, pitch rad, roll rad), got {mount!r}")
    return CameraMount.forward(0.0, 0.0, *values.tolist())


def _check_image_size(image: np.ndarray, size: tuple[int, int]) -> None:
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


def _positive_whole(name: str, value) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
        raise GroundImageError(f"{name} must be a whole number of pixels >= 1, got {value!r}")
    return int(value)


def _checked_quadrilateral(corners, face_size: int) -> np.ndarray:
    """``corners`` (4, 2) after checking they can fix a homography: inside the face, apart, a convex quadrilateral
    without flat angles."""
    corners = np.asarray(corners, dtype=np.float64)
    if corners.shape != (4, 2) or not np.isfinite(corners).all():
        raise GroundImageError(f"corners must be four finite (u, v) pixels, shape (4, 2), got {corners.shape}")
    if not np.all((corners >= -0.5) & (corners <= face_size - 0.5)):
        raise GroundImageError(
            f"corners must lie inside the {face_size} x {face_size} front face, got {corners.tolist()}"
        )
    gaps = np.linalg.norm(corners[:, None] - corners[None], axis=-1)[np.triu_indices(4, 1)]
    if gaps.min() < MIN_CORNER_SPACING_PX:
        raise GroundImageError(
            f"two corners are only {gaps.min():.1f} px apart: pick four corners that span the board, at least "
            f"{MIN_CORNER_SPACING_PX:.0f} px apart"
        )
    to_next = np.roll(corners, -1, axis=0) - corners
    to_previous = np.roll(corners, 1, axis=0) - corners
    cross = to_next[:, 0] * to_previous[:, 1] - to_next[:, 1] * to_previous[:, 0]
    sines = cross / (np.linalg.norm(to_next, axis=1) * np.linalg.norm(to_previous, axis=1))
    if not (np.all(sines > math.sin(MIN_CORNER_ANGLE)) or np.all(sines < -math.sin(MIN_CORNER_ANGLE))):
        raise GroundImageError(
            "the four corners do not make a convex quadrilateral (three are nearly on a line, or they are not "
            "in turn round the board): pick them in the order near-right, far-right, far-left, near-left"
        )
    return corners


def _homography(source: np.ndarray, target: np.ndarray) -> np.ndarray:
    """The homography (3, 3) taking points ``source`` (N, 2) to ``target`` (N, 2) (``cv2.findHomography``, least
    squares; exact for four, to 1e-4 px), scaled so that w > 0 at the points."""
    homography, _ = cv2.findHomography(np.asarray(source, np.float64), np.asarray(target, np.float64), 0)
    found = homography is not None and np.isfinite(homography).all()
    w = homography[2] @ np.append(np.mean(source, axis=0), 1.0) if found else 0.0
    if w == 0:
        raise GroundImageError("no homography fits these corners: they are degenerate (collinear or coincident)")
    return homography / np.sign(w)


def _apply_homography(homography: np.ndarray, uv) -> np.ndarray:
    """``homography`` applied to points ``uv`` (..., 2); NaN where a point maps behind (w <= 0)."""
    uv = _as_points(uv)
    mapped = uv @ homography[:, :2].T + homography[:, 2]
    with np.errstate(invalid="ignore", divide="ignore"):
        w = mapped[..., 2:]
        return np.where(w > 0, mapped[..., :2] / w, np.nan)


def _check_extent(table: RemapTable, what: str, max_outside: float) -> None:
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
