"""The room's ceiling and its lamps: what the camera sees above the walls, and what a glossy floor mirrors.

The lamps are rectangles ``lamp_m`` = (length, width) metres in a grid of ``pitch_m`` = (along, across) metres,
turned ``yaw_rad`` about the vertical (the length along the grid's first axis) and shifted by ``offset_m`` in the
world's (x, y). A glossy floor mirrors them at the ceiling's ``height_m`` above the floor: the camera at height h
sees their mirror image at depth h + H, so it moves across the image at h / (h + H) of the floor's speed, a second
layer on the floor's texture. The mirrored lamp adds ``reflection`` grey levels at its centre and fades beyond its
edge over about ``softness_m`` metres (on the ceiling's plane), the gloss's blur.

The defaults are the simulator's room as the presets render it: a 2.8 m ceiling, 1.2 x 0.3 m lamps 2.4 m apart.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

LIT, UNLIT = 230.0, 170.0  # grey levels of a lamp and of the plain ceiling, seen directly


@dataclass(frozen=True)
class Ceiling:
    """A flat ceiling ``height_m`` metres above the floor with a grid of lamps (see the module)."""

    height_m: float = 2.8
    pitch_m: tuple[float, float] = (2.4, 2.4)
    lamp_m: tuple[float, float] = (1.2, 0.3)
    yaw_rad: float = 0.0
    offset_m: tuple[float, float] = (0.0, 0.0)
    reflection: float = 60.0
    softness_m: float = 0.25

    def __post_init__(self):
        along, across = self.pitch_m
        length, width = self.lamp_m
        if not (self.height_m > 0 and along > 0 and across > 0 and self.softness_m > 0):
            raise ValueError(f"a ceiling needs height, pitch and softness > 0, got {self}")
        if not (0 < length < along and 0 < width < across):
            raise ValueError(f"lamps of {self.lamp_m} m do not fit a grid of {self.pitch_m} m")
        if not (math.isfinite(self.reflection) and self.reflection >= 0):
            raise ValueError(f"a lamp's reflection is >= 0 grey levels, got {self.reflection!r}")

    def distances(self, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """How far the ceiling points (x, y) (float32 arrays, metres in the world) are from the nearest lamp's
        centre line, along its length and across it (metres, >= 0)."""
        x = x - np.float32(self.offset_m[0])
        y = y - np.float32(self.offset_m[1])
        if self.yaw_rad:
            c, s = np.float32(math.cos(self.yaw_rad)), np.float32(math.sin(self.yaw_rad))
            x, y = c * x + s * y, c * y - s * x
        along, across = self.pitch_m
        return np.abs(wrap(x, along) - np.float32(along / 2)), np.abs(wrap(y, across) - np.float32(across / 2))

    def shade(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Grey levels (float32) of the ceiling seen directly at the points (x, y) (metres in the world)."""
        du, dv = self.distances(x, y)
        lamps = (du < self.lamp_m[0] / 2) & (dv < self.lamp_m[1] / 2)
        return np.where(lamps, np.float32(LIT), np.float32(UNLIT))

    def mirrored(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Grey levels (float32) a glossy floor adds where it mirrors the ceiling points (x, y) (metres in the
        world): ``reflection`` on a lamp, fading as exp(-(d / softness)^2) at a distance d beyond its edge."""
        du, dv = self.distances(x, y)
        length, width = self.lamp_m
        beyond_u = np.maximum(du - length / 2, 0) / self.softness_m
        beyond_v = np.maximum(dv - width / 2, 0) / self.softness_m
        return self.reflection * np.exp(-(beyond_u**2) - beyond_v**2)


DEFAULT_CEILING = Ceiling()  # the room the presets are rendered in


def wrap(values: np.ndarray, period: float) -> np.ndarray:
    """``values % period`` (float32), several times faster than numpy's floating-point remainder."""
    return values - np.floor(values * np.float32(1.0 / period)) * np.float32(period)
