"""The ground plane image (GPI, the first paper's Section 3.4, chapter 03): the cubemap's front face's floor
trapezoid warped by the homography of eq. 22, found from four corners of a chessboard lying on the floor, to a
rectangle; the bottom face cropped and concatenated below it (the paper's Fig. 9).

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

import functools
import math
from dataclasses import dataclass

import cv2
import numpy as np

from gpo.cameras import CameraModel
from gpo.cameras.mount import MountError, estimate_mount
from gpo.cameras.targets import Chessboard, FloorBoard
from gpo.floor_image.cubemap import Cubemap
from gpo.floor_image.image import (
    FloorImage,
    GroundImageError,
    RemapTable,
    as_points,
    cached_table,
    check_extent,
    check_frame_size,
    positive_whole,
)

SEAM_SAMPLES = 33  # points along the front face's bottom edge fitted to the GPI's seam row


MIN_CORNER_SPACING_PX = 5.0  # four corners closer than this cannot fix a homography


MIN_CORNER_ANGLE = math.radians(5.0)  # nor corners of a quadrilateral this flat


MAX_MAGNIFICATION = 20.0  # GPI rows per front-face pixel beyond which the GPI shows nothing new, only blur


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
        uv = as_points(uv)
        width, height = self.size
        with np.errstate(invalid="ignore"):
            inside = (uv[..., 0] >= -0.5) & (uv[..., 0] <= width - 0.5)
            inside &= (uv[..., 1] >= -0.5) & (uv[..., 1] <= height - 0.5)
            upper = inside & (uv[..., 1] < self.front_rows - 0.5)
        front = np.where(upper[..., None], apply_homography(np.linalg.inv(self.homography), uv), np.nan)
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
        return cached_table(description, self.floor, self.cubemap.camera, build, self.cache)

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
        table = cached_table(
            description, nominal, self.cubemap.camera, functools.partial(self.to_fisheye, gpi_uv), self.cache
        )
        check_extent(table, "the GPI (the front face's floor ahead, the bottom face's crop)", max_outside)
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

    ``gpo.cameras.mount.estimate_mount`` finds the board (``detect_corners``, sub-pixel) in the front face and puts its
    corners in the board's order; the four returned are the board frame's inner corners (1, 1), (nx-1, 1),
    (nx-1, ny-1), (1, ny-1) (for the board of ``FLOOR_BOARDS``: near-right, far-right, far-left, near-left).
    """
    check_frame_size(fisheye_image, (cubemap.camera.width, cubemap.camera.height))
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
    camera: CameraModel,
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
    (default ``gpo.floor_image.cubemap.default_face_size``). ``ahead_m``: how far beyond the front face's bottom edge
    the GPI reaches on the floor, metres. ``bottom_rows``: rows of the bottom face kept below (default: those the
    fisheye sees across the whole width). ``placement`` (board and where it lies in base_link with the robot at
    rest) gives the rectangle's proportions and the GPI's place on the robot.
    """
    cubemap = Cubemap(camera, face_size)
    if corners is None:
        corners = front_face_corners(fisheye_image, cubemap, placement)
    else:
        check_frame_size(fisheye_image, (camera.width, camera.height))
    face_corners = _checked_quadrilateral(corners, cubemap.face_size)
    board_xy = placement.corners_world()[outer_corner_indices(placement.board), :2]
    face_to_floor = fit_homography(face_corners, board_xy)
    rows = _bottom_rows(cubemap) if bottom_rows is None else positive_whole("bottom_rows", bottom_rows)
    floor = _gpi_floor(cubemap.face_size, face_to_floor, ahead_m, rows)
    homography = fit_homography(face_corners, floor.base_to_pixel(board_xy))  # eq. 22
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
    edge_floor = apply_homography(face_to_floor, np.column_stack([edge_u, np.full(SEAM_SAMPLES, face_size - 0.5)]))
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
    next_row = apply_homography(to_face, column + np.array([0.0, 1.0]))
    step = np.linalg.norm(next_row - apply_homography(to_face, column), axis=1)
    too_far = ~(step >= 1.0 / MAX_MAGNIFICATION)
    if too_far.any():
        allowed = math.floor((front_rows - 1 - rows[too_far].max()) * floor.metres_per_pixel * 100) / 100
        raise GroundImageError(
            f"ahead_m={ahead_m} m reaches floor the front face hardly resolves (one face pixel over more than "
            f"{MAX_MAGNIFICATION:.0f} GPI rows, or past the horizon): choose ahead_m <= {allowed:.2f}"
        )


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


def fit_homography(source: np.ndarray, target: np.ndarray) -> np.ndarray:
    """The homography (3, 3) taking points ``source`` (N, 2) to ``target`` (N, 2) (``cv2.findHomography``, least
    squares; exact for four, to 1e-4 px), scaled so that w > 0 at the points."""
    homography, _ = cv2.findHomography(np.asarray(source, np.float64), np.asarray(target, np.float64), 0)
    found = homography is not None and np.isfinite(homography).all()
    w = homography[2] @ np.append(np.mean(source, axis=0), 1.0) if found else 0.0
    if w == 0:
        raise GroundImageError("no homography fits these corners: they are degenerate (collinear or coincident)")
    return homography / np.sign(w)


def apply_homography(homography: np.ndarray, uv) -> np.ndarray:
    """``homography`` applied to points ``uv`` (..., 2); NaN where a point maps behind (w <= 0)."""
    uv = as_points(uv)
    mapped = uv @ homography[:, :2].T + homography[:, 2]
    with np.errstate(invalid="ignore", divide="ignore"):
        w = mapped[..., 2:]
        return np.where(w > 0, mapped[..., :2] / w, np.nan)
