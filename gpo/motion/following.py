"""Keypoints detected on keyframes and followed between them by pyramidal Lucas-Kanade (``FeatureParameters.follow``
``lk``): the floor feature odometer at a fraction of its cost.

The second paper detects and describes keypoints in every frame and matches them with the previous frame's
(``gpo.motion.keypoints.FeatureTracker``); SIFT's detection is most of a frame's time. Between two frames the floor
moves a few tens of pixels and turns a degree or two, which Lucas-Kanade follows for far less. So here a keyframe's
keypoints are detected once (``gpo.motion.keypoints.locate``), and in each later frame the window
about each of them in the keyframe is searched for by ``cv2.calcOpticalFlowPyrLK`` with the config's ``klt``
window, pyramid and stopping rule: from the keyframe's image, so that each frame's errors are its own, starting
where the keypoint was in the latest frame moved by that frame's motion, in a view turned back onto the keyframe
once the floor has turned (``gpo.motion.turned_view``); a keypoint is followed on while searching back from the
frame returns within ``forward_backward_px`` of it. Each frame is measured against the keyframe: the pairs (a
keypoint in the keyframe, where it was found) go through the paper's histogram filter and invariance check
(``gpo.motion.keypoints.filtered``) to the rigid fit, as matches do.

The keyframe is kept as ``FeatureParameters.keyframe`` says: while at least ``min_overlap`` of its keypoints are
still followed, for at most ``max_frames`` frames. The frame that ends it becomes the new keyframe, and its
keypoints are detected then. When the followed keypoints cannot measure a frame (too few followed or kept: a
blurred frame, a jump beyond the pyramid's reach), the frame's keypoints, detected for the new keyframe, are matched
with the keyframe's and filtered, as the paper does every frame: matching happens only when it is needed, and
so does describing the two frames' keypoints (SIFT's descriptors cost about as much as finding its keypoints).

Lucas-Kanade assumes that a patch keeps its brightness, which the exposure's flicker and the vignetting break: each
frame is levelled first as the floor image's KLT flow levels it (``prepare``, a ``FollowFrame``; it depends on the
frame alone). Pixels (u, v): u right, v down, as OpenCV; points are pixel centres of the full image.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from gpo.motion.keypoints import FeatureMatches, FeatureParameters, Located, filtered, locate, matched, timed
from gpo.motion.klt import KLTParameters
from gpo.motion.levelling import levelled, reduced_local_mean
from gpo.motion.median import median_of
from gpo.motion.turned_view import TurnedView

PREDICTED_LEVELS = 1  # pyramid levels above the full image searched once the latest frame's motion predicts a start
FLAT_FIELD_REDUCTION = 4  # a frame's local mean for the levelling is taken on the frame reduced this many times


@dataclass(frozen=True, eq=False)
class FollowFrame:
    """A frame made ready to follow keypoints into (``KeypointFollower.prepare``): the grey ``image`` (H, W) uint8,
    where a keyframe's keypoints are detected, and the image Lucas-Kanade searches, ``levelled`` (H, W) uint8: as the
    floor image's KLT flow sees it (``gpo.motion.levelling``), divided by its local mean (``klt.flat_field_px``,
    taken on the frame reduced ``FLAT_FIELD_REDUCTION`` times: ``reduced_local_mean``)
    and scaled to one mean and contrast, so that neither the exposure's flicker from frame to frame nor the
    vignetting fixed to the camera pulls the searches."""

    image: np.ndarray
    levelled: np.ndarray


class KeypointFollower:
    """Keypoints detected on keyframes and followed between them by pyramidal Lucas-Kanade (see the module).

    ``parameters``: the keypoints, the filters and the keyframe policy; ``klt``: Lucas-Kanade's window, pyramid,
    stopping rule and forward-backward check (``window_px``, ``pyramid_levels``, ``max_iterations``,
    ``epsilon_px``, ``forward_backward_px``), the share of the searches that must pass it (``min_kept_ratio``) and
    the levelling (``normalise_brightness``, ``flat_field_px``); ``mask`` (H, W), optional: nonzero where the image
    may be used, for the detection (``detect``) and the followed keypoints alike. ``track(frame)`` returns the frame's
    ``FeatureMatches`` against the keyframe (None for the first frame); ``restart()`` forgets the frames before. The
    invariance check draws from one generator, ``np.random.default_rng(parameters.seed)``: the same frames give the
    same matches."""

    def __init__(self, parameters: FeatureParameters, klt: KLTParameters | None = None, mask=None):
        self.parameters = parameters
        self.klt = klt if klt is not None else KLTParameters()
        self._mask = None if mask is None else np.asarray(mask).astype(bool)
        self._valid = None if mask is None else self._mask.astype(np.uint8)
        self._rng = np.random.default_rng(parameters.seed)
        self.restart()

    def restart(self) -> None:
        """Forget the frames before: the next ``track`` call starts afresh."""
        self._keyframe: Located | None = None
        self._followed = np.zeros(0, int)  # the keyframe's keypoints still followed, by index
        self._last = np.zeros((0, 2), np.float32)  # where they were in the latest frame, pixels
        self._image: np.ndarray | None = None  # the keyframe, levelled
        self._velocity: np.ndarray | None = None  # the latest frame's median motion, pixels a second
        self._time_s = 0.0
        self._frames = 0  # frames measured against the keyframe so far

    @property
    def keyframe_is_latest(self) -> bool:
        """Whether the next frame is measured from the latest one (the latest frame is the keyframe)."""
        return self._frames == 0

    def prepare(self, image: np.ndarray) -> FollowFrame:
        """``image`` (H, W) uint8 made ready to follow keypoints into (``FollowFrame``), levelled as ``klt`` says
        (``normalise_brightness``, ``flat_field_px``). It depends on the frame alone, so frames can be prepared ahead,
        in another thread, while earlier ones are followed."""
        p = self.klt
        if not p.normalise_brightness:
            return FollowFrame(image, image)
        level = image.astype(np.float32)
        local_mean = reduced_local_mean(level, p.flat_field_px, FLAT_FIELD_REDUCTION) if p.flat_field_px else None
        return FollowFrame(image, levelled(level, local_mean, self._valid))

    def track(self, frame: FollowFrame | np.ndarray, time_s: float | None = None) -> FeatureMatches | None:
        """The pairs from the keyframe's keypoints to ``frame`` (an image (H, W) uint8, or what ``prepare`` made of
        one), filtered; None for the first frame. ``time_s``: the frame's time in seconds, so that the predicted
        motion scales with the time since the previous frame (a dropped frame doubles it); None counts frames."""
        if not isinstance(frame, FollowFrame):
            frame = self.prepare(frame)
        elapsed = 1.0 if time_s is None or self._keyframe is None else time_s - self._time_s
        self._time_s = 0.0 if time_s is None else time_s
        seconds: dict = {}
        if self._keyframe is None:
            self._new_keyframe(frame, seconds)
            return None
        keyframe, searched = self._keyframe, len(self._followed)
        current, pairs, moved = timed(seconds, "follow", self._follow, frame, elapsed)
        flag = _too_few(len(pairs), searched, self.parameters.min_matches, self.klt.min_kept_ratio)
        measured = filtered(keyframe, current, pairs, self.parameters, self._rng, seconds, flag)
        self._velocity = None if measured.flag is not None else (median_of(moved, axis=0) / elapsed).astype(np.float32)
        frames = self._frames + 1
        if measured.flag is None and self.parameters.keyframe.keeps(len(pairs), len(keyframe), frames):
            self._frames, self._followed, self._last = frames, pairs[:, 0], current.points.astype(np.float32)
            return measured
        detected = self._new_keyframe(frame, seconds)
        if measured.flag is not None:  # the followed keypoints cannot measure it: the keyframe's matched instead
            described = timed(seconds, "describe", lambda: (keyframe.described(), detected.described()))
            measured = matched(*described, self.parameters, self._rng, seconds)
        return measured

    def _follow(self, frame: FollowFrame, elapsed: float) -> tuple[Located, np.ndarray, np.ndarray]:
        """The keyframe's followed keypoints searched for in ``frame``, ``elapsed`` (seconds, or frames) after the
        latest frame: the keypoints where they were found (with the keyframe's sizes), the pairs
        (M, 2) (keyframe index, index among them) and each one's motion since the latest frame (M, 2), pixels.

        Each keypoint's window is searched for from the keyframe's image, not the latest frame's, so that a
        search's small error is made once, not added up frame after frame (a chain of searches turned a path's
        heading 0.3-1.2 degrees where the keyframe's turned it 0.1-0.3 on draws of the population), starting where
        the keypoint was in the latest frame moved by the latest frame's motion; a frame turned from the keyframe is
        searched in a view turned back (``gpo.motion.turned_view``). Once the motion is known, the search runs on
        ``PREDICTED_LEVELS`` levels of the pyramid above the full image instead of all of them (a start predicted
        from the latest frame is a few pixels off; a start further off fails the forward-backward check, and the
        frame is matched with the keyframe), and the search back to the keyframe on the full image only: a right
        track is then near its start."""
        p = self.klt
        keyframe, followed = self._keyframe, self._followed
        if not len(followed):
            return Located(np.zeros((0, 2)), np.zeros(0)), np.zeros((0, 2), int), np.zeros((0, 2))
        start = keyframe.points[followed].astype(np.float32)
        shift = np.zeros(2, np.float32) if self._velocity is None else (self._velocity * elapsed).astype(np.float32)
        guess, image = self._last + shift, frame.levelled
        turn = TurnedView.between(start, guess, image.shape)
        if turn is not None:
            image, guess = turn.view(image), turn.to_view(guess)
        criteria = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, p.max_iterations, p.epsilon_px)
        lk = {"winSize": (p.window_px, p.window_px), "criteria": criteria, "flags": cv2.OPTFLOW_USE_INITIAL_FLOW}
        start, guess = start.reshape(-1, 1, 2), guess.reshape(-1, 1, 2)
        levels = p.pyramid_levels if self._velocity is None else min(p.pyramid_levels, PREDICTED_LEVELS)
        end, status, _ = cv2.calcOpticalFlowPyrLK(self._image, image, start, guess, maxLevel=levels, **lk)
        levels = 0 if self._velocity is not None else p.pyramid_levels
        back, back_status, _ = cv2.calcOpticalFlowPyrLK(image, self._image, end, start.copy(), maxLevel=levels, **lk)
        start, end, back = start.reshape(-1, 2), end.reshape(-1, 2), back.reshape(-1, 2)
        if turn is not None:
            end = turn.from_view(end)
        keep = (status.ravel() == 1) & (back_status.ravel() == 1)
        keep &= np.einsum("ij,ij->i", back - start, back - start) < p.forward_backward_px**2
        keep &= self._inside(end, frame.image.shape)
        followed = followed[keep]
        current = Located(end[keep].astype(float), keyframe.sizes[followed])
        return current, np.column_stack([followed, np.arange(len(followed))]), end[keep] - self._last[keep]

    def _inside(self, points: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
        """Which ``points`` (N, 2) have their whole Lucas-Kanade window inside the image (H, W) and lie on a usable
        pixel of the mask."""
        half = self.klt.window_px // 2
        height, width = shape
        inside = (points >= half).all(axis=1) & (points[:, 0] <= width - 1 - half) & (points[:, 1] <= height - 1 - half)
        if self._mask is not None:
            u, v = np.rint(points[inside]).astype(int).T
            inside[inside] = self._mask[v, u]
        return inside

    def _new_keyframe(self, frame: FollowFrame, seconds: dict) -> Located:
        """``frame`` becomes the keyframe: its keypoints detected, all of them followed from here; they are described
        only if a frame must be matched with them."""
        keypoints = timed(seconds, "detect", locate, frame.image, self.parameters, self._mask)
        self._keyframe, self._image, self._frames = keypoints, frame.levelled, 0
        self._followed = np.arange(len(keypoints))
        self._last = keypoints.points.astype(np.float32)
        return keypoints


def _too_few(followed: int, searched: int, min_matches: int, min_kept_ratio: float) -> str | None:
    """Why ``followed`` keypoints, of the ``searched`` for, are too few to filter, or None: fewer than
    ``min_matches``, or than ``min_kept_ratio`` of those searched for (a frame where most searches fail is blurred or
    beyond the pyramid's reach, and the few that pass may have found the wrong place)."""
    if followed < max(min_matches, min_kept_ratio * searched):
        return f"too few keypoints followed: {followed} of {searched} (a bad or blurred frame, or too fast)"
    return None
