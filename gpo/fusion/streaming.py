"""The two sources' messages into the filter, as they arrive (``StreamingFusion``) or from a recording (``fuse``).

Each source is used differentially (``gpo.fusion.ekf``): a floor frame gives the increment from the floor odometry's
previous pose, weighted by how well its flow was measured (``gpo.fusion.settings.floor_variance_scale``). The 200 Hz
tracking camera is **rate-matched** to the floor: its pose at each floor frame is its last one at or before the
frame, so each of its increments spans a floor interval and the filter makes 30 updates a second, not 230. The
filter takes both sources' increments in time order (the floor's first at a tie) and reports its state at each floor
frame once every increment up to the frame is in: a frame waits for the first tracking pose after it (at 200 Hz,
about 5 ms). ``fuse`` feeds a recorded pair of paths through the same ``StreamingFusion``, so the live filter and
the recorded one are one computation.
"""

from __future__ import annotations

import heapq
import itertools
import math
from collections import Counter, deque
from dataclasses import dataclass

import numpy as np

from gpo.fusion.ekf import (
    BIASES,
    OdometryFusion,
    ProcessNoise,
    increment_covariance,
    tracking_increment_covariance,
)
from gpo.fusion.settings import FusionSettings, floor_variance_scale
from gpo.io.trajectory import Trajectory
from gpo.odometry.kinematics import between

STAMP_SLACK_S = 1e-9  # a tracking pose stamped this little after a floor frame still counts as at or before it
FLOOR_FIRST, TRACKING_NEXT = 0, 1  # the order of two increments ending at the same time
DOUBTED_FLOOR = "floor in doubt"  # an event's source: a floor step not fused, the camera's biases forgotten


@dataclass(frozen=True)
class FusedPose:
    """The filter at a floor frame: its time ``time_s`` (seconds), its ``state`` (7,: x, y, theta of base_link in
    odom (m, rad), v (m/s), omega (rad/s), the tracking camera's scale error and yaw bias (rad/s)) and ``covariance``
    (7, 7)."""

    time_s: float
    state: np.ndarray
    covariance: np.ndarray

    @property
    def pose(self) -> np.ndarray:
        """x, y (m) and theta (rad) of base_link in odom."""
        return self.state[:3]


@dataclass
class _Frame:
    """A floor frame waiting to be settled: its time, the floor's increment into it (as an event) and whether its pose
    was finite."""

    time_s: float
    events: list
    finite: bool


class StreamingFusion:
    """The EKF of ``gpo.fusion.ekf`` fed as messages arrive: ``add_floor`` for each floor odometry pose,
    ``add_tracking`` for each pose of base_link from the tracking camera's odometry, each source in the order of its
    stamps; each call returns the ``FusedPose`` of every floor frame it settled, and ``finish`` those left at the end.

    The filter starts at the first floor pose. A floor frame is settled when a tracking pose after it has arrived
    (``STAMP_SLACK_S``), or at ``finish``. A tracking pose that is not finite, or not after the one before, is dropped;
    a tracking increment over more than ``tracking_max_gap_s`` is not fused (its end becomes the next one's start);
    a floor pose that is not finite is dropped and its frame gets the filter's prediction: all counted in
    ``dropped``, by reason.
    """

    def __init__(self, settings: FusionSettings | None = None):
        self.settings = settings or FusionSettings()
        self.dropped: Counter = Counter()
        self._fusion: OdometryFusion | None = None
        self._floor: tuple[float, np.ndarray] | None = None  # the last finite floor pose's time and pose
        self._frames: deque[_Frame] = deque()  # floor frames waiting for a tracking pose after them
        self._tracking: deque[tuple[float, np.ndarray]] = deque()  # tracking poses from the last one matched on
        self._matched: tuple[float, np.ndarray] | None = None  # the tracking pose matched to the last settled frame
        self._events: list = []  # increments waiting to be fused, a heap by end time, the floor's first at a tie
        self._order = itertools.count()
        self._start_s = math.inf  # the first finite floor pose's time, where the filter starts
        self._last_floor_s = -math.inf  # the last floor pose's time, finite or not

    @property
    def refused(self) -> int:
        """Increments the filter's NIS gate refused as outliers so far."""
        return 0 if self._fusion is None else self._fusion.refused

    def add_floor(self, time_s: float, pose, inliers: int, spread_px: float = math.nan) -> list[FusedPose]:
        """The floor odometry's pose (x, y, theta of base_link in odom) at ``time_s`` (its header stamp in seconds),
        after a step that ``inliers`` inlier vectors spread by ``spread_px`` pixels measured (0: not measured, the
        step not fused; a spread of NaN counts as the reference). Times must increase.

        An infinite spread is a step in doubt (``gpo.pipeline.odometer.FrameRecord.fused_spread_px``: the floor's
        tracks and its whole view disagreed): it is not fused, and what the filter learned of the tracking camera's
        biases is forgotten (``OdometryFusion.forget_biases``), for the floor that misread this step is the one that
        taught them. On a glossy floor the flow reads spins 1.5-2.7 % short in steps nothing flags; the filter took
        that for the camera's yaw bias, 31 degrees a minute on population draw 16 where the camera's own is 2, and the
        fused path ended 23.8 % off where the camera alone ends 0.43 %."""
        if not time_s > self._last_floor_s:
            raise ValueError(f"floor poses must come in time order: {time_s:.9f} s after {self._last_floor_s:.9f} s")
        self._last_floor_s = time_s
        pose = np.asarray(pose, dtype=float)
        finite = bool(np.isfinite(pose).all())
        events = []
        if not finite:
            self.dropped["floor: pose not finite"] += 1
        elif self._floor is None:
            s = self.settings
            noise = ProcessNoise(s.accel_mps2, s.angular_accel_radps2)
            jitter = (s.tracking_jitter_m, s.tracking_jitter_rad)
            self._fusion = OdometryFusion(time_s, noise, pose=pose, biases=s.bias_model, jitter=jitter)
            self._start_s = time_s
        else:
            start, previous = self._floor
            dt = time_s - start
            doubted = inliers > 0 and math.isinf(spread_px)
            if doubted:
                self.dropped["floor: step in doubt (tracks and whole view disagree), not fused"] += 1
                increment, covariance = None, None
            else:
                scale = floor_variance_scale(np.float64(inliers), np.float64(spread_px), self.settings)
                covariance = increment_covariance(self.settings.floor_speed_sigma_mps,
                                                  self.settings.floor_turn_sigma_radps, dt) * scale
                increment = between(previous, pose) if inliers > 0 else None
            source = DOUBTED_FLOOR if doubted else "floor"
            events.append(self._event(time_s, FLOOR_FIRST, source, increment, dt, covariance))
        if finite:
            self._floor = (time_s, pose)
        self._frames.append(_Frame(time_s, events, finite))
        return self._settle()

    def add_tracking(self, time_s: float, pose) -> list[FusedPose]:
        """A pose (x, y, theta) of base_link from the tracking camera's odometry at ``time_s`` (its header stamp in
        seconds; ``gpo.io.trajectory.base_from_sensor_odometry`` turns the camera's own pose into base_link's)."""
        pose = np.asarray(pose, dtype=float)
        if not (np.isfinite(pose).all() and math.isfinite(time_s)):
            self.dropped["tracking: pose not finite"] += 1
        elif self._tracking and time_s <= self._tracking[-1][0]:
            kind = "repeated" if time_s == self._tracking[-1][0] else "out of order (dropped)"
            self.dropped[f"tracking: stamp {kind}"] += 1
        else:
            self._tracking.append((time_s, pose))
        return self._settle()

    def finish(self) -> list[FusedPose]:
        """Settle the floor frames still waiting with the tracking poses received so far, then fuse every increment
        left."""
        settled = self._settle(final=True)
        if self._fusion is not None:
            self._fuse_until(math.inf)
        return settled

    def _event(self, end_s, rank, source, increment, dt, covariance) -> tuple:
        return (end_s, rank, next(self._order), source, increment, dt, covariance)

    def _settle(self, final: bool = False) -> list[FusedPose]:
        """Settle, in order, the waiting floor frames that a tracking pose after them (or ``final``) allows."""
        settled = []
        while self._frames:
            frame = self._frames[0]
            after = self._tracking and self._tracking[-1][0] > frame.time_s + STAMP_SLACK_S
            if frame.finite and not (final or after):
                break
            self._frames.popleft()
            if frame.finite:
                frame.events += self._tracking_increment(frame.time_s)
            for event in frame.events:
                heapq.heappush(self._events, event)
            if self._fusion is None:
                continue  # before the first finite floor pose: no filter yet
            self._fuse_until(frame.time_s)
            self._fusion.predict(max(frame.time_s, self._fusion.time_s))
            settled.append(FusedPose(frame.time_s, self._fusion.state, self._fusion.covariance))
        return settled

    def _tracking_increment(self, time_s: float) -> list:
        """The tracking camera's increment into its last pose at or before the floor frame at ``time_s``, as an event:
        none when there is no such pose or it is the one matched to the frame before."""
        while len(self._tracking) > 1 and self._tracking[1][0] <= time_s + STAMP_SLACK_S:
            self._tracking.popleft()
        if not self._tracking or self._tracking[0][0] > time_s + STAMP_SLACK_S:
            return []
        previous, self._matched = self._matched, self._tracking[0]
        if previous is None or previous[0] == self._matched[0]:
            return []
        (start, before), (end, after) = previous, self._matched
        increment = between(before, after)
        if end - start > self.settings.tracking_max_gap_s:
            self.dropped["tracking: step over a gap"] += 1
            increment = None
        walks = (self.settings.tracking_position_walk_m_per_sqrt_s, self.settings.tracking_yaw_walk_rad_per_sqrt_s)
        covariance = tracking_increment_covariance(*walks, end - start)
        return [self._event(end, TRACKING_NEXT, "tracking", increment, end - start, covariance)]

    def _fuse_until(self, time_s: float) -> None:
        """Fuse the waiting increments that end at or before ``time_s``, in time order."""
        while self._events and self._events[0][0] <= time_s:
            end, _, _, source, increment, dt, covariance = heapq.heappop(self._events)
            if end <= self._start_s:
                continue
            if source == DOUBTED_FLOOR:
                self._fusion.forget_biases()
                source = "floor"
            self._fusion.add(source, end, increment, dt, covariance)


@dataclass(frozen=True)
class FusedPath:
    """The EKF's ``trajectory`` of base_link (odom), the state's ``covariances`` (N, 7, 7) and the camera's estimated
    ``biases`` (N, 2: scale, yaw bias rad/s) at its poses, how many measurements the NIS gate ``refused`` as
    outliers, and the messages or steps ``dropped`` before the filter, counted by reason."""

    trajectory: Trajectory
    covariances: np.ndarray
    biases: np.ndarray
    refused: int
    dropped: dict[str, int]


def fuse(
    floor: Trajectory, inliers: np.ndarray, tracking: Trajectory, settings: FusionSettings, spread_px=None
) -> FusedPath:
    """The EKF's path of base_link at the floor odometry's stamps, with its covariance and the camera's biases: both
    recorded paths through one ``StreamingFusion``.

    ``floor``: the floor odometry's base_link poses; ``inliers`` (N,): the flow's inlier vectors behind the step into
    each pose, 0 where the step was not measured (coasted and held steps are not fused); ``spread_px`` (N,), when
    known: their spread (``FusionSettings``; NaN counts as the reference). ``tracking``: the tracking camera's
    odometry already turned into base_link poses (``gpo.io.trajectory.base_from_sensor_odometry``). Unlike a live
    stream, a recording is first put in the order of its stamps (what was reordered, and a repeated stamp's later
    messages, counted in ``dropped``); poses that are not finite are dropped and counted as ``StreamingFusion`` does.
    """
    inliers = np.asarray(inliers, dtype=float)
    if inliers.shape != (len(floor),):
        raise ValueError(f"inliers must have one count per floor pose ({len(floor)}), got shape {inliers.shape}")
    spread = np.full(len(floor), np.nan) if spread_px is None else np.asarray(spread_px, dtype=float)
    if spread.shape != (len(floor),):
        raise ValueError(f"spread_px must have one value per floor pose ({len(floor)}), got shape {spread.shape}")
    dropped = Counter()
    floor_times, floor_poses = np.asarray(floor.times, dtype=float), planar(floor)
    tracking_times, tracking_poses = np.asarray(tracking.times, dtype=float), planar(tracking)
    floor_order = _ordered(floor_times, floor_poses, dropped, "floor")
    tracking_order = _ordered(tracking_times, tracking_poses, dropped, "tracking")
    fusion = StreamingFusion(settings)
    for k in tracking_order:
        fusion.add_tracking(float(tracking_times[k]), tracking_poses[k])
    settled = [pose for k in floor_order for pose in fusion.add_floor(floor_times[k], floor_poses[k], inliers[k],
                                                                       spread[k])]
    settled += fusion.finish()  # one pose for each floor pose fed, in order
    states = np.array([pose.state for pose in settled])
    trajectory = Trajectory.from_planar(floor.stamps_ns[floor_order], *states[:, :3].T, frame_id=floor.frame_id)
    covariances = np.array([pose.covariance for pose in settled])
    return FusedPath(trajectory, covariances, states[:, BIASES], fusion.refused, dict(dropped + fusion.dropped))


def planar(path) -> np.ndarray:
    """``path``'s poses as (x, y, theta) (N, 3): its positions' x and y (m) and its yaw (rad)."""
    return np.column_stack([path.positions[:, :2], path.yaw])


def _ordered(times: np.ndarray, poses: np.ndarray, dropped: Counter, source: str) -> np.ndarray:
    """The indices of a path's finite poses (``times`` s, planar ``poses``) in the order of their stamps, a repeated
    stamp once (its first message); what was left out or reordered counted in ``dropped``. At least two such poses."""
    finite = np.isfinite(poses).all(axis=1) & np.isfinite(times)
    if not finite.all():
        dropped[f"{source}: pose not finite"] += int((~finite).sum())
    index = np.flatnonzero(finite)
    if np.any(np.diff(times[index]) < 0):
        dropped[f"{source}: stamp out of order (reordered)"] += int(np.sum(np.diff(times[index]) < 0))
    index = index[np.argsort(times[index], kind="stable")]
    repeated = np.r_[False, np.diff(times[index]) == 0]
    if repeated.any():
        dropped[f"{source}: stamp repeated"] += int(repeated.sum())
    index = index[~repeated]
    if len(index) < 2:
        raise ValueError(f"the {source} path needs at least two poses with finite values and distinct stamps")
    return index
