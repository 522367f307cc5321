"""Finding a chessboard's inner corners in an image of any camera model: gpo's one chessboard detector.

Calibration (``gpo.cameras.calibrate``) fits a camera model to the corners found here and the mount
(``gpo.cameras.mount``) a board's pose on the floor; neither looks for a board itself, and this module fits nothing.
It also holds what the pattern size means (``parse_board``) and the check that corners form the board's grid.

Frames and units
----------------
Pixels are (u, v), u to the right and v down, (0, 0) the centre of the top-left pixel, as in OpenCV. The camera
optical frame: x right, y down, z forward. A perspective view is a virtual distortion-free pinhole camera at the
camera's optical centre, turned by a rotation camera <- view; its image is square, its principal point at the image's
centre and its focal length in the view's pixels. Angles are in radians.

The pattern size is counted in inner corners, where four squares meet, as OpenCV counts it: (corners per row,
corners per column), which is Kalibr's (targetCols, targetRows). A board of 8 x 6 squares has 7 x 5 inner corners;
5 x 7 finds it as well (the grid turned a quarter turn).

Where the board is looked for
-----------------------------
OpenCV's sector-based detector (``cv2.findChessboardCornersSB``) runs on the image first. On a fisheye's periphery
the board's rows bend too much for it; given a model of the camera (a rough one will do, such as
``gpo.cameras.calibrate.initial_eucm``), the board is then looked for in perspective views (``PerspectiveView``),
where its rows are straight again: 90 degrees wide, along the rays of a 3 x 3 grid of image pixels, centre first,
each with its x axis square to the camera's y axis, so that image rows stay rows. There the sector detector runs
with its accuracy flag, and the corners go back to the image through the view's exact mapping: view pixel -> ray ->
turned into the camera frame -> ``camera.project``. A view whose corners do not all map back is passed over.

Two searches
------------
The views and the corner order are the same for every caller; a ``Search`` says only how hard the detector looks in
the image itself and where the corners' sub-pixel precision comes from:

- ``CALIBRATION``: every view counts and the fit rests on every corner, so the sector detector searches exhaustively
  on the normalised image with its accuracy flag, the classic detector (``cv2.findChessboardCorners``) follows where
  it misses, and ``cv2.cornerSubPix`` then refines every corner on the image's own pixels (a window 0.4 times the
  closest corner spacing, 2 to 10 px half-size), which also measures a corner found in a view on the image rather
  than on the view's interpolation.
- ``MOUNT``: the sector detector's own sub-pixel corners (its accuracy flag), without exhaustive search or
  refinement. The mount searches each image up to four times (its board, the board one row or one column larger,
  a second board), and its chapters are measured with these corners: the calibration's search would move them
  (by 0.6 px, the largest shift in the median simulated floor image).

Corner order
------------
Corners are returned ordered like ``gpo.cameras.targets.Chessboard.inner_corners()``: row by row along the board's
x axis, and handed so that the board's z axis faces the camera (OpenCV's detectors return the mirror image of that
order, with z pointing away). A board is symmetric under a half turn when its squares are even x even (the default
8 x 6), and also under a quarter turn when it is square: the image cannot tell such turns apart. Where the colours
can tell, corner 0 is the one at the black square that touches the board's origin; where they cannot, corner 0 is
chosen so that the first row points as far to the right of the image as possible. Every image follows this one rule.
"""

from __future__ import annotations

import hashlib
import threading
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass

import cv2
import numpy as np
from scipy.spatial.transform import Rotation

from gpo.cameras.base import CameraModel


@dataclass(frozen=True)
class Search:
    """How the detector looks in the camera's image (the module docstring says why each caller uses its own).

    ``flags``: ``cv2.findChessboardCornersSB``'s flags on the image. ``classic``: whether the classic
    ``cv2.findChessboardCorners`` runs where that misses. ``refine``: whether ``cv2.cornerSubPix`` refines the
    corners on the image's pixels afterwards.
    """

    flags: int
    classic: bool
    refine: bool


CALIBRATION = Search(
    cv2.CALIB_CB_NORMALIZE_IMAGE | cv2.CALIB_CB_EXHAUSTIVE | cv2.CALIB_CB_ACCURACY, classic=True, refine=True
)
MOUNT = Search(cv2.CALIB_CB_ACCURACY, classic=False, refine=False)
CLASSIC_FLAGS = cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE
VIEW_FLAGS = cv2.CALIB_CB_ACCURACY  # the sector detector in a perspective view: sub-pixel, mapped back exactly
VIEW_FIELD_OF_VIEW = np.radians(90.0)
SUBPIX_CRITERIA = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_COUNT, 50, 1e-3)
GRID_TOLERANCE = 2.0  # see forms_grid
REMEMBERED = 512
"""How many of the detector's answers one process keeps (``_remembered``)."""
_ANSWERS: OrderedDict[tuple, np.ndarray | None] = OrderedDict()
_ANSWERS_LOCK = threading.Lock()


def find_corners(
    image: np.ndarray,
    pattern_size: tuple[int, int],
    camera: CameraModel | None = None,
    search: Search = CALIBRATION,
    rectify: bool | None = None,
) -> np.ndarray | None:
    """The inner corners of a chessboard of ``pattern_size`` in ``image``, (N, 2) pixels in board order, or None.

    ``image``: 8-bit, grey or BGR. ``camera``: a model of the camera that took it, of its size, for the perspective
    views. ``rectify`` None: on the image, then, if the board is not found there and a camera is given, in the
    perspective views; True: in the views only; False: on the image only. ``search``: ``CALIBRATION`` or ``MOUNT``
    (see the module docstring). Raises ``ValueError`` for an image that is not 8-bit or not of the camera's size.
    """
    grey = _checked_grey(image, camera)
    if rectify and camera is None:
        raise ValueError("the perspective views (rectify=True) need a camera model")
    pattern_size = tuple(pattern_size)
    corners = None
    if rectify is not True:
        corners = _remembered(
            grey, ("picture", pattern_size, search), lambda: _find_in_picture(grey, pattern_size, search)
        )
    if corners is None and rectify is not False and camera is not None:
        corners = _remembered(grey, ("views", pattern_size, camera), lambda: _find_in_views(grey, pattern_size, camera))
    if corners is None:
        return None
    if search.refine:
        corners = _refine(grey, corners, pattern_size)
    return _order_like_board(grey, corners, pattern_size)


@dataclass(frozen=True, eq=False)
class PerspectiveView:
    """A distortion-free pinhole view of ``camera``: a virtual camera at its optical centre, turned by ``rotation``
    (camera <- view), with a square image of ``size`` pixels, its principal point at the image's centre and a focal
    length of ``focal`` view pixels. ``rays`` is its one mapping: ``render`` samples the camera's image through it and
    ``to_camera_image`` takes points found in the view back through it."""

    camera: CameraModel
    rotation: Rotation
    focal: float
    size: int

    @classmethod
    def along(cls, camera: CameraModel, axis, field_of_view: float = VIEW_FIELD_OF_VIEW) -> PerspectiveView:
        """The view looking along ``axis`` (3,) of the camera frame, ``field_of_view`` radians wide, with its x axis
        square to the camera's y axis (``view_rotation``); its focal length is the camera's mean one, or less where
        that would make the view wider than the camera's image."""
        half_width = np.tan(field_of_view / 2.0)
        focal = min(0.5 * (camera.fx + camera.fy), max(camera.width, camera.height) / (2.0 * half_width))
        return cls(camera, view_rotation(axis), focal, round(2.0 * focal * half_width))

    def rays(self, pixels) -> np.ndarray:
        """Rays (..., 3) in the camera frame, not normalised, of view ``pixels`` (..., 2)."""
        pixels = np.asarray(pixels, dtype=float)
        centre = (self.size - 1) / 2.0
        in_view = np.concatenate([(pixels - centre) / self.focal, np.ones((*pixels.shape[:-1], 1))], axis=-1)
        return self.rotation.apply(in_view.reshape(-1, 3)).reshape(in_view.shape)

    def to_camera_image(self, pixels) -> tuple[np.ndarray, np.ndarray]:
        """View ``pixels`` (..., 2) as pixels (..., 2) of the camera's image, and whether each has one (...)."""
        return self.camera.project(self.rays(pixels))

    def render(self, image: np.ndarray) -> np.ndarray:
        """The view (``size`` x ``size``) of the camera's ``image``: each pixel sampled bilinearly where its ray
        projects; a pixel whose ray does not project, or projects outside the image, repeats the image's edge."""
        pixels = np.stack(np.meshgrid(np.arange(self.size), np.arange(self.size)), axis=-1)
        source, _ = self.to_camera_image(pixels)
        maps = np.nan_to_num(source, nan=-1.0).astype(np.float32)
        return cv2.remap(image, maps[..., 0], maps[..., 1], cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)


def view_rotation(axis) -> Rotation:
    """camera <- view for a view whose optical axis is ``axis`` (3,) and whose x axis is square to the camera's y
    (to its x when ``axis`` is nearly the camera's y)."""
    z = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    x = np.cross([0.0, 1.0, 0.0] if abs(z[1]) < 0.9 else [1.0, 0.0, 0.0], z)
    x /= np.linalg.norm(x)
    return Rotation.from_matrix(np.column_stack([x, np.cross(z, x), z]))


def planar_pose(rays: np.ndarray, points: np.ndarray) -> tuple[Rotation, np.ndarray] | None:
    """camera <- board from unit rays (N, 3) to the board's ``points`` (N, 3, metres, on its plane z = 0), or None.

    The rays are turned into a virtual pinhole camera looking along their mean (``view_rotation``), where
    ``cv2.solvePnP`` (IPPE, for planar targets) solves the pose on normalised points: any camera model's rays, a
    fisheye's beyond 90 degrees included. Rays more than 87 degrees off the mean are left out; None when fewer than
    four are left or no pose fits. A start for a fit of the reprojection error, not the fit itself."""
    view = view_rotation(rays.mean(axis=0))
    in_view = view.inv().apply(rays)
    ahead = in_view[:, 2] > 0.05
    if ahead.sum() < 4:
        return None
    found, rotvec, position = cv2.solvePnP(
        np.ascontiguousarray(points[ahead]), in_view[ahead, :2] / in_view[ahead, 2:], np.eye(3), None,
        flags=cv2.SOLVEPNP_IPPE,
    )
    if not found:
        return None
    return view * Rotation.from_rotvec(rotvec.ravel()), view.apply(position.ravel())


def forms_grid(corners: np.ndarray, pattern_size: tuple[int, int]) -> bool:
    """Do the corners (N, 2) pixels form the board's grid, in order? Along every row and column, the second difference
    of neighbouring corners must stay within ``GRID_TOLERANCE`` times the shorter of its two steps (a fisheye's
    curvature and perspective keep it below 0.4 on real boards; a swapped pair gives 3)."""
    grid = _as_grid(corners, pattern_size)
    for lines in (grid, grid.transpose(1, 0, 2)):
        steps = np.linalg.norm(np.diff(lines, axis=1), axis=-1)
        bends = np.linalg.norm(np.diff(lines, n=2, axis=1), axis=-1)
        if np.any(bends > GRID_TOLERANCE * np.minimum(steps[:, 1:], steps[:, :-1])):
            return False
    return True


def parse_board(text: str) -> tuple[int, int]:
    """``"7x5"`` -> (7, 5): inner corners per row x per column, OpenCV's pattern size and Kalibr's
    targetCols x targetRows. A board of 8 x 6 squares is ``"7x5"``."""
    parts = text.lower().replace(" ", "").split("x")
    if len(parts) != 2 or not all(part.isdigit() for part in parts):
        raise ValueError(
            f"board '{text}': expected inner corners per row x per column, such as '7x5' for a board of 8 x 6 squares"
        )
    return check_pattern_size((int(parts[0]), int(parts[1])))


def check_pattern_size(pattern_size) -> tuple[int, int]:
    """``pattern_size`` as (inner corners per row, per column), whole numbers of at least 3, else ``ValueError``."""
    per_row, per_column = (int(n) for n in pattern_size)
    if per_row < 3 or per_column < 3 or (per_row, per_column) != tuple(pattern_size):
        raise ValueError(
            f"the board must have at least 3 x 3 inner corners (whole numbers, per row x per column), "
            f"got {pattern_size}"
        )
    return per_row, per_column


def pattern_text(pattern_size: tuple[int, int]) -> str:
    """(7, 5) -> ``"7x5"``, as ``parse_board`` reads it."""
    return f"{pattern_size[0]}x{pattern_size[1]}"


def whole_board(image: np.ndarray, pattern_size: tuple[int, int] = (3, 3)) -> tuple[int, int] | None:
    """The inner corners (per row, per column, in the order of ``pattern_size``: the longer first if it is) of the
    whole board in ``image`` that holds at least ``pattern_size``, or None where none is found in the image itself.

    The sector detector with ``cv2.CALIB_CB_LARGER`` grows the pattern found to every corner of the board it lies on:
    a ``pattern_size`` smaller than the board is told apart from the board itself. A board cut off by the image's
    edge gives the part in view."""
    grey = _checked_grey(image, None)
    found, _, meta = cv2.findChessboardCornersSBWithMeta(grey, pattern_size, CALIBRATION.flags | cv2.CALIB_CB_LARGER)
    if not found or meta is None:
        return None
    longer, shorter = max(meta.shape), min(meta.shape)
    return (longer, shorter) if pattern_size[0] >= pattern_size[1] else (shorter, longer)


def larger_board(
    image: np.ndarray,
    pattern_size: tuple[int, int],
    camera: CameraModel | None = None,
    rectify: bool | None = None,
) -> tuple[tuple[int, int], bool] | None:
    """A board in ``image`` with more inner corners than ``pattern_size``, or None: (its inner corners, whether that is
    the whole board's count rather than a lower bound). Corners found for ``pattern_size`` on such a board are a part
    of it, in the wrong places.

    On the image itself (``rectify`` None or False), ``whole_board`` grows a pattern to every corner of its board: the
    given one, then a 3 x 3 (it does not grow from every size). In the perspective views (``camera`` given, ``rectify``
    None or True), a pattern one row or one column larger is looked for with ``find_corners``'s ``MOUNT`` search,
    which gives a lower bound. (On the image, that search and the classic detector read a board's outer edge against
    a white margin as one more row of corners.)"""
    if rectify is not True:
        for seed in (pattern_size, (3, 3)):
            whole = whole_board(image, seed)
            if whole is not None and whole[0] * whole[1] > pattern_size[0] * pattern_size[1]:
                return whole, True
    if camera is None or rectify is False:
        return None
    nx, ny = pattern_size
    for larger in ((nx + 1, ny), (nx, ny + 1)):
        if find_corners(image, larger, camera, MOUNT, rectify=True) is not None:
            return larger, False
    return None


def pattern_hint(images: list[np.ndarray], pattern_size: tuple[int, int], names: list[str], looks: int = 2) -> str:
    """A hint, or "", when no board of ``pattern_size`` was found in ``images`` (named ``names``): the board that is in
    view, the largest ``whole_board`` finds in the first ``looks`` of them. Larger than ``pattern_size``: give its
    size. Smaller: either the squares were counted for the corners, or the board is partly hidden (and that part must
    not be calibrated)."""
    seen = []
    for seed in (pattern_size, (3, 3)):  # the given pattern grows to its board; a smaller one finds one smaller
        seen = [(size, name) for image, name in zip(images[:looks], names, strict=False)
                if (size := whole_board(image, seed)) is not None]
        if seen:
            break
    if not seen:
        return ""
    (found, name), given = max(seen, key=lambda item: item[0][0] * item[0][1]), pattern_text(pattern_size)
    if found[0] >= pattern_size[0] and found[1] >= pattern_size[1]:
        return (
            f" {name} shows a board of {pattern_text(found)} inner corners: give --board {pattern_text(found)} (a part "
            "of a board gives a wrong calibration)"
        )
    return (
        f" {name} shows a board of {pattern_text(found)} inner corners, or part of one: if {given} counted the board's "
        f"squares, give --board {pattern_text(found)}; if {given} is right, the board is partly hidden or cut off in "
        "the views, and a part of it gives a wrong calibration"
    )


def _remembered(grey: np.ndarray, question: tuple, find: Callable[[], np.ndarray | None]) -> np.ndarray | None:
    """``find()``, the detector's answer to ``question`` on the image ``grey``, or the answer it gave before in this
    process (the last ``REMEMBERED`` answers are kept, named by a digest of the image, not the image): calibrating one
    set of views with another camera model, or the mount's chapter redrawn, finds the corners without running the
    detector again. A copy, so that a caller's changes stay its own."""
    key = (hashlib.blake2b(grey.tobytes(), digest_size=16).digest(), grey.shape, question)
    with _ANSWERS_LOCK:
        known = key in _ANSWERS
        if known:
            _ANSWERS.move_to_end(key)
            corners = _ANSWERS[key]
    if not known:
        corners = find()
        with _ANSWERS_LOCK:
            _ANSWERS[key] = corners
            while len(_ANSWERS) > REMEMBERED:
                _ANSWERS.popitem(last=False)
    return None if corners is None else corners.copy()


def _checked_grey(image: np.ndarray, camera: CameraModel | None) -> np.ndarray:
    """``image`` as one 8-bit grey channel, after checking it is 8-bit and, with a ``camera``, of its size."""
    image = np.asarray(image)
    if image.dtype != np.uint8:
        raise ValueError(f"image must be 8-bit (uint8), got {image.dtype}")
    if camera is not None and image.shape[:2] != (camera.height, camera.width):
        raise ValueError(
            f"image is {image.shape[1]} x {image.shape[0]} pixels but the camera model is "
            f"{camera.width} x {camera.height}"
        )
    return cv2.cvtColor(image, cv2.COLOR_BGR2GRAY) if image.ndim == 3 else image


def _find_in_picture(grey: np.ndarray, pattern_size: tuple[int, int], search: Search) -> np.ndarray | None:
    """Corners (N, 2) pixels in the detector's order as ``search`` finds them in ``grey`` (no refinement), or None."""
    found, corners = cv2.findChessboardCornersSB(grey, pattern_size, flags=search.flags)
    if not found and search.classic:
        found, corners = cv2.findChessboardCorners(grey, pattern_size, flags=CLASSIC_FLAGS)
    return corners.reshape(-1, 2).astype(np.float64) if found else None


def _find_in_views(grey: np.ndarray, pattern_size: tuple[int, int], camera: CameraModel) -> np.ndarray | None:
    """Corners (N, 2) pixels of the camera's image found in the first perspective view that shows the board, or None."""
    for axis in _view_axes(camera):
        view = PerspectiveView.along(camera, axis)
        found, corners = cv2.findChessboardCornersSB(view.render(grey), pattern_size, flags=VIEW_FLAGS)
        if found:
            pixels, valid = view.to_camera_image(corners.reshape(-1, 2).astype(np.float64))
            if valid.all():
                return pixels
    return None


def _view_axes(camera: CameraModel) -> list[np.ndarray]:
    """Axes of the perspective views, camera frame: the rays of a 3 x 3 grid of image pixels, centre first."""
    u = camera.width * np.array([0.5, 0.2, 0.8])
    v = camera.height * np.array([0.5, 0.8, 0.2])
    grid = np.stack(np.meshgrid(u, v), axis=-1).reshape(-1, 2)
    rays, valid = camera.unproject(grid)
    return list(rays[valid])


def _refine(grey: np.ndarray, corners: np.ndarray, pattern_size: tuple[int, int]) -> np.ndarray:
    """``cv2.cornerSubPix`` on ``grey`` with a window of 0.4 times the closest corner spacing (2 to 10 px half-size)."""
    grid = _as_grid(corners, pattern_size)
    spacing = min(
        np.linalg.norm(np.diff(grid, axis=0), axis=-1).min(), np.linalg.norm(np.diff(grid, axis=1), axis=-1).min()
    )
    half = int(np.clip(0.4 * spacing, 2, 10))
    refined = cv2.cornerSubPix(
        grey, corners.astype(np.float32).reshape(-1, 1, 2), (half, half), (-1, -1), SUBPIX_CRITERIA
    )
    return refined.reshape(-1, 2).astype(np.float64)


def _as_grid(corners: np.ndarray, pattern_size: tuple[int, int]) -> np.ndarray:
    """Corners (N, 2) as rows of the grid, (corners per column, corners per row, 2)."""
    per_row, per_column = pattern_size
    return corners.reshape(per_column, per_row, 2)


def _order_like_board(grey: np.ndarray, corners: np.ndarray, pattern_size: tuple[int, int]) -> np.ndarray:
    """The corners (N, 2) reordered to the board order of the module docstring."""
    grid = _as_grid(corners, pattern_size)
    step_x, step_y = grid[0, 1] - grid[0, 0], grid[1, 0] - grid[0, 0]
    if step_x[0] * step_y[1] - step_x[1] * step_y[0] > 0:  # seen with z away from the camera: mirror
        grid = grid[:, ::-1]
    candidates = [grid, grid[::-1, ::-1]]
    if grid.shape[0] == grid.shape[1]:
        candidates += [np.rot90(grid), np.rot90(grid, 3)]
    black_origin = [candidate for candidate in candidates if _origin_square_is_black(grey, candidate)]
    if 0 < len(black_origin) < len(candidates):
        candidates = black_origin

    def rightwards(candidate: np.ndarray) -> float:
        row = candidate[0, -1] - candidate[0, 0]
        return row[0] / np.linalg.norm(row)

    return max(candidates, key=rightwards).reshape(-1, 2).copy()


def _origin_square_is_black(grey: np.ndarray, grid: np.ndarray) -> bool:
    """Is the square at the board origin of this order darker than its neighbour along x?"""
    step_x, step_y = grid[0, 1] - grid[0, 0], grid[1, 0] - grid[0, 0]
    origin_square = grid[0, 0] - 0.5 * step_x - 0.5 * step_y
    next_square = grid[0, 0] + 0.5 * step_x - 0.5 * step_y
    return _grey_level_at(grey, origin_square) < _grey_level_at(grey, next_square)


def _grey_level_at(grey: np.ndarray, point: np.ndarray) -> float:
    """Mean grey level of the 3 x 3 pixels around ``point`` (2,) pixels, sampled bilinearly."""
    return float(cv2.getRectSubPix(grey, (3, 3), (float(point[0]), float(point[1]))).mean())
