"""How the floor moves between two frames, from matched keypoints: the second paper's floor feature odometer.

Chapter 08. The second paper's AGV looks straight down at the floor with a pinhole camera. Each frame's keypoints
are matched with the previous frame's; two filters throw out the wrong matches; a rigid 2-D transform (theta, Tx,
Ty) fitted to the rest, in metres, is the robot's motion over the frame, and the poses are composed,
A_i^0 = A_1^0 ... A_i^{i-1} (its eq. 4; ``gpo.kinematics.compose``).

- **Keypoints** (``detect``): the paper uses SURF, which OpenCV's PyPI wheels do not include (it is patented and
  lives in the non-free contrib module), so SIFT stands in, and ORB as the fast option. A keypoint whose
  descriptor support would cross the image border, or touch a masked pixel (a light spot, the robot's own
  shadow), is dropped: its descriptor would describe the border, not the floor.
- **Matching** (``match``): the two nearest neighbours of each descriptor, kept when the nearest is clearly nearer
  than the second (Lowe's ratio test), optionally only when the match is mutual (cross check).
- **Histogram filter** (``histogram_filter``): a rigid motion between two frames moves all floor points by about
  the same vector when the turn is small. The match vectors' orientations go into 180 bins of 2 degrees over the
  full circle, centred on their circular mean so that vectors around +-180 degrees do not split; the matches
  within mu +- sigma of the histogram (bin centres weighted by counts) are kept; then the same with the kept
  vectors' lengths in 160 bins.
- **Geometric invariance check** (``invariance_check``, the paper's Algorithm 1): a rigid motion keeps distances.
  Groups of C matches form closed loops p_1 -> ... -> p_C -> p_1 in both frames; a group is kept when every side
  keeps its length, min(l, l^) / max(l, l^) >= t. A match is kept when it is in a kept loop.
- ``degenerate`` tells when the kept points are too close to a line for a rotation.

Pixels (u, v): u right, v down, as OpenCV. Angles in degrees where people read them (the histograms).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import cv2
import numpy as np

from gpo.kinematics import increment_from_point_pairs, seen_after

DETECTORS = ("orb", "sift")
ORB_PATCH_PX = 31  # cv2.ORB_create's patchSize: its descriptor samples a 31 x 31 patch around the keypoint
SHORT_SIDE_PX = 2.0  # a loop side shorter than this in both frames is too short to judge and passes


class FeatureError(ValueError):
    """An image or a parameter the feature odometer cannot use."""


@dataclass(frozen=True)
class FeatureParameters:
    """The keypoints, matching and filters of the floor feature odometer.

    ``detector``: ``sift`` (SURF's stand-in) or ``orb`` (fast, but its keypoints sit on a coarse grid: chapter 08);
    ``max_features``: keypoints per frame, the strongest; ``scale``: the image is resized by this factor before
    detection (OpenCV's SIFT doubles its input first, so 0.5 costs about a quarter), the keypoints are given in the
    full image's pixels. ``roi``: (u, v, width, height) of the part of the image searched, pixels (None: all);
    the paper reached 70 Hz with one. ``ratio``: Lowe's ratio test (1.0: off); ``cross_check``: keep only mutual
    best matches.
    ``histogram_filter`` with ``orientation_bins`` and ``length_bins``; ``invariance_check`` with
    ``invariance_threshold`` (t), ``cardinality`` (C; None: 3 below 12 matches, 4 below 40, else 5) and
    ``rounds`` (random partitions of the matches into loops, each match tested once per round). ``min_matches``:
    fewer kept, the frame is flagged. ``refit_px``: after the rigid fit on the kept matches, it is fitted again on
    every match that the first fit moves to within this many pixels of its partner (0: the paper's fit alone; the
    re-admission undoes the bias of keeping only the vectors near the histograms' means, chapter 08).
    ``seed``: the invariance check's random generator.
    """

    detector: str = "sift"
    max_features: int = 300
    scale: float = 0.5
    roi: tuple[int, int, int, int] | None = None
    ratio: float = 0.8
    cross_check: bool = False
    histogram_filter: bool = True
    orientation_bins: int = 180
    length_bins: int = 160
    invariance_check: bool = True
    invariance_threshold: float = 0.85
    cardinality: int | None = None
    rounds: int = 3
    min_matches: int = 6
    refit_px: float = 1.5
    seed: int = 0

    def __post_init__(self):
        if self.detector not in DETECTORS:
            raise FeatureError(f"detector must be one of {', '.join(DETECTORS)}, got {self.detector!r}")
        for name in ("max_features", "orientation_bins", "length_bins", "rounds"):
            if not (isinstance(getattr(self, name), int) and getattr(self, name) >= 1):
                raise FeatureError(f"{name} must be a whole number >= 1, got {getattr(self, name)!r}")
        if not 0 < self.scale <= 1:
            raise FeatureError(f"scale must lie in (0, 1], got {self.scale!r}")
        if self.roi is not None:
            object.__setattr__(self, "roi", tuple(int(value) for value in self.roi))
        if self.roi is not None and (len(self.roi) != 4 or min(self.roi) < 0 or min(self.roi[2:]) < 32):
            raise FeatureError(f"roi must be (u, v, width, height) with width and height >= 32 px, got {self.roi!r}")
        if not 0 < self.ratio <= 1:
            raise FeatureError(f"ratio must lie in (0, 1], got {self.ratio!r}")
        if not 0 < self.invariance_threshold <= 1:
            raise FeatureError(f"invariance_threshold must lie in (0, 1], got {self.invariance_threshold!r}")
        if self.cardinality is not None and not (isinstance(self.cardinality, int) and self.cardinality >= 3):
            raise FeatureError(f"cardinality must be None or a whole number >= 3, got {self.cardinality!r}")
        if not self.refit_px >= 0:
            raise FeatureError(f"refit_px must be >= 0 (0: no refit), got {self.refit_px!r}")
        if not (isinstance(self.min_matches, int) and self.min_matches >= 2):
            raise FeatureError(f"min_matches must be a whole number >= 2, got {self.min_matches!r}")


@dataclass(frozen=True, eq=False)
class Keypoints:
    """A frame's keypoints: ``points`` (N, 2) pixels, ``descriptors`` (N, D), ``sizes`` (N,) diameters, pixels."""

    points: np.ndarray
    descriptors: np.ndarray
    sizes: np.ndarray

    def __len__(self) -> int:
        return len(self.points)


def detect(image: np.ndarray, parameters: FeatureParameters, mask=None) -> Keypoints:
    """The keypoints of a grey 8-bit ``image`` whose descriptor support lies inside the image and off ``mask``
    (same size, nonzero = usable; None: the whole image)."""
    image = np.asarray(image)
    if image.dtype != np.uint8 or image.ndim != 2:
        raise FeatureError(f"keypoints need a grey 8-bit image (H, W), got {image.dtype} {image.shape}")
    usable = np.full(image.shape, 255, np.uint8) if mask is None else _mask(mask, image.shape)
    u0, v0 = 0, 0
    if parameters.roi is not None:
        u0, v0, width, height = parameters.roi
        if u0 + width > image.shape[1] or v0 + height > image.shape[0]:
            raise FeatureError(
                f"the roi {parameters.roi} reaches outside the {image.shape[1]} x {image.shape[0]} image"
            )
        image, usable = image[v0 : v0 + height, u0 : u0 + width], usable[v0 : v0 + height, u0 : u0 + width]
    scale = parameters.scale
    if scale != 1.0:
        image = cv2.resize(image, None, fx=scale, fy=scale, interpolation=cv2.INTER_AREA)
        usable = cv2.resize(usable, (image.shape[1], image.shape[0]), interpolation=cv2.INTER_NEAREST)
    found, descriptors = _detector(parameters).detectAndCompute(image, usable)
    if not found:
        return _no_keypoints(parameters)
    points = np.array([k.pt for k in found], dtype=np.float64)
    sizes = np.array([k.size for k in found], dtype=np.float64)
    radius = np.maximum(sizes / 2, ORB_PATCH_PX / 2 if parameters.detector == "orb" else 0.0)
    inside = _support_inside(points, radius, usable)
    full = (points[inside] + 0.5) / scale - 0.5 + [u0, v0]
    return Keypoints(full, descriptors[inside], sizes[inside] / scale)


def match(previous: Keypoints, current: Keypoints, parameters: FeatureParameters) -> np.ndarray:
    """Index pairs (M, 2) (previous, current) of the matches that pass the ratio test (and the cross check)."""
    if len(previous) < 2 or len(current) < 2:
        return np.zeros((0, 2), dtype=int)
    norm = cv2.NORM_HAMMING if parameters.detector == "orb" else cv2.NORM_L2
    matcher = cv2.BFMatcher(norm)
    pairs = [
        (best.queryIdx, best.trainIdx)
        for best, second in matcher.knnMatch(previous.descriptors, current.descriptors, k=2)
        if best.distance < parameters.ratio * second.distance or parameters.ratio == 1.0
    ]
    pairs = np.array(pairs, dtype=int).reshape(-1, 2)
    if parameters.cross_check and len(pairs):
        back = {m.queryIdx: m.trainIdx for m in matcher.match(current.descriptors, previous.descriptors)}
        pairs = pairs[[back.get(c) == p for p, c in pairs]].reshape(-1, 2)
    return pairs


@dataclass(frozen=True, eq=False)
class HistogramStage:
    """One histogram of the filter: the ``values`` per match (degrees or pixels), the histogram (``counts``,
    ``edges``), its ``mean`` and ``sigma``, and which matches it ``kept``."""

    values: np.ndarray
    counts: np.ndarray
    edges: np.ndarray
    mean: float
    sigma: float
    kept: np.ndarray


def histogram_filter(
    start, end, orientation_bins: int = 180, length_bins: int = 160
) -> tuple[np.ndarray, HistogramStage, HistogramStage | None]:
    """The paper's histogram filter on the match vectors ``end - start`` (pixels): the matches whose orientation,
    then whose length, lies within mu +- sigma of its histogram. Returns the mask over all matches and both
    stages (the second None when the first kept nothing)."""
    vectors = np.asarray(end, dtype=float) - np.asarray(start, dtype=float)
    angles = np.degrees(np.arctan2(vectors[:, 1], vectors[:, 0]))
    centre = np.degrees(np.angle(np.exp(1j * np.radians(angles)).sum())) if len(angles) else 0.0
    turned = (angles - centre + 180.0) % 360.0 - 180.0  # about the circular mean, in [-180, 180)
    orientation = _stage(turned, orientation_bins, (-180.0, 180.0), np.ones(len(turned), bool))
    orientation = HistogramStage(
        angles,
        orientation.counts,
        orientation.edges + centre,
        orientation.mean + centre,
        orientation.sigma,
        orientation.kept,
    )
    if not orientation.kept.any():
        return orientation.kept, orientation, None
    lengths = np.hypot(vectors[:, 0], vectors[:, 1])
    chosen = lengths[orientation.kept]
    length = _stage(lengths, length_bins, (chosen.min(), max(chosen.max(), chosen.min() + 1e-9)), orientation.kept)
    return length.kept, orientation, length


@dataclass(frozen=True, eq=False)
class InvarianceCheck:
    """Algorithm 1's work: the ``loops`` tried (match indices in loop order), which were ``kept_loops``, the
    matches ``kept`` (in at least one kept loop) and the ``cardinality`` C."""

    loops: list[np.ndarray]
    kept_loops: np.ndarray
    kept: np.ndarray
    cardinality: int


def choose_cardinality(matches: int) -> int:
    """C for ``matches`` matches: 3 below 12, 4 below 40, else 5 (a longer loop is a stricter test, and needs
    more matches to make loops of)."""
    return 3 if matches < 12 else 4 if matches < 40 else 5


def invariance_check(
    start, end, threshold: float = 0.85, cardinality: int | None = None, rounds: int = 3, rng=None
) -> InvarianceCheck:
    """The paper's Algorithm 1 on matched points ``start`` and ``end`` (N, 2), pixels.

    Each round shuffles the matches and cuts them into loops of C, the last one filled up with other matches, so
    that every match is tested once a round. A loop is kept when each of its sides, the same in both frames, has
    min(l, l^) / max(l, l^) >= ``threshold`` (sides shorter than ``SHORT_SIDE_PX`` in both pass: too short to
    judge)."""
    start, end = np.asarray(start, dtype=float), np.asarray(end, dtype=float)
    count = len(start)
    size = cardinality or choose_cardinality(count)
    rng = rng if rng is not None else np.random.default_rng(0)
    if count < size:
        return InvarianceCheck([], np.zeros(0, bool), np.zeros(count, bool), size)
    loops = []
    for _ in range(rounds):
        order = rng.permutation(count)
        short = -len(order) % size
        if short:
            order = np.concatenate([order, rng.choice(order[: len(order) - size + short], short, replace=False)])
        loops.extend(order.reshape(-1, size))
    loops = np.array(loops)
    sides = [np.linalg.norm(points[np.roll(loops, -1, axis=1)] - points[loops], axis=2) for points in (start, end)]
    low, high = np.minimum(*sides), np.maximum(*sides)
    with np.errstate(invalid="ignore", divide="ignore"):
        kept_sides = (low / high >= threshold) | (high < SHORT_SIDE_PX)
    kept_loops = kept_sides.all(axis=1)
    kept = np.zeros(count, bool)
    kept[loops[kept_loops].ravel()] = True
    return InvarianceCheck(list(loops), kept_loops, kept, size)


def refit(start, end, increment, tolerance: float, min_matches: int) -> np.ndarray:
    """The increment (dx, dy, dtheta) fitted again on every pair of ``start`` and ``end`` (N, 2) that ``increment``
    explains to within ``tolerance`` (the points' unit), kept or not by the filters; ``increment`` itself when
    fewer than ``min_matches`` pairs are. Keeping only the vectors near the histograms' means keeps, in a turn,
    the matches whose errors make the turn look smaller; re-admitting every match the fit explains undoes that."""
    close = np.hypot(*(np.asarray(end) - seen_after(start, increment)).T) < tolerance
    return increment_from_point_pairs(start[close], end[close]) if close.sum() >= min_matches else increment


def degenerate(points, min_spread_px: float = 2.0) -> bool:
    """True when ``points`` (N, 2) lie (nearly) on a line or on a point: their spread across the best line, the
    smallest singular value of the centred points over sqrt(N), is under ``min_spread_px``."""
    points = np.asarray(points, dtype=float)
    if len(points) < 3:
        return True
    spread = np.linalg.svd(points - points.mean(axis=0), compute_uv=False)[-1] / np.sqrt(len(points))
    return bool(spread < min_spread_px)


@dataclass(frozen=True, eq=False)
class FeatureMatches:
    """One frame pair: both frames' keypoints, the matches ``pairs`` (M, 2), the stages' work (``histogram``:
    orientation and length stages, ``invariance``; None when off), the matches ``kept`` by every stage that is on,
    the ``flag`` (None when measured, else why not) and the ``seconds`` each stage took."""

    previous: Keypoints
    current: Keypoints
    pairs: np.ndarray
    histogram: tuple[HistogramStage, HistogramStage | None] | None
    invariance: InvarianceCheck | None
    kept: np.ndarray
    flag: str | None
    seconds: dict

    @property
    def start(self) -> np.ndarray:
        """The kept matches' points in the previous frame (K, 2), pixels."""
        return self.previous.points[self.pairs[self.kept, 0]]

    @property
    def end(self) -> np.ndarray:
        """The kept matches' points in the current frame (K, 2), pixels."""
        return self.current.points[self.pairs[self.kept, 1]]

    @property
    def matched(self) -> tuple[np.ndarray, np.ndarray]:
        """Every match's points (M, 2) in the previous and the current frame, pixels, kept or not."""
        return self.previous.points[self.pairs[:, 0]], self.current.points[self.pairs[:, 1]]


class FeatureTracker:
    """Matches each frame's keypoints with the previous frame's: ``track(image, mask)`` returns the
    ``FeatureMatches`` of the pair (None for the first frame); ``restart()`` forgets the previous frame."""

    def __init__(self, parameters: FeatureParameters = FeatureParameters()):
        self.parameters = parameters
        self._rng = np.random.default_rng(parameters.seed)
        self._previous: Keypoints | None = None

    def restart(self) -> None:
        self._previous = None

    def track(self, image: np.ndarray, mask=None) -> FeatureMatches | None:
        seconds = {}
        started = time.perf_counter()
        current = detect(image, self.parameters, mask)
        seconds["detect"] = time.perf_counter() - started
        previous, self._previous = self._previous, current
        if previous is None:
            return None
        return self.matches(previous, current, seconds)

    def matches(self, previous: Keypoints, current: Keypoints, seconds: dict | None = None) -> FeatureMatches:
        """Match two frames' keypoints and filter the matches (the stages that ``parameters`` switch on)."""
        parameters, seconds = self.parameters, dict(seconds or {})
        started = time.perf_counter()
        pairs = match(previous, current, parameters)
        seconds["match"] = time.perf_counter() - started
        kept, histogram, invariance, flag = np.ones(len(pairs), bool), None, None, None
        if min(len(previous), len(current)) < parameters.min_matches:
            flag = f"too few keypoints: {len(previous)} and {len(current)} (at least {parameters.min_matches})"
        elif len(pairs) < parameters.min_matches:
            flag = f"too few matches: {len(pairs)} (at least {parameters.min_matches})"
        start, end = previous.points[pairs[:, 0]], current.points[pairs[:, 1]]
        if flag is None and parameters.histogram_filter:
            started = time.perf_counter()
            kept, *stages = histogram_filter(start, end, parameters.orientation_bins, parameters.length_bins)
            histogram = tuple(stages)
            seconds["histogram"] = time.perf_counter() - started
            flag = (
                None
                if kept.sum() >= parameters.min_matches
                else f"too few matches left by the histogram filter: {kept.sum()}"
            )
        if flag is None and parameters.invariance_check:
            started = time.perf_counter()
            chosen = np.flatnonzero(kept)
            invariance = invariance_check(
                start[chosen],
                end[chosen],
                parameters.invariance_threshold,
                parameters.cardinality,
                parameters.rounds,
                self._rng,
            )
            kept = np.zeros(len(pairs), bool)
            kept[chosen[invariance.kept]] = True
            seconds["invariance"] = time.perf_counter() - started
            if kept.sum() < parameters.min_matches:
                flag = f"too few matches left by the invariance check: {kept.sum()}"
        return FeatureMatches(previous, current, pairs, histogram, invariance, kept, flag, seconds)


def _detector(parameters: FeatureParameters):
    if parameters.detector == "orb":
        return cv2.ORB_create(nfeatures=parameters.max_features, patchSize=ORB_PATCH_PX)
    return cv2.SIFT_create(nfeatures=parameters.max_features)


def _no_keypoints(parameters: FeatureParameters) -> Keypoints:
    width = 32 if parameters.detector == "orb" else 128
    dtype = np.uint8 if parameters.detector == "orb" else np.float32
    return Keypoints(np.zeros((0, 2)), np.zeros((0, width), dtype), np.zeros(0))


def _mask(mask, shape) -> np.ndarray:
    mask = np.asarray(mask)
    if mask.shape != shape:
        raise FeatureError(f"the mask is {mask.shape}, the image {shape}: they must be the same size")
    return np.where(mask != 0, 255, 0).astype(np.uint8)


def _support_inside(points: np.ndarray, radius: np.ndarray, usable: np.ndarray) -> np.ndarray:
    """True where the disc of ``radius`` about each point lies inside the image and on usable pixels."""
    height, width = usable.shape
    inside = (
        (points[:, 0] - radius >= 0)
        & (points[:, 1] - radius >= 0)
        & (points[:, 0] + radius <= width - 1)
        & (points[:, 1] + radius <= height - 1)
    )
    if usable.all():
        return inside
    blocked = cv2.distanceTransform(usable, cv2.DIST_L2, 5)  # distance to the nearest masked pixel
    u, v = np.clip(np.round(points).astype(int), 0, [width - 1, height - 1]).T
    return inside & (blocked[v, u] > radius)


def _stage(values: np.ndarray, bins: int, limits, among: np.ndarray) -> HistogramStage:
    """The histogram of ``values[among]`` and the matches among them within its mu +- sigma."""
    counts, edges = np.histogram(values[among], bins=bins, range=limits)
    centres = 0.5 * (edges[:-1] + edges[1:])
    total = max(counts.sum(), 1)
    mean = float(centres @ counts / total)
    sigma = float(np.sqrt(((centres - mean) ** 2) @ counts / total))
    width = max(sigma, 0.5 * (edges[1] - edges[0]))  # at least half a bin: identical values are all kept
    kept = among & (np.abs(values - mean) <= width)
    return HistogramStage(values, counts, edges, mean, sigma, kept)
