"""A frame seen turned back onto its keyframe, so that Lucas-Kanade's square, unturned windows meet the floor as they
left it: Lucas-Kanade follows a shift, not a turn, and reads a turn of a few degrees across its windows short. The
floor image's KLT flow (``gpo.motion.klt``) and the keypoints followed from a keyframe (``gpo.motion.following``)
search a frame turned further than ``TURN_VIEW_RAD`` from its keyframe in such a view. Pixels (u, v): u right, v
down, as OpenCV.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

TURN_VIEW_RAD = np.radians(1.0)  # a frame turned further than this from its keyframe is tracked in a view turned back


@dataclass(frozen=True)
class TurnedView:
    """A frame seen turned back by ``angle`` radians about the image's ``centre`` (u, v) pixels (see the module)."""

    angle: float
    centre: np.ndarray

    @classmethod
    def between(cls, points: np.ndarray, moved: np.ndarray, shape: tuple[int, int]) -> TurnedView | None:
        """The turn that takes ``points`` (N, 2) to ``moved`` (N, 2) in an image of ``shape`` (H, W), or None when it is
        under ``TURN_VIEW_RAD`` (a window then follows the floor well enough)."""
        a, b = points - points.mean(axis=0), moved - moved.mean(axis=0)
        angle = float(np.arctan2(np.sum(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]), np.sum(a * b)))
        if abs(angle) < TURN_VIEW_RAD:
            return None
        return cls(angle, np.array([(shape[1] - 1) / 2, (shape[0] - 1) / 2], np.float32))

    @property
    def _rotation(self) -> np.ndarray:
        cos, sin = np.cos(self.angle), np.sin(self.angle)
        return np.array([[cos, -sin], [sin, cos]], np.float32)

    def view(self, image: np.ndarray) -> np.ndarray:
        """``image`` turned back: the view's pixel x shows the image's ``from_view(x)`` (bilinear)."""
        rotation = self._rotation
        warp = np.hstack([rotation, (self.centre - rotation @ self.centre)[:, None]])
        flags = cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP
        return cv2.warpAffine(image, warp, image.shape[::-1], flags=flags, borderMode=cv2.BORDER_REPLICATE)

    def to_view(self, pixels: np.ndarray) -> np.ndarray:
        """The image's ``pixels`` (N, 2) where the view shows them."""
        return ((pixels - self.centre) @ self._rotation + self.centre).astype(np.float32)

    def from_view(self, pixels: np.ndarray) -> np.ndarray:
        """The view's ``pixels`` (N, 2) where the image has them."""
        return ((pixels - self.centre) @ self._rotation.T + self.centre).astype(np.float32)
