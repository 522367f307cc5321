"""Floor textures for the simulator, built from photographs that ship inside scikit-image.

A floor is a large grey image lying on the world plane z = 0: texel (row i, column j) has its
centre at world ``(x0 + j * texel, y0 + i * texel)`` metres. The texture is not periodic:
randomly rotated, flipped and scaled crops of the photographs ``gravel`` and ``grass`` are
blended with feathered, variance-preserving weights ("texture bombing"), then
shaped into one of three floor kinds that mirror the second paper's test floors:

- ``"wood"`` — high texture: planks with streaked grain, knots of tone, dark seams;
- ``"raised"`` — average texture: 0.6 m raised-floor tiles with a speckled surface and seams;
- ``"industrial"`` — low texture: smooth screed with sparse faint scratches; the renderer adds
  a view-dependent reflective sheen for this kind.

A kind's ``contrast`` scales its surface's departures from its mean grey level (1: the kind as described). The
second paper's Table 1 grades the industrial floor's texture low or very low, and its text says the low one holds
"an higher number of visual features, even if of a small margin": ``VERY_LOW_CONTRAST`` is the screed at three
quarters of its contrast.

Low-frequency stains and world-fixed lighting go on top of every kind. A mip-map pyramid of
the texture lets the renderer anti-alias (see ``gpo.sim.render``). Everything is seeded.

A ``FloorDesign`` names what a recording's floor is made of: one kind, or several kinds mixed in patches
(a hall where planks meet screed), and the photographs its grain comes from (``PHOTOS``).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import cv2
import numpy as np
import skimage.data

FLOOR_KINDS = ("wood", "raised", "industrial")
PHOTOS = ("gravel", "grass", "brick", "moon")  # scikit-image's grey photographs a floor's grain may come from
DEFAULT_PHOTOS = PHOTOS[:2]
MIX_EDGE_M = 0.01  # where two kinds of a mixed floor meet, one fades into the other over about this width, metres
VERY_LOW_CONTRAST = 0.75  # the second paper's "very low" texture (its Table 1): the screed's grain and scratches at 3/4


@dataclass(frozen=True, eq=False)
class FloorTexture:
    """A mip-mapped floor image on the world plane z = 0.

    ``levels[k]`` is the texture at ``texel * 2**k`` metres per texel (uint8); ``origin`` is the
    world (x, y) in metres of the centre of texel (0, 0) of level 0; rows run along +y, columns
    along +x. ``sheen`` tells the renderer to add a reflective highlight.
    """

    levels: tuple[np.ndarray, ...]
    origin: tuple[float, float]
    texel: float
    kind: str
    sheen: bool

    @property
    def extent(self) -> tuple[float, float, float, float]:
        """(x_min, x_max, y_min, y_max) in metres covered by the texture."""
        height, width = self.levels[0].shape
        x0, y0 = self.origin
        half = 0.5 * self.texel
        return x0 - half, x0 + (width - 0.5) * self.texel, y0 - half, y0 + (height - 0.5) * self.texel


def make_floor(
    kind: str,
    extent: tuple[float, float, float, float],
    texel: float = 1e-3,
    seed: int | Sequence[int] = 0,
    photos: Sequence[str] = DEFAULT_PHOTOS,
    contrast: float = 1.0,
) -> FloorTexture:
    """A floor of ``kind`` covering ``extent`` = (x_min, x_max, y_min, y_max) metres at ``texel`` metres per texel,
    its grain from ``photos`` (some of ``PHOTOS``); ``seed``: an integer or a sequence of them (numpy's seeding);
    ``contrast`` (> 0) scales the kind's surface about its mean grey level before the stains and lighting."""
    if kind not in FLOOR_KINDS:
        raise ValueError(f"unknown floor kind {kind!r}; the kinds are {', '.join(FLOOR_KINDS)}")
    _check_photos(photos)
    x_min, x_max, y_min, y_max = extent
    if not (x_max > x_min and y_max > y_min and texel > 0 and contrast > 0):
        raise ValueError(
            f"a floor needs x_max > x_min, y_max > y_min, texel > 0 and contrast > 0, got {extent}, {texel}, {contrast}"
        )
    shape = (int(np.ceil((y_max - y_min) / texel)), int(np.ceil((x_max - x_min) / texel)))
    rng = np.random.default_rng(seed)
    grain = _bombed_grain(shape, rng, photos)
    surface = {"wood": _wood, "raised": _raised_floor, "industrial": _industrial}[kind](grain, texel, rng)
    if contrast != 1.0:
        mean = np.float32(surface.mean())
        surface = mean + np.float32(contrast) * (surface - mean)
    surface *= _low_frequency(shape, texel, cell_m=0.35, rng=rng, amplitude=0.08)  # stains
    surface *= _low_frequency(shape, texel, cell_m=2.0, rng=rng, amplitude=0.12)  # lighting
    image = np.clip(surface, 0, 255).astype(np.uint8)
    return FloorTexture(
        mip_pyramid(image), (x_min + 0.5 * texel, y_min + 0.5 * texel), texel, kind, kind == "industrial"
    )


@dataclass(frozen=True)
class FloorDesign:
    """What a floor is made of: ``kinds`` (of ``FLOOR_KINDS``; several are mixed in patches of about ``patch_m``
    metres, each meeting the next over ``MIX_EDGE_M``) and the ``photos`` its grain comes from (of ``PHOTOS``).
    ``sheen``: None gives the floor the reflective sheen its kinds have (the industrial screed's); False or True
    takes it off or puts it on (a matte screed, a polished wood), the texture unchanged. ``contrast``: each kind's
    (``make_floor``)."""

    kinds: tuple[str, ...]
    photos: tuple[str, ...] = DEFAULT_PHOTOS
    patch_m: float = 1.0
    sheen: bool | None = None
    contrast: float = 1.0

    def __post_init__(self):
        if not self.kinds or any(kind not in FLOOR_KINDS for kind in self.kinds):
            raise ValueError(f"a floor design needs kinds of {', '.join(FLOOR_KINDS)}, got {self.kinds!r}")
        _check_photos(self.photos)
        if not self.patch_m > 0:
            raise ValueError(f"patch_m must be > 0, got {self.patch_m!r}")
        if not self.contrast > 0:
            raise ValueError(f"contrast must be > 0, got {self.contrast!r}")
        if self.sheen not in (None, False, True):
            raise ValueError(f"sheen is None (as the kinds have it), False or True, got {self.sheen!r}")

    def texture(self, extent: tuple[float, float, float, float], texel: float, seed: int) -> FloorTexture:
        """The floor covering ``extent`` (x_min, x_max, y_min, y_max, metres) at ``texel`` metres per texel: one
        kind as ``make_floor`` makes it, or each kind made with its own seed and blended by the weights
        softmax(f_k / (``MIX_EDGE_M`` / ``patch_m``)) of smooth random fields f_k varying over ``patch_m``."""
        if len(self.kinds) == 1:
            floor = make_floor(self.kinds[0], extent, texel, seed, self.photos, self.contrast)
            return floor if self.sheen is None else replace(floor, sheen=self.sheen)
        floors = [
            make_floor(kind, extent, texel, [seed, k], self.photos, self.contrast) for k, kind in enumerate(self.kinds)
        ]
        shape = floors[0].levels[0].shape
        rng = np.random.default_rng([seed, len(self.kinds)])
        fields = np.stack([_low_frequency(shape, texel, self.patch_m, rng, 1.0) for _ in self.kinds])
        fields *= self.patch_m / MIX_EDGE_M
        weights = np.exp(fields - fields.max(axis=0))
        image = sum(w * f.levels[0] for w, f in zip(weights, floors, strict=True)) / weights.sum(axis=0)
        image = np.clip(np.rint(image), 0, 255).astype(np.uint8)
        sheen = any(floor.sheen for floor in floors) if self.sheen is None else self.sheen
        return FloorTexture(mip_pyramid(image), floors[0].origin, texel, "+".join(self.kinds), sheen)


def _check_photos(photos: Sequence[str]) -> None:
    if not photos or any(photo not in PHOTOS for photo in photos):
        raise ValueError(f"a floor's grain comes from some of the photographs {', '.join(PHOTOS)}, got {photos!r}")


def _photo_variants(
    rng: np.random.Generator, photos: Sequence[str], count: int = 24, size: int = 256
) -> list[np.ndarray]:
    """Zero-mean, unit-variance square crops of the ``photos``, randomly rotated, flipped and scaled."""
    photos = [getattr(skimage.data, name)().astype(np.float32) for name in photos]
    variants = []
    for _ in range(count):
        photo = photos[rng.integers(len(photos))]
        centre = (photo.shape[1] / 2.0, photo.shape[0] / 2.0)
        rotation = cv2.getRotationMatrix2D(centre, rng.uniform(0.0, 360.0), rng.uniform(0.8, 1.25))
        rotated = cv2.warpAffine(
            photo, rotation, photo.shape[::-1], flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT
        )
        top = (photo.shape[0] - size) // 2
        crop = rotated[top : top + size, top : top + size]
        if rng.random() < 0.5:
            crop = crop[:, ::-1]
        crop = crop - cv2.GaussianBlur(crop, (0, 0), 24.0)  # keep the grain, drop the photo's lighting
        variants.append((crop - crop.mean()) / crop.std())
    return variants


def _bombed_grain(
    shape: tuple[int, int], rng: np.random.Generator, photos: Sequence[str], spacing: int = 96
) -> np.ndarray:
    """Non-periodic zero-mean, unit-variance grain: feathered photo crops at jittered grid points.

    The sum of crops weighted by windows w_i is divided by sqrt(sum w_i^2), which keeps the
    variance constant where crops overlap (a plain weighted mean would fade the contrast there).
    """
    variants = _photo_variants(rng, photos)
    size = variants[0].shape[0]
    ramp = np.sin(np.linspace(0.0, np.pi, size, dtype=np.float32)) ** 2
    window = np.outer(ramp, ramp)
    feathered = [window * variant for variant in variants]
    squared = window * window
    height, width = shape
    weighted = np.zeros((height + 2 * size + spacing, width + 2 * size + spacing), np.float32)
    weights = np.zeros_like(weighted)
    for top in range(0, height + size, spacing):
        for left in range(0, width + size, spacing):
            i, j = top + rng.integers(spacing), left + rng.integers(spacing)
            weighted[i : i + size, j : j + size] += feathered[rng.integers(len(variants))]
            weights[i : i + size, j : j + size] += squared
    region = (slice(size, size + height), slice(size, size + width))
    norm = np.sqrt(np.maximum(weights[region], np.float32(1e-6), out=weights[region]), out=weights[region])
    return np.divide(weighted[region], norm, out=weighted[region])


def _low_frequency(
    shape: tuple[int, int], texel: float, cell_m: float, rng: np.random.Generator, amplitude: float
) -> np.ndarray:
    """A smooth random field around 1 (1 +- amplitude), varying over about ``cell_m`` metres."""
    cells = (int(np.ceil(shape[0] * texel / cell_m)) + 2, int(np.ceil(shape[1] * texel / cell_m)) + 2)
    coarse = rng.normal(0.0, 1.0, cells).astype(np.float32)
    field = np.tanh(cv2.resize(coarse, shape[::-1], interpolation=cv2.INTER_CUBIC))
    field *= amplitude
    field += 1.0
    return field


def _wood(grain: np.ndarray, texel: float, rng: np.random.Generator) -> np.ndarray:
    """Planks along x, 0.12-0.18 m wide, staggered ends, streaked grain and per-plank tone."""
    height, width = grain.shape
    streaks = cv2.GaussianBlur(grain, (0, 0), sigmaX=12.0, sigmaY=0.8)
    streaks /= streaks.std()
    rows = np.arange(height) * texel
    cols = np.arange(width) * texel
    surface = np.empty_like(grain)
    edge = 0.0
    while edge < rows[-1] + texel:
        plank_width = rng.uniform(0.12, 0.18)
        in_plank = slice(int(edge / texel), int((edge + plank_width) / texel))
        board_length = rng.uniform(0.9, 1.6)
        ends = np.arange(-rng.uniform(0, board_length), cols[-1] + board_length, board_length)
        board = np.searchsorted(ends, cols)
        tone = rng.normal(135.0, 18.0, len(ends) + 1)[board]
        surface[in_plank] = tone + 30.0 * streaks[in_plank] + 10.0 * grain[in_plank]
        seam_rows = slice(in_plank.start, in_plank.start + max(1, int(0.002 / texel)))
        surface[seam_rows] = 45.0
        seam_cols = np.abs(cols[None, :] - ends[np.clip(board, 0, len(ends) - 1)][None, :]) < 0.0015
        surface[in_plank] = np.where(seam_cols, 50.0, surface[in_plank])
        edge += plank_width
    return surface


def _raised_floor(grain: np.ndarray, texel: float, rng: np.random.Generator) -> np.ndarray:
    """0.6 m square tiles, each with its own tone, a speckled surface and 3 mm dark seams."""
    height, width = grain.shape
    tile = 0.6
    rows = (np.arange(height) * texel) // tile
    cols = (np.arange(width) * texel) // tile
    tones = rng.normal(150.0, 6.0, (int(rows[-1]) + 1, int(cols[-1]) + 1))
    surface = tones[rows.astype(int)[:, None], cols.astype(int)[None, :]] + 16.0 * grain
    seam = 0.003
    on_row_seam = ((np.arange(height) * texel) % tile) < seam
    on_col_seam = ((np.arange(width) * texel) % tile) < seam
    surface[on_row_seam] = 70.0
    surface[:, on_col_seam] = 70.0
    return surface.astype(np.float32)


def _industrial(grain: np.ndarray, texel: float, rng: np.random.Generator) -> np.ndarray:
    """Smooth screed: faint blurred grain and sparse thin scratches of a few grey levels."""
    height, width = grain.shape
    surface = 160.0 + 4.0 * cv2.GaussianBlur(grain, (0, 0), 3.0) / 0.5
    scratches = np.zeros((height, width), np.float32)
    area_m2 = height * width * texel * texel
    for _ in range(int(rng.poisson(2.5 * area_m2))):
        start = rng.uniform([0, 0], [width, height])
        length = rng.uniform(0.03, 0.3) / texel
        angle = rng.uniform(0, np.pi)
        end = start + length * np.array([np.cos(angle), np.sin(angle)])
        cv2.line(scratches, tuple(int(v) for v in start), tuple(int(v) for v in end), float(rng.uniform(-12, 12)), 1)
    return surface + cv2.GaussianBlur(scratches, (0, 0), 0.7)


def mip_pyramid(image: np.ndarray, smallest: int = 8) -> tuple[np.ndarray, ...]:
    """Level k halves level k-1 (``cv2.pyrDown``) until a side would drop below ``smallest`` texels.

    ``image`` is (H, W) or (H, W, channels); each channel is filtered on its own.
    """
    levels = [image]
    while min(levels[-1].shape[:2]) // 2 >= smallest:
        levels.append(cv2.pyrDown(levels[-1]))
    return tuple(levels)
