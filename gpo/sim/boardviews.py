"""Chessboard views for intrinsic calibration: a board held at many poses in front of a camera.

The poses spread the board over the whole image, the fisheye's periphery included, tilted up to
``max_tilt`` so that the focal length and the distortion can be told apart. Each view comes with
its truth: the board's pose and where its inner corners project.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from gpo.cameras import CameraModel
from gpo.cameras.targets import Chessboard
from gpo.sim.render import render_board_view

CALIBRATION_BOARD = Chessboard((8, 6), 0.030, 0.020)


@dataclass(frozen=True, eq=False)
class BoardView:
    """One rendered view: the uint8 ``image``, the board's pose (``rotation`` camera <- board,
    ``position`` of its origin in the camera frame, metres) and its inner corners' true pixels (N, 2)."""

    image: np.ndarray
    rotation: Rotation
    position: np.ndarray
    corners: np.ndarray


def board_poses(
    camera: CameraModel,
    count: int,
    board: Chessboard = CALIBRATION_BOARD,
    distance: tuple[float, float] = (0.25, 0.5),
    max_tilt: float = np.radians(45.0),
    margin_px: float = 20.0,
    seed: int = 0,
) -> list[tuple[Rotation, np.ndarray]]:
    """``count`` board poses whose every inner corner lands in the image, ``margin_px`` from its border.

    The board's centre sits on the ray of a random pixel, ``distance`` metres away, facing the
    camera, then tilted by up to ``max_tilt`` radians and turned about its normal at random.
    """
    rng = np.random.default_rng(seed)
    corners = board.inner_corners()
    centre = np.array([board.squares[0] * board.square / 2.0, board.squares[1] * board.square / 2.0, 0.0])
    poses = []
    for _ in range(1000 * count):
        if len(poses) == count:
            return poses
        pixel = rng.uniform([margin_px, margin_px], [camera.width - margin_px, camera.height - margin_px])
        ray, valid = camera.unproject(pixel)
        if not valid:
            continue
        facing, _ = Rotation.align_vectors(-ray, [0.0, 0.0, 1.0])  # board normal towards the camera
        tilt_axis = rng.normal(size=2)
        tilt = Rotation.from_rotvec(np.append(tilt_axis / np.linalg.norm(tilt_axis), 0.0) * rng.uniform(0, max_tilt))
        rotation = facing * tilt * Rotation.from_euler("z", rng.uniform(-np.pi, np.pi))
        position = rng.uniform(*distance) * ray - rotation.apply(centre)
        pixels, valid = camera.project(rotation.apply(corners) + position)
        inside = (pixels >= margin_px).all() and (pixels <= [camera.width - margin_px, camera.height - margin_px]).all()
        if valid.all() and inside:
            poses.append((rotation, position))
    raise RuntimeError(f"found only {len(poses)} of {count} board poses that fit in the image")


def board_views(camera: CameraModel, count: int = 20, board: Chessboard = CALIBRATION_BOARD, seed: int = 0):
    """``count`` rendered ``BoardView`` of ``board`` at ``board_poses`` (each view's noise seeded by its index)."""
    views = []
    for index, (rotation, position) in enumerate(board_poses(camera, count, board, seed=seed)):
        image = render_board_view(camera, board, (rotation, position), seed=seed * 1000 + index)
        corners, _ = camera.project(rotation.apply(board.inner_corners()) + position)
        views.append(BoardView(image, rotation, position, corners))
    return views
