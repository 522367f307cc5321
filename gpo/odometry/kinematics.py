"""From the floor's motion to the robot's: the metric scale, the paper's bicycle model, exact rigid-body kinematics.

Frames and units
----------------
``base_link`` (REP-103): x forward, y left, origin at the rear-axle centre on the floor. A planar pose
(x, y, theta) is base_link's position in metres and heading in radians in the odometry frame; an
**increment** (dx, dy, dtheta) is the pose of base_link at the end of a frame interval in base_link at its
start. Arrays broadcast: every function takes scalars or arrays (..., 2) / (..., 3).

The measurement
---------------
The floor does not move, so when the floor image shows a floor point move from ``c`` to ``q`` (both in
base_link, metres, ``floor_displacement``), the robot's point at ``c`` moved by about ``d = c - q``. The first
paper reads that vector as the motion of a **virtual front wheel** a wheelbase L ahead of the rear axle (the
floor image's centre) and feeds it to a kinematic bicycle model.

The first paper's eqs. 23-34, as printed
----------------------------------------
Its (dx, dy) are the two components of the median motion vector m_bar in the GPI, V and delta the virtual
front wheel's speed and steering, l_r the distance from the rear axle to the centre of mass, L the wheelbase::

    (23) scale = z / f                                 z the camera's height, f its focal length (pixels)
    (24) m_bar = scale * m                             the pixel motion m in metres
    (25) V     = sqrt(dx^2 + dy^2) / dt
    (26) delta = arctan(dy / dx) - pi / 2
    (27) S     = L / tan(delta)                        rear axle to the instantaneous centre (IC)
    (28) beta  = arctan(l_r / S) = arctan(l_r tan(delta) / L)
    (29) R     = S / cos(beta)                         the centre of mass to the IC
    (30) theta_dot = omega = V / R = V tan(delta) cos(beta) / L
    (31) theta = theta + theta_dot dt
    (32) x_dot = V cos(theta + beta)
    (33) y_dot = V sin(theta + beta)
    (34) (x, y, theta)_{t+1} = (x, y, theta)_t + (x_dot, y_dot, theta_dot) dt

Where this module computes them otherwise (``PaperBicycle``, ``metres_per_pixel``):

- eqs. 23-24: ``metres_per_pixel(z, f)`` is eq. 23; the pipeline's ortho-GPI has its scale by construction
  (``FloorImage.metres_per_pixel``) and its affine map applies eq. 24 with the image's axes.
- eq. 26 is in the GPI's axes, where straight ahead lies along the image's y axis, hence the -pi/2. Here d is in
  base_link (x forward, y left), where straight ahead is d_y = 0, so delta = arctan(d_y / d_x) with no offset.
  With the paper's (dx, dy) taken as the wheel's motion towards the robot's right and forward (dx = -d_y,
  dy = d_x), eq. 26 read with the two-argument arctangent, atan2(dy, dx) - pi/2, is exactly this delta for
  every forward motion; read with the one-argument arctan as printed it is this delta when the wheel moves to
  the right and this delta - pi when it moves to the left, so the printed form needs atan2 to mean a steering
  angle. ``tests/test_paper_equations.py`` shows both.
- eqs. 27 and 29 are computed as printed (``instant_centre_distance``, ``turning_radius``); with delta = 0, S and
  R are infinite and eq. 30 is 0.
- eqs. 30-34 as printed, at the reference point l_r ahead of the rear axle; ``step`` returns the pose of
  base_link, l_r behind it. Eq. 31 is the third row of eq. 34; eqs. 32-33 use the heading at the frame's start.

Where the printed model falls short of the motion it measures (chapter 06 measures each):

- eq. 26's arctangent folds the direction of travel into a half turn and eq. 25's V is never negative, so
  reverse driving reads as driving forward, and on a turn on the spot (d_x ~ 0) the sign of delta flips with
  the noise in d_x;
- eq. 30 takes V as the reference point's speed, while eq. 25 measures the front wheel's; they agree only when
  the reference point is the front wheel (l_r = L): otherwise the heading rate is off by cos(beta) / cos(delta)
  (``paper_heading_rate_ratio``), 9.5 % at delta = 24 degrees with l_r = 0;
- the Euler step (34) treats the frame's chord as a straight line.

The **exact** kinematics of a rigid robot that does not slide sideways at its rear axle (the base_link origin)
need no model at all: a speed v of the rear axle and a yaw rate omega move the point (L, 0) at
(v, omega L), so v = V cos(delta) and omega = V sin(delta) / L with delta = atan2 and V signed, which holds
forwards, backwards and on the spot (``exact_velocities``); a constant (v, omega) over dt is an exact circular
arc (``arc_increment``), and ``increment_from_point_motion`` inverts the whole frame's motion of the
measured point exactly, in closed form (no first-order step at all).

A third route needs no kinematic model either: the rigid 2-D motion of many floor points between two frames
(``increment_from_point_pairs``) is the frame's increment, sideways sliding included.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

SMALL_ANGLE = 1e-3  # below this (rad) the arc functions use their Taylor series (exact to 1e-20 there)


def metres_per_pixel(height_m: float, focal_px: float) -> float:
    """Eqs. (23)-(24): the floor length one pixel spans in a top view from ``height_m`` with focal ``focal_px``."""
    if not (height_m > 0 and focal_px > 0):
        raise ValueError(f"height_m and focal_px must be positive, got {height_m!r} and {focal_px!r}")
    return float(height_m) / float(focal_px)


# ---------------------------------------------------------------------------------------------- SE(2)


def compose(pose, increment) -> np.ndarray:
    """The pose (..., 3) reached from ``pose`` (x, y, theta) by ``increment`` (dx, dy, dtheta) in its own frame."""
    pose, increment = np.asarray(pose, dtype=float), np.asarray(increment, dtype=float)
    cos, sin = np.cos(pose[..., 2]), np.sin(pose[..., 2])
    x = pose[..., 0] + cos * increment[..., 0] - sin * increment[..., 1]
    y = pose[..., 1] + sin * increment[..., 0] + cos * increment[..., 1]
    return np.stack([x, y, pose[..., 2] + increment[..., 2]], axis=-1)


def between(start, end) -> np.ndarray:
    """The increment (..., 3) from pose ``start`` to pose ``end``: ``compose(start, between(start, end)) == end``."""
    start, end = np.asarray(start, dtype=float), np.asarray(end, dtype=float)
    cos, sin = np.cos(start[..., 2]), np.sin(start[..., 2])
    dx, dy = end[..., 0] - start[..., 0], end[..., 1] - start[..., 1]
    turn = np.angle(np.exp(1j * (end[..., 2] - start[..., 2])))
    return np.stack([cos * dx + sin * dy, -sin * dx + cos * dy, turn], axis=-1)


def integrate(increments, start=(0.0, 0.0, 0.0)) -> np.ndarray:
    """Poses (N + 1, 3): ``start`` and the poses reached by the ``increments`` (N, 3) one after another."""
    poses = [np.asarray(start, dtype=float)]
    for increment in np.asarray(increments, dtype=float).reshape(-1, 3):
        poses.append(compose(poses[-1], increment))
    return np.array(poses)


def _sinc_cosc(phi):
    """sin(phi)/phi and (1 - cos(phi))/phi, with the series near phi = 0; floats for a float ``phi``."""
    if isinstance(phi, float) and math.isfinite(phi):  # one angle (np.float64 is a float too): math is much faster
        if abs(phi) < SMALL_ANGLE:
            p2 = phi**2
            return 1.0 - p2 / 6.0 + p2**2 / 120.0, phi * (0.5 - p2 / 24.0 + p2**2 / 720.0)
        return math.sin(phi) / phi, 2.0 * math.sin(phi / 2.0) ** 2 / phi
    phi = np.asarray(phi, dtype=float)
    small = np.abs(phi) < SMALL_ANGLE
    safe = np.where(small, 1.0, phi)
    versine = 2.0 * np.sin(safe / 2.0) ** 2  # 1 - cos, without the cancellation
    p2 = phi**2
    sinc = np.where(small, 1.0 - p2 / 6.0 + p2**2 / 120.0, np.sin(safe) / safe)
    cosc = np.where(small, phi * (0.5 - p2 / 24.0 + p2**2 / 720.0), versine / safe)
    return sinc, cosc


def arc_increment(v, omega, dt) -> np.ndarray:
    """The exact increment (..., 3) of driving ``dt`` seconds at rear-axle speed ``v`` (m/s) and yaw rate ``omega``
    (rad/s): a circular arc (a straight line when omega = 0), base_link never sliding sideways."""
    one = all(isinstance(a, float) for a in (v, omega, dt))  # one step, as the EKF predicts: no arrays needed
    if not one:
        v, omega, dt = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in (v, omega, dt)))
    phi, distance = omega * dt, v * dt
    sinc, cosc = _sinc_cosc(phi)
    parts = [distance * sinc, distance * cosc, phi]
    return np.array(parts) if one else np.stack(parts, axis=-1)


# --------------------------------------------------------------------------------- the paper's model


@dataclass(frozen=True)
class PaperBicycle:
    """The first paper's kinematic bicycle model, eqs. (25)-(34) (listed in the module docstring), in base_link.

    ``wheelbase_m`` L: from the rear axle to the virtual front wheel, the floor point whose motion is
    measured (the floor image's centre). ``rear_to_reference_m`` l_r: from the rear axle to the reference
    point whose pose the model integrates (the paper's centre of gravity); l_r = L makes eq. 30 exact.
    """

    wheelbase_m: float
    rear_to_reference_m: float

    def __post_init__(self):
        if not self.wheelbase_m > 0:
            raise ValueError(f"wheelbase_m (L) must be positive, got {self.wheelbase_m!r}")
        if not 0 <= self.rear_to_reference_m <= self.wheelbase_m:
            raise ValueError(
                f"rear_to_reference_m (l_r) must lie between 0 and the wheelbase {self.wheelbase_m} m, "
                f"got {self.rear_to_reference_m!r}"
            )

    def inputs(self, displacement_m, dt_s) -> tuple[np.ndarray, np.ndarray]:
        """Eqs. (25)-(26): speed V (m/s, never negative) and steering delta (rad) from the front wheel's
        displacement (..., 2) in base_link over ``dt_s``: delta = arctan(d_y / d_x), eq. 26 in base_link's axes
        (the paper's arctan(dy / dx) - pi/2 is in the GPI's; module docstring)."""
        d = np.asarray(displacement_m, dtype=float)
        speed = np.hypot(d[..., 0], d[..., 1]) / dt_s
        with np.errstate(divide="ignore", invalid="ignore"):
            steering = np.arctan(d[..., 1] / d[..., 0])
        return speed, np.nan_to_num(steering)

    def slip(self, steering) -> np.ndarray:
        """Eq. (28): the slip angle beta (rad) at the reference point."""
        return np.arctan(self.rear_to_reference_m * np.tan(steering) / self.wheelbase_m)

    def instant_centre_distance(self, steering) -> np.ndarray:
        """Eq. (27): S = L / tan(delta), from the rear axle to the instantaneous centre (m), infinite when straight."""
        with np.errstate(divide="ignore"):
            return self.wheelbase_m / np.tan(steering)

    def turning_radius(self, steering) -> np.ndarray:
        """Eq. (29): R = S / cos(beta), the reference point's turning radius (m), infinite when driving straight."""
        return self.instant_centre_distance(steering) / np.cos(self.slip(steering))

    def rates(self, speed, steering, theta) -> np.ndarray:
        """Eqs. (30), (32), (33): (x_dot, y_dot, theta_dot) of the reference point in the odometry frame."""
        beta = self.slip(steering)
        theta_dot = speed * np.cos(beta) * np.tan(steering) / self.wheelbase_m
        return np.stack([speed * np.cos(theta + beta), speed * np.sin(theta + beta), theta_dot], axis=-1)

    def step(self, pose, displacement_m, dt_s) -> np.ndarray:
        """Eqs. (25)-(34): base_link's pose (x, y, theta) after one frame whose front-wheel displacement (2,) m
        in base_link was measured. The model moves its reference point by the Euler step of eq. (34) (its third
        row is eq. 31); base_link lies l_r behind it."""
        pose = np.asarray(pose, dtype=float)
        speed, steering = self.inputs(displacement_m, dt_s)
        lever = self.rear_to_reference_m
        reference = pose[:2] + lever * np.array([np.cos(pose[2]), np.sin(pose[2])])
        x_dot, y_dot, theta_dot = self.rates(speed, steering, pose[2])
        x, y, theta = reference[0] + x_dot * dt_s, reference[1] + y_dot * dt_s, pose[2] + theta_dot * dt_s
        return np.array([x - lever * np.cos(theta), y - lever * np.sin(theta), theta])


def paper_heading_rate_ratio(steering, wheelbase_m: float, rear_to_reference_m: float) -> np.ndarray:
    """Eq. (30)'s heading rate over the true one for a front-wheel speed V at steering ``steering`` (rad):
    cos(beta) / cos(delta). 1 when l_r = L; above 1 otherwise."""
    beta = np.arctan(rear_to_reference_m * np.tan(steering) / wheelbase_m)
    return np.cos(beta) / np.cos(steering)


# ------------------------------------------------------------------------------------- the exact kinematics


def exact_velocities(speed, steering, wheelbase_m: float) -> tuple[np.ndarray, np.ndarray]:
    """Rear-axle speed v = V cos(delta) (m/s) and yaw rate omega = V sin(delta) / L (rad/s) of a rigid robot whose
    point (L, 0) moves at speed V (signed) in direction delta (rad, from atan2)."""
    return speed * np.cos(steering), speed * np.sin(steering) / wheelbase_m


def point_velocity_inputs(velocity_mps) -> tuple[np.ndarray, np.ndarray]:
    """Signed speed V and steering delta in (-90, 90] degrees of a point moving at ``velocity_mps`` (..., 2):
    V < 0 when it moves backwards, so that reverse driving and turning on the spot keep their sense."""
    velocity = np.asarray(velocity_mps, dtype=float)
    steering = np.arctan2(velocity[..., 1], velocity[..., 0])
    backwards = np.cos(steering) < -1e-12
    steering = np.where(backwards, np.angle(np.exp(1j * (steering + np.pi))), steering)
    speed = np.where(backwards, -1.0, 1.0) * np.hypot(velocity[..., 0], velocity[..., 1])
    return speed, steering


def increment_from_point_motion(point_m, moved_to_m) -> np.ndarray:
    """The exact increment (dx, dy, dtheta) of a frame in which the floor point seen at ``point_m`` (2,) in base_link
    is seen at ``moved_to_m`` (2,) at the frame's end, for a rigid robot moving on one circular arc without sliding
    sideways at its rear axle (constant v and omega over the frame: forwards, backwards or on the spot).

    The point seen at c is seen at q = T^-1 c, so c = R(phi) q + t. The rear axle moves along the chord of its arc,
    and a chord lies at half the arc's turn: t is parallel to (cos phi/2, sin phi/2). Projecting c - R(phi) q on
    the normal of that direction leaves tan(phi / 2) = (c_y - q_y) / (c_x + q_x): the turn in closed form, then
    t = c - R(phi) q. The point must lie ahead of or behind the rear axle (|c_x| > 1 mm): at the axle the turn is
    not observable. A frame turns less than half a turn.
    """
    c, q = np.asarray(point_m, dtype=float), np.asarray(moved_to_m, dtype=float)
    if abs(c[0]) < 1e-3:
        raise ValueError(f"the measured point {c} m is at the rear axle, where a turn moves it not at all")
    phi = 2.0 * math.atan((c[1] - q[1]) / (c[0] + q[0]))
    cos, sin = math.cos(phi), math.sin(phi)
    return np.array([c[0] - (cos * q[0] - sin * q[1]), c[1] - (sin * q[0] + cos * q[1]), phi])


# -------------------------------------------------------------------------------------- rigid point sets


def rigid_fit(source, target, weights=None) -> tuple[float, np.ndarray]:
    """The rotation angle (rad) and translation (2,) that best map ``source`` (N, 2) onto ``target`` (N, 2) in the
    least-squares sense: target ~ R source + t (Kabsch/Umeyama in 2-D, no scale). Needs two distinct points."""
    source, target = np.asarray(source, dtype=float), np.asarray(target, dtype=float)
    w = np.ones(len(source)) if weights is None else np.asarray(weights, dtype=float)
    if source.shape != target.shape or source.ndim != 2 or source.shape[1] != 2 or len(w) != len(source):
        raise ValueError(f"source and target must be matching (N, 2) arrays, got {source.shape} and {target.shape}")
    w = w / w.sum()
    source_mean, target_mean = w @ source, w @ target
    a, b = source - source_mean, target - target_mean
    cross = w @ (a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0])
    dot = w @ (a[:, 0] * b[:, 0] + a[:, 1] * b[:, 1])
    if np.hypot(cross, dot) < 1e-18:
        raise ValueError("the points coincide: a rotation needs two distinct points")
    angle = float(np.arctan2(cross, dot))
    rotation = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
    return angle, target_mean - rotation @ source_mean


def seen_after(points_m, increment) -> np.ndarray:
    """Where floor points seen at ``points_m`` (N, 2) in base_link are seen after the robot moves by ``increment``
    (dx, dy, dtheta): T^-1 applied to them, the inverse of ``increment_from_point_pairs``."""
    points_m = np.asarray(points_m, dtype=float)
    dx, dy, turn = (float(v) for v in increment)
    cos, sin = np.cos(turn), np.sin(turn)
    shifted = points_m - [dx, dy]
    return np.column_stack([cos * shifted[:, 0] + sin * shifted[:, 1], -sin * shifted[:, 0] + cos * shifted[:, 1]])


def increment_from_point_pairs(start_m, end_m, weights=None) -> np.ndarray:
    """The increment (dx, dy, dtheta) of a frame in which floor points seen at ``start_m`` (N, 2) in base_link are
    seen at ``end_m`` (N, 2) at its end: the floor moved by the inverse of the robot's motion, end = T^-1 start."""
    return increment_from_floor_motion(*rigid_fit(start_m, end_m, weights))


def increment_from_floor_motion(angle: float, translation) -> np.ndarray:
    """The increment (dx, dy, dtheta) of a frame over which the floor moved rigidly, end = R(``angle``) start +
    ``translation`` (rad; (2,), metres, base_link): the inverse of that motion."""
    cos, sin = np.cos(angle), np.sin(angle)
    back = -np.array([cos * translation[0] + sin * translation[1], -sin * translation[0] + cos * translation[1]])
    return np.array([back[0], back[1], -angle])
