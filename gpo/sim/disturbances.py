"""What gets in the way of a floor camera so that some of the floor's motion vectors are outliers; the renderer
(``gpo.sim.render.FloorRenderer``) draws them.

``MovingSheet`` — a printed sheet lying on the floor and dragged across it, so what is printed on
it moves with the sheet, not with the floor (``print_sheet`` makes its print); the renderer looks it up
as part of the floor, anti-aliased alike.
``Glint`` — a lamp on the robot mirrored in a glossy floor: a bright spot with sparkles, fixed in
``base_link`` and so fixed in the image, whatever the floor does.
``Disturbances`` places them: how many, how large, how fast, drawn from a seed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

# the ortho-GPI's floor (gpo.floor_image.image.FloorImage.top_view): x, y in base_link, m
GPI_PATCH_M = (0.70, 0.90, -0.10, 0.10)
SHEET_PAD = 2  # transparent texels around a printed sheet, so that its edge fades out in bilinear lookups


@dataclass(frozen=True)
class MovingSheet:
    """A flat printed sheet (paper or cardboard) lying on the floor and dragged across it at constant velocity.

    World frame, metres, radians, seconds: at time t its centre is ``centre_m + velocity_mps * (t - at_s)``
    and its x axis (along its length) points at heading ``yaw_rad + yaw_rate_radps * (t - at_s)``.
    ``size_m`` = (length, width); ``seed`` chooses what is printed on it (``print_sheet``).
    """

    size_m: tuple[float, float]
    centre_m: tuple[float, float]
    at_s: float
    velocity_mps: tuple[float, float]
    yaw_rad: float
    yaw_rate_radps: float = 0.0
    seed: int = 0

    def pose(self, time_s: float) -> tuple[float, float, float]:
        """(x, y, yaw) of the sheet's centre and x axis in world at ``time_s``."""
        elapsed = time_s - self.at_s
        x, y = np.add(self.centre_m, np.multiply(self.velocity_mps, elapsed))
        return float(x), float(y), self.yaw_rad + self.yaw_rate_radps * elapsed

    def to_sheet(self, world_x: np.ndarray, world_y: np.ndarray, time_s: float) -> tuple[np.ndarray, np.ndarray]:
        """Sheet-frame (x, y) metres (origin at the centre) of world points (``world_x``, ``world_y``) at ``time_s``."""
        x, y, yaw = self.pose(time_s)
        c, s = np.cos(yaw), np.sin(yaw)
        dx, dy = world_x - x, world_y - y
        return c * dx + s * dy, c * dy - s * dx

    @property
    def reach_m(self) -> float:
        """Distance from the centre to the farthest point of the sheet, metres."""
        return 0.5 * float(np.hypot(*self.size_m))


def print_sheet(size_m: tuple[float, float], texel: float, seed: int) -> np.ndarray:
    """What a sheet of ``size_m`` = (length, width) metres looks like, at ``texel`` metres per texel.

    (H, W, 2) float32: grey level premultiplied by coverage, and coverage (alpha); columns run along the
    sheet's x, rows along its y, the sheet's centre is the middle texel. Texels the edge cuts are partly
    covered and ``SHEET_PAD`` transparent texels surround the sheet, so its outline is exact on average.
    Paper (light, black print) or cardboard (brown-grey, dark print), seeded: a bold header bar, lines of
    text (5 mm letters) and a block of random squares like a QR code, all strong corners for a tracker.
    """
    rng = np.random.default_rng(seed)
    halves = [int(np.ceil(0.5 * side / texel + 0.5)) + SHEET_PAD for side in size_m]
    cols, rows = (2 * half + 1 for half in halves)
    paper, ink = (225, 30) if rng.random() < 0.6 else (150, 45)
    grey = np.full((rows, cols), paper, np.uint8)  # cv2.putText draws on 8-bit images only
    left, top = (half - 0.5 * side / texel for half, side in zip(halves, size_m, strict=True))
    right, bottom, margin = cols - 1 - left, rows - 1 - top, 0.008 / texel
    step, block = 0.009 / texel, 0.3 * size_m[1] / texel
    header = top + margin + 0.012 / texel
    scale = 0.005 / texel / 22.0  # Hershey simplex capitals are about 22 px high at scale 1
    for line in np.arange(header + step, bottom - margin - block, step):
        text = "".join(rng.choice(list("ABCDEFGHKMNPRSTUVWXYZ0123456789   "), 40))
        cv2.putText(
            grey, text, (round(left + margin), round(line)), cv2.FONT_HERSHEY_SIMPLEX, scale, ink, 1, cv2.LINE_AA
        )
    inside = np.zeros_like(grey, bool)
    inside[round(top + margin) : round(bottom - margin), round(left + margin) : round(right - margin)] = True
    grey[~inside] = paper
    cv2.rectangle(grey, (round(left + margin), round(top + margin)), (round(right - margin), round(header)), ink, -1)
    cells = np.where(rng.random((6, 6)) < 0.5, ink, paper).astype(np.uint8)
    corner = (round(right - margin - block), round(bottom - margin - block))
    grey[corner[1] : corner[1] + round(block), corner[0] : corner[0] + round(block)] = cv2.resize(
        cells, (round(block),) * 2, interpolation=cv2.INTER_NEAREST
    )
    cover = [
        np.clip(0.5 * side / texel + 0.5 - np.abs(np.arange(2 * half + 1) - half), 0.0, 1.0)
        for half, side in zip(halves, size_m, strict=True)
    ]
    alpha = np.outer(cover[1], cover[0]).astype(np.float32)
    return np.dstack(
        [grey[::-1] * alpha, alpha]
    )  # the first row printed is at the sheet's +y edge: it reads from above


@dataclass(frozen=True)
class Glint:
    """A lamp on the robot mirrored in a glossy floor: a bright spot fixed in ``base_link``, so fixed in the image.

    Centred on the floor point ``centre_m`` = (x, y) metres in base_link: a halo adding ``peak`` grey levels
    (enough to saturate its core) that falls to e⁻² of it at ``radius_m``, and ``sparkles`` specks of the
    floor's polish (Gaussian, ``sparkle_m`` standard deviation, as bright as the halo's peak) scattered up to
    1.3 ``radius_m`` from the centre, placed by ``seed``. Its brightness swings by ± ``flicker`` (relative) at
    ``flicker_hz``, from ``flicker_phase_rad`` at time 0.
    """

    centre_m: tuple[float, float]
    radius_m: float = 0.03
    peak: float = 200.0
    sparkles: int = 80
    sparkle_m: float = 0.0009
    flicker: float = 0.2
    flicker_hz: float = 1.7
    flicker_phase_rad: float = 0.0
    seed: int = 0

    def brightness(self, floor_xy: np.ndarray) -> np.ndarray:
        """Grey levels (...) the glint adds at the base_link floor points ``floor_xy`` (..., 2) metres, unflickered."""
        rng = np.random.default_rng(self.seed)
        offset = floor_xy - np.asarray(self.centre_m)
        glow = np.exp(-2.0 * np.sum(offset**2, axis=-1) / self.radius_m**2)
        angle = rng.uniform(0.0, 2 * np.pi, self.sparkles)
        distance = 1.3 * self.radius_m * np.sqrt(rng.random(self.sparkles))
        specks = distance[:, None] * np.column_stack([np.cos(angle), np.sin(angle)])
        for speck, strength in zip(specks, rng.uniform(0.5, 1.0, self.sparkles), strict=True):
            glow = glow + strength * np.exp(-0.5 * np.sum((offset - speck) ** 2, axis=-1) / self.sparkle_m**2)
        return self.peak * glow

    def gain(self, time_s: float) -> float:
        """The flicker factor at ``time_s`` seconds."""
        return 1.0 + self.flicker * np.sin(2 * np.pi * self.flicker_hz * time_s + self.flicker_phase_rad)


@dataclass(frozen=True)
class Disturbances:
    """What to put in the camera's way so that some floor motion vectors are outliers (counts, sizes, speeds).

    ``sheets`` printed sheets, ``sheet_length_m`` long (m, uniform in that range) and 1/√2 as wide, each
    dragged across the floor patch ``patch_m`` once at ``sheet_speed_mps`` (m/s, uniform in that range);
    ``glints`` lamp reflections of radius ``glint_radius_m`` (m, uniform in that range) inside that patch,
    in every frame. ``patch_m`` = (x_min, x_max, y_min, y_max) metres of floor in base_link, the ortho-GPI's
    by default. Everything is drawn from ``seed``; the default disturbs nothing. ``place_sheets`` and
    ``place_glints`` make the ``MovingSheet`` and ``Glint`` objects a ``FloorRenderer`` takes.
    """

    sheets: int = 0
    glints: int = 0
    sheet_length_m: tuple[float, float] = (0.07, 0.13)
    sheet_speed_mps: tuple[float, float] = (0.08, 0.2)
    glint_radius_m: tuple[float, float] = (0.025, 0.04)
    patch_m: tuple[float, float, float, float] = GPI_PATCH_M
    seed: int = 0

    def place_sheets(self, times_s: np.ndarray, poses: np.ndarray) -> tuple[MovingSheet, ...]:
        """Sheets that cross the patch while the robot drives ``poses`` (N, 3: x, y, yaw in world) at ``times_s`` (N,).

        Sheet k has its centre on a random point of the patch at a random moment of the k-th of ``sheets``
        equal shares of the drive, moving across the robot's heading (±30°) and turning slowly (±0.5 rad/s).
        """
        rng = np.random.default_rng([self.seed, 0])
        x_min, x_max, y_min, y_max = self.patch_m
        sheets = []
        for k in range(self.sheets):
            index = round((k + rng.uniform(0.2, 0.8)) / self.sheets * (len(times_s) - 1))
            x, y, yaw = (float(value) for value in poses[index])
            ahead, left = (float(value) for value in rng.uniform([x_min, y_min], [x_max, y_max]))
            heading = yaw + float(rng.choice([-0.5, 0.5])) * math.pi + rng.uniform(-math.pi / 6, math.pi / 6)
            speed, length = rng.uniform(*self.sheet_speed_mps), rng.uniform(*self.sheet_length_m)
            sheets.append(
                MovingSheet(
                    size_m=(length, length / math.sqrt(2)),
                    centre_m=(
                        x + math.cos(yaw) * ahead - math.sin(yaw) * left,
                        y + math.sin(yaw) * ahead + math.cos(yaw) * left,
                    ),
                    at_s=float(times_s[index]),
                    velocity_mps=(speed * math.cos(heading), speed * math.sin(heading)),
                    yaw_rad=rng.uniform(-math.pi, math.pi),
                    yaw_rate_radps=rng.uniform(-0.5, 0.5),
                    seed=int(rng.integers(2**31)),
                )
            )
        return tuple(sheets)

    def place_glints(self) -> tuple[Glint, ...]:
        """Glints centred on random points of the patch, at least their radius inside its edges."""
        rng = np.random.default_rng([self.seed, 1])
        x_min, x_max, y_min, y_max = self.patch_m
        glints = []
        for _ in range(self.glints):
            radius = rng.uniform(*self.glint_radius_m)
            centre = rng.uniform([x_min + radius, y_min + radius], [x_max - radius, y_max - radius])
            phase, seed = rng.uniform(0, 2 * np.pi), int(rng.integers(2**31))
            glints.append(Glint((float(centre[0]), float(centre[1])), radius, flicker_phase_rad=phase, seed=seed))
        return tuple(glints)
