"""An extended Kalman filter that fuses odometry sources into one path of ``base_link``, and calibrates one of them.

State (``STATE``): x, y (m) and heading theta (rad) of base_link in the odometry frame, its forward speed v (m/s)
and yaw rate omega (rad/s), and two **biases** of the calibrated source (the tracking camera): its ``scale`` error
(its distances are 1 + scale times the true ones) and its ``yaw_bias`` (rad/s added to every turn rate). Process
model: v and omega stay constant over a step, driven by white acceleration noise (``ProcessNoise``); the pose moves
along the exact arc they describe (``gpo.odometry.kinematics.arc_increment``), the covariance through the Jacobian of
that motion; the biases are random walks (``BiasModel``).

Every source is used **differentially**, like robot_localization's differential mode: only a source's pose
increments count (already turned into base_link: ``gpo.io.trajectory.base_from_sensor_odometry``), never its absolute
pose, which drifts. An increment over [t0, t1] is a measurement of the filter's own motion between those times: the
filter keeps a copy of its pose at t0 for each source (stochastic cloning, Roumeliotis and Burdick 2002), and the
measurement is the forward part and the turn of ``between(clone, pose)`` (``MEASURED``), with the covariance the
increment carries. For the calibrated source the expected measurement is that motion as the biased source sees it,
((1 + scale) dx, dtheta + yaw_bias dt): where both sources measure, their disagreement is what the biases are
estimated from; where only the calibrated one does (a floor outage), its increments are corrected by them.
base_link does not slide sideways, so a source's sideways steps are its own error and are not fused.
Measurements must come in time order; ``OdometryFusion.add`` refuses stale ones (earlier than the filter's time)
and the caller decides what to skip.

The calibrated source's increments are correlated: each is the difference of two poses that each carry white
jitter, so consecutive increments share one pose's jitter with opposite signs, and n increments add up to the
jitter of two poses, not of 2n. The filter keeps that correlation exactly: the jitter of the source's last pose
(along its heading and in yaw) is a state (``JITTER``), cloned with the pose; an increment measures
motion + new jitter - last jitter + the random walks' noise (``tracking_increment_covariance``). How the two
sources' messages become the filter's increments, live or from a recording: ``gpo.fusion.streaming``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.linalg.lapack import dpotrf

from gpo.odometry.kinematics import arc_increment

STATE = ("x", "y", "theta", "v", "omega", "scale", "yaw_bias")
MOTION = 5  # the state's motion part: x, y, theta, v, omega
BIASES = slice(5, 7)
JITTER = slice(7, 9)  # the calibrated source's jitter (along its heading m, yaw rad) at its last pose
NEW_JITTER = slice(9, 11)  # its jitter at the pose ending the step being fused
AUGMENTED = 11  # the clones follow
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


@dataclass(frozen=True)
class BiasModel:
    """The calibrated source's biases before any measurement, zero mean with standard deviations ``scale_sigma``
    (a fraction: 0.05 = distances 5 % off) and ``yaw_bias_sigma_radps`` (rad/s), and how fast they may wander:
    random walks of ``scale_walk_per_sqrt_s`` (1/sqrt(s)) and ``yaw_bias_walk_radps_per_sqrt_s`` (rad/s/sqrt(s))."""

    scale_sigma: float = 0.05
    yaw_bias_sigma_radps: float = 0.005
    scale_walk_per_sqrt_s: float = 1e-4
    yaw_bias_walk_radps_per_sqrt_s: float = 1e-5


def motion_jacobian(state: np.ndarray, dt: float) -> np.ndarray:
    """F (5, 5): the derivative of the first-order motion x += v cos(theta) dt, y += v sin(theta) dt,
    theta += omega dt with respect to the state's motion part (x, y, theta, v, omega)."""
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


def tracking_increment_covariance(position_walk_m_per_sqrt_s: float, yaw_walk_rad_per_sqrt_s: float, dt: float):
    """R (2, 2) of (dx, dtheta) of a tracking camera's increment over ``dt`` seconds whose position and heading are
    random walks (m/sqrt(s), rad/sqrt(s)): their variance grows with dt. (The jitter on each pose is a state of the
    filter, ``JITTER``, because it correlates consecutive increments.)"""
    return np.diag([position_walk_m_per_sqrt_s**2 * dt, yaw_walk_rad_per_sqrt_s**2 * dt])


def increment_jacobians(clone: np.ndarray, pose: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The derivatives (3, 3) of ``gpo.odometry.kinematics.between(clone, pose)`` with respect to ``clone`` and to
    ``pose``
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
    start), dx and dtheta are measured as those of ``between(clone, pose)``, for the source named ``calibrated``
    as ((1 + scale) dx, dtheta + yaw_bias dt_s). Whatever the state's v and omega did inside the step, the pose is
    corrected by the whole increment, so the path does not lag behind a source by part of its interval.
    """

    def __init__(
        self,
        start_s: float,
        noise: ProcessNoise = ProcessNoise(),
        pose=(0.0, 0.0, 0.0),
        sources=("floor", "tracking"),
        calibrated: str | None = "tracking",
        biases: BiasModel = BiasModel(),
        jitter=(0.0, 0.0),
    ):
        self.noise, self.biases = noise, biases
        self.time_s = float(start_s)
        self.calibrated = calibrated
        self._jitter_variance = np.square(np.asarray(jitter, dtype=float))
        # imported here: filterpy's package imports scipy.stats, half a second a process that never fuses pays
        from filterpy.kalman import ExtendedKalmanFilter

        size = AUGMENTED + 3 * len(sources)
        self._filter = ExtendedKalmanFilter(dim_x=size, dim_z=len(MEASURED))
        self._filter.x = np.zeros(size)
        self._filter.x[:3] = pose
        self._filter.x[AUGMENTED:] = np.tile(np.asarray(pose, dtype=float), len(sources))
        self._filter.P = np.zeros((size, size))
        self._filter.P[3:5, 3:5] = np.eye(2)  # the pose is the given one, the motion unknown
        self.forget_biases()  # the biases start at their prior
        self._fresh_jitter(JITTER)
        self._clones = {name: (AUGMENTED + 3 * k, self.time_s) for k, name in enumerate(sources)}
        self._jitter = 1e-12 * np.eye(size)  # added to the covariance before _check's Cholesky factorisation
        self.refused = 0

    @property
    def state(self) -> np.ndarray:
        """The state (7,) at ``time_s``: x, y, theta, v, omega, scale, yaw_bias."""
        return self._filter.x[: len(STATE)].copy()

    @property
    def covariance(self) -> np.ndarray:
        """The state's covariance (7, 7)."""
        return self._filter.P[: len(STATE), : len(STATE)].copy()

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
        ekf, state = self._filter, self._filter.x[:MOTION]
        motion = motion_jacobian(state, dt)
        # P = F P F' with F the identity outside the motion block (biases and clones stay): only its rows and columns
        ekf.P[:MOTION] = motion @ ekf.P[:MOTION]
        ekf.P[:, :MOTION] = ekf.P[:, :MOTION] @ motion.T
        ekf.P[:MOTION, :MOTION] += process_covariance(state, dt, self.noise)
        ekf.P[5, 5] += self.biases.scale_walk_per_sqrt_s**2 * dt
        ekf.P[6, 6] += self.biases.yaw_bias_walk_radps_per_sqrt_s**2 * dt
        step = arc_increment(state[3], state[4], dt)
        cos, sin = math.cos(state[2]), math.sin(state[2])
        moved = np.array([cos * step[0] - sin * step[1], sin * step[0] + cos * step[1], step[2], 0.0, 0.0])
        ekf.x[:MOTION] = state + moved
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
        calibrated = source == self.calibrated
        if calibrated:
            self._fresh_jitter(NEW_JITTER)
        fused = (
            increment is not None
            and abs(time_s - dt_s - since) < 1e-6
            and self._update(index, increment, covariance, dt_s if calibrated else None)
        )
        if calibrated and fused:  # the new pose's jitter is the next step's old one
            self._copy(NEW_JITTER, JITTER)
        elif calibrated:  # not fused: the jitter of the pose the clone moves to is a fresh draw
            self._fresh_jitter(JITTER)
        self._clone(source)
        self._check()
        return fused

    def forget_biases(self) -> None:
        """Put the calibrated source's biases back to their prior (``BiasModel``): zero, with the prior's variances,
        uncorrelated with the rest of the state."""
        ekf = self._filter
        ekf.x[BIASES] = 0.0
        ekf.P[BIASES, :] = 0.0
        ekf.P[:, BIASES] = 0.0
        ekf.P[5, 5], ekf.P[6, 6] = self.biases.scale_sigma**2, self.biases.yaw_bias_sigma_radps**2

    def _update(self, index: int, increment, covariance, biased_dt: float | None) -> bool:
        """Fuse one increment against the clone at ``index``; ``biased_dt``: the step's seconds when the source is
        the calibrated one (its measurement then carries the biases), else None."""
        ekf, clone = self._filter, slice(index, index + 3)
        measured = np.asarray(increment, dtype=float)[MEASURED]
        covariance = np.asarray(covariance, dtype=float)
        # the expected measurement and its Jacobian at the state, once for the NIS gate and filterpy's update:
        # between(clone, pose) is the difference turned into the clone's frame, by_pose that rotation
        by_clone, by_pose = increment_jacobians(ekf.x[clone], ekf.x[:3])
        moved = (by_pose @ (ekf.x[:3] - ekf.x[clone]))[MEASURED]
        moved[1] = _wrap(moved[1])
        linear = np.zeros((len(MEASURED), len(ekf.x)))
        linear[:, :3], linear[:, clone] = by_pose[MEASURED], by_clone[MEASURED]
        expected = moved
        if biased_dt is not None:  # ((1 + scale) dx, dtheta + yaw_bias dt) + new jitter - old jitter
            scale, yaw_bias = ekf.x[BIASES]
            jitter = ekf.x[NEW_JITTER] - ekf.x[JITTER]
            expected = np.array([(1.0 + scale) * moved[0] + jitter[0], moved[1] + yaw_bias * biased_dt + jitter[1]])
            linear[0] *= 1.0 + scale
            linear[0, 5], linear[1, 6] = moved[0], biased_dt
            linear[:, JITTER], linear[:, NEW_JITTER] = -np.eye(2), np.eye(2)
        innovation = _residual(measured, expected)
        spread = linear @ ekf.P @ linear.T + covariance
        if _nis(innovation, spread) > MAX_NIS:
            self.refused += 1
            return False
        ekf.update(measured, lambda _: linear, lambda _: expected, R=covariance, residual=_residual)
        return True

    def _fresh_jitter(self, block: slice) -> None:
        """A new pose's jitter in ``block``: zero mean, its variance, uncorrelated with everything else."""
        ekf = self._filter
        ekf.x[block] = 0.0
        ekf.P[block, :] = 0.0
        ekf.P[:, block] = 0.0
        ekf.P[block, block] = np.diag(self._jitter_variance)

    def _copy(self, source: slice, target: slice) -> None:
        """Copy the states ``source`` with their covariance and correlations into ``target``."""
        ekf = self._filter
        ekf.x[target] = ekf.x[source]
        ekf.P[target, :] = ekf.P[source, :]
        ekf.P[:, target] = ekf.P[:, source]

    def _clone(self, source: str) -> None:
        """Copy the pose, its covariance and its correlations into ``source``'s clone, stamped now."""
        index, _ = self._clones[source]
        self._copy(slice(0, 3), slice(index, index + 3))
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
