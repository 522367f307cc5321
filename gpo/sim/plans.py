"""A motion plan: segments driven one after the other, joined where neither speed nor turn rate would jump
(``gpo.sim.segments``), sampled at any time with its exact ground truth.

The robot keeps moving from one segment into the next only where neither v nor ω would jump: both
segments drive the same way and their curvatures meet (a straight into a ``Bend`` or an ``SCurve``, an
arc into the same arc). Elsewhere (a straight into an arc, a change of direction, a spin, a stop) it
comes to rest at the join, as ω = κ v cannot change instantly otherwise. Junction speeds are lowered
where the acceleration limit demands, forwards then backwards, as in any trajectory planner.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import get_args

import numpy as np

from gpo.cameras.base import finite, positive
from gpo.io.trajectory import NS_PER_S, Trajectory
from gpo.sim.segments import (
    DEFAULT_LIMITS,
    MotionLimits,
    PathSegment,
    Segment,
    Slide,
    SpeedProfile,
    junction_speeds,
)

_TIME_SLACK_S = 1e-9  # sample times may pass the plan's ends by one nanosecond of stamp rounding


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
    speed: SpeedProfile
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
        self.start = tuple(finite(f"start[{i}]", value) for i, value in enumerate(start))
        self.limits = limits
        self._legs = self._place(junction_speeds(self.segments, limits))
        self._starts = np.array([leg.start_s for leg in self._legs])
        self.duration_s = self._legs[-1].start_s + self._legs[-1].speed.duration_s

    def _place(self, speeds: list[float]) -> list[_Leg]:
        legs, clock, pose = [], 0.0, self.start
        for segment, (v_in, v_out) in zip(self.segments, itertools.pairwise(speeds), strict=True):
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
        return sum(seg.path_length_m for seg in self.segments if isinstance(seg, PathSegment | Slide))

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
        stamps_ns, times = sample_clock(self.duration_s, rate_hz, start_ns)
        state = self.sample(times)
        rng = np.random.default_rng(seed)
        noise = rng.standard_normal((3, len(times))) * np.array([[noise_m], [noise_m], [noise_rad]])
        return Trajectory.from_planar(
            stamps_ns, state.x + noise[0], state.y + noise[1], state.yaw + noise[2], 0.0, "world", "base_link"
        )


def sample_clock(duration_s: float, rate_hz: float, start_ns: int) -> tuple[np.ndarray, np.ndarray]:
    """Integer stamps (ns) every 1 / ``rate_hz`` seconds from ``start_ns`` over ``duration_s``, and the
    matching float seconds since the start."""
    rate_hz = positive("rate_hz", rate_hz)
    if int(start_ns) != start_ns:
        raise ValueError(f"start_ns must be an integer number of nanoseconds, got {start_ns!r}")
    count = math.floor(duration_s * rate_hz + 1e-9) + 1
    offsets_ns = np.round(np.arange(count) * (NS_PER_S / rate_hz)).astype(np.int64)
    return int(start_ns) + offsets_ns, offsets_ns / NS_PER_S
