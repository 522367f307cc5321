"""How the floor image moves from frame to frame: Shi-Tomasi corners, pyramidal Lucas-Kanade, the median vector.

Chapter 05. ``FloorFlow`` keeps a set of tracked corners on the floor image (the ortho-GPI, a metric top view,
``gpo.floor_image``) and re-detects them (``cv2.goodFeaturesToTrack``) when too few are left. For each new frame it
tracks them with pyramidal Lucas-Kanade (``cv2.calcOpticalFlowPyrLK``), each search starting where the previous
frame's median motion predicts, so that the pyramid has to find only the change of motion, not the motion. Then
it tracks the results back to the previous frame from the same prediction and keeps the tracks that return to
where they started (the forward-backward check). Once the motion is known (the previous frame was measured), the
backward search runs on the full-resolution image only: a right track is then a few pixels from its start.
The kept tracks' vectors give the frame's **median** motion vector, robust to the outliers that moving objects
and highlights make, and the mean, for the first paper's comparison (its Table 3).

With a ``KeyframePolicy`` (``gpo.motion.keyframes``) of more than one frame, the tracks are measured from a keyframe
instead of the previous frame: the keyframe's corners are followed into each new frame, each search starting where the
track was in the previous frame plus the median motion, until too few of them are left or the policy's frames are
used up; then the latest frame becomes the keyframe (its corners detected afresh). A measurement's ``start`` points
then lie in the keyframe, and ``keyframe_is_latest`` says when the next frame is measured from the latest one.

Each frame gets a ``FlowQuality``; a frame that cannot be measured is flagged with the reason, never turned into
a wrong vector: no texture (no local contrast beyond the sensor's noise, ``floor_texture``), too few corners, too
few tracks kept (a bad frame, motion blur), vectors that disagree (no consensus), or a change of motion near the
pyramid's reach (too fast).

A frame may hold a second, slower layer of vectors (``FlowQuality.slower``): a glossy floor's reflections of the
ceiling's lights move through the floor image at a few hundredths of the floor's speed (``gpo.motion.layers``); on
a screed whose own grain is fainter they are much of the texture the corners find, pull the median short, and no
check above fails. The frame is not flagged for them (the median is still the best estimate at hand); the run's
summary counts such frames (``pipeline.OdometryResult.summary``), and the whole-view check
(``gpo.motion.overview``) and ``floor_layer`` (for ``gpo-exact``) tell the floor's motion from theirs.

Each floor image is first levelled (``gpo.motion.levelling``: exposure flicker and vignetting break Lucas-Kanade's
constant brightness). Pixels (u, v): u right, v down, as OpenCV.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import cv2
import numpy as np

from gpo.motion.keyframes import FRAME_TO_FRAME, KeyframePolicy
from gpo.motion.layers import layered, slower_count, slower_layer
from gpo.motion.levelling import levelled
from gpo.motion.median import median_of
from gpo.motion.overview import Overview, OverviewShift, Schedule, disagrees, replaces_median
from gpo.motion.ranges import check_rules, in_range
from gpo.motion.turned_view import TurnedView

MAD_TO_SIGMA = 1.4826  # the median absolute deviation of a normal distribution times this is its sigma


CONTRAST_BOX_PX = 41  # the local mean for the texture measure when there is no flat field


TEXTURE_LAG_PX = 3  # the texture measure compares the floor image with itself this far away (see floor_texture)


OVERVIEW_GRID = 4  # the whole-view check's measurement: this many by this many points over the image's middle half
WARY_FLOOR = 1 / 3  # a wary check's tolerance never below this share of overview_tolerance_px: on the population's
# matte floors the whole view's shift scatters about the tracks' median by 0.2-0.27 px (median), 0.4-0.8 px (p90)


class FlowError(ValueError):
    """A floor image the tracker cannot use (wrong type, wrong size)."""


@dataclass(frozen=True)
class KLTParameters:
    """Corner detection and Lucas-Kanade tracking on a floor image.

    ``max_corners``, ``quality_level`` and ``min_distance_px``, ``block_size``: ``cv2.goodFeaturesToTrack``.
    ``window_px`` (odd) and ``pyramid_levels``: ``cv2.calcOpticalFlowPyrLK``'s window and pyramid; the pyramid
    reaches a motion of about ``window_px / 2 * 2**pyramid_levels`` pixels. ``max_iterations`` and ``epsilon_px``:
    its stopping rule. ``forward_backward_px``: a track is kept when tracking it back ends this close to where it
    started. ``redetect_below``: fewer tracks than this left, corners are detected afresh (frame-to-frame; a keyframe's
    corners are detected afresh at every keyframe). ``min_tracks`` and
    ``min_kept_ratio``: fewer kept than this many, or than this share of the tracks followed, the frame is flagged.
    ``inlier_px``: a vector is an inlier when it lies this close to the median, or within three robust sigmas of
    it if they are wider; fewer than ``min_inlier_ratio`` of the kept vectors inliers flags the frame (no
    consensus). Two groups of tracks of about equal size (the floor and something moving by itself) widen the
    spread until every vector counts: the median then lies between them and nothing flags it.
    ``min_texture_grey``: a floor image whose local contrast beyond the sensor's noise (``floor_texture``, grey
    levels) is lower holds nothing to track, and the frame is flagged.
    ``flat_field_px``: each image is divided by its mean over boxes this wide before tracking, which removes slow
    brightness gradients (0: not). ``normalise_brightness``: False tracks the images as they come (no flat field,
    no common mean and contrast), to see what the normalisation is for.
    ``overview_scale``: the whole-view check (``gpo.motion.overview``) correlates views this many times wider and
    longer than the floor image (0: no check; the estimators that take it say so); ``overview_tolerance_px``: a flow
    median within this of the overview's shift's line and short of it along the line by more (floor-image pixels), or
    further than this from it and further from the predicted motion, is replaced by it
    (``gpo.motion.overview.replaces_median``), when the overview's correlation peak reaches ``overview_min_peak``.
    ``overview_wary_share``: once the tracks and the whole view have disagreed, the next frame's tracks must come
    within this share of the overview's shift (never nearer than ``WARY_FLOOR`` of ``overview_tolerance_px``, the
    whole view's own scatter) to count as agreeing, until a frame's do (0: the tolerance stays fixed). On a glossy
    screed the corners detected afresh after the overview took over are mostly the reflections' edges, and the first
    frame measured from them read the floor's motion 30-40 % short while lying within ``overview_tolerance_px`` of the
    overview's shift (population draw 8: 4-5 pixels a frame); see ``FloorFlow.track``.
    """

    max_corners: int = 150
    quality_level: float = 0.01
    min_distance_px: float = 8.0
    block_size: int = 7
    window_px: int = 21
    pyramid_levels: int = 3
    max_iterations: int = 20
    epsilon_px: float = 0.03
    forward_backward_px: float = 0.5
    redetect_below: int = 60
    min_tracks: int = 12
    min_kept_ratio: float = 0.3
    inlier_px: float = 1.0
    min_inlier_ratio: float = 0.5
    min_texture_grey: float = 1.5
    flat_field_px: int = 41
    normalise_brightness: bool = True
    overview_scale: float = 2.0
    overview_tolerance_px: float = 1.5
    overview_min_peak: float = 0.3  # pairs of independent noise images peak at up to 0.11, floors at 0.6-0.9
    overview_wary_share: float = 0.15

    def __post_init__(self):
        check_rules(self._ranges(), self)

    def _ranges(self) -> dict[str, tuple[bool, str]]:
        """Each parameter: whether its value lies in the range a real rig can use, and that range with its unit."""
        window_ok, _ = in_range(self.window_px, 5, 101, whole=True)
        flat_ok, _ = in_range(self.flat_field_px, 3, 1001, whole=True)
        overview_ok, _ = in_range(self.overview_scale, 1.5, 8)
        return {
            "max_corners": in_range(self.max_corners, 1, 10_000, " corners", whole=True),
            "quality_level": in_range(self.quality_level, 0, 1, ", a share of the best corner's score", low_open=True),
            "min_distance_px": in_range(self.min_distance_px, 0, 1000, " px"),
            "block_size": in_range(self.block_size, 3, 63, " px", whole=True),
            "window_px": (window_ok and self.window_px % 2 == 1, "an odd whole number from 5 to 101 px"),
            "pyramid_levels": in_range(self.pyramid_levels, 0, 8, " levels", whole=True),
            "max_iterations": in_range(self.max_iterations, 1, 1000, " iterations", whole=True),
            "epsilon_px": in_range(self.epsilon_px, 0, 10, " px", low_open=True),
            "forward_backward_px": in_range(self.forward_backward_px, 0, 100, " px", low_open=True),
            "redetect_below": in_range(self.redetect_below, 0, 10_000, " tracks", whole=True),
            "min_tracks": in_range(self.min_tracks, 2, 10_000, " tracks", whole=True),
            "min_kept_ratio": in_range(self.min_kept_ratio, 0, 1, ", a share of the tracks followed"),
            "inlier_px": in_range(self.inlier_px, 0, 100, " px", low_open=True),
            "min_inlier_ratio": in_range(self.min_inlier_ratio, 0, 1, ", a share of the kept vectors"),
            "min_texture_grey": in_range(self.min_texture_grey, 0, 255, " grey levels"),
            "flat_field_px": (self.flat_field_px == 0 or flat_ok, "0 (none) or a whole number from 3 to 1001 px"),
            "overview_scale": (self.overview_scale == 0 or overview_ok, "0 (no check) or a number from 1.5 to 8"),
            "overview_tolerance_px": in_range(self.overview_tolerance_px, 0, 100, " px", low_open=True),
            "overview_min_peak": in_range(self.overview_min_peak, 0, 1, ", a share of the correlation"),
            "overview_wary_share": in_range(self.overview_wary_share, 0, 1, ", a share of the overview's shift"),
        }

    @property
    def reach_px(self) -> float:
        """The largest motion the pyramid can follow, about half a window at the coarsest level, pixels."""
        return self.window_px / 2 * 2**self.pyramid_levels


@dataclass(frozen=True)
class FlowQuality:
    """How well a frame's motion was measured.

    ``tracked``: tracks followed from the previous frame; ``kept``: those passing the forward-backward check;
    ``inliers``: kept vectors near the median; ``spread_px``: their robust standard deviation (1.4826 MAD),
    pixels; ``flag``: None when the frame is measured, else why it is not; ``slower``: kept vectors moving along
    the median at under ``SLOWER_SPEED`` of its length, once it is ``SLOWER_MIN_PX`` long (a slower layer, such
    as reflections; see the module); ``overview``: the frame's motion is the whole-view check's
    (``gpo.motion.overview``), the tracks having disagreed with it; ``disagreed``: the tracks and the whole-view
    check disagreed (``gpo.motion.overview.disagrees``), or the check measured a flagged frame: whichever measured
    it, the frame's motion is in doubt (the fused route does not fuse it, ``gpo.fusion.streaming``); ``layers``: the
    kept tracks since the keyframe may move in two layers (``gpo.motion.layers.layered``).
    """

    tracked: int
    kept: int
    inliers: int
    spread_px: float
    flag: str | None = None
    slower: int = 0
    overview: bool = False
    disagreed: bool = False
    layers: bool = False

    @property
    def ok(self) -> bool:
        return self.flag is None

    @property
    def inlier_ratio(self) -> float:
        return self.inliers / self.kept if self.kept else 0.0

    @property
    def slower_layer(self) -> bool:
        """Whether at least ``SLOWER_LAYER_SHARE`` of the kept vectors move in a slower layer."""
        return slower_layer(self.slower, self.kept)


@dataclass(frozen=True, eq=False)
class FlowMeasurement:
    """One frame's floor motion: kept tracks from ``start`` (N, 2) to ``end`` (N, 2) pixels, their ``median`` and
    ``mean`` vectors (2,) pixels (NaN when flagged), the ``inlier`` mask (N,) and the ``quality``."""

    start: np.ndarray
    end: np.ndarray
    median: np.ndarray
    mean: np.ndarray
    inlier: np.ndarray
    quality: FlowQuality

    @property
    def vectors(self) -> np.ndarray:
        """The kept tracks' motion vectors (N, 2), pixels."""
        return self.end - self.start

    @property
    def flag(self) -> str | None:
        """Why the frame's motion could not be measured (``quality.flag``), or None."""
        return self.quality.flag

    @property
    def from_previous(self) -> bool:
        """Whether the motion was measured from the frame before, not from the keyframe (the whole-view check's
        shift, ``gpo.motion.overview``)."""
        return self.quality.overview

    @property
    def counts(self) -> tuple[int, int, int, float, int, bool, bool]:
        """(tracked, kept, inliers, spread in pixels, vectors in a slower layer, measured by the whole-view check,
        in doubt), as a frame's record holds them."""
        q = self.quality
        return q.tracked, q.kept, q.inliers, q.spread_px, q.slower, q.overview, q.disagreed


@dataclass(frozen=True, eq=False)
class FlowFrame:
    """A floor image made ready to track (``FloorFlow.prepare``): flat-fielded and scaled to one mean and contrast
    (``image``, uint8), with its local contrast beyond noise (``texture``, grey levels; ``floor_texture``) and the
    wider view the whole-view check correlates (``wide``: the view, or what makes it; None without the check), made
    when first read (``overview``): the check runs in the frames that need it (``gpo.motion.overview.Schedule``)."""

    image: np.ndarray
    texture: float
    wide: np.ndarray | Callable[[], np.ndarray] | None = None

    @functools.cached_property
    def overview(self) -> np.ndarray | None:
        """The wider view the whole-view check correlates (float32), or None without the check."""
        wide = self.wide() if callable(self.wide) else self.wide
        return None if wide is None else wide.astype(np.float32)


@dataclass
class FloorFlow:
    """KLT tracking on a stream of floor images of one size, each frame against the one before it or, with a
    ``keyframe`` policy of more than one frame, against a keyframe (see the module).

    ``mask`` (H, W) bool or uint8, optional: where corners may be detected (the floor image's valid pixels);
    it is shrunk by half a window so that no corner's window leaves it. Call ``track(image)`` once per
    frame in order; the first frame only starts the tracks and returns None. ``restart()`` drops them (after a
    gap, or a flagged frame that broke the chain).
    """

    parameters: KLTParameters = field(default_factory=KLTParameters)
    mask: np.ndarray | None = None
    keyframe: KeyframePolicy = FRAME_TO_FRAME
    _image: np.ndarray | None = field(default=None, init=False, repr=False)  # the keyframe (or the previous frame)
    _texture: float = field(default=0.0, init=False, repr=False)
    _velocity: np.ndarray = field(default_factory=lambda: np.zeros(2, np.float32), init=False, repr=False)
    _predicted: bool = field(default=False, init=False, repr=False)
    _time_s: float = field(default=0.0, init=False, repr=False)
    _points: np.ndarray | None = field(default=None, init=False, repr=False)  # tracks to follow, in the keyframe
    _last: np.ndarray | None = field(default=None, init=False, repr=False)  # where they were in the latest frame
    _corners: int = field(default=0, init=False, repr=False)  # the keyframe's tracks at its start
    _frames: int = field(default=0, init=False, repr=False)  # frames measured against the keyframe so far
    _fresh: bool = field(default=False, init=False, repr=False)  # the keyframe's tracks are corners detected in it
    _detect_mask: np.ndarray | None = field(default=None, init=False, repr=False)
    _valid: np.ndarray | None = field(default=None, init=False, repr=False)
    _size: tuple[int, int] | None = field(default=None, init=False, repr=False)
    _overview: Overview | None = field(default=None, init=False, repr=False)
    _schedule: Schedule = field(default_factory=Schedule, init=False, repr=False)  # when the whole-view check runs
    _view: FlowFrame | None = field(default=None, init=False, repr=False)  # the latest frame, for its wider view
    _wary: bool = field(default=False, init=False, repr=False)  # the last frame's tracks and whole view disagreed

    def restart(self) -> None:
        """Forget the previous frame: the next ``track`` call starts afresh."""
        self._image, self._points, self._last, self._frames = None, None, None, 0
        self._overview, self._schedule, self._view, self._wary = None, Schedule(), None, False
        self._velocity, self._predicted = np.zeros(2, np.float32), False

    @property
    def keyframe_is_latest(self) -> bool:
        """Whether the next frame is measured from the latest frame tracked (it became the keyframe), not from an
        earlier one."""
        return self._frames == 0

    def prepare(self, image: np.ndarray, overview: np.ndarray | Callable[[], np.ndarray] | None = None) -> FlowFrame:
        """``image`` (H, W) uint8 made ready to track (``FlowFrame``), with the wider ``overview`` of the same frame (or
        what makes it, called when the check needs it) when the whole-view check runs
        (``KLTParameters.overview_scale``). It depends on the frame alone, so frames can be prepared ahead, in another
        thread, while earlier ones are tracked."""
        self._check(image)
        return FlowFrame(*self._normalised(image), overview)

    def track(self, image: np.ndarray | FlowFrame, time_s: float | None = None) -> FlowMeasurement | None:
        """The motion from the keyframe (the previous frame, frame-to-frame) to ``image`` (H, W) uint8, or to the
        frame ``prepare`` made of it; None for the first frame.

        ``time_s``: the frame's time in seconds, so that the predicted motion scales with the time since the
        previous frame (a dropped frame doubles it); None counts frames instead.

        After a frame whose tracks and whole view disagreed the check is wary (``KLTParameters.overview_wary_share``):
        a smaller disagreement puts the frame in doubt, and the whole view's shift replaces the tracks' median when it
        lies nearer the predicted motion, until the tracks agree with it again
        (``gpo.motion.overview.replaces_median``).
        """
        if isinstance(image, FlowFrame):
            self._check(image.image)  # it may come from another tracker's ``prepare``
        else:
            image = self.prepare(image)
        previous_view, self._view = self._view, image
        view, image, texture = image, image.image, image.texture
        reference, points, last = self._image, self._points, self._last
        elapsed = 1.0 if time_s is None or reference is None else time_s - self._time_s
        self._time_s = 0.0 if time_s is None else time_s
        if reference is None:
            self._new_keyframe(image, texture, self._detect(image), detected=True)
            return None
        if min(texture, self._texture) < self.parameters.min_texture_grey:
            flag = f"no texture: local contrast {min(texture, self._texture):.1f} grey levels"
            nothing = np.zeros((0, 2), np.float32)
            self._new_keyframe(image, texture, nothing)
            self._predicted = False
            return _flagged(nothing, nothing, 0, flag)
        if not self._fresh and len(points) < self.parameters.redetect_below:
            self._new_keyframe(reference, self._texture, self._detect(reference), detected=True)
            points, last = self._points, self._last
        prediction = (self._velocity * elapsed).astype(np.float32)
        measurement, kept, frame_median = self._measure(reference, image, points, last, prediction)
        found = self._observe(previous_view, view, measurement)
        if found is not None:
            measurement = self._checked(measurement, found, frame_median, prediction, self._wary_tolerance(found))
            self._wary = measurement.quality.disagreed
            if measurement.quality.disagreed:
                self._schedule.alert()
        if measurement.quality.overview:  # a translation from the previous frame: the next start from this one
            self._velocity, self._predicted = (measurement.median / elapsed).astype(np.float32), True
            self._new_keyframe(image, texture, self._detect(image), detected=True)
            return measurement
        self._predicted = measurement.quality.ok
        if measurement.quality.ok:
            self._velocity = (frame_median / elapsed).astype(np.float32)
        self._frames += 1
        followed = len(measurement.start)
        if measurement.quality.ok and self.keyframe.keeps(followed, self._corners, self._frames):
            self._points, self._last = measurement.start, measurement.end
        else:
            self._new_keyframe(image, texture, measurement.end if kept is not None else points)
        return measurement

    def _new_keyframe(self, image: np.ndarray, texture: float, points: np.ndarray, detected: bool = False) -> None:
        """``image`` becomes the keyframe, ``points`` (N, 2) its tracks to follow (the tracks that reached it), or,
        with keyframes of more than one frame, its own corners detected afresh, spread over the whole floor image."""
        if not detected and self.keyframe.max_frames > 1:
            points, detected = self._detect(image), True
        self._image, self._texture, self._points, self._last = image, texture, points, points
        self._corners, self._frames, self._fresh = len(points), 0, detected

    def _measure(
        self, reference, image, points, last, prediction
    ) -> tuple[FlowMeasurement, np.ndarray | None, np.ndarray | None]:
        """The tracks from ``points`` (N, 2) in ``reference`` to ``image``, each search starting where the track was
        in the latest frame (``last``, N, 2) moved by ``prediction`` (2,) pixels: the measurement, which of the points
        it kept (None: too few to follow) and the median of the kept tracks' motions since the latest frame (pixels).

        The frame's quality (the spread of the motions, the inliers, their consensus, a slower layer) is read from
        the tracks' motions since the latest frame, which is the whole measurement frame-to-frame: measured from a
        keyframe, the motion across the patch also differs by the turn since the keyframe, which is no error."""
        p = self.parameters
        nothing = np.zeros((0, 2), np.float32)
        if len(points) < p.min_tracks:
            flag = f"too few corners ({len(points)} < {p.min_tracks}): no texture to track"
            return _flagged(nothing, nothing, len(points), flag), None, None
        criteria = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, p.max_iterations, p.epsilon_px)
        window = (p.window_px, p.window_px)
        start = points.reshape(-1, 1, 2)
        shift = ((last - points) + prediction).reshape(-1, 1, 2)
        guess = (start + shift).reshape(-1, 2)  # where each search starts
        turn = None if self.keyframe.max_frames == 1 else TurnedView.between(points, guess, image.shape)
        if turn is not None:  # the frame turned back onto the keyframe, the searches' starts with it
            image = turn.view(image)
            shift = turn.to_view(guess).reshape(-1, 1, 2) - start
        lk = {"winSize": window, "maxLevel": p.pyramid_levels, "criteria": criteria}
        lk["flags"] = cv2.OPTFLOW_USE_INITIAL_FLOW
        end, status, _ = cv2.calcOpticalFlowPyrLK(reference, image, start, start + shift, **lk)
        if self._predicted:
            lk["maxLevel"] = 0
        back, back_status, _ = cv2.calcOpticalFlowPyrLK(image, reference, end, end - shift, **lk)
        start, end, back = start.reshape(-1, 2), end.reshape(-1, 2), back.reshape(-1, 2)
        found = end - start - shift.reshape(-1, 2)  # what the pyramid had to find beyond each search's start
        if turn is not None:
            end = turn.from_view(end)
        keep = (status.ravel() == 1) & (back_status.ravel() == 1)
        keep &= np.einsum("ij,ij->i", back - start, back - start) < p.forward_backward_px**2
        keep &= self._inside(end)
        start, end, found = start[keep], end[keep], found[keep]
        if len(start) < max(p.min_tracks, p.min_kept_ratio * len(points)):
            flag = f"too few tracks kept ({len(start)} of {len(points)}): a bad or blurred frame"
            return _flagged(start, end, len(points), flag), keep, None
        vectors, moved = end - start, end - last[keep]  # since the keyframe; since the latest frame
        frame_median = median_of(moved, axis=0)
        distance = np.hypot(*(moved - frame_median).T)
        spread = MAD_TO_SIGMA * float(median_of(distance))
        inlier = distance <= max(p.inlier_px, 3.0 * spread)
        slower = slower_count(moved, frame_median)
        layers = layered(vectors)
        quality = FlowQuality(len(points), len(start), int(inlier.sum()), spread, slower=slower, layers=layers)
        flag = None
        change = np.hypot(*median_of(found, axis=0))
        if quality.inlier_ratio < p.min_inlier_ratio:
            flag = f"no consensus: {quality.inliers} of {quality.kept} vectors near the median"
        elif change > 0.8 * p.reach_px:
            flag = f"too fast: the motion changed by {change:.0f} px, near the pyramid's reach {p.reach_px:.0f} px"
        if flag:
            return _flagged(start, end, len(points), flag, inlier, spread), keep, None
        median = frame_median if last is points else median_of(vectors, axis=0)
        measurement = FlowMeasurement(start, end, median, vectors.mean(axis=0), inlier, quality)
        return measurement, keep, frame_median

    def _observe(self, previous: FlowFrame | None, frame: FlowFrame, measured: FlowMeasurement) -> OverviewShift | None:
        """The whole-view check's shift from the ``previous`` frame's wider view to ``frame``'s
        (``gpo.motion.overview``), or None: no check, no previous frame, or the check not due (``Schedule``: the
        tracks ``measured`` flagged, the check wary and two layers of tracks each make it due)."""
        if frame.wide is None or previous is None or previous.wide is None:
            return None
        needed = measured.flag is not None or self._wary or measured.quality.layers
        if not self._schedule.due(needed):
            return None
        before, view = previous.overview, frame.overview
        if self._overview is None:
            self._overview = Overview(self.parameters.overview_scale, view.shape[::-1])
        return self._overview.shift(before, view)

    def _wary_tolerance(self, found: OverviewShift) -> float | None:
        """After a frame in doubt, how far (floor-image pixels) the tracks' median may lie from the overview's shift
        ``found`` and still agree with it: ``overview_wary_share`` of the shift's length, within ``WARY_FLOOR`` of
        ``overview_tolerance_px`` and that tolerance itself (``KLTParameters``); None when the check is not wary."""
        p = self.parameters
        if not (self._wary and p.overview_wary_share):
            return None
        wary = p.overview_wary_share * float(np.hypot(*found.shift_px))
        return min(p.overview_tolerance_px, max(WARY_FLOOR * p.overview_tolerance_px, wary))

    def _checked(
        self, measurement: FlowMeasurement, found: OverviewShift, moved: np.ndarray, predicted: np.ndarray,
        wary_px: float | None,
    ) -> FlowMeasurement:
        """``measurement``, or where the whole-view check's shift replaces the tracks' median motion since the previous
        frame (``moved``; ``predicted``: the motion predicted from the frame before; ``gpo.motion.overview``), that
        shift measured at the floor image's middle from the previous frame: a ``OVERVIEW_GRID`` square grid of
        points. ``wary_px``: after a frame in doubt, how far apart (pixels) they still agree (``_wary_tolerance``)."""
        p = self.parameters
        tolerance = p.overview_tolerance_px
        if not replaces_median(moved, measurement.flag, found, predicted, tolerance, p.overview_min_peak, wary_px):
            if measurement.flag is None and disagrees(moved, found, wary_px or tolerance, p.overview_min_peak):
                return replace(measurement, quality=replace(measurement.quality, disagreed=True))
            return measurement
        width, height = self._size
        u, v = np.meshgrid(*(np.linspace(0.25, 0.75, OVERVIEW_GRID) * (side - 1) for side in (width, height)))
        start = np.column_stack([u.ravel(), v.ravel()]).astype(np.float32)
        shift, count = found.shift_px, len(start)
        quality = FlowQuality(count, count, count, float("nan"), overview=True, disagreed=True)
        return FlowMeasurement(start, start + shift.astype(np.float32), shift, shift, np.ones(count, bool), quality)

    def _check(self, image: np.ndarray) -> None:
        if not isinstance(image, np.ndarray) or image.dtype != np.uint8 or image.ndim != 2:
            raise FlowError(f"a floor image is a 2-D uint8 array, got {getattr(image, 'dtype', type(image))}")
        size = image.shape[::-1]
        if self._size is None:
            self._size = size
            self._valid = None if self.mask is None or self.mask.all() else self.mask.astype(np.uint8)
            self._detect_mask = self._shrunk_mask(image.shape)
        elif size != self._size:
            raise FlowError(f"floor image size changed from {self._size} to {size} (width, height)")

    def _normalised(self, image: np.ndarray) -> tuple[np.ndarray, float]:
        """``image`` levelled over the mask (``gpo.motion.levelling``: on the simulated T265 rig the vignetting turned
        the rigid fit's rotations 1 % short, which the flat field removes), and its local contrast beyond noise in
        grey levels (``floor_texture``)."""
        size = self.parameters.flat_field_px or CONTRAST_BOX_PX
        floor = image.astype(np.float32)
        local_mean = cv2.blur(floor, (size, size))
        texture = floor_texture(floor - local_mean, self._valid)
        if not self.parameters.normalise_brightness:
            return image, texture
        return levelled(floor, local_mean if self.parameters.flat_field_px else None, self._valid), texture

    def _shrunk_mask(self, shape) -> np.ndarray:
        """Where a corner's whole window lies inside the mask and the image."""
        inside = np.zeros(shape, np.uint8)
        if self.mask is None:
            inside[:] = 255
        else:
            if self.mask.shape != shape:
                raise FlowError(f"mask shape {self.mask.shape} differs from the floor image's {shape}")
            inside[self.mask.astype(bool)] = 255
        half = self.parameters.window_px // 2 + 1
        inside = cv2.erode(inside, np.ones((2 * half + 1, 2 * half + 1), np.uint8))  # the image's edge does not erode
        inside[:half], inside[-half:], inside[:, :half], inside[:, -half:] = 0, 0, 0, 0
        return inside

    def _detect(self, image: np.ndarray) -> np.ndarray:
        p = self.parameters
        corners = cv2.goodFeaturesToTrack(
            image, p.max_corners, p.quality_level, p.min_distance_px, mask=self._detect_mask, blockSize=p.block_size
        )
        return np.zeros((0, 2), np.float32) if corners is None else corners.reshape(-1, 2)

    def _inside(self, points: np.ndarray) -> np.ndarray:
        """Tracks whose end still has its window inside the image (the mask's shrunk region at the rounded pixel)."""
        width, height = self._size
        u, v = np.rint(points[:, 0]).astype(int), np.rint(points[:, 1]).astype(int)
        inside = (u >= 0) & (u < width) & (v >= 0) & (v < height)
        inside[inside] = self._detect_mask[v[inside], u[inside]] > 0
        return inside


def floor_texture(detail: np.ndarray, valid: np.ndarray | None = None) -> float:
    """The floor image's local contrast beyond the sensor's noise, grey levels: the square root of how much
    ``detail`` (the image less its local mean, float32) agrees with itself ``TEXTURE_LAG_PX`` pixels across and
    down (its autocovariance there), over the pixels ``valid`` (uint8, nonzero) at both ends; 0 when it disagrees.

    Sensor noise adds to every pixel's variance, and a standard deviation counts it as contrast: on the simulated
    T265 a uniform grey floor reads 1.5-2.7 grey levels, a matte screed that gpo-exact follows to about 0.1 % of the
    distance 3.3-4.9. But each pixel's noise is its own, spread by the floor image's resampling over a pixel or two,
    so it adds next to nothing to the covariance 3 px away (0.2-0.4), while the floor's grain is wider than that
    and adds to both (the screed 2.3-3.9). A smeared frame keeps its texture along one direction, and the forward-
    backward check flags it.
    """
    lag = TEXTURE_LAG_PX
    products, weights = 0.0, 0.0
    for ahead, behind in ((np.s_[:, lag:], np.s_[:, :-lag]), (np.s_[lag:, :], np.s_[:-lag, :])):
        pair = detail[ahead] * detail[behind]
        if valid is None:
            products, weights = products + float(pair.sum(dtype=np.float64)), weights + pair.size
        else:
            both = (valid[ahead] > 0) & (valid[behind] > 0)
            products, weights = products + float(pair[both].sum(dtype=np.float64)), weights + int(both.sum())
    return float(np.sqrt(max(products / max(weights, 1), 0.0)))


def _flagged(start, end, tracked: int, flag: str, inlier=None, spread: float = float("nan")) -> FlowMeasurement:
    nan = np.full(2, np.nan)
    inlier = np.zeros(len(start), bool) if inlier is None else inlier
    quality = FlowQuality(tracked, len(start), int(inlier.sum()), spread, flag)
    return FlowMeasurement(start, end, nan, nan, inlier, quality)
