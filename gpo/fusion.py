"""An extended Kalman filter that fuses odometry sources into one path of ``base_link``.

State (``STATE``): x, y (m) and heading theta (rad) of base_link in the odometry frame, its forward speed v (m/s)
and yaw rate omega (rad/s). Process model: v and omega stay constant over a step, driven by white acceleration
noise (``ProcessNoise``); the pose moves along the exact arc they describe (``gpo.kinematics.arc_increment``),
and the covariance through the Jacobian of that motion.

Every source is used **differentially**, like robot_localization's differential mode: only a source's pose
increments count (already turned into base_link: ``gpo.trajectory.base_from_sensor_odometry``), never its absolute
pose, which drifts. An increment over [t0, t1] is a measurement of the filter's own motion between those times: the
filter keeps a copy of its pose at t0 for each source (stochastic cloning, Roumeliotis and Burdick 2002), and the
measurement is the forward part and the turn of ``between(clone, pose)`` (``MEASURED``), with the covariance the
increment carries (``increment_covariance``). base_link does not slide sideways, so a source's sideways steps are
its own error and are not fused.
Measurements must come in time order; ``OdometryFusion.add`` refuses stale ones (earlier than the filter's time)
and the caller decides what to skip.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from filterpy.kalman import ExtendedKalmanFilter
from scipy.linalg.lapack import dpotrf

from gpo.kinematics import arc_increment, between
from gpo.trajectory import Trajectory

STATE = ("x", "y", "theta", "v", "omega")
MEASURED = [0, 2]  # of a base_link increment (dx, dy, dtheta): base_link does not slide sideways, dy is not fused
MAX_NIS = 50.0  # an innovation this many sigmas squared away is refused as an outlier


class FilterDiverged(RuntimeError):
    """The filter's covariance stopped being a covariance (not finite, or not positive definite)."""


@dataclass(frozen=True)
class ProcessNoise:
    """White noise driving the constant-velocity model: ``accel_mps2`` (m/s^2 per sqrt(Hz)) on v and
    ``angular_accel_radps2`` (rad/s^2 per sqrt(Hz)) on omega."""

    accel_mps2: float = 0.1
    angular_accel_radps2: float = 0.3


def motion_jacobian(state: np.ndarray, dt: float) -> np.ndarray:
    """F (5, 5): the derivative of the first-order motion x += v cos(theta) dt, y += v sin(theta) dt,
    theta += omega dt with respect to the state."""
    v, cos, sin = state[3], math.cos(state[2]), math.sin(state[2])
    jacobian = np.eye(5)
    jacobian[0, 2], jacobian[0, 3] = -v * sin * dt, cos * dt
    jacobian[1, 2], jacobian[1, 3] = v * cos * dt, sin * dt
    jacobian[2, 4] = dt
    return jacobian


def process_covariance(state: np.ndarray, dt: float, noise: ProcessNoise) -> np.ndarray:
    """Q (5, 5) of one step: the accelerations' white noise integrated once into (v, omega) and twice into the pose."""
    theta = state[2]
    gain = np.array(
        [
            [0.5 * dt**2 * math.cos(theta), 0.0],
            [0.5 * dt**2 * math.sin(theta), 0.0],
            [0.0, 0.5 * dt**2],
            [dt, 0.0],
            [0.0, dt],
        ]
    )
    density = np.array([noise.accel_mps2**2, noise.angular_accel_radps2**2]) / dt  # a diagonal matrix's diagonal
    return (gain * density) @ gain.T


def increment_covariance(speed_sigma_mps: float, turn_sigma_radps: float, dt: float) -> np.ndarray:
    """R (2, 2) of the measured part (dx, dtheta) of a base_link increment over ``dt`` seconds whose mean forward
    speed scatters by ``speed_sigma_mps`` and whose mean yaw rate by ``turn_sigma_radps``."""
    return np.diag(np.square([speed_sigma_mps * dt, turn_sigma_radps * dt]))


def increment_jacobians(clone: np.ndarray, pose: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The derivatives (3, 3) of ``gpo.kinematics.between(clone, pose)`` with respect to ``clone`` and to ``pose``
    (each x, y, theta)."""
    cos, sin = math.cos(clone[2]), math.sin(clone[2])
    dx, dy = pose[0] - clone[0], pose[1] - clone[1]
    rotation = np.array([[cos, sin, 0.0], [-sin, cos, 0.0], [0.0, 0.0, 1.0]])
    by_clone = -rotation
    by_clone[0, 2], by_clone[1, 2] = -sin * dx + cos * dy, -cos * dx - sin * dy
    return by_clone, rotation


class OdometryFusion:
    """The EKF of ``STATE`` over time (seconds), with one cloned pose per source (stochastic cloning).

    Each source in ``sources`` keeps a copy of the pose at the end of its last step, correlated with the state as
    the pose was; of its next increment (dx, dy, dtheta over [time_s - dt_s, time_s], in base_link at the step's
    start), dx and dtheta are measured as those of ``between(clone, pose)``. Whatever the state's v and omega did
    inside the step, the pose is corrected by the whole increment, so the path does not lag behind a source by part
    of its interval.
    """

    def __init__(
        self, start_s: float, noise: ProcessNoise = ProcessNoise(), pose=(0.0, 0.0, 0.0), sources=("floor", "tracking")
    ):
        self.noise = noise
        self.time_s = float(start_s)
        size = 5 + 3 * len(sources)
        self._filter = ExtendedKalmanFilter(dim_x=size, dim_z=len(MEASURED))
        self._filter.x = np.array([*pose, 0.0, 0.0, *np.tile(np.asarray(pose, dtype=float), len(sources))])
        self._filter.P = np.zeros((size, size))
        self._filter.P[3:5, 3:5] = np.eye(2)  # the pose is the given one, the motion unknown
        self._clones = {name: (5 + 3 * k, self.time_s) for k, name in enumerate(sources)}
        self._jitter = 1e-12 * np.eye(size)  # added to the covariance before _check's Cholesky factorisation
        self.refused = 0

    @property
    def state(self) -> np.ndarray:
        """The state (5,) at ``time_s``."""
        return self._filter.x[:5].copy()

    @property
    def covariance(self) -> np.ndarray:
        """The state's covariance (5, 5)."""
        return self._filter.P[:5, :5].copy()

    def predict(self, time_s: float) -> None:
        """Move the state to ``time_s`` (not before the filter's time) with the constant-velocity model; the
        clones stay where they are."""
        self._predict(time_s)
        self._check()

    def _predict(self, time_s: float) -> None:
        dt = time_s - self.time_s
        if dt < 0:
            raise ValueError(f"cannot predict back in time: {time_s:.6f} s is before the filter's {self.time_s:.6f} s")
        if dt == 0:
            return
        ekf, state = self._filter, self._filter.x[:5]
        motion = motion_jacobian(state, dt)
        # P = F P F' with F the identity outside the state's block (the clones stay): only its first rows and columns
        ekf.P[:5] = motion @ ekf.P[:5]
        ekf.P[:, :5] = ekf.P[:, :5] @ motion.T
        ekf.P[:5, :5] += process_covariance(state, dt, self.noise)
        step = arc_increment(state[3], state[4], dt)
        cos, sin = math.cos(state[2]), math.sin(state[2])
        ekf.x[:5] = state + np.array([cos * step[0] - sin * step[1], sin * step[0] + cos * step[1], step[2], 0.0, 0.0])
        self.time_s = time_s

    def add(self, source: str, time_s: float, increment, dt_s: float, covariance) -> bool:
        """Fuse ``source``'s base_link increment (dx, dy, dtheta) over the ``dt_s`` seconds ending at ``time_s``, with
        the covariance (2, 2) of its (dx, dtheta) (``increment_covariance``); ``increment=None`` for a step the
        source did not measure. Returns True when fused; False when refused as an outlier (normalised innovation
        squared above ``MAX_NIS``, counted in ``refused``), not measured, or not starting where the source's last
        step ended (within 1 us): such a step only moves the source's clone to ``time_s``.
        Raises ValueError for an unknown source, a step ending before the filter's time or non-finite numbers."""
        if source not in self._clones:
            raise ValueError(f"unknown source {source!r}; this filter fuses {', '.join(self._clones)}")
        if not dt_s > 0:
            raise ValueError(f"a step needs dt_s > 0, got {dt_s}")
        if increment is not None and not np.isfinite(np.asarray(increment, dtype=float)).all():
            raise ValueError(f"a measurement needs a finite increment, got {increment}")
        self._predict(time_s)
        index, since = self._clones[source]
        fused = (
            increment is not None and abs(time_s - dt_s - since) < 1e-6 and self._update(index, increment, covariance)
        )
        self._clone(source)
        self._check()
        return fused

    def _update(self, index: int, increment, covariance) -> bool:
        ekf, clone = self._filter, slice(index, index + 3)
        measured = np.asarray(increment, dtype=float)[MEASURED]
        covariance = np.asarray(covariance, dtype=float)
        # the expected measurement and its Jacobian at the state, once for the NIS gate and filterpy's update:
        # between(clone, pose) is the difference turned into the clone's frame, by_pose that rotation
        by_clone, by_pose = increment_jacobians(ekf.x[clone], ekf.x[:3])
        expected = (by_pose @ (ekf.x[:3] - ekf.x[clone]))[MEASURED]
        expected[1] = _wrap(expected[1])
        linear = np.zeros((len(MEASURED), len(ekf.x)))
        linear[:, :3], linear[:, clone] = by_pose[MEASURED], by_clone[MEASURED]
        innovation = _residual(measured, expected)
        spread = linear @ ekf.P @ linear.T + covariance
        if _nis(innovation, spread) > MAX_NIS:
            self.refused += 1
            return False
        ekf.update(measured, lambda _: linear, lambda _: expected, R=covariance, residual=_residual)
        return True

    def _clone(self, source: str) -> None:
        """Copy the pose, its covariance and its correlations into ``source``'s clone, stamped now."""
        index, _ = self._clones[source]
        ekf, clone = self._filter, slice(index, index + 3)
        ekf.x[clone] = ekf.x[:3]
        ekf.P[clone, :] = ekf.P[:3, :]
        ekf.P[:, clone] = ekf.P[:, :3]
        self._clones[source] = (index, self.time_s)

    def _check(self) -> None:
        covariance = self._filter.P
        if not np.isfinite(covariance).all():
            raise FilterDiverged(f"the covariance at {self.time_s:.3f} s is no longer finite")
        _, failed = dpotrf(0.5 * (covariance + covariance.T) + self._jitter, lower=True)  # LAPACK's Cholesky
        if failed:
            raise FilterDiverged(f"the covariance at {self.time_s:.3f} s is no longer positive definite")


def _wrap(angle: float) -> float:
    """``angle`` (rad) wrapped to (-pi, pi]."""
    return math.atan2(math.sin(angle), math.cos(angle))


def _nis(innovation: np.ndarray, spread: np.ndarray) -> float:
    """The normalised innovation squared, innovation' spread^-1 innovation, of a (2,) innovation with covariance
    ``spread`` (2, 2), in closed form (numpy's solvers cost more in overhead than the sum)."""
    (a, b), (c, d) = spread.tolist()
    i, j = innovation.tolist()
    return (i * (d * i - b * j) + j * (a * j - c * i)) / (a * d - b * c)


def _residual(measured: np.ndarray, expected: np.ndarray) -> np.ndarray:
    """measured - expected of (dx, dtheta), the turn wrapped."""
    difference = measured - expected
    difference[1] = _wrap(difference[1])
    return difference


@dataclass(frozen=True)
class FusionSettings:
    """What ``--method fused`` fuses: the floor odometry of ``floor_method`` with a tracking camera's own odometry on
    ``tracking_topic`` (nav_msgs/Odometry of ``tracking_frame``, whose pose in base_link the bag's /tf_static holds).
    Each source's increment over dt has the covariance of a mean velocity that scatters by these standard
    deviations (m/s along and across, rad/s; ``increment_covariance``); a floor frame
    whose flow kept fewer than ``floor_reference_inliers`` inlier tracks has its variance scaled up by
    reference / inliers (the median of n tracks scatters as 1 / sqrt(n)). The process noise is
    ``ProcessNoise(accel_mps2, angular_accel_radps2)``."""

    floor_method: str = "gpo-exact"
    tracking_topic: str = "/camera/odom/sample"
    tracking_frame: str = "camera_pose_frame"
    floor_speed_sigma_mps: float = 0.002
    floor_turn_sigma_radps: float = 0.03
    tracking_speed_sigma_mps: float = 0.15
    tracking_turn_sigma_radps: float = 0.15
    floor_reference_inliers: int = 60
    accel_mps2: float = ProcessNoise.accel_mps2
    angular_accel_radps2: float = ProcessNoise.angular_accel_radps2


@dataclass(frozen=True)
class FusedPath:
    """The EKF's ``trajectory`` of base_link (odom), the state's ``covariances`` (N, 5, 5) at its poses, and how many
    measurements were ``refused`` as outliers."""

    trajectory: Trajectory
    covariances: np.ndarray
    refused: int


def fuse(floor: Trajectory, inliers: np.ndarray, tracking: Trajectory, settings: FusionSettings) -> FusedPath:
    """The EKF's path of base_link at the floor odometry's stamps, with its covariance.

    ``floor``: the floor odometry's base_link poses; ``inliers`` (N,): the flow's inlier tracks behind the step into
    each pose, 0 where the step was not measured (coasted and held steps are not fused). ``tracking``: the tracking
    camera's odometry already turned into base_link poses (``gpo.trajectory.base_from_sensor_odometry``); only its
    increments are used. Each source's poses are taken in the order of their stamps, a repeated stamp once; the
    sources' steps are fused in the order of their end times.
    """
    inliers = np.asarray(inliers, dtype=float)
    if inliers.shape != (len(floor),):
        raise ValueError(f"inliers must have one count per floor pose ({len(floor)}), got shape {inliers.shape}")
    floor_sigmas = settings.floor_speed_sigma_mps, settings.floor_turn_sigma_radps
    tracking_sigmas = settings.tracking_speed_sigma_mps, settings.tracking_turn_sigma_radps
    floor_scale = settings.floor_reference_inliers / np.maximum(inliers, 1.0)
    events = [
        *_steps("floor", floor, floor_sigmas, np.maximum(1.0, floor_scale), inliers > 0),
        *_steps("tracking", tracking, tracking_sigmas, np.ones(len(tracking)), np.ones(len(tracking), dtype=bool)),
    ]
    events.sort(key=lambda event: event[1])
    start = floor.times[0]
    fusion = OdometryFusion(start, ProcessNoise(settings.accel_mps2, settings.angular_accel_radps2))
    wanted = iter(floor.times[1:])
    poses, covariances, next_time = [fusion.state[:3]], [fusion.covariance], next(wanted, None)
    for source, time_s, increment, dt, covariance in events:
        while next_time is not None and next_time < time_s:
            fusion.predict(max(next_time, fusion.time_s))
            poses.append(fusion.state[:3])
            covariances.append(fusion.covariance)
            next_time = next(wanted, None)
        if time_s > start:
            fusion.add(source, time_s, increment, dt, covariance)
    while next_time is not None:
        fusion.predict(max(next_time, fusion.time_s))
        poses.append(fusion.state[:3])
        covariances.append(fusion.covariance)
        next_time = next(wanted, None)
    poses = np.array(poses)
    trajectory = Trajectory.from_planar(floor.stamps_ns, *poses.T, frame_id=floor.frame_id)
    return FusedPath(trajectory, np.array(covariances), fusion.refused)


def _steps(source: str, path: Trajectory, sigmas, variance_scale: np.ndarray, measured: np.ndarray):
    """(source, end time s, base_link increment or None where not ``measured``, dt s, covariance (2, 2)) of each
    step between consecutive distinct stamps of ``path``, its poses taken in the order of their stamps.
    ``variance_scale`` and ``measured`` (N,) belong to the step into each pose."""
    times = np.asarray(path.times, dtype=float)
    order = np.argsort(times, kind="stable")
    order = order[np.r_[True, np.diff(times[order]) > 0]]  # a repeated stamp once, its first message
    planar = np.column_stack([path.positions[:, :2], path.yaw])[order]
    increments, times = between(planar[:-1], planar[1:]), times[order]
    return [
        (
            source,
            times[k + 1],
            increments[k] if measured[order[k + 1]] else None,
            times[k + 1] - times[k],
            increment_covariance(*sigmas, times[k + 1] - times[k]) * variance_scale[order[k + 1]],
        )
        for k in range(len(order) - 1)
    ]
