"""Calibration targets: a chessboard, and a chessboard lying on the floor at a known place.

Board frame: origin at the outer corner of the squares, x and y along the rows of squares, z out
of the printed side. Floor placement: the board frame's origin at (x, y) on the floor z = 0 and its
x axis turned by ``yaw`` about z, in whatever frame the placement is given (``world``, or
``base_link`` with the robot at rest).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Chessboard:
    """A chessboard of ``squares`` = (along x, along y) squares of ``square`` metres with a white margin.

    Board frame: origin at the outer corner of the squares, x and y along the rows, z out of the
    printed side. The inner corners are at (i * square, j * square) for 1 <= i < nx, 1 <= j < ny.
    """

    squares: tuple[int, int] = (8, 6)
    square: float = 0.02
    margin: float = 0.02

    def inner_corners(self) -> np.ndarray:
        """Inner corners in the board frame, (N, 3) metres, row by row along x (OpenCV's order)."""
        nx, ny = self.squares
        i, j = np.meshgrid(np.arange(1, nx), np.arange(1, ny))
        return np.column_stack([i.ravel() * self.square, j.ravel() * self.square, np.zeros(i.size)])

    @property
    def pattern_size(self) -> tuple[int, int]:
        """Inner corners per row and per column, as ``cv2.findChessboardCorners`` wants them."""
        return self.squares[0] - 1, self.squares[1] - 1

    def shade(self, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Reflectance (0 black, 1 white) of board points ``xy (..., 2)`` and whether they lie on the board."""
        nx, ny = self.squares
        x, y = xy[..., 0], xy[..., 1]
        on_board = (x >= -self.margin) & (x <= nx * self.square + self.margin)
        on_board &= (y >= -self.margin) & (y <= ny * self.square + self.margin)
        in_squares = (x >= 0) & (x < nx * self.square) & (y >= 0) & (y < ny * self.square)
        black = (np.floor(x / self.square) + np.floor(y / self.square)) % 2 == 0
        return np.where(in_squares & black, 0.0, 1.0), on_board


@dataclass(frozen=True)
class FloorBoard:
    """A chessboard lying printed side up on the floor; its frame at world (x, y) turned by ``yaw`` radians."""

    board: Chessboard
    x: float
    y: float
    yaw: float

    def corners_world(self) -> np.ndarray:
        """Inner corners in the world frame, (N, 3) metres."""
        c, s = np.cos(self.yaw), np.sin(self.yaw)
        corners = self.board.inner_corners()
        return np.column_stack(
            [
                self.x + c * corners[:, 0] - s * corners[:, 1],
                self.y + s * corners[:, 0] + c * corners[:, 1],
                corners[:, 2],
            ]
        )

    def to_board(self, world_xy: np.ndarray) -> np.ndarray:
        """World floor points (..., 2) in the board frame."""
        c, s = np.cos(self.yaw), np.sin(self.yaw)
        dx, dy = world_xy[..., 0] - self.x, world_xy[..., 1] - self.y
        return np.stack([c * dx + s * dy, -s * dx + c * dy], axis=-1)
