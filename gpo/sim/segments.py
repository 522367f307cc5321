"""The segments a simulated robot's path is made of, and the speed profile it drives each with.

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

Geometry is exact: straights and arcs in closed form (the SE(2) exponential), smooth turns by
Gauss-Legendre quadrature of the heading, exact to rounding. Poses join exactly at segment ends.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from gpo.cameras.base import finite, positive

# composite Gauss-Legendre rule on [0, 1]: 16 panels of 8 nodes, exact to rounding for smooth headings
_PANELS, _ORDER = 16, 8


_unit_nodes, _unit_weights = np.polynomial.legendre.leggauss(_ORDER)


_QUAD_NODES = ((np.arange(_PANELS)[:, None] + (_unit_nodes + 1) / 2) / _PANELS).ravel()


_QUAD_WEIGHTS = np.tile(_unit_weights / (2 * _PANELS), _PANELS)


def _nonzero(name: str, value) -> float:
    value = finite(name, value)
    if value == 0:
        raise ValueError(f"{name} must not be 0")
    return value


def non_negative(name: str, value) -> float:
    value = finite(name, value)
    if value < 0:
        raise ValueError(f"{name} must be >= 0, got {value}")
    return value


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
            positive(f"MotionLimits.{name}", getattr(self, name))


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


def _root(function, low: float, high: float, xtol: float) -> float:
    """The root of ``function`` between ``low`` and ``high``, to ``xtol`` (Brent's method). scipy.optimize is imported
    here, by what draws a path, not by every process that imports the simulator."""
    from scipy.optimize import brentq

    return brentq(function, low, high, xtol=xtol)


def _fastest_reachable(v_from: float, v_limit: float, length: float, accel: float, jerk: float) -> float:
    """The highest speed <= ``v_limit`` that a ramp starting at ``v_from`` reaches within ``length``."""
    if v_limit <= v_from or _ramp_distance(v_from, v_limit, accel, jerk) <= length:
        return v_limit
    return _root(lambda v: _ramp_distance(v_from, v, accel, jerk) - length, v_from, v_limit, 1e-13)


@dataclass(frozen=True)
class SpeedProfile:
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
        peak = _root(spare, lowest, cruise, 1e-13)
    return SpeedProfile(v_in, peak, v_out, max(spare(peak), 0.0) / peak, accel, jerk)


class PathSegment:
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

    def speed_profile(self, v_in: float, v_out: float, limits: MotionLimits) -> SpeedProfile:
        return _speed_profile(v_in, self.cruise_mps, v_out, self.path_length_m, limits.accel_mps2, limits.jerk_mps3)

    def motion(self, q, q_dot, q_ddot):
        """Local (x, y, θ), v, ω, a, ω̇, v_y after progress q (m, unsigned) at rate q̇ and q̈: s = ±q, ω = κv,
        ω̇ = κa + κ'v², v_y = 0."""
        s, v, a = self.direction * q, self.direction * q_dot, self.direction * q_ddot
        x, y, yaw = self.local_pose(s)
        kappa, dkappa = self.curvature(s)
        return x, y, yaw, v, kappa * v, a, kappa * a + dkappa * v**2, np.zeros_like(q)


@dataclass(frozen=True)
class Straight(PathSegment):
    """Drive straight for ``distance_m`` metres (negative: in reverse) at up to ``speed_mps`` (> 0).

    Pose at signed arc length s: (s, 0, 0).
    """

    distance_m: float
    speed_mps: float = 0.4

    def __post_init__(self):
        _nonzero("Straight.distance_m", self.distance_m)
        positive("Straight.speed_mps", self.speed_mps)

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
class Arc(PathSegment):
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
        positive("Arc.radius_m", self.radius_m)
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


class _SmoothTurn(PathSegment):
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
        positive("Bend.length_m", self.length_m)
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
        positive("SCurve.length_m", self.length_m)
        _nonzero("SCurve.offset_m", self.offset_m)
        _nonzero("SCurve.speed_mps", self.speed_mps)
        ratio = self.offset_m / self.signed_length_m
        most = _scurve_offset_ratio(_SCURVE_MAX_PEAK_HEADING)
        if abs(ratio) > most:
            raise ValueError(
                f"SCurve.offset_m = {self.offset_m} m is more than a {self.length_m} m S-curve can shift "
                f"(at most {most * self.length_m:.3f} m)"
            )
        peak = _root(lambda psi: _scurve_offset_ratio(psi) - abs(ratio), 0.0, _SCURVE_MAX_PEAK_HEADING, 1e-14)
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
        positive("Spin.rate_radps", self.rate_radps)

    def speed_profile(self, v_in: float, v_out: float, limits: MotionLimits) -> SpeedProfile:
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
        positive("Stop.duration_s", self.duration_s)

    def speed_profile(self, v_in: float, v_out: float, limits: MotionLimits) -> SpeedProfile:
        return SpeedProfile(0.0, 0.0, 0.0, float(self.duration_s), limits.accel_mps2, limits.jerk_mps3)

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
        finite("Slide.forward_m", self.forward_m)
        finite("Slide.left_m", self.left_m)
        positive("Slide.speed_mps", self.speed_mps)
        if self.forward_m == 0 and self.left_m == 0:
            raise ValueError("Slide.forward_m and Slide.left_m must not both be 0")

    @property
    def path_length_m(self) -> float:
        return math.hypot(self.forward_m, self.left_m)

    def speed_profile(self, v_in: float, v_out: float, limits: MotionLimits) -> SpeedProfile:
        return _speed_profile(0.0, self.speed_mps, 0.0, self.path_length_m, limits.accel_mps2, limits.jerk_mps3)

    def motion(self, q, q_dot, q_ddot):
        along, across = self.forward_m / self.path_length_m, self.left_m / self.path_length_m
        zero = np.zeros_like(q)
        return along * q, across * q, zero, along * q_dot, zero, along * q_ddot, zero, across * q_dot


Segment = Straight | Arc | Bend | SCurve | Spin | Stop | Slide


def _handover_limit(before: Segment, after: Segment) -> float:
    """Highest speed at which ``before`` may pass on to ``after`` without a jump in v or ω: both drive along
    a path in the same direction and their curvatures meet; otherwise the robot stops at the join (0)."""
    if not (isinstance(before, PathSegment) and isinstance(after, PathSegment)):
        return 0.0
    if before.direction != after.direction:
        return 0.0
    curvature_out = float(before.curvature(np.float64(before.signed_length_m))[0])
    curvature_in = float(after.curvature(np.float64(0.0))[0])
    if abs(curvature_out - curvature_in) > 1e-9:
        return 0.0
    return min(before.cruise_mps, after.cruise_mps)


def junction_speeds(segments: Sequence[Segment], limits: MotionLimits) -> list[float]:
    """Speed magnitudes at the n + 1 joins of n segments, at rest at both ends of the plan.

    Start from the handover limits, then lower each so that the acceleration limits can reach it over
    the segment before it (forward pass) and leave it over the segment after it (backward pass).
    """
    speeds = [0.0, *(_handover_limit(a, b) for a, b in itertools.pairwise(segments)), 0.0]
    paths = [(i, seg) for i, seg in enumerate(segments) if isinstance(seg, PathSegment)]
    accel, jerk = limits.accel_mps2, limits.jerk_mps3
    for i, seg in paths:
        speeds[i + 1] = _fastest_reachable(speeds[i], speeds[i + 1], seg.path_length_m, accel, jerk)
    for i, seg in reversed(paths):
        speeds[i] = _fastest_reachable(speeds[i + 1], speeds[i], seg.path_length_m, accel, jerk)
    return speeds
