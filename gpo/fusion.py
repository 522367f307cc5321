"""An extended Kalman filter that fuses odometry sources into one path of ``base_link``.

State (``STATE``): x, y (m) and heading theta (rad) of base_link in the odometry frame, its forward speed v (m/s)
and yaw rate omega (rad/s). Process model: v and omega stay constant over a step, driven by white acceleration
noise (``ProcessNoise``); the pose moves along the exact arc they describe (``gpo.kinematics.arc_increment``),
and the covariance through the Jacobian of that motion.

Every source is used **differentially**, like robot_localization's differential mode: a source's pose increment
over its own interval dt (already turned into base_link: ``gpo.trajectory.base_from_sensor_odometry``) becomes a
measurement of (v, omega) = (arc length / dt, turn / dt). Absolute poses that drift (a tracking camera's odometry)
therefore never pull the filter's pose, only their motion counts, weighted by the covariance each measurement
carries.
Measurements must come in time order; ``OdometryFusion.add`` refuses stale ones (earlier than the filter's time)
and the caller decides what to skip.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from filterpy.kalman import ExtendedKalmanFilter

from gpo.kinematics import arc_increment, between
from gpo.trajectory import Trajectory

STATE = ("x", "y", "theta", "v", "omega")
VELOCITIES = np.array([[0.0, 0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 0.0, 1.0]])  # H: a source measures (v, omega)
MAX_NIS = 50.0  # an innovation this many sigmas squared away is refused as an outlier


class FilterDiverged(RuntimeError):
    """The filter's covariance stopped being a covariance (not finite, or not positive definite)."""


@dataclass(frozen=True)
class ProcessNoise:
    """White noise driving the constant-velocity model: ``accel_mps2`` (m/s^2 per sqrt(Hz)) on v and
    ``angular_accel_radps2`` (rad/s^2 per sqrt(Hz)) on omega."""

    accel_mps2: float = 0.5
    angular_accel_radps2: float = 1.0


def motion_jacobian(state: np.ndarray, dt: float) -> np.ndarray:
    """F (5, 5): the derivative of the first-order motion x += v cos(theta) dt, y += v sin(theta) dt,
    theta += omega dt with respect to the state."""
    theta, v = state[2], state[3]
    jacobian = np.eye(5)
    jacobian[0, 2], jacobian[0, 3] = -v * np.sin(theta) * dt, np.cos(theta) * dt
    jacobian[1, 2], jacobian[1, 3] = v * np.cos(theta) * dt, np.sin(theta) * dt
    jacobian[2, 4] = dt
    return jacobian


def process_covariance(state: np.ndarray, dt: float, noise: ProcessNoise) -> np.ndarray:
    """Q (5, 5) of one step: the accelerations' white noise integrated once into (v, omega) and twice into the pose."""
    theta = state[2]
    gain = np.array(
        [
            [0.5 * dt**2 * np.cos(theta), 0.0],
            [0.5 * dt**2 * np.sin(theta), 0.0],
            [0.0, 0.5 * dt**2],
            [dt, 0.0],
            [0.0, dt],
        ]
    )
    density = np.diag([noise.accel_mps2**2, noise.angular_accel_radps2**2]) / dt
    return gain @ density @ gain.T


def velocity_measurement(increment, dt: float) -> np.ndarray:
    """(v, omega) of a base_link increment (dx, dy, dtheta) over ``dt`` seconds, as the arc through it: the turn
    over dt, and the arc length over dt, from the step's component along the chord an arc of that turn would have
    (at half the turn: ``gpo.kinematics.arc_increment``). Exact for an arc; a step's sideways noise then leaves the
    speed unbiased, where the step's length (always longer than its projection) would read it too fast."""
    dx, dy, turn = (float(value) for value in increment)
    half = 0.5 * turn
    along = dx * np.cos(half) + dy * np.sin(half)
    arc = along if abs(half) < 1e-9 else along * half / np.sin(half)
    return np.array([arc / dt, turn / dt])


class OdometryFusion:
    """The EKF of ``STATE`` over time (seconds). ``add(time_s, increment, dt_s, covariance)`` takes a source's base_link
    increment over [time_s - dt_s, time_s] with the covariance (2, 2) of the (v, omega) it implies."""

    def __init__(self, start_s: float, noise: ProcessNoise = ProcessNoise(), pose=(0.0, 0.0, 0.0)):
        self.noise = noise
        self.time_s = float(start_s)
        self._filter = ExtendedKalmanFilter(dim_x=5, dim_z=2)
        self._filter.x = np.array([*pose, 0.0, 0.0], dtype=float)
        self._filter.P = np.diag([1e-12, 1e-12, 1e-12, 1.0, 1.0])  # the pose is the origin; the motion unknown
        self.refused = 0

    @property
    def state(self) -> np.ndarray:
        """The state (5,) at ``time_s``."""
        return self._filter.x.copy()

    @property
    def covariance(self) -> np.ndarray:
        """The state's covariance (5, 5)."""
        return self._filter.P.copy()

    def predict(self, time_s: float) -> None:
        """Move the state to ``time_s`` (not before the filter's time) with the constant-velocity model."""
        dt = time_s - self.time_s
        if dt < 0:
            raise ValueError(f"cannot predict back in time: {time_s:.6f} s is before the filter's {self.time_s:.6f} s")
        if dt == 0:
            return
        ekf, state = self._filter, self._filter.x
        ekf.F = motion_jacobian(state, dt)
        ekf.Q = process_covariance(state, dt, self.noise)
        step = arc_increment(state[3], state[4], dt)
        cos, sin = np.cos(state[2]), np.sin(state[2])
        ekf.P = ekf.F @ ekf.P @ ekf.F.T + ekf.Q
        ekf.x = state + np.array([cos * step[0] - sin * step[1], sin * step[0] + cos * step[1], step[2], 0.0, 0.0])
        self.time_s = time_s
        self._check()

    def add(self, time_s: float, increment, dt_s: float, covariance) -> bool:
        """Fuse one source's increment (dx, dy, dtheta) over the ``dt_s`` seconds ending at ``time_s``; returns
        False when the measurement is refused as an outlier (its normalised innovation squared above ``MAX_NIS``).
        Raises ValueError for a measurement before the filter's time or with non-finite numbers."""
        increment = np.asarray(increment, dtype=float)
        if not (np.isfinite(increment).all() and dt_s > 0):
            raise ValueError(f"a measurement needs a finite increment and dt_s > 0, got {increment} over {dt_s}")
        self.predict(time_s)
        measured = velocity_measurement(increment, dt_s)
        ekf = self._filter
        innovation = measured - ekf.x[3:]
        spread = VELOCITIES @ ekf.P @ VELOCITIES.T + covariance
        if innovation @ np.linalg.solve(spread, innovation) > MAX_NIS:
            self.refused += 1
            return False
        ekf.update(measured, lambda _: VELOCITIES, lambda state: state[3:], R=np.asarray(covariance, dtype=float))
        self._check()
        return True

    def _check(self) -> None:
        covariance = self._filter.P
        try:
            np.linalg.cholesky(0.5 * (covariance + covariance.T) + 1e-12 * np.eye(5))
        except np.linalg.LinAlgError:
            raise FilterDiverged(f"the covariance at {self.time_s:.3f} s is no longer positive definite") from None
        if not np.isfinite(covariance).all():
            raise FilterDiverged(f"the covariance at {self.time_s:.3f} s is no longer finite")


@dataclass(frozen=True)
class FusionSettings:
    """What ``--method fused`` fuses: the floor odometry of ``floor_method`` with a tracking camera's own odometry on
    ``tracking_topic`` (nav_msgs/Odometry of ``tracking_frame``, whose pose in base_link the bag's /tf_static holds).
    Each source's increments are (v, omega) measurements with these standard deviations (m/s, rad/s); a floor frame
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
    accel_mps2: float = 0.1
    angular_accel_radps2: float = 0.3


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
    increments are used. Both may hold repeated or unordered stamps: steps that do not move forward in time are
    left out, and the sources' steps are fused in time order.
    """
    inliers = np.asarray(inliers, dtype=float)
    if inliers.shape != (len(floor),):
        raise ValueError(f"inliers must have one count per floor pose ({len(floor)}), got shape {inliers.shape}")
    floor_covariance = np.diag([settings.floor_speed_sigma_mps, settings.floor_turn_sigma_radps]) ** 2
    tracking_covariance = np.diag([settings.tracking_speed_sigma_mps, settings.tracking_turn_sigma_radps]) ** 2
    measured = inliers[1:] > 0
    floor_scale = np.maximum(1.0, settings.floor_reference_inliers / np.where(measured, inliers[1:], 1.0))
    events = [
        *_increments(floor, floor_covariance * floor_scale[:, None, None], measured),
        *_increments(tracking, np.broadcast_to(tracking_covariance, (max(len(tracking) - 1, 0), 2, 2)), None),
    ]
    events.sort(key=lambda event: event[0])
    start = floor.times[0]
    fusion = OdometryFusion(start, ProcessNoise(settings.accel_mps2, settings.angular_accel_radps2))
    wanted = iter(floor.times[1:])
    poses, covariances, next_time = [fusion.state[:3]], [fusion.covariance], next(wanted, None)
    for time_s, increment, dt, covariance in events:
        while next_time is not None and next_time < time_s:
            fusion.predict(max(next_time, fusion.time_s))
            poses.append(fusion.state[:3])
            covariances.append(fusion.covariance)
            next_time = next(wanted, None)
        if time_s > start:
            fusion.add(time_s, increment, dt, covariance)
    while next_time is not None:
        fusion.predict(max(next_time, fusion.time_s))
        poses.append(fusion.state[:3])
        covariances.append(fusion.covariance)
        next_time = next(wanted, None)
    poses = np.array(poses)
    trajectory = Trajectory.from_planar(floor.stamps_ns, *poses.T, frame_id=floor.frame_id)
    return FusedPath(trajectory, np.array(covariances), fusion.refused)


def _increments(trajectory: Trajectory, covariances: np.ndarray, use: np.ndarray | None):
    """(end time s, base_link increment, dt s, covariance) of each step of ``trajectory`` that moves forward in time
    and where ``use`` (None: everywhere) is True; ``covariances`` (N - 1, 2, 2), one per step."""
    planar = np.column_stack([trajectory.positions[:, :2], np.unwrap(trajectory.yaw)])
    steps = between(planar[:-1], planar[1:])
    times = trajectory.times
    forward = np.diff(times) > 0
    return [
        (times[k + 1], steps[k], times[k + 1] - times[k], covariances[k])
        for k in np.flatnonzero(forward if use is None else use & forward)
    ]
