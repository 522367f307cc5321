"""How the simulated robot moves: motion plans with smooth speed profiles, their exact ground truth,
and the drifting odometry a tracking camera (like an Intel RealSense T265) reports along them.

One module for motion (about 1 100 lines): the segment kinds, the speed profile across their junctions, the plan
that samples them, the tracking camera's drift along a plan and the named paths built from the segments change
together (a new path most often needs a new segment kind or limit), and the recordings' cache key hashes them as one.

This module is over 600 lines because it holds both the segment kinematics and the named paths every
recording drives (the first paper's tests and the second paper's experiments I-IX).

Frames and units (REP-103/105)
------------------------------
``world`` is fixed, z up, the floor is z = 0. ``base_link`` is the robot: origin at the rear-axle
centre on the floor, x forward, y left, z up. The planar state is the pose (x, y, θ) of base_link in
world (metres, radians; θ is the yaw, unwrapped, so it may leave (-π, π]), the speed v along base x
(m/s, negative in reverse), the speed v_y along base y (m/s; zero except in a ``Slide``) and the turn
rate ω about z (rad/s, positive counter-clockwise).

Kinematics (unicycle, as a differential-drive pallet robot moves; an omnidirectional robot also slides)::

    ẋ = v cos θ - v_y sin θ,    ẏ = v sin θ + v_y cos θ,    θ̇ = ω

A path segment is a curve of curvature κ(s) = dθ/ds over the signed arc length s from its start
(s < 0 in reverse). Following it at v = ṡ gives ω = κ v and ω̇ = κ a + (dκ/ds) v², a = v̇.

Segments
--------
=========================================  ==================================================================
``Straight(distance_m, speed_mps)``        straight line; ``distance_m < 0`` drives in reverse
``Arc(radius_m, angle_rad, speed_mps)``    circle until the heading changed by ``angle_rad``; reverse: ``speed_mps < 0``
``Bend(angle_rad, length_m, speed_mps)``   smooth turn, curvature rising and falling to zero; reverse: ``speed_mps < 0``
``SCurve(length_m, offset_m, speed_mps)``  smooth lane change ``offset_m`` to the left; reverse: ``speed_mps < 0``
``Spin(angle_rad, rate_radps)``            turn on the spot about base_link's origin (v = 0)
``Slide(forward_m, left_m, speed_mps)``    omnidirectional: move in a straight line sideways or diagonally, heading held
``Stop(duration_s)``                       stand still
=========================================  ==================================================================

Speeds and rates are upper limits; the plan ramps between them. Positive angles turn
counter-clockwise (to the left). Lengths along a path are path lengths, reverse counts positive.

Speed profiles
--------------
Every change of speed is the jerk-limited "double S" ramp (Biagiotti & Melchiorri, *Trajectory Planning
for Automatic Machines and Robots*, 2008, sec. 3.4): the jerk is +J, then 0 while the acceleration holds
at its limit A (if the change |Δv| >= A² / J is large enough to reach it), then -J::

    t_j = A / J,  t_a = |Δv| / A - A / J      (|Δv| >= A² / J)
    t_j = √(|Δv| / J),  t_a = 0               (otherwise)
    T = 2 t_j + t_a,   distance = (v0 + v1) T / 2

The acceleration is continuous, |a| <= A and |ȧ| <= J (``MotionLimits``), the same in spins for ω. A
segment ramps from its entry speed up to its own speed (or less, if it is too short), holds it and
ramps to its exit speed.

The robot keeps moving from one segment into the next only where neither v nor ω would jump: both
segments drive the same way and their curvatures meet (a straight into a ``Bend`` or an ``SCurve``, an
arc into the same arc). Elsewhere (a straight into an arc, a change of direction, a spin, a stop) it
comes to rest at the join, as ω = κ v cannot change instantly otherwise. Junction speeds are lowered
where the acceleration limit demands, forwards then backwards, as in any trajectory planner.

Geometry is exact: straights and arcs in closed form (the SE(2) exponential), smooth turns by
Gauss-Legendre quadrature of the heading, exact to rounding. Poses join exactly at segment ends.

Tracking odometry
-----------------
``tracking_odometry`` reports what a T265 would: the pose of its body frame ``camera_pose_frame``
(x forward, y left, z up, as realsense-ros publishes it) in ``camera_odom_frame``, the body frame at the
first sample, with seeded drift that acts on increments (see ``TrackingDrift``). ``camera_truth`` is
the same without drift.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import get_args

import numpy as np
from scipy.optimize import brentq
from scipy.spatial.transform import Rotation

from gpo.trajectory import NS_PER_S, Trajectory

# composite Gauss-Legendre rule on [0, 1]: 16 panels of 8 nodes, exact to rounding for smooth headings
_PANELS, _ORDER = 16, 8
_unit_nodes, _unit_weights = np.polynomial.legendre.leggauss(_ORDER)
_QUAD_NODES = ((np.arange(_PANELS)[:, None] + (_unit_nodes + 1) / 2) / _PANELS).ravel()
_QUAD_WEIGHTS = np.tile(_unit_weights / (2 * _PANELS), _PANELS)

_TIME_SLACK_S = 1e-9  # sample times may pass the plan's ends by one nanosecond of stamp rounding


def _finite(name: str, value) -> float:
    value = float(value)
    if not math.isfinite(value):
        raise ValueError(f"{name} must be a finite number, got {value}")
    return value


def _positive(name: str, value) -> float:
    value = _finite(name, value)
    if value <= 0:
        raise ValueError(f"{name} must be > 0, got {value}")
    return value


def _nonzero(name: str, value) -> float:
    value = _finite(name, value)
    if value == 0:
        raise ValueError(f"{name} must not be 0")
    return value


def _non_negative(name: str, value) -> float:
    value = _finite(name, value)
    if value < 0:
        raise ValueError(f"{name} must be >= 0, got {value}")
    return value


# ---------------------------------------------------------------------------------------------- limits


@dataclass(frozen=True)
class MotionLimits:
    """How hard the robot may speed up and slow down.

    ``accel_mps2`` (m/s²) and ``jerk_mps3`` (m/s³) bound a = v̇ and ȧ along the path;
    ``angular_accel_radps2`` (rad/s²) and ``angular_jerk_radps3`` (rad/s³) bound ω̇ and ω̈ when spinning.
    """

    accel_mps2: float = 0.5
    jerk_mps3: float = 2.0
    angular_accel_radps2: float = 1.0
    angular_jerk_radps3: float = 4.0

    def __post_init__(self):
        for name in ("accel_mps2", "jerk_mps3", "angular_accel_radps2", "angular_jerk_radps3"):
            _positive(f"MotionLimits.{name}", getattr(self, name))


DEFAULT_LIMITS = MotionLimits()


def _ramp_phases(dv: float, accel: float, jerk: float) -> tuple[float, float]:
    """Durations (t_j, t_a) of the shortest ramp changing the speed by ``dv``: jerk ±``jerk`` for t_j each, and
    constant acceleration ``accel`` for t_a in between, where |Δv| is large enough to reach it (|Δv| >= a² / J)."""
    dv = abs(dv)
    if dv >= accel**2 / jerk:
        return accel / jerk, dv / accel - accel / jerk
    return math.sqrt(dv / jerk), 0.0


def _ramp_time(dv: float, accel: float, jerk: float) -> float:
    """Duration T = 2 t_j + t_a of the shortest ramp changing the speed by ``dv``."""
    t_jerk, t_accel = _ramp_phases(dv, accel, jerk)
    return 2 * t_jerk + t_accel


def _ramp_distance(v0: float, v1: float, accel: float, jerk: float) -> float:
    """Distance covered by the shortest ramp from speed ``v0`` to ``v1``: (v0 + v1) T / 2, by symmetry."""
    return (v0 + v1) / 2 * _ramp_time(v1 - v0, accel, jerk)


def _ramp(v0: float, v1: float, accel: float, jerk: float, tau: np.ndarray):
    """Distance ∫v, speed v and acceleration a at ``tau`` seconds (within the ramp) of the ramp v0 -> v1.

    The jerk is ±J on [0, t_j], 0 on [t_j, t_j + t_a], ∓J on [t_j + t_a, T]. With ⟨x⟩ⁿ = max(x, 0)ⁿ / n!
    and the sum Σₙ = ⟨τ⟩ⁿ - ⟨τ - t_j⟩ⁿ - ⟨τ - t_j - t_a⟩ⁿ + ⟨τ - T⟩ⁿ:  a = ±J Σ₁,  v = v0 ± J Σ₂,  ∫v = v0 τ ± J Σ₃.
    """
    t_jerk, t_accel = _ramp_phases(v1 - v0, accel, jerk)
    knots = ((1, 0.0), (-1, t_jerk), (-1, t_jerk + t_accel), (1, 2 * t_jerk + t_accel))
    signed_jerk = math.copysign(jerk, v1 - v0)

    def bracket(power):
        return sum(sign * np.maximum(tau - knot, 0.0) ** power for sign, knot in knots) / math.factorial(power)

    return v0 * tau + signed_jerk * bracket(3), v0 + signed_jerk * bracket(2), signed_jerk * bracket(1)


def _fastest_reachable(v_from: float, v_limit: float, length: float, accel: float, jerk: float) -> float:
    """The highest speed <= ``v_limit`` that a ramp starting at ``v_from`` reaches within ``length``."""
    if v_limit <= v_from or _ramp_distance(v_from, v_limit, accel, jerk) <= length:
        return v_limit
    return brentq(lambda v: _ramp_distance(v_from, v, accel, jerk) - length, v_from, v_limit, xtol=1e-13)


@dataclass(frozen=True)
class _SpeedProfile:
    """Speed magnitude over one segment: ramp ``start`` -> ``peak`` in ``rise_s``, hold ``peak`` for ``hold_s``,
    ramp ``peak`` -> ``end`` in ``fall_s``, within ``accel`` and ``jerk``. Units: m/s on paths, rad/s in spins."""

    start: float
    peak: float
    end: float
    hold_s: float
    accel: float
    jerk: float

    @property
    def rise_s(self) -> float:
        return _ramp_time(self.peak - self.start, self.accel, self.jerk)

    @property
    def fall_s(self) -> float:
        return _ramp_time(self.end - self.peak, self.accel, self.jerk)

    @property
    def duration_s(self) -> float:
        return self.rise_s + self.hold_s + self.fall_s

    def __call__(self, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Progress q (m or rad), its rate q̇ and q̈, ``tau`` seconds into the segment."""
        rise_s, limits = self.rise_s, (self.accel, self.jerk)
        in_fall = tau - rise_s - self.hold_s
        q_rise, v_rise, a_rise = _ramp(self.start, self.peak, *limits, np.clip(tau, 0, rise_s))
        q_fall, v_fall, a_fall = _ramp(self.peak, self.end, *limits, np.clip(in_fall, 0, self.fall_s))
        progress = q_rise + self.peak * np.clip(tau - rise_s, 0, self.hold_s) + q_fall
        rising, falling = tau < rise_s, in_fall > 0
        rate = np.where(rising, v_rise, np.where(falling, v_fall, self.peak))
        rate_dot = np.where(rising, a_rise, np.where(falling, a_fall, 0.0))
        return progress, rate, rate_dot


def _speed_profile(v_in: float, cruise: float, v_out: float, length: float, accel: float, jerk: float):
    """The quickest profile over ``length`` from ``v_in`` to ``v_out`` that never exceeds ``cruise``.

    The join speeds must be reachable: a ramp from ``v_in`` to ``v_out`` fits in ``length``.
    """

    def spare(peak):
        return length - _ramp_distance(v_in, peak, accel, jerk) - _ramp_distance(peak, v_out, accel, jerk)

    lowest = max(v_in, v_out)
    if spare(cruise) >= 0:
        peak = cruise
    elif spare(lowest) <= 0:
        peak = lowest
    else:
        peak = brentq(spare, lowest, cruise, xtol=1e-13)
    return _SpeedProfile(v_in, peak, v_out, max(spare(peak), 0.0) / peak, accel, jerk)


# -------------------------------------------------------------------------------------------- segments


class _PathSegment:
    """Driving along a curve: signed arc length s from the start (s < 0 in reverse), curvature κ(s).

    Subclasses have a field ``speed_mps`` and give ``signed_length_m``, ``local_pose(s)`` -> (x, y, θ)
    relative to the start pose and ``curvature(s)`` -> (κ, dκ/ds).
    """

    @property
    def cruise_mps(self) -> float:
        """The highest speed along the segment, m/s (> 0)."""
        return abs(float(self.speed_mps))

    @property
    def path_length_m(self) -> float:
        return abs(self.signed_length_m)

    @property
    def direction(self) -> float:
        """+1 forwards, -1 in reverse."""
        return math.copysign(1.0, self.signed_length_m)

    def speed_profile(self, v_in: float, v_out: float, limits: MotionLimits) -> _SpeedProfile:
        return _speed_profile(v_in, self.cruise_mps, v_out, self.path_length_m, limits.accel_mps2, limits.jerk_mps3)

    def motion(self, q, q_dot, q_ddot):
        """Local (x, y, θ), v, ω, a, ω̇, v_y after progress q (m, unsigned) at rate q̇ and q̈: s = ±q, ω = κv,
        ω̇ = κa + κ'v², v_y = 0."""
        s, v, a = self.direction * q, self.direction * q_dot, self.direction * q_ddot
        x, y, yaw = self.local_pose(s)
        kappa, dkappa = self.curvature(s)
        return x, y, yaw, v, kappa * v, a, kappa * a + dkappa * v**2, np.zeros_like(q)


@dataclass(frozen=True)
class Straight(_PathSegment):
    """Drive straight for ``distance_m`` metres (negative: in reverse) at up to ``speed_mps`` (> 0).

    Pose at signed arc length s: (s, 0, 0).
    """

    distance_m: float
    speed_mps: float = 0.4

    def __post_init__(self):
        _nonzero("Straight.distance_m", self.distance_m)
        _positive("Straight.speed_mps", self.speed_mps)

    @property
    def signed_length_m(self) -> float:
        return float(self.distance_m)

    def local_pose(self, s):
        zero = np.zeros_like(s)
        return s, zero, zero

    def curvature(self, s):
        zero = np.zeros_like(s)
        return zero, zero


@dataclass(frozen=True)
class Arc(_PathSegment):
    """Follow a circle of ``radius_m`` until the heading has changed by ``angle_rad``, at up to |``speed_mps``|.

    Positive ``angle_rad`` turns counter-clockwise (a left turn driving forwards); negative ``speed_mps``
    drives the arc in reverse. With κ = dθ/ds the pose at signed arc length s is the SE(2) exponential
    (sin κs / κ, (1 - cos κs) / κ, κs): forwards the arc ends at (R sin φ, R (1 - cos φ), φ), in reverse at
    (-R sin φ, -R (1 - cos φ), φ), in the start frame. Turn rate ω = v / R.
    """

    radius_m: float
    angle_rad: float
    speed_mps: float = 0.3

    def __post_init__(self):
        _positive("Arc.radius_m", self.radius_m)
        _nonzero("Arc.angle_rad", self.angle_rad)
        _nonzero("Arc.speed_mps", self.speed_mps)

    @property
    def signed_length_m(self) -> float:
        return math.copysign(self.radius_m * abs(self.angle_rad), self.speed_mps)

    @property
    def kappa(self) -> float:
        """Signed curvature dθ/ds, 1/m."""
        return self.angle_rad / self.signed_length_m

    def local_pose(self, s):
        turned = self.kappa * s
        return np.sin(turned) / self.kappa, (1 - np.cos(turned)) / self.kappa, turned

    def curvature(self, s):
        zero = np.zeros_like(s)
        return zero + self.kappa, zero


class _SmoothTurn(_PathSegment):
    """A curve given by its heading θ(u) over the fraction u = s / S of its signed length S.

    κ = θ_u / S, dκ/ds = θ_uu / S²; the position is x(s) = ∫0^s cos θ, y(s) = ∫0^s sin θ, by
    Gauss-Legendre quadrature. Subclasses have fields ``length_m`` (> 0) and ``speed_mps`` (< 0: reverse)
    and give ``heading(u)`` -> (θ, θ_u, θ_uu).
    """

    @property
    def signed_length_m(self) -> float:
        return math.copysign(self.length_m, self.speed_mps)

    def local_pose(self, s):
        length = self.signed_length_m
        s = np.asarray(s, dtype=np.float64)
        along = self.heading(s[..., None] / length * _QUAD_NODES)[0]
        x = s * (np.cos(along) @ _QUAD_WEIGHTS)
        y = s * (np.sin(along) @ _QUAD_WEIGHTS)
        return x, y, self.heading(s / length)[0]

    def curvature(self, s):
        length = self.signed_length_m
        _, theta_u, theta_uu = self.heading(np.asarray(s) / length)
        return theta_u / length, theta_uu / length**2


def _smooth_step(u):
    """Cycloidal step h(u) = u - sin(2πu) / (2π) and its derivatives h' = 1 - cos 2πu, h'' = 2π sin 2πu.

    h(0) = 0, h(1) = 1, and h', h'' vanish at both ends.
    """
    angle = 2 * np.pi * u
    return u - np.sin(angle) / (2 * np.pi), 1 - np.cos(angle), 2 * np.pi * np.sin(angle)


@dataclass(frozen=True)
class Bend(_SmoothTurn):
    """Turn the heading by ``angle_rad`` over ``length_m`` metres of path at up to |``speed_mps``| (< 0: reverse).

    θ(u) = φ h(u) with the cycloidal step h, so the curvature κ = φ (1 - cos 2πu) / S rises from zero and
    falls back to zero: the robot drives into and out of it from a straight without stopping. Its
    peak curvature is twice that of an arc of the same length and angle.
    """

    angle_rad: float
    length_m: float
    speed_mps: float = 0.3

    def __post_init__(self):
        _nonzero("Bend.angle_rad", self.angle_rad)
        _positive("Bend.length_m", self.length_m)
        _nonzero("Bend.speed_mps", self.speed_mps)

    def heading(self, u):
        h, dh, ddh = _smooth_step(u)
        return self.angle_rad * h, self.angle_rad * dh, self.angle_rad * ddh


def _scurve_heading_shape(u):
    """sin⁴(πu) and its first two derivatives: 0 at both ends with zero slope and bend, 1 at u = 1/2."""
    s, c = np.sin(np.pi * u), np.cos(np.pi * u)
    return s**4, 4 * np.pi * s**3 * c, 4 * np.pi**2 * s**2 * (3 * c**2 - s**2)


def _scurve_offset_ratio(peak_heading: float) -> float:
    """Lateral offset per metre of path of an S-curve whose heading peaks at ``peak_heading``: ∫0^1 sin θ(u) du."""
    return float(np.sin(peak_heading * _scurve_heading_shape(_QUAD_NODES)[0]) @ _QUAD_WEIGHTS)


_SCURVE_MAX_PEAK_HEADING = np.pi / 2


@dataclass(frozen=True)
class SCurve(_SmoothTurn):
    """A lane change: ``offset_m`` to the left (negative: right) over ``length_m`` metres of path, heading unchanged.

    Drives at up to |``speed_mps``| (< 0: in reverse, still ending ``offset_m`` to the left). The heading is
    θ(u) = ψ sin⁴(πu): it swings to ψ and back, the curvature is zero with zero slope at both ends, so it
    joins straights without stopping. ψ (``peak_heading_rad``) is solved from the offset; at most π/2,
    which allows an offset of up to 0.457 ``length_m``.
    """

    length_m: float
    offset_m: float
    speed_mps: float = 0.3
    peak_heading_rad: float = field(init=False)

    def __post_init__(self):
        _positive("SCurve.length_m", self.length_m)
        _nonzero("SCurve.offset_m", self.offset_m)
        _nonzero("SCurve.speed_mps", self.speed_mps)
        ratio = self.offset_m / self.signed_length_m
        most = _scurve_offset_ratio(_SCURVE_MAX_PEAK_HEADING)
        if abs(ratio) > most:
            raise ValueError(
                f"SCurve.offset_m = {self.offset_m} m is more than a {self.length_m} m S-curve can shift "
                f"(at most {most * self.length_m:.3f} m)"
            )
        peak = brentq(lambda psi: _scurve_offset_ratio(psi) - abs(ratio), 0.0, _SCURVE_MAX_PEAK_HEADING, xtol=1e-14)
        object.__setattr__(self, "peak_heading_rad", math.copysign(peak, ratio))

    def heading(self, u):
        return tuple(self.peak_heading_rad * part for part in _scurve_heading_shape(u))


@dataclass(frozen=True)
class Spin:
    """Turn on the spot about base_link's origin by ``angle_rad`` (positive: counter-clockwise) at up to
    ``rate_radps`` (> 0); v = 0, the position does not change. Starts and ends at rest."""

    angle_rad: float
    rate_radps: float = 0.5

    def __post_init__(self):
        _nonzero("Spin.angle_rad", self.angle_rad)
        _positive("Spin.rate_radps", self.rate_radps)

    def speed_profile(self, v_in: float, v_out: float, limits: MotionLimits) -> _SpeedProfile:
        return _speed_profile(
            0.0, self.rate_radps, 0.0, abs(self.angle_rad), limits.angular_accel_radps2, limits.angular_jerk_radps3
        )

    def motion(self, q, q_dot, q_ddot):
        turn = math.copysign(1.0, self.angle_rad)
        zero = np.zeros_like(q)
        return zero, zero, turn * q, zero, turn * q_dot, zero, turn * q_ddot, zero


@dataclass(frozen=True)
class Stop:
    """Stand still for ``duration_s`` seconds (> 0); the robot comes to rest before it."""

    duration_s: float

    def __post_init__(self):
        _positive("Stop.duration_s", self.duration_s)

    def speed_profile(self, v_in: float, v_out: float, limits: MotionLimits) -> _SpeedProfile:
        return _SpeedProfile(0.0, 0.0, 0.0, float(self.duration_s), limits.accel_mps2, limits.jerk_mps3)

    def motion(self, q, q_dot, q_ddot):
        zero = np.zeros_like(q)
        return (zero,) * 8


@dataclass(frozen=True)
class Slide:
    """An omnidirectional robot's move without turning: ``forward_m`` along and ``left_m`` across the heading it
    starts with, in a straight line, at up to ``speed_mps`` (> 0); sideways when ``forward_m`` = 0, diagonal
    otherwise. Starts and ends at rest, like a spin; its speed ramps as a straight's. With u = (forward, left)
    / length, the pose after progress q is (u_x q, u_y q, 0), v = u_x q̇ and v_y = u_y q̇."""

    forward_m: float
    left_m: float
    speed_mps: float = 0.4

    def __post_init__(self):
        _finite("Slide.forward_m", self.forward_m)
        _finite("Slide.left_m", self.left_m)
        _positive("Slide.speed_mps", self.speed_mps)
        if self.forward_m == 0 and self.left_m == 0:
            raise ValueError("Slide.forward_m and Slide.left_m must not both be 0")

    @property
    def path_length_m(self) -> float:
        return math.hypot(self.forward_m, self.left_m)

    def speed_profile(self, v_in: float, v_out: float, limits: MotionLimits) -> _SpeedProfile:
        return _speed_profile(0.0, self.speed_mps, 0.0, self.path_length_m, limits.accel_mps2, limits.jerk_mps3)

    def motion(self, q, q_dot, q_ddot):
        along, across = self.forward_m / self.path_length_m, self.left_m / self.path_length_m
        zero = np.zeros_like(q)
        return along * q, across * q, zero, along * q_dot, zero, along * q_ddot, zero, across * q_dot


Segment = Straight | Arc | Bend | SCurve | Spin | Stop | Slide


def _handover_limit(before: Segment, after: Segment) -> float:
    """Highest speed at which ``before`` may pass on to ``after`` without a jump in v or ω: both drive along
    a path in the same direction and their curvatures meet; otherwise the robot stops at the join (0)."""
    if not (isinstance(before, _PathSegment) and isinstance(after, _PathSegment)):
        return 0.0
    if before.direction != after.direction:
        return 0.0
    curvature_out = float(before.curvature(np.float64(before.signed_length_m))[0])
    curvature_in = float(after.curvature(np.float64(0.0))[0])
    if abs(curvature_out - curvature_in) > 1e-9:
        return 0.0
    return min(before.cruise_mps, after.cruise_mps)


def _junction_speeds(segments: Sequence[Segment], limits: MotionLimits) -> list[float]:
    """Speed magnitudes at the n + 1 joins of n segments, at rest at both ends of the plan.

    Start from the handover limits, then lower each so that the acceleration limits can reach it over
    the segment before it (forward pass) and leave it over the segment after it (backward pass).
    """
    speeds = [0.0, *(_handover_limit(a, b) for a, b in itertools.pairwise(segments)), 0.0]
    paths = [(i, seg) for i, seg in enumerate(segments) if isinstance(seg, _PathSegment)]
    accel, jerk = limits.accel_mps2, limits.jerk_mps3
    for i, seg in paths:
        speeds[i + 1] = _fastest_reachable(speeds[i], speeds[i + 1], seg.path_length_m, accel, jerk)
    for i, seg in reversed(paths):
        speeds[i] = _fastest_reachable(speeds[i + 1], speeds[i], seg.path_length_m, accel, jerk)
    return speeds


# ------------------------------------------------------------------------------------------------- plan


@dataclass(frozen=True, eq=False)
class PlanarState:
    """The robot's state at ``times_s`` (N,) seconds since the plan's start; every field is (N,).

    ``x``, ``y`` (m) and ``yaw`` (rad, unwrapped) of base_link in world; ``v`` (m/s, along base x,
    negative in reverse), ``omega`` (rad/s, about z), ``accel`` = v̇ (m/s²), ``angular_accel`` = ω̇ (rad/s²),
    ``lateral`` = v_y (m/s, along base y: nonzero only in a ``Slide``).
    """

    times_s: np.ndarray
    x: np.ndarray
    y: np.ndarray
    yaw: np.ndarray
    v: np.ndarray
    omega: np.ndarray
    accel: np.ndarray
    angular_accel: np.ndarray
    lateral: np.ndarray


@dataclass(frozen=True, eq=False)
class _Leg:
    """One segment placed in time (``start_s``) and space (``origin`` = (x, y, θ) of base_link at its start)."""

    segment: Segment
    start_s: float
    speed: _SpeedProfile
    origin: tuple[float, float, float]

    def state(self, tau: np.ndarray) -> tuple[np.ndarray, ...]:
        """World x, y, θ, v, ω, a, ω̇, v_y at ``tau`` seconds into the leg: the start pose composed with the local
        one."""
        x, y, yaw, *rates = self.segment.motion(*self.speed(tau))
        x0, y0, yaw0 = self.origin
        cos0, sin0 = math.cos(yaw0), math.sin(yaw0)
        return x0 + cos0 * x - sin0 * y, y0 + sin0 * x + cos0 * y, yaw0 + yaw, *rates

    def end_pose(self) -> tuple[float, float, float]:
        x, y, yaw = (float(value[0]) for value in self.state(np.array([self.speed.duration_s]))[:3])
        return x, y, yaw


class MotionPlan:
    """A robot driving ``segments`` one after another from ``start`` = (x m, y m, yaw rad) in world.

    >>> plan = MotionPlan([Straight(1.0), Arc(0.5, np.pi / 2), Spin(-np.pi / 2), Straight(-0.5)])
    >>> state = plan.sample(np.linspace(0.0, plan.duration_s, 100))
    """

    def __init__(
        self,
        segments: Sequence[Segment],
        start: Sequence[float] = (0.0, 0.0, 0.0),
        limits: MotionLimits = DEFAULT_LIMITS,
    ):
        self.segments = tuple(segments)
        if not self.segments:
            raise ValueError("a motion plan needs at least one segment")
        for number, segment in enumerate(self.segments):
            if not isinstance(segment, Segment):
                names = ", ".join(kind.__name__ for kind in get_args(Segment))
                raise TypeError(f"segment {number} is a {type(segment).__name__}; expected one of {names}")
        if len(start) != 3:
            raise ValueError(f"start must be (x, y, yaw), got {len(start)} numbers")
        self.start = tuple(_finite(f"start[{i}]", value) for i, value in enumerate(start))
        self.limits = limits
        self._legs = self._place(_junction_speeds(self.segments, limits))
        self._starts = np.array([leg.start_s for leg in self._legs])
        self.duration_s = self._legs[-1].start_s + self._legs[-1].speed.duration_s

    def _place(self, junction_speeds: list[float]) -> list[_Leg]:
        legs, clock, pose = [], 0.0, self.start
        for segment, (v_in, v_out) in zip(self.segments, itertools.pairwise(junction_speeds), strict=True):
            leg = _Leg(segment, clock, segment.speed_profile(v_in, v_out, self.limits), pose)
            legs.append(leg)
            clock, pose = clock + leg.speed.duration_s, leg.end_pose()
        return legs

    @property
    def boundaries_s(self) -> np.ndarray:
        """Times of the segment joins, including 0 and ``duration_s``: (n + 1,) seconds."""
        return np.append(self._starts, self.duration_s)

    @property
    def distance_m(self) -> float:
        """Path length driven, metres; reverse and slides count positive, spins and stops count zero."""
        return sum(seg.path_length_m for seg in self.segments if isinstance(seg, _PathSegment | Slide))

    def sample(self, times_s) -> PlanarState:
        """The state at ``times_s`` (scalar or (N,) seconds within [0, ``duration_s``])."""
        times = np.atleast_1d(np.asarray(times_s, dtype=np.float64))
        if times.ndim != 1:
            raise ValueError(f"times_s must be a scalar or a 1-D array, got shape {times.shape}")
        if times.size and not (
            np.isfinite(times).all()
            and times.min() >= -_TIME_SLACK_S
            and times.max() <= self.duration_s + _TIME_SLACK_S
        ):
            raise ValueError(
                f"times_s must lie within the plan's [0, {self.duration_s:.6f}] s, "
                f"got [{times.min():.6f}, {times.max():.6f}] s"
            )
        times = np.clip(times, 0.0, self.duration_s)
        leg_of = np.searchsorted(self._starts, times, side="right") - 1
        values = np.empty((8, times.size))
        for k in np.unique(leg_of):
            chosen = leg_of == k
            values[:, chosen] = self._legs[k].state(times[chosen] - self._legs[k].start_s)
        return PlanarState(times, *values)

    def ground_truth(
        self, rate_hz: float = 120.0, start_ns: int = 0, noise_m: float = 0.0, noise_rad: float = 0.0, seed: int = 0
    ) -> Trajectory:
        """base_link in ``world`` at ``rate_hz``, stamped from ``start_ns``, like motion capture.

        Exact unless ``noise_m`` (m, each of x and y) or ``noise_rad`` (yaw) ask for seeded white noise.
        """
        stamps_ns, times = _clock(self.duration_s, rate_hz, start_ns)
        state = self.sample(times)
        rng = np.random.default_rng(seed)
        noise = rng.standard_normal((3, len(times))) * np.array([[noise_m], [noise_m], [noise_rad]])
        return Trajectory.from_planar(
            stamps_ns, state.x + noise[0], state.y + noise[1], state.yaw + noise[2], 0.0, "world", "base_link"
        )


def _clock(duration_s: float, rate_hz: float, start_ns: int) -> tuple[np.ndarray, np.ndarray]:
    """Integer stamps (ns) every 1 / ``rate_hz`` seconds from ``start_ns`` over ``duration_s``, and the
    matching float seconds since the start."""
    rate_hz = _positive("rate_hz", rate_hz)
    if int(start_ns) != start_ns:
        raise ValueError(f"start_ns must be an integer number of nanoseconds, got {start_ns!r}")
    count = math.floor(duration_s * rate_hz + 1e-9) + 1
    offsets_ns = np.round(np.arange(count) * (NS_PER_S / rate_hz)).astype(np.int64)
    return int(start_ns) + offsets_ns, offsets_ns / NS_PER_S


# ------------------------------------------------------------------------------------- tracking camera


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
        _finite("TrackingDrift.scale_error", self.scale_error)
        _finite("TrackingDrift.yaw_bias_radps", self.yaw_bias_radps)
        for name in ("yaw_walk_rad_per_sqrt_s", "position_walk_m_per_sqrt_s", "jitter_m", "jitter_rad"):
            _non_negative(f"TrackingDrift.{name}", getattr(self, name))


T265_DRIFT = TrackingDrift()
NO_DRIFT = TrackingDrift(0.0, 0.0, 0.0, 0.0, 0.0, 0.0)


def _body_mount(mount) -> tuple[np.ndarray, Rotation]:
    """(position (3,) m, rotation base <- camera body) from a (translation, rotation) pair, the rotation a
    scipy ``Rotation`` or a quaternion (x, y, z, w); or from a ``gpo.rig.CameraMount`` (its body frame)."""
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
    stamps_ns, times = _clock(plan.duration_s, rate_hz, start_ns)
    state = plan.sample(times)
    base = Rotation.from_euler("z", state.yaw[:, None])
    camera_rotations = base * rotation
    camera_positions = np.column_stack([state.x, state.y, np.zeros_like(state.x)]) + base.apply(translation)
    first = camera_rotations[0].inv()
    return stamps_ns, first.apply(camera_positions - camera_positions[0]), first * camera_rotations


def camera_truth(plan: MotionPlan, mount, rate_hz: float = 200.0, start_ns: int = 0) -> Trajectory:
    """The tracking camera's exact pose: ``camera_pose_frame`` in ``camera_odom_frame``, identity at the first sample.

    ``mount`` is the camera body frame (x forward, y left, z up) in base_link: a pair (translation (3,) m,
    rotation as a scipy ``Rotation`` or a quaternion (x, y, z, w)), or a ``gpo.rig.CameraMount``.
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


# ------------------------------------------------------------------------------------------ named paths


def path_sample() -> list[Segment]:
    """For the notebooks, about 15 s and 3.3 m: a straight, a stop, a left arc, a short reverse, a spin."""
    return [
        Straight(1.5, 0.5),
        Stop(0.5),
        Arc(0.8, np.pi / 2, 0.45),
        Straight(-0.5, 0.3),
        Spin(np.pi / 2, 0.6),
    ]


def path_test() -> list[Segment]:
    """For unit tests, about 3 s and 0.8 m: a straight that runs into a smooth left bend."""
    return [Straight(0.3, 0.4), Bend(np.pi / 8, 0.5, 0.35)]


def path_short1() -> list[Segment]:
    """Like the first paper's Test1: 3 m straight ahead."""
    return [Straight(3.0, 0.4)]


def path_short2() -> list[Segment]:
    """Like Test2, a curve: 1.5 m straight, a smooth 90 degree left bend over 2 m, 1 m straight (4.5 m)."""
    return [Straight(1.5, 0.4), Bend(np.pi / 2, 2.0, 0.3), Straight(1.0, 0.4)]


# short3 and the long paths drive forward only and turn no tighter than 1 m in radius (a Bend of angle φ over
# S metres peaks at curvature 2φ / S), as the first paper's robot, which follows a bicycle model, can: it
# cannot spin on the spot.


def path_short3() -> list[Segment]:
    """Like Test3, a curve, forward only: 1 m ahead, a 0.4 m lane change to the left over 2.5 m, 0.5 m ahead (4.0 m)."""
    return [Straight(1.0, 0.4), SCurve(2.5, 0.4, 0.3), Straight(0.5, 0.4)]


def path_long1() -> list[Segment]:
    """Like the first paper's Test4, a loop: once round four smooth 90 degree left corners (3.2 m each, 1.02 m
    tightest radius) joined by 1.2 m and 0.4 m straights, from the middle of a long side back to it: about
    4.9 m x 4.1 m, 16.0 m."""
    corner = Bend(np.pi / 2, 3.2, 0.35)
    return [
        Straight(0.6, 0.5),
        corner,
        Straight(0.4, 0.4),
        corner,
        Straight(1.2, 0.5),
        corner,
        Straight(0.4, 0.4),
        corner,
        Straight(0.6, 0.5),
    ]


def path_long2() -> list[Segment]:
    """Like Test5, S-curves: a straight into two lane changes (0.5 m left, then right), a U-turn on a 1 m arc
    (from rest, as a car steers before it rolls) and two lane changes back (15.3 m)."""
    return [
        Straight(1.0, 0.5),
        SCurve(2.8, 0.5, 0.4),
        SCurve(2.8, -0.5, 0.4),
        Arc(1.0, np.pi, 0.3),
        SCurve(2.8, 0.5, 0.4),
        SCurve(2.8, -0.5, 0.4),
    ]


def path_long3() -> list[Segment]:
    """Like Test6, stop-and-go with turns: straights broken by stops, left turns on 1.2 m and 1.0 m arcs (each
    from rest) and a smooth left bend, spiralling round within about 5.4 m x 4.2 m (15.7 m)."""
    return [
        Straight(3.0, 0.5),
        Stop(1.5),
        Arc(1.2, np.pi / 2, 0.3),
        Straight(2.0, 0.4),
        Stop(1.0),
        Arc(1.0, np.pi / 2, 0.3),
        Straight(2.5, 0.5),
        Stop(1.5),
        Bend(np.pi / 2, 3.2, 0.35),
        Straight(1.5, 0.5),
    ]


def path_downward() -> list[Segment]:
    """For the second paper's AGV and its downward camera, 10 m at 0.3-0.5 m/s: straights, a smooth bend, a
    lane change, a stop, a reverse leg and a turn on the spot."""
    return [
        Straight(3.0, 0.5),
        Bend(np.pi / 2, 2.0, 0.35),
        Straight(1.0, 0.5),
        SCurve(2.0, 0.4, 0.35),
        Stop(1.0),
        Straight(-1.0, 0.3),
        Spin(-np.pi / 2, 0.5),
        Straight(1.0, 0.4),
    ]


def path_downward_short() -> list[Segment]:
    """A short drive for the downward camera over each floor kind, 4.3 m: a straight, a left bend, a stop, a
    reverse leg and a quarter turn on the spot."""
    return [
        Straight(1.5, 0.45),
        Bend(np.pi / 2, 1.5, 0.35),
        Straight(0.8, 0.45),
        Stop(0.5),
        Straight(-0.5, 0.3),
        Spin(-np.pi / 2, 0.6),
    ]


def path_downward_long() -> list[Segment]:
    """The second paper's longer test for its downward camera, 16.5 m at 0.35-0.5 m/s: a long straight, a left
    bend, a lane change and a right bend, ending at rest."""
    return [
        Straight(4.0, 0.5),
        Bend(np.pi / 2, 2.5, 0.35),
        Straight(3.0, 0.5),
        SCurve(3.0, 0.5, 0.4),
        Bend(-np.pi / 2, 2.0, 0.35),
        Straight(2.0, 0.5),
    ]


# --------------------------------------------------------- the second paper's experiments (its Tables 1 and 2)

PAPER_TURN_RATE_RADPS = np.radians(20.0)  # the second paper's fastest measured rotation, about 20 deg/s (exp. VIII)
STAGE_LIMITS = MotionLimits(accel_mps2=2.0, jerk_mps3=50.0, angular_accel_radps2=4.0, angular_jerk_radps3=100.0)
STAGE_REST_S = 0.1  # the stage stands still this long after each step: the paper's images are taken at rest
CART_ROOM_M = (4.0, 3.5)  # the motion-capture room the cart wanders in (experiments I-II), metres, centred on the start
STAGE_ARM_M = 0.277  # the camera's distance from the rotational stage's axis (experiments VII-VIII: 0.87 m per 180 deg)


def random_cart(
    distance_m: float, speed_mps: float, seed: int, room_m=CART_ROOM_M, max_rate_radps=PAPER_TURN_RATE_RADPS
) -> list[Segment]:
    """A cart pushed at random about a room (the second paper's experiments I-II): seeded draws of straights,
    smooth bends, diagonal slides and turns on the spot, until ``distance_m`` is driven.

    Turns lean towards the room's centre (the angle to it plus 40 degrees of Gaussian noise); every segment keeps
    base_link inside ``room_m`` (x, y extent, centred on the start), and draws that would leave it are drawn
    again. Nothing turns faster than ``max_rate_radps``: a bend of angle φ over S metres at speed v peaks at
    ω = 2 |φ| v / S, so S = 2 |φ| v / ω_max. The draws depend on ``seed`` alone."""
    rng = np.random.default_rng(seed)
    half = np.asarray(room_m, dtype=float) / 2
    segments, pose, driven = [], (0.0, 0.0, 0.0), 0.0
    while driven < distance_m:
        x, y, yaw = pose
        to_centre = math.remainder(math.atan2(-y, -x) - yaw, 2 * math.pi) if math.hypot(x, y) > 0.3 else 0.0
        turn = float(np.clip(to_centre + rng.normal(0.0, np.radians(40)), -np.radians(120), np.radians(120)))
        turn = math.copysign(max(abs(turn), np.radians(20)), turn)
        kind = rng.choice(["straight", "bend", "slide", "spin"], p=[0.35, 0.45, 0.12, 0.08])
        if kind == "straight":
            candidate = Straight(float(rng.uniform(0.3, 1.0)), speed_mps)
        elif kind == "bend":
            candidate = Bend(turn, 2 * abs(turn) * speed_mps / max_rate_radps, speed_mps)
        elif kind == "slide":
            across = float(rng.choice([-1, 1]) * rng.uniform(0.2, 0.4))
            candidate = Slide(float(rng.uniform(-0.3, 0.4)), across, speed_mps)
        else:
            candidate = Spin(float(np.clip(turn, -np.radians(60), np.radians(60))), max_rate_radps)
        plan = MotionPlan([candidate], pose)
        state = plan.sample(np.linspace(0.0, plan.duration_s, 25))
        if (np.abs(state.x) <= half[0]).all() and (np.abs(state.y) <= half[1]).all():
            segments.append(candidate)
            pose = (float(state.x[-1]), float(state.y[-1]), float(state.yaw[-1]))
            driven += plan.distance_m
    return segments


def path_cart_i() -> list[Segment]:
    """Experiment I: a cart pushed at random over a wood floor, about 18 m, slowly (the paper: 17.83 m at 0.16 m/s)."""
    return random_cart(17.8, 0.24, seed=1)


def path_cart_ii() -> list[Segment]:
    """Experiment II: the same, faster (the paper: 19.27 m at 0.29 m/s)."""
    return random_cart(19.2, 0.6, seed=2)


def stage_steps(lengths_m) -> list[Segment]:
    """A linear stage pushing the camera forward by each of ``lengths_m`` in turn, resting ``STAGE_REST_S`` after each
    step (and before the first)."""
    steps = [Stop(STAGE_REST_S)]
    for length in lengths_m:
        steps += [Straight(float(length), 0.2), Stop(STAGE_REST_S)]
    return steps


def path_stage_iv() -> list[Segment]:
    """Experiment IV: 50 steps of 10 mm on the linear stage, 0.50 m."""
    return stage_steps(np.full(50, 0.010))


def path_stage_v() -> list[Segment]:
    """Experiment V: 100 steps of 5-20 mm (seeded) on the linear stage, 1.24 m in all."""
    steps = np.random.default_rng(5).uniform(0.005, 0.020, 100)
    return stage_steps(steps * 1.24 / steps.sum())


def path_stage_vi() -> list[Segment]:
    """Experiment VI: one continuous run along the linear stage, 3.18 m at 0.12 m/s."""
    return [Straight(3.18, 0.125)]


def path_rotation_vii() -> list[Segment]:
    """Experiment VII: the rotational stage turns the camera clockwise by 90 degrees in steps of one degree, its arm
    ``STAGE_ARM_M`` long (0.44 m of travel), resting after each step."""
    step = Arc(STAGE_ARM_M, -np.radians(1.0), 0.1)
    return [Stop(STAGE_REST_S), *itertools.chain.from_iterable((step, Stop(STAGE_REST_S)) for _ in range(90))]


def path_rotation_viii() -> list[Segment]:
    """Experiment VIII: the rotational stage turns the camera by 180 degrees in one go at 20 deg/s (0.87 m)."""
    return [Arc(STAGE_ARM_M, np.pi, STAGE_ARM_M * PAPER_TURN_RATE_RADPS)]


def path_agv_ix() -> list[Segment]:
    """Experiment IX: the omnidirectional AGV, four laps of 20.2 m (81 m) at up to 0.75 m/s (about 0.6 m/s on
    average while moving) inside a 5 x 3 m area: ahead, a quarter turn, ahead, sideways, a quarter turn back,
    diagonally and in reverse, turning at 20 deg/s."""
    lap = [
        Straight(5.0, 0.75),
        Spin(np.pi / 2, PAPER_TURN_RATE_RADPS),
        Straight(3.0, 0.75),
        Slide(0.0, 5.0, 0.75),
        Spin(-np.pi / 2, PAPER_TURN_RATE_RADPS),
        Slide(3.0, -3.0, 0.75),
        Straight(-3.0, 0.75),
    ]
    return lap * 4


PATHS: dict[str, Callable[[], list[Segment]]] = {
    "sample": path_sample,
    "test": path_test,
    "short1": path_short1,
    "short2": path_short2,
    "short3": path_short3,
    "long1": path_long1,
    "long2": path_long2,
    "long3": path_long3,
    "downward": path_downward,
    "downward-short": path_downward_short,
    "downward-long": path_downward_long,
    "cart-i": path_cart_i,
    "cart-ii": path_cart_ii,
    "stage-iv": path_stage_iv,
    "stage-v": path_stage_v,
    "stage-vi": path_stage_vi,
    "rotation-vii": path_rotation_vii,
    "rotation-viii": path_rotation_viii,
    "agv-ix": path_agv_ix,
}
# the stages move faster than a robot: a 10 mm step takes 0.2 s
PATH_LIMITS = dict.fromkeys(("stage-iv", "stage-v", "stage-vi", "rotation-vii", "rotation-viii"), STAGE_LIMITS)


def named_plan(name: str, start: Sequence[float] = (0.0, 0.0, 0.0), limits: MotionLimits | None = None):
    """The ``MotionPlan`` of one of ``PATHS`` from ``start`` = (x, y, yaw), with ``limits`` (None: the path's own,
    ``PATH_LIMITS``, else ``DEFAULT_LIMITS``)."""
    if name not in PATHS:
        raise ValueError(f"unknown path {name!r}; the named paths are {', '.join(PATHS)}")
    return MotionPlan(PATHS[name](), start, limits or PATH_LIMITS.get(name, DEFAULT_LIMITS))
