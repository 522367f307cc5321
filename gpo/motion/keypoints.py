# long: one job, the second paper's image work in the order chapter 08 reads it (keypoints, matches, both filters, the
# tracker), each step tied to the paper in its docstring
"""How the floor moves between two frames, from matched keypoints: the second paper's floor feature odometer.

Chapter 08. The second paper's AGV carries a monocular pinhole camera that looks straight down at the floor. Each
frame's keypoints are matched with the previous frame's, two filters throw out the wrong matches, and a rigid 2-D
transform A_i^{i-1} = (theta, Tx, Ty) fitted to the rest, in metres, is the robot's motion over the frame. The
poses are composed, A_i^0 = A_1^0 A_2^1 ... A_i^{i-1} (its eq. 4). This module does the image and point work only;
the caller turns the kept pixels into floor points, fits the transform (``gpo.odometry.kinematics.rigid_fit``, or
``increment_from_point_pairs`` for the robot's increment) and composes it (``gpo.odometry.kinematics.compose``).

- **Keypoints** (``detect``): the paper uses SURF, which OpenCV's PyPI wheels do not include (it is patented and
  lives in the non-free contrib module), so SIFT stands in for it, and ORB is the fast option. A keypoint is
  dropped when its descriptor's support, a disc about it, leaves the image or touches a masked pixel (a light
  spot, the robot's shadow): that descriptor would describe the border or the spot, which move with the camera,
  not the floor. The disc's radius is ``SUPPORT_PER_SIZE`` times the keypoint's diameter (``cv2.KeyPoint.size``):
  half of it for ORB, whose 31 x 31 patch at the keypoint's pyramid level is ``size`` wide; three times it for
  SIFT, half the side of its 4 x 4 grid of histograms, each three keypoint scales (``size / 2``) wide (the grid's
  turned corners reach further, where its Gaussian weight has fallen below 0.6). A keypoint's point is the pixel
  centre of what it marks: by default OpenCV's SIFT reports its keypoints a quarter of its input's pixel right of
  and below it (so SIFT is made with the precise upscale), and its ORB a keypoint of a coarser pyramid level up
  and left of it (``_orb_points`` follows it back). The same offset in every frame would cancel on an ideal lens,
  but a lens with radial distortion maps one pixel offset to floor offsets that differ across the image, and
  driving straight then reads as a slow turn: a 0.5 px offset turns the path 0.08 degrees a metre under a 520 px
  lens with k1 = -0.35, k2 = 0.15 seen 0.25 m above the floor.
- **Matching** (``match``): the two nearest descriptors of each previous keypoint among the current ones
  (``cv2.BFMatcher``: Hamming distance for ORB, Euclidean for SIFT); a match is kept when the nearest is clearly
  nearer than the second (Lowe's ratio test) and, optionally, when it is mutual (the cross check).
- **Histogram filter** (``histogram_filter``): between two close frames a rigid motion moves every floor point by
  about the same vector d = end - start. The orientations of the vectors are binned, the matches within mu +- sigma
  of that histogram are kept, then the same is done with the kept vectors' lengths.
- **Geometric invariance check** (``invariance_check``, the paper's Algorithm 1): a rigid motion keeps distances.
  Random groups of C matches form closed loops p_1 -> ... -> p_C -> p_1 in both frames; a group is kept when every
  side keeps its length, min(l, l^) / max(l, l^) >= t, and a match is kept when it lies in a kept loop.
- ``degenerate`` tells the caller when the kept points lie too close to a line (or a point) to fit a rotation.

The rules this module adds to the paper's description are documented where they are used: the histogram's mu and
sigma (``histogram_filter``), the loops' cardinality and rounds (``invariance_check``), the support disc
(``detect``). ``refit`` is the pipeline's addition to the paper's fit.

Pixels (u, v): u right, v down, as OpenCV; points are pixel centres of the full image. Orientations are
atan2(d_v, d_u) in degrees: 0 to the right, 90 down, growing clockwise on screen since v points down.
"""

from __future__ import annotations

import math
import numbers
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from functools import cached_property

import cv2
import numpy as np

from gpo.motion.keyframes import FRAME_TO_FRAME, KeyframePolicy
from gpo.motion.ranges import MAX_IMAGE_PX, OutOfRange, check_rules, in_range

DETECTORS = ("orb", "sift")


FOLLOWERS = ("match", "lk")  # how a keyframe's keypoints are found in later frames (``FeatureParameters.follow``)


SUPPORT_PER_SIZE = {"orb": 0.5, "sift": 3.0}  # the descriptor support's radius over the keypoint diameter


DESCRIPTOR = {"orb": (32, np.uint8, cv2.NORM_HAMMING), "sift": (128, np.float32, cv2.NORM_L2)}  # width, type, norm


SHORT_VECTOR_PX = 1.0  # a match vector shorter than this has no orientation worth binning


LOCALISATION_PX = 0.5  # the histogram bands are never narrower than this much motion


SHORT_SIDE_PX = 2.0  # a loop side shorter than this in both frames is too short to judge and passes


MIN_ROI_PX = 32  # the smallest region of interest, width and height


ORB_SCALE_FACTOR, ORB_LEVELS = 1.2, 8  # ORB's pyramid: each level this much smaller than the one before, and how many


class FeatureError(ValueError):
    """An image, a mask or a parameter the feature odometer cannot use."""


class FeatureParametersOutOfRange(OutOfRange, FeatureError):
    """``FeatureParameters`` outside their ranges, each named (``gpo.motion.ranges.OutOfRange``)."""


def _whole(value, lowest: int) -> bool:
    return isinstance(value, numbers.Integral) and not isinstance(value, bool) and value >= lowest


@dataclass(frozen=True)
class FeatureParameters:
    """The keypoints, matching and filters of the floor feature odometer.

    ``detector``: ``orb`` (fast) or ``sift`` (SURF's stand-in); ``max_features``: keypoints per frame, the strongest.
    ``contrast_threshold``: SIFT's (OpenCV's ``contrastThreshold``; lower finds more keypoints on a smooth floor);
    ``fast_threshold``: ORB's corner threshold, grey levels (OpenCV's ``fastThreshold``).
    ``scale``: the image is resized by this factor before detection (OpenCV's SIFT doubles its input first, so 0.5
    costs about a quarter); ``roi``: (u, v, width, height) of the part of the image searched, pixels (None: all),
    the paper reached 70 Hz with one. Keypoints are always given in the full image's pixels.
    ``ratio``: Lowe's ratio test on the two nearest neighbours (1.0: off); ``cross_check``: keep only mutual matches.
    ``histogram_filter`` with ``orientation_bins`` (over 180 degrees) and ``length_bins``; ``invariance_check`` with
    ``invariance_threshold`` (t), ``cardinality`` (C; None: ``choose_cardinality``) and ``rounds`` (random
    partitions of the matches into loops). ``min_matches``: fewer matches left after the filters flag the frame.
    ``refit_px``: for the caller (``refit``), the fit is repeated on every match the first fit moves to within this
    many pixels of its partner (0: the paper's fit alone). ``seed``: the invariance check's random generator.
    The suite's rules beside the paper's (``histogram_filter``, ``invariance_check``; each off gives the paper's):
    ``circular_binning``, ``band_floor_px`` (0: plain mu +- sigma) and ``short_side_px`` (0: every side judged).
    ``keyframe``: how long the frames after a keyframe are matched with it instead of with the frame before them
    (``gpo.motion.keyframes``; the share is of the kept matches of the first frame matched with it); the paper's is
    ``FRAME_TO_FRAME``, every frame matched with the one before.
    ``follow``: how the keyframe's keypoints are found in the frames after it: ``match``, keypoints detected and
    described in every frame and matched with the keyframe's (``FeatureTracker``, the paper's way), or ``lk``,
    followed from frame to frame by pyramidal Lucas-Kanade and detected only on keyframes
    (``gpo.motion.following.KeypointFollower``).
    """

    detector: str = "orb"
    max_features: int = 500
    contrast_threshold: float = 0.04
    fast_threshold: int = 20
    scale: float = 1.0
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
    circular_binning: bool = True
    band_floor_px: float = LOCALISATION_PX
    short_side_px: float = SHORT_SIDE_PX
    keyframe: KeyframePolicy = field(default=FRAME_TO_FRAME)
    follow: str = "match"

    def __post_init__(self):
        if isinstance(self.roi, list):  # as YAML gives it
            object.__setattr__(self, "roi", tuple(self.roi))
        if isinstance(self.keyframe, dict):
            object.__setattr__(self, "keyframe", KeyframePolicy(**self.keyframe))
        check_rules(self._rules(), self, FeatureParametersOutOfRange)

    def _rules(self) -> dict[str, tuple[bool, str]]:
        """Each field: (whether its value is allowed, what is expected)."""
        roi = self.roi
        roi_ok = roi is None or (
            isinstance(roi, tuple)
            and len(roi) == 4
            and all(in_range(value, 0, MAX_IMAGE_PX, whole=True)[0] for value in roi)
            and min(roi[2:]) >= MIN_ROI_PX
        )
        cardinality_ok, cardinality = in_range(self.cardinality, 3, 10_000, " matches per loop", whole=True)
        flags = ("cross_check", "histogram_filter", "invariance_check", "circular_binning")
        return {
            "detector": (self.detector in DETECTORS, f"one of {', '.join(map(repr, DETECTORS))}"),
            "max_features": in_range(self.max_features, 1, 100_000, " keypoints", whole=True),
            "contrast_threshold": in_range(self.contrast_threshold, 0, 1, " (SIFT's)", low_open=True),
            "fast_threshold": in_range(self.fast_threshold, 1, 255, " grey levels (ORB's FAST)", whole=True),
            "scale": in_range(self.scale, 0, 1, ", the image's resize factor", low_open=True),
            "roi": (
                roi_ok,
                f"None or (u, v, width, height), whole pixels up to {MAX_IMAGE_PX}, width and height >= {MIN_ROI_PX}",
            ),
            "ratio": in_range(self.ratio, 0, 1, " (1: no ratio test)", low_open=True),
            **{name: (isinstance(getattr(self, name), bool), "True or False") for name in flags},
            "orientation_bins": in_range(self.orientation_bins, 1, 3600, " bins", whole=True),
            "length_bins": in_range(self.length_bins, 1, 10_000, " bins", whole=True),
            "invariance_threshold": in_range(self.invariance_threshold, 0, 1, ", a side ratio", low_open=True),
            "cardinality": (self.cardinality is None or cardinality_ok, f"None or {cardinality}"),
            "rounds": in_range(self.rounds, 1, 100_000, " loops", whole=True),
            "min_matches": in_range(self.min_matches, 2, 100_000, " matches", whole=True),
            "refit_px": in_range(self.refit_px, 0, 100, " px (0: no refit)"),
            "seed": (_whole(self.seed, 0), "a whole number >= 0"),
            "band_floor_px": in_range(self.band_floor_px, 0, 100, " px (0: plain mu +- sigma)"),
            "short_side_px": in_range(self.short_side_px, 0, 100, " px (0: every side judged)"),
            "keyframe": (isinstance(self.keyframe, KeyframePolicy), "a keyframe policy: min_overlap and max_frames"),
            "follow": (self.follow in FOLLOWERS, f"one of {', '.join(map(repr, FOLLOWERS))}"),
        }


@dataclass(frozen=True, eq=False)
class Keypoints:
    """A frame's keypoints: ``points`` (N, 2) pixels of the full image, ``descriptors`` (N, D) (uint8 for ORB,
    float32 for SIFT) and ``sizes`` (N,) keypoint diameters, pixels."""

    points: np.ndarray
    descriptors: np.ndarray
    sizes: np.ndarray

    def __len__(self) -> int:
        return len(self.points)


@dataclass(frozen=True, eq=False)
class Located:
    """Keypoints found but not yet described (``locate``): ``points`` (N, 2) pixels of the full image and ``sizes``
    (N,) diameters, pixels, as ``Keypoints``; ``described()`` gives them with their descriptors, computed on the
    first call (``describe``, None for keypoints that cannot be described: followed ones, ``gpo.motion.following``).
    """

    points: np.ndarray
    sizes: np.ndarray
    describe: Callable[[], np.ndarray] | None = field(default=None, repr=False)

    def __len__(self) -> int:
        return len(self.points)

    @cached_property
    def _descriptors(self) -> np.ndarray:
        if self.describe is None:
            raise FeatureError("these keypoints were followed, not detected: they have no descriptors of their own")
        return self.describe()

    def described(self) -> Keypoints:
        """The keypoints with their descriptors (computed once)."""
        return Keypoints(self.points, self._descriptors, self.sizes)


def detect(image: np.ndarray, parameters: FeatureParameters, mask=None) -> Keypoints:
    """The keypoints of a grey 8-bit ``image`` (H, W) whose descriptor support lies inside the image (the region of
    interest, if any) and off ``mask``, described.

    ``mask`` (H, W), optional: nonzero where the image may be used. The support is the disc of radius
    ``SUPPORT_PER_SIZE[detector] * size`` about the keypoint (ORB: size / 2, at least 15.5 px; SIFT: 3 size), in
    the pixels it was detected in (after ``scale``). A keypoint is dropped when that disc crosses the border of
    the image (or region of interest), or when a masked pixel lies within the radius plus half a pixel's diagonal
    of it (the distance to the mask is read at the keypoint's rounded pixel), on the keypoint itself included.
    """
    searched, usable, corner = _searched(image, parameters, mask)
    found, descriptors = _detector(parameters).detectAndCompute(searched, None if usable.all() else usable)
    if not found:
        return _no_keypoints(parameters.detector)
    inside, points, sizes = _placed(found, searched.shape, usable, corner, parameters)
    return Keypoints(points, descriptors[inside], sizes)


def locate(image: np.ndarray, parameters: FeatureParameters, mask=None) -> Located:
    """The keypoints ``detect`` finds in ``image`` (H, W), not yet described: their descriptors are computed when
    first asked for (``Located.described``), the same as ``detect``'s. Detecting alone costs SIFT about half of
    detecting and describing (the Gaussian pyramid is built again to describe)."""
    searched, usable, corner = _searched(image, parameters, mask)
    found = _detector(parameters).detect(searched, None if usable.all() else usable)
    if not found:
        empty = _no_keypoints(parameters.detector)
        return Located(empty.points, empty.sizes, lambda: empty.descriptors)
    inside, points, sizes = _placed(found, searched.shape, usable, corner, parameters)
    kept = [keypoint for keypoint, chosen in zip(found, inside, strict=True) if chosen]
    return Located(points, sizes, lambda: _described(searched, kept, parameters))


def _searched(image, parameters: FeatureParameters, mask) -> tuple[np.ndarray, np.ndarray, tuple[int, int]]:
    """The image keypoints are searched in (cut to the region of interest, resized by ``scale``), its mask (255 where
    usable) and the region's corner (u, v) in the full image."""
    image = _grey(image)
    usable = _usable(mask, image.shape)
    corner, image, usable = _region(image, usable, parameters.roi)
    scale = parameters.scale
    if scale != 1.0:
        image = cv2.resize(image, None, fx=scale, fy=scale, interpolation=cv2.INTER_AREA)
        area = cv2.resize(usable, image.shape[::-1], interpolation=cv2.INTER_AREA)
        usable = np.where(area == 255, 255, 0).astype(np.uint8)  # a pixel that saw any masked pixel is masked
    return image, usable, corner


def _placed(found, shape, usable, corner, parameters: FeatureParameters) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Which of the keypoints ``found`` in the searched image (H, W) keep their support clear (``detect``), and the
    kept ones' points (pixel centres of the full image) and sizes (diameters, full image pixels)."""
    points = np.array([keypoint.pt for keypoint in found], dtype=float)
    if parameters.detector == "orb":
        points = _orb_points(points, np.array([keypoint.octave for keypoint in found]), shape)
    sizes = np.array([keypoint.size for keypoint in found], dtype=float)
    inside = _support_clear(points, SUPPORT_PER_SIZE[parameters.detector] * sizes, usable)
    scale = parameters.scale
    return inside, (points[inside] + 0.5) / scale - 0.5 + corner, sizes[inside] / scale


def _described(searched: np.ndarray, found: list, parameters: FeatureParameters) -> np.ndarray:
    """The descriptors (N, D) of the keypoints ``found`` in the ``searched`` image."""
    if not found:
        return _no_keypoints(parameters.detector).descriptors
    described, descriptors = _detector(parameters).compute(searched, found)
    if len(described) != len(found):
        raise FeatureError(f"{len(found) - len(described)} of {len(found)} keypoints could not be described")
    return descriptors


def _grey(image) -> np.ndarray:
    if not isinstance(image, np.ndarray) or image.dtype != np.uint8 or image.ndim != 2 or min(image.shape) == 0:
        described = f"{image.dtype} {image.shape}" if isinstance(image, np.ndarray) else type(image).__name__
        raise FeatureError(f"keypoints need a grey 8-bit image (H, W), got {described}")
    return image


def _usable(mask, shape) -> np.ndarray:
    """``mask`` as 255 where usable, 0 where not (uint8, all 255 when there is none)."""
    if mask is None:
        return np.full(shape, 255, np.uint8)
    mask = np.asarray(mask)
    if mask.shape != shape:
        raise FeatureError(f"the mask is {mask.shape}, the image {shape}: they must be the same size")
    return np.where(mask != 0, 255, 0).astype(np.uint8)


def _region(image, usable, roi) -> tuple[tuple[int, int], np.ndarray, np.ndarray]:
    """The region of interest's corner (u, v) and the image and mask cut to it."""
    if roi is None:
        return (0, 0), image, usable
    u, v, width, height = roi
    if u + width > image.shape[1] or v + height > image.shape[0]:
        raise FeatureError(f"the roi {roi} reaches outside the {image.shape[1]} x {image.shape[0]} image")
    window = np.s_[v : v + height, u : u + width]
    return (u, v), image[window], usable[window]


def _detector(parameters: FeatureParameters):
    if parameters.detector == "orb":
        return cv2.ORB_create(
            nfeatures=parameters.max_features,
            scaleFactor=ORB_SCALE_FACTOR,
            nlevels=ORB_LEVELS,
            fastThreshold=parameters.fast_threshold,
        )
    # OpenCV's SIFT first doubles the image; by default its keypoints then lie a quarter of a pixel right of and
    # below the blobs they mark (opencv/opencv#23123); the precise upscale maps pixel x to 2x and puts them on them
    return cv2.SIFT_create(
        nfeatures=parameters.max_features,
        contrastThreshold=parameters.contrast_threshold,
        enable_precise_upscale=True,
    )


def _orb_points(reported: np.ndarray, levels: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """ORB's keypoints (N, 2) as pixel centres of the image (H, W) it searched.

    OpenCV's ORB finds a keypoint at a pixel of its pyramid level L, an image of round(W / s_L) x round(H / s_L)
    pixels (s_L = ``ORB_SCALE_FACTOR`` ** L, in float32) resized from level L - 1, and reports that pixel times
    s_L. A resize maps pixel centres, x_(L-1) = (x_L + 1/2) W_(L-1) / W_L - 1/2, so the reported point lies
    (s_L - 1) / 2 pixels, more or less with the rounding, up and left of the corner: more than a pixel on the
    coarsest levels. Here each level's point is followed down the pyramid as the resizes map it."""
    height, width = shape
    scales = np.float32(ORB_SCALE_FACTOR) ** np.arange(ORB_LEVELS, dtype=np.float32)
    sizes = np.rint(np.array([width, height], np.float32) / scales[:, None]).astype(float)  # as OpenCV's cvRound
    points = reported / scales[levels].astype(float)[:, None]  # pixels of the keypoint's level
    for level in range(int(levels.max(initial=0)), 0, -1):
        deeper = levels >= level
        points[deeper] = (points[deeper] + 0.5) * (sizes[level - 1] / sizes[level]) - 0.5
    return points


def _no_keypoints(detector: str) -> Keypoints:
    width, dtype, _ = DESCRIPTOR[detector]
    return Keypoints(np.zeros((0, 2)), np.zeros((0, width), dtype), np.zeros(0))


def _support_clear(points: np.ndarray, radius: np.ndarray, usable: np.ndarray) -> np.ndarray:
    """True where the disc of ``radius`` about each point lies inside the image and holds no masked pixel."""
    height, width = usable.shape
    low, high = points - radius[:, None], points + radius[:, None]
    inside = (low >= 0).all(axis=1) & (high <= [width - 1, height - 1]).all(axis=1)
    if usable.all():
        return inside
    clearance = cv2.distanceTransform(usable, cv2.DIST_L2, cv2.DIST_MASK_PRECISE)  # to the nearest masked pixel
    u, v = np.clip(np.rint(points).astype(int), 0, [width - 1, height - 1]).T
    return inside & (clearance[v, u] - np.sqrt(0.5) > radius)


def match(previous: Keypoints, current: Keypoints, parameters: FeatureParameters) -> np.ndarray:
    """Index pairs (M, 2), (previous index, current index), of the matches that pass the ratio test (and, with
    ``cross_check``, whose current keypoint's own best match is the previous one). Empty when either set is; the
    ratio test needs a second neighbour, so a single current keypoint matches only with the test off."""
    if len(previous) == 0 or len(current) == 0:
        return np.zeros((0, 2), dtype=int)
    matcher = cv2.BFMatcher(DESCRIPTOR[parameters.detector][2])
    neighbours = matcher.knnMatch(previous.descriptors, current.descriptors, k=2)
    pairs = [(n[0].queryIdx, n[0].trainIdx) for n in neighbours if _distinct(n, parameters.ratio)]
    pairs = np.array(pairs, dtype=int).reshape(-1, 2)
    if parameters.cross_check and len(pairs):
        best_previous = np.full(len(current), -1)
        for reverse in matcher.match(current.descriptors, previous.descriptors):
            best_previous[reverse.queryIdx] = reverse.trainIdx
        pairs = pairs[best_previous[pairs[:, 1]] == pairs[:, 0]]
    return pairs


def _distinct(neighbours, ratio: float) -> bool:
    """Lowe's ratio test on a descriptor's nearest ``neighbours`` (best first)."""
    if ratio == 1.0:
        return len(neighbours) > 0
    return len(neighbours) == 2 and neighbours[0].distance < ratio * neighbours[1].distance


@dataclass(frozen=True, eq=False)
class HistogramStage:
    """One histogram of the filter, for plotting: the ``values`` per match (degrees for the orientation, unwrapped to
    lie within 180 degrees of the histogram's centre; pixels for the length), the histogram (``counts``, ``edges``,
    as ``np.histogram``), its ``mean`` mu and ``sigma`` (NaN for an empty histogram) and which matches it ``kept``."""

    values: np.ndarray
    counts: np.ndarray
    edges: np.ndarray
    mean: float
    sigma: float
    kept: np.ndarray


def histogram_filter(
    start, end, orientation_bins: int = 180, length_bins: int = 160, circular: bool = True,
    band_floor_px: float = LOCALISATION_PX,
) -> tuple[np.ndarray, HistogramStage, HistogramStage | None]:
    """The paper's histogram filter on the match vectors d = ``end`` - ``start`` ((N, 2) each, pixels).

    Returns the mask of kept matches (N,), the orientation stage and the length stage (None when the first kept
    nothing). ``circular`` False bins as the paper does: the joining line's orientation, atan2(d_v, d_u) modulo 180
    degrees, every vector in ``orientation_bins`` bins over 0-180 degrees. With ``circular`` (the suite's rules):

    - mu and sigma are those of the histogram: the mean and standard deviation of the bin centres weighted by the
      counts, i.e. of the binned values (each value counts as its bin's centre, at most half a bin away).
    - Orientation is the full angle atan2(d_v, d_u), and angles wrap: the histogram is centred on the vectors'
      circular mean and covers 180 degrees about it in ``orientation_bins`` bins (one degree each by default), so
      vectors about +-180 degrees do not split, and motion in any direction is handled alike. A vector more than
      90 degrees from the circular mean points against the motion: it lies outside the histogram and is dropped.
    - A vector shorter than ``SHORT_VECTOR_PX`` has no orientation worth binning (half a pixel of error turns it
      by up to 30 degrees): it stays out of the orientation histogram and passes that stage; the length stage
      judges it. So a still frame (every vector about 0) passes, and keeps its matches.
    - The lengths kept by the first stage are binned in ``length_bins`` bins from the least to the greatest (or
      to ``LOCALISATION_PX`` above the least, if they lie closer together).
    - Each band is mu +- sigma, but never narrower than ``band_floor_px`` (``LOCALISATION_PX``) of motion: +-0.5 px
      in length and the angle 0.5 px makes at the vectors' median length in orientation. Vectors that differ by less
      than the keypoints' localisation are not told apart; in particular all equal vectors (sigma = 0) are all kept.
    """
    vectors = np.asarray(end, dtype=float) - np.asarray(start, dtype=float)
    lengths = np.hypot(vectors[:, 0], vectors[:, 1])
    orientation = _orientation_stage(vectors, lengths, orientation_bins, circular, band_floor_px)
    if not orientation.kept.any():
        return orientation.kept, orientation, None
    length = _length_stage(lengths, orientation.kept, length_bins, band_floor_px)
    return length.kept, orientation, length


def _orientation_stage(vectors, lengths, bins: int, circular: bool, band_floor_px: float) -> HistogramStage:
    angles = np.degrees(np.arctan2(vectors[:, 1], vectors[:, 0]))
    judged = lengths >= SHORT_VECTOR_PX if circular else np.ones(len(lengths), bool)
    centre = _circular_mean_deg(angles[judged]) if circular else 90.0
    values = centre + (angles - centre + 180.0) % 360.0 - 180.0 if circular else angles % 180.0
    counts, edges = np.histogram(values[judged], bins=bins, range=(centre - 90.0, centre + 90.0))
    mean, sigma = _binned_moments(counts, edges)
    floor = np.degrees(np.arctan2(band_floor_px, np.median(lengths[judged]))) if judged.any() else 0.0
    within = (np.abs(values - mean) <= max(sigma, floor)) & (np.abs(values - centre) <= 90.0)
    return HistogramStage(values, counts, edges, mean, sigma, ~judged | within)


def _length_stage(lengths: np.ndarray, among: np.ndarray, bins: int, band_floor_px: float) -> HistogramStage:
    low, high = lengths[among].min(), lengths[among].max()
    counts, edges = np.histogram(lengths[among], bins=bins, range=(low, max(high, low + LOCALISATION_PX)))
    mean, sigma = _binned_moments(counts, edges)
    kept = among & (np.abs(lengths - mean) <= max(sigma, band_floor_px))
    return HistogramStage(lengths, counts, edges, mean, sigma, kept)


def _circular_mean_deg(angles_deg: np.ndarray) -> float:
    """The direction of the mean unit vector of ``angles_deg``, degrees (0 for none)."""
    return float(np.degrees(np.angle(np.exp(1j * np.radians(angles_deg)).sum())))


def _binned_moments(counts: np.ndarray, edges: np.ndarray) -> tuple[float, float]:
    """The mean and standard deviation of a histogram: its bin centres weighted by their counts."""
    total = counts.sum()
    if total == 0:
        return float("nan"), float("nan")
    centres = 0.5 * (edges[:-1] + edges[1:])
    mean = float(centres @ counts / total)
    return mean, float(np.sqrt((centres - mean) ** 2 @ counts / total))


@dataclass(frozen=True, eq=False)
class InvarianceCheck:
    """Algorithm 1's work, for plotting: the ``loops`` tried (each (C,) match indices in loop order), which were
    ``kept_loops``, the matches ``kept`` (in at least one kept loop) and the ``cardinality`` C."""

    loops: list[np.ndarray]
    kept_loops: np.ndarray
    kept: np.ndarray
    cardinality: int


def choose_cardinality(matches: int) -> int:
    """C for ``matches`` matches: 3 below 12, 4 below 40, else 5. A longer loop is a stricter test (each of its C
    sides must keep its length), but a right match is kept only when all C - 1 others in its loop are right too,
    which takes many matches and few wrong ones."""
    return 3 if matches < 12 else 4 if matches < 40 else 5


def invariance_check(
    start, end, threshold: float = 0.85, cardinality: int | None = None, rounds: int = 3, rng=None,
    short_side_px: float = SHORT_SIDE_PX,
) -> InvarianceCheck:
    """The paper's Algorithm 1 on matched points ``start`` and ``end`` ((N, 2) each, pixels).

    Each of the ``rounds`` shuffles the matches (``rng``, a ``np.random.Generator``; None: seed 0) and cuts them into
    consecutive loops of C = ``cardinality`` (None: ``choose_cardinality``); the last, short loop is filled up with
    other matches drawn at random, so that every match is tested once a round. A loop p_1 -> ... -> p_C -> p_1 is
    kept when each side, of length l in the start frame and l^ in the end frame, has
    min(l, l^) / max(l, l^) >= ``threshold``; a side shorter than ``short_side_px`` in both frames is too short to
    judge (a pixel of error is half of ``SHORT_SIDE_PX``) and passes (0: every side judged, as the paper has it).
    A match is kept when it lies in at least one kept loop. With a share w of right matches, a right one is missed
    in all rounds with probability (1 - w^(C-1))^rounds: 0.7 % for w = 0.95, C = 5 and the default 3 rounds.
    Fewer matches than C: none is kept.
    """
    start, end = np.asarray(start, dtype=float), np.asarray(end, dtype=float)
    count = len(start)
    size = cardinality if cardinality is not None else choose_cardinality(count)
    rng = rng if rng is not None else np.random.default_rng(0)
    if count < size:
        return InvarianceCheck([], np.zeros(0, bool), np.zeros(count, bool), size)
    loops = np.concatenate([_partition(count, size, rng) for _ in range(rounds)])
    kept_loops = _sides_kept(start, loops, threshold, end, short_side_px).all(axis=1)
    kept = np.zeros(count, bool)
    kept[loops[kept_loops].ravel()] = True
    return InvarianceCheck(list(loops), kept_loops, kept, size)


def _partition(count: int, size: int, rng: np.random.Generator) -> np.ndarray:
    """One round's loops (count / size rounded up, size): a random order of the matches cut into consecutive groups,
    the last one filled up with matches drawn from the other groups."""
    order = rng.permutation(count)
    missing = -count % size
    if missing:
        last_start = count - (size - missing)
        order = np.concatenate([order, rng.choice(order[:last_start], missing, replace=False)])
    return order.reshape(-1, size)


def _sides_kept(start, loops: np.ndarray, threshold: float, end, short_side_px: float) -> np.ndarray:
    """Whether each side (loops, C) of each loop keeps its length from ``start`` to ``end``."""
    following = np.roll(loops, -1, axis=1)
    before, after = (np.linalg.norm(points[following] - points[loops], axis=2) for points in (start, end))
    shorter, longer = np.minimum(before, after), np.maximum(before, after)
    ratio = np.divide(shorter, longer, out=np.ones_like(longer), where=longer > 0)
    return (ratio >= threshold) | (longer < short_side_px)


@dataclass(frozen=True, eq=False)
class FeatureMatches:
    """One frame pair, everything the chapter draws: both frames' ``previous`` and ``current`` keypoints, the
    matches ``pairs`` (M, 2) after the ratio test and cross check, the stages' work (``histogram``: the orientation
    and length stages; ``invariance``; None when off or not reached), the matches ``kept`` (M,) by every stage that
    ran, the ``flag`` (None when measured, else why not) and the wall time in ``seconds`` of each stage that ran
    ("detect": the current frame's keypoints, "match", "histogram", "invariance"; for a frame matched again with the
    frame before, ``from_previous``, both matchings' times)."""

    previous: Keypoints
    current: Keypoints
    pairs: np.ndarray
    histogram: tuple[HistogramStage, HistogramStage | None] | None
    invariance: InvarianceCheck | None
    kept: np.ndarray
    flag: str | None
    seconds: dict
    from_previous: bool = False

    @property
    def counts(self) -> tuple[int, int, int, float, int, bool, bool]:
        """(matches, kept, kept, NaN, 0, False, False): a frame's record's counts (tracked, kept, inliers, spread in
        pixels, slower vectors, whole-view check, in doubt), as for a KLT flow
        (``gpo.motion.klt.FlowMeasurement.counts``)."""
        kept = int(self.kept.sum())
        return len(self.pairs), kept, kept, math.nan, 0, False, False

    @property
    def histogram_kept(self) -> np.ndarray:
        """Which matches (M,) the histogram filter kept (all when it did not run): the invariance check's input, in
        whose order ``invariance.loops`` count."""
        if self.histogram is None:
            return np.ones(len(self.pairs), bool)
        orientation, length = self.histogram
        return (length if length is not None else orientation).kept

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
    """Matches each frame's keypoints with a keyframe's: the frame before it, or with ``parameters.keyframe`` an earlier
    frame kept while enough of its matches hold (``gpo.motion.keyframes``). ``track(image, mask)`` returns the pair's
    ``FeatureMatches`` (None for the first frame); each image is detected once, its keypoints serving the frames
    after it. ``follow(keypoints)`` does the same with keypoints already detected, so that settings of the matching
    and the filters can be compared on one detection. ``restart()`` forgets the frames before. The invariance check
    draws from one generator, ``np.random.default_rng(parameters.seed)``, made here: the same frames give the same
    matches.

    A frame matched with a keyframe that keeps fewer than ``min_overlap`` of the matches its first frame kept (or is
    flagged) is matched again with the frame before it (``FeatureMatches.from_previous``) and becomes the keyframe:
    a keyframe half out of view leaves few matches, and a fit on few, on a glossy floor partly the reflections', turns
    the heading by a degree at once. The keyframe is also renewed after ``max_frames`` frames."""

    def __init__(self, parameters: FeatureParameters | None = None):
        self.parameters = parameters if parameters is not None else FeatureParameters()
        self._rng = np.random.default_rng(self.parameters.seed)
        self._previous: Keypoints | None = None
        self._keyframe: Keypoints | None = None
        self._frames = 0  # frames matched with the keyframe so far
        self._first_kept = 0  # matches kept by the first of them

    def restart(self) -> None:
        """Forget the frames before: the next ``track`` call starts afresh."""
        self._previous = self._keyframe = None
        self._frames = 0

    @property
    def keyframe_is_latest(self) -> bool:
        """Whether the next frame is matched with the latest one (the latest frame is the keyframe)."""
        return self._frames == 0

    def track(self, image: np.ndarray, mask=None) -> FeatureMatches | None:
        """The matches from the keyframe to ``image`` (H, W) uint8, ``mask`` as for ``detect``."""
        seconds = {}
        current = timed(seconds, "detect", detect, image, self.parameters, mask)
        return self.follow(current, seconds)

    def follow(self, current: Keypoints, seconds: dict | None = None) -> FeatureMatches | None:
        """The matches from the keyframe's keypoints to ``current`` (None for the first frame)."""
        keyframe, previous, self._previous = self._keyframe, self._previous, current
        if keyframe is None:
            self._keyframe, self._frames = current, 0
            return None
        measured = self.matches(keyframe, current, seconds)
        kept, frames, policy = int(measured.kept.sum()), self._frames + 1, self.parameters.keyframe
        first = kept if frames == 1 else self._first_kept
        holds = measured.flag is None and kept >= policy.min_overlap * first
        if frames > 1 and not holds:  # too little of the keyframe left: from the frame before, the new keyframe
            measured = replace(self.matches(previous, current, measured.seconds), from_previous=True)
        if holds and policy.keeps(kept, first, frames):
            self._frames, self._first_kept = frames, first
        else:
            self._keyframe, self._frames = current, 0
        return measured

    def matches(self, previous: Keypoints, current: Keypoints, seconds: dict | None = None) -> FeatureMatches:
        """Match two frames' keypoints and filter the matches with the stages the parameters switch on, stopping
        at the first that leaves too few."""
        return matched(previous, current, self.parameters, self._rng, seconds)


def matched(
    previous: Keypoints, current: Keypoints, parameters: FeatureParameters, rng: np.random.Generator,
    seconds: dict | None = None,
) -> FeatureMatches:
    """Two frames' keypoints matched (``match``) and ``filtered``; the wall time of each stage is added to a copy of
    ``seconds``."""
    seconds = dict(seconds or {})
    pairs = timed(seconds, "match", match, previous, current, parameters)
    flag = _too_few_to_filter(len(previous), len(current), len(pairs), parameters.min_matches)
    return filtered(previous, current, pairs, parameters, rng, seconds, flag)


def filtered(
    previous: Keypoints, current: Keypoints, pairs: np.ndarray, parameters: FeatureParameters,
    rng: np.random.Generator, seconds: dict, flag: str | None = None,
) -> FeatureMatches:
    """The matches ``pairs`` (M, 2) of ``previous`` and ``current`` through the filters ``parameters`` switch on (the
    histogram filter, then the invariance check drawing from ``rng``), stopping at the first that leaves too few;
    ``flag``: why they are not filtered at all (too few to start with). Each stage's wall time is added to
    ``seconds``, which the result keeps."""
    p = parameters
    start, end = previous.points[pairs[:, 0]], current.points[pairs[:, 1]]
    kept, histogram, invariance = np.ones(len(pairs), bool), None, None
    if flag is None and p.histogram_filter:
        bins = (p.orientation_bins, p.length_bins, p.circular_binning, p.band_floor_px)
        kept, *stages = timed(seconds, "histogram", histogram_filter, start, end, *bins)
        histogram = tuple(stages)
        flag = _too_few_left(int(kept.sum()), "histogram filter", p.min_matches)
    if flag is None and p.invariance_check:
        chosen = np.flatnonzero(kept)
        check = (start[chosen], end[chosen], p.invariance_threshold, p.cardinality, p.rounds, rng, p.short_side_px)
        invariance = timed(seconds, "invariance", invariance_check, *check)
        kept = np.zeros(len(pairs), bool)
        kept[chosen[invariance.kept]] = True
        flag = _too_few_left(int(kept.sum()), "invariance check", p.min_matches)
    return FeatureMatches(previous, current, pairs, histogram, invariance, kept, flag, seconds)


def timed(seconds: dict, stage: str, function, *arguments):
    """``function(*arguments)``, its wall time added to ``seconds[stage]``."""
    started = time.perf_counter()
    result = function(*arguments)
    seconds[stage] = seconds.get(stage, 0.0) + time.perf_counter() - started
    return result


def _too_few_to_filter(previous: int, current: int, pairs: int, min_matches: int) -> str | None:
    if min(previous, current) < min_matches:
        return f"too few keypoints: {previous} and {current} (at least {min_matches} in each frame)"
    if pairs < min_matches:
        return f"too few matches: {pairs} of {previous} and {current} keypoints (at least {min_matches})"
    return None


def _too_few_left(kept: int, stage: str, min_matches: int) -> str | None:
    if kept == 0:
        return f"all matches rejected by the {stage}"
    if kept < min_matches:
        return f"too few matches left by the {stage}: {kept} (at least {min_matches})"
    return None
