"""The ortho-rectified GPI (the first paper's Section 3.5, chapter 04): a second homography, from the corners of a
2 x 4-square block of the chessboard to a metric rectangle, so that the image has a known metres per pixel and a
known place on the robot's floor; composed with the GPI's stages into one ``RemapTable``.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import cv2
import numpy as np

from gpo.cameras import CameraModel
from gpo.cameras.mount import MountError, detect_corners
from gpo.cameras.targets import Chessboard, FloorBoard
from gpo.floor_image.gpi import GroundPlaneImage, apply_homography, fit_homography, ground_plane_image
from gpo.floor_image.image import (
    FloorImage,
    GroundImageError,
    RemapTable,
    cached_table,
    check_extent,
)

BLOCK_SQUARES = (4, 2)  # the 2 x 4-square block of the paper's Table 1: 4 squares along the board's x, 2 along y


DEFAULT_BLOCK = (2, 2)  # its first inner corner (i, j): the centre block of the 8 x 6-square board


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
        return apply_homography(np.linalg.inv(self.homography), uv)

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
        return cached_table(description, self.floor, self.gpi.cubemap.camera, build, self.cache)

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
    floor: FloorImage,
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
    rectification = OrthoRectification(gpi, fit_homography(found, truth), floor, found, gpi.cache)
    check_extent(rectification.table, "the GPI (the front face's floor ahead, the bottom face's crop)", max_outside)
    return rectification


def chessboard_route(
    fisheye_image: np.ndarray,
    camera: CameraModel,
    placement: FloorBoard,
    floor: FloorImage,
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

    Found by ``gpo.cameras.mount.detect_corners`` (sub-pixel) on the image; each is matched to where ``floor`` puts the
    board lying at ``placement``, within half a square.
    """
    height, width = image.shape[:2]
    if (width, height) != (floor.width, floor.height):
        raise GroundImageError(
            f"the floor image is {width} x {height} pixels but its description is {floor.width} x {floor.height}"
        )
    board = placement.board
    try:
        found = detect_corners(image, None, board, rectify=False)  # a floor image: no camera model, no views
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
