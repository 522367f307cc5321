"""``features``: the second paper's rigid 2-D transform (theta, Tx, Ty, its eqs. 3-4) of the kept keypoint matches in
metres as the robot's increment, fitted again on every match it explains (``refit``, the suite's addition), from
the paper's fit, the turn the matches share about the kept matches' centre (``turn_about_kept``) or the fit on the
kept matches that agree on one motion (``agreeing``: a few gross mismatches the filters let through turn a
least-squares fit by degrees), whichever explains most of them. A frame where fewer than ``min_matches`` of the kept
matches agree on one motion is not measured but flagged, and the robot coasts across it: on a glossy floor of few
keypoints, four matches that agree and two matched to other keypoints turned the robot 15 degrees in one frame
(population draw 45)."""

from __future__ import annotations

import numpy as np

from gpo.motion.keypoints import FeatureError
from gpo.odometry.estimators.base import FloorEstimator, agreeing
from gpo.odometry.kinematics import increment_from_floor_motion, increment_from_point_pairs, seen_after

REFIT_ROUNDS = 5  # at most this many fits in ``refit``


TURN_LEVER_PX = 20.0  # ``turn_about_kept`` reads the turn of the pairs at least this far from the kept matches' centre


def degenerate(points, min_spread_px: float = 2.0) -> bool:
    """True when ``points`` (N, 2) lie (nearly) on a line or on a point, so that they fix no rotation: their spread
    across the best line, the smallest singular value of the centred points over sqrt(N), is under
    ``min_spread_px`` (the points' unit, pixels by default). Fewer than three points are degenerate."""
    points = np.asarray(points, dtype=float)
    if points.ndim != 2 or points.shape[1] != 2:
        raise FeatureError(f"points must be an (N, 2) array, got shape {points.shape}")
    if len(points) < 3:
        return True
    spread = np.linalg.svd(points - points.mean(axis=0), compute_uv=False)[-1] / np.sqrt(len(points))
    return bool(spread < min_spread_px)


def explained(start, end, increment, tolerance: float) -> np.ndarray:
    """Which pairs of ``start`` and ``end`` (N, 2) ``increment`` explains: the end within ``tolerance`` of where the
    increment moves the start."""
    return np.hypot(*(np.asarray(end, dtype=float) - seen_after(start, increment)).T) < tolerance


def refit(start, end, increment, tolerance: float, min_matches: int) -> np.ndarray:
    """The increment (dx, dy, dtheta) fitted again on every pair of ``start`` and ``end`` (N, 2) that ``increment``
    explains to within ``tolerance`` (the points' unit), kept by the filters or not, and again on the pairs the new
    fit explains, until they stop changing (at most ``REFIT_ROUNDS`` fits); the last increment fitted on at least
    ``min_matches`` pairs (``increment`` itself when none was).

    Why: the histogram filter keeps the vectors near the histograms' means, which in a turn selects the matches
    whose localisation errors make the turn look smaller; the paper's fit on them reads a 3 degree turn of a
    320 x 240 image up to 0.6 degrees short with ORB, whose keypoints lie on the grid of their pyramid level.
    Re-admitting every match the fit explains undoes that; a first fit that far off needs a second round."""
    start, end = np.asarray(start, dtype=float), np.asarray(end, dtype=float)
    admitted = None
    for _ in range(REFIT_ROUNDS):
        close = explained(start, end, increment, tolerance)
        if close.sum() < min_matches or (admitted is not None and (close == admitted).all()):
            break
        increment, admitted = increment_from_point_pairs(start[close], end[close]), close
    return increment


def turn_about_kept(start, end, kept, min_lever: float) -> np.ndarray | None:
    """The increment (dx, dy, dtheta) that moves the centre of the ``kept`` pairs of ``start`` and ``end`` (N, 2) as
    they moved, turning by the median of the turns the pairs at least ``min_lever`` from it (the points' unit) make
    about it; None when fewer than three pairs lie that far.

    Why: in a turn the histogram filter keeps the vectors near the histograms' means, a patch of the image where
    the vectors differ least, so the paper's fit on them reads the turn short; on a floor of few keypoints, seen by
    a camera far from the turn's centre, by a third (a quarter turn read 31 degrees short). ``refit`` then gates
    every pair by that fit, admits only pairs near the patch and settles short too (0.6 %). The kept pairs' centre
    moves the same under any turn about it, and every pair, kept or not, says how far the floor turned about it:
    the median of their word is right where at least half of the far pairs are."""
    start, end = np.asarray(start, dtype=float), np.asarray(end, dtype=float)
    centre_start, centre_end = start[kept].mean(axis=0), end[kept].mean(axis=0)
    before, after = start - centre_start, end - centre_end
    far = np.hypot(*before.T) >= min_lever
    if far.sum() < 3:
        return None
    before, after = before[far], after[far]
    turns = np.arctan2(before[:, 0] * after[:, 1] - before[:, 1] * after[:, 0], (before * after).sum(axis=1))
    angle = float(np.median(turns))  # end = R(angle) start + t, as rigid_fit's
    cos, sin = np.cos(angle), np.sin(angle)
    return increment_from_floor_motion(angle, centre_end - np.array([[cos, -sin], [sin, cos]]) @ centre_start)


class RigidKeypoints(FloorEstimator):
    """The rigid transform of the kept matches, on the floor, refitted on every match it explains to ``refit_px``.

    Each frame's keypoints are put on the floor once: a frame is the start of the next frame's matches, and a keyframe
    of every frame's until the next (the two latest frames' floor points are held)."""

    NAME = "features"
    MOTION = "keypoints"

    def __init__(self, config, geometry):
        super().__init__(config, geometry)
        self._held: list[tuple] = []  # (keypoints, their floor points, which reach the floor), the latest used last

    def _on_floor(self, keypoints) -> tuple[np.ndarray, np.ndarray]:
        """Every one of ``keypoints`` on the floor of base_link (N, 2) metres, and which reach it (N,)."""
        for held in self._held:
            if held[0] is keypoints:
                self._held = [other for other in self._held if other is not held] + [held]
                return held[1:]
        held = (keypoints, *self.geometry.on_floor(keypoints.points))
        self._held = [*self._held[-1:], held]
        return held[1:]

    def increment(self, matches, dt: float) -> tuple[np.ndarray | None, str | None]:
        parameters = self.config.features
        (start, seen_start), (end, seen_end) = self._on_floor(matches.previous), self._on_floor(matches.current)
        first, second = matches.pairs.T  # every match once, kept or not
        start, end, on_floor = start[first], end[second], seen_start[first] & seen_end[second]
        kept = matches.kept & on_floor
        if kept.sum() < parameters.min_matches or degenerate(matches.start):
            return None, f"degenerate: {kept.sum()} kept matches on the floor, (nearly) on one line"
        increment = increment_from_point_pairs(start[kept], end[kept])
        if parameters.refit_px > 0:
            tolerance = parameters.refit_px * self.geometry.pixel_m
            start, end, kept = start[on_floor], end[on_floor], kept[on_floor]
            agree = agreeing(start[kept], end[kept], tolerance)
            agreed = 0 if agree is None else int(agree.sum())
            if agreed < parameters.min_matches:
                return None, (f"too few kept matches agree on one motion: {agreed} of {int(kept.sum())} "
                              f"(at least {parameters.min_matches})")
            turned = turn_about_kept(start, end, kept, TURN_LEVER_PX * self.geometry.pixel_m)
            firsts = [increment] if turned is None else [increment, turned]  # in this order: the first best wins
            firsts.append(increment_from_point_pairs(start[kept][agree], end[kept][agree]))
            first = max(firsts, key=lambda candidate: explained(start, end, candidate, tolerance).sum())
            increment = refit(start, end, first, tolerance, parameters.min_matches)
        return increment, None
