"""What a tracking camera (like an Intel RealSense T265) reports along a plan: its own drifting odometry.

``tracking_odometry`` reports what a T265 would: the pose of its body frame ``camera_pose_frame``
(x forward, y left, z up, as realsense-ros publishes it) in ``camera_odom_frame``, the body frame at the
first sample, with seeded drift that acts on increments (see ``TrackingDrift``). ``camera_truth`` is
the same without drift.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from gpo.cameras.base import finite
from gpo.io.trajectory import NS_PER_S, Trajectory
from gpo.sim.plans import MotionPlan, sample_clock
from gpo.sim.segments import non_negative


@dataclass(frozen=True)
class TrackingDrift:
    """How a tracking camera's odometry drifts. All errors act on increments, so they accumulate.

    Per step Δt between samples, with n, m standard normal and u the floor normal (up) in the odometry frame::

        Ψ_k = Ψ_{k-1} + b Δt + q_ψ √Δt n_k                       (yaw error about u)
        p̂_k = p̂_{k-1} + R_u(Ψ_{k-1}) [(1 + ε) Δp_k + q_p √Δt m_k]  (Δp_k: true step of the camera)
        R̂_k = R_u(Ψ_k) R_k

    then white noise on each reported pose but the first. Fields: ``scale_error`` ε (0.02 = distances
    2 % too long); ``yaw_bias_radps`` b (rad/s); ``yaw_walk_rad_per_sqrt_s`` q_ψ (rad/√s);
    ``position_walk_m_per_sqrt_s`` q_p (m/√s, each axis); ``jitter_m`` (m, each axis) and ``jitter_rad``
    (rad, about u) of white noise.

    The defaults give 0.09-0.24 m of final error (10th-90th percentile over 20 seeds) on the 15-16 m paths
    ``long1``-``long3`` at up to 0.5 m/s, 0.16 m on average, as the first paper measured for its T265
    (0.166 m on average).
    """

    scale_error: float = 0.02
    yaw_bias_radps: float = 1e-3
    yaw_walk_rad_per_sqrt_s: float = 1e-3
    position_walk_m_per_sqrt_s: float = 5e-3
    jitter_m: float = 5e-4
    jitter_rad: float = 5e-4

    def __post_init__(self):
        finite("TrackingDrift.scale_error", self.scale_error)
        finite("TrackingDrift.yaw_bias_radps", self.yaw_bias_radps)
        for name in ("yaw_walk_rad_per_sqrt_s", "position_walk_m_per_sqrt_s", "jitter_m", "jitter_rad"):
            non_negative(f"TrackingDrift.{name}", getattr(self, name))


T265_DRIFT = TrackingDrift()


NO_DRIFT = TrackingDrift(0.0, 0.0, 0.0, 0.0, 0.0, 0.0)


def _body_mount(mount) -> tuple[np.ndarray, Rotation]:
    """(position (3,) m, rotation base <- camera body) from a (translation, rotation) pair, the rotation a
    scipy ``Rotation`` or a quaternion (x, y, z, w); or from a ``gpo.cameras.rig.CameraMount`` (its body frame)."""
    if hasattr(mount, "body_rotation"):
        return np.asarray(mount.position, dtype=np.float64), mount.body_rotation
    translation, rotation = mount
    translation = np.asarray(translation, dtype=np.float64)
    if translation.shape != (3,) or not np.isfinite(translation).all():
        raise ValueError(f"the mount's translation must be 3 finite numbers in metres, got {translation!r}")
    if not isinstance(rotation, Rotation):
        quaternion = np.asarray(rotation, dtype=np.float64)
        if quaternion.shape != (4,):
            raise ValueError(
                f"the mount's rotation must be a scipy Rotation or a quaternion (x, y, z, w), got {rotation!r}"
            )
        rotation = Rotation.from_quat(quaternion)
    if not rotation.single:
        raise ValueError("the mount's rotation must be a single rotation")
    return translation, rotation


def _camera_in_first_pose(plan: MotionPlan, mount, rate_hz: float, start_ns: int):
    """Stamps (ns), positions (N, 3) and rotations of the camera body frame in the body frame at the first sample.

    world <- camera = (world <- base) (base <- camera); odometry <- camera = (world <- camera_0)⁻¹ (world <- camera).
    """
    translation, rotation = _body_mount(mount)
    stamps_ns, times = sample_clock(plan.duration_s, rate_hz, start_ns)
    state = plan.sample(times)
    base = Rotation.from_euler("z", state.yaw[:, None])
    camera_rotations = base * rotation
    camera_positions = np.column_stack([state.x, state.y, np.zeros_like(state.x)]) + base.apply(translation)
    first = camera_rotations[0].inv()
    return stamps_ns, first.apply(camera_positions - camera_positions[0]), first * camera_rotations


def camera_truth(plan: MotionPlan, mount, rate_hz: float = 200.0, start_ns: int = 0) -> Trajectory:
    """The tracking camera's exact pose: ``camera_pose_frame`` in ``camera_odom_frame``, identity at the first sample.

    ``mount`` is the camera body frame (x forward, y left, z up) in base_link: a pair (translation (3,) m,
    rotation as a scipy ``Rotation`` or a quaternion (x, y, z, w)), or a ``gpo.cameras.rig.CameraMount``.
    """
    stamps_ns, positions, rotations = _camera_in_first_pose(plan, mount, rate_hz, start_ns)
    return Trajectory(stamps_ns, positions, rotations.as_quat(), "camera_odom_frame", "camera_pose_frame")


def tracking_odometry(
    plan: MotionPlan,
    mount,
    rate_hz: float = 200.0,
    drift: TrackingDrift = T265_DRIFT,
    seed: int = 0,
    start_ns: int = 0,
) -> Trajectory:
    """The odometry a T265-like tracking camera reports while the robot follows ``plan``.

    ``camera_pose_frame`` in ``camera_odom_frame`` (the camera body frame at the first sample, so the
    first pose is the identity) at ``rate_hz``, stamped from ``start_ns``, with ``drift`` seeded by
    ``seed`` (see ``TrackingDrift``; ``NO_DRIFT`` gives ``camera_truth``). ``mount`` as in ``camera_truth``.
    The yaw error turns about the floor normal as the camera sees it, because a visual-inertial
    tracker knows gravity and drifts only in heading. A real T265 levels its odometry frame with
    gravity, so its first pose carries the mount's pitch and roll; here the first pose is the identity.
    """
    stamps_ns, positions, rotations = _camera_in_first_pose(plan, mount, rate_hz, start_ns)
    up = _body_mount(mount)[1].inv().apply([0.0, 0.0, 1.0])
    rng = np.random.default_rng(seed)
    count = len(stamps_ns)
    dt = np.diff(stamps_ns) / NS_PER_S
    yaw_steps = drift.yaw_bias_radps * dt + drift.yaw_walk_rad_per_sqrt_s * np.sqrt(dt) * rng.standard_normal(count - 1)
    yaw_error = np.concatenate([[0.0], np.cumsum(yaw_steps)])
    steps = (1 + drift.scale_error) * np.diff(positions, axis=0)
    steps += drift.position_walk_m_per_sqrt_s * np.sqrt(dt)[:, None] * rng.standard_normal((count - 1, 3))
    turned = _about(up, yaw_error[:-1]).apply(steps)
    estimated = np.concatenate([np.zeros((1, 3)), np.cumsum(turned, axis=0)])
    jitter_position = drift.jitter_m * rng.standard_normal((count, 3))
    jitter_yaw = drift.jitter_rad * rng.standard_normal(count)
    jitter_position[0], jitter_yaw[0] = 0.0, 0.0
    orientations = _about(up, yaw_error + jitter_yaw) * rotations
    return Trajectory(
        stamps_ns, estimated + jitter_position, orientations.as_quat(), "camera_odom_frame", "camera_pose_frame"
    )


def _about(axis: np.ndarray, angles: np.ndarray) -> Rotation:
    """Rotations by ``angles`` (N,) radians about the unit ``axis`` (3,)."""
    return Rotation.from_rotvec(np.outer(angles, axis))
