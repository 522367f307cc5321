"""The named paths every recording drives: the first paper's tests and paths, the second paper's experiments I-IX
(``PATHS``, ``named_plan``), built from the segments of ``gpo.sim.segments``.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Sequence

import numpy as np

from gpo.sim.plans import MotionPlan
from gpo.sim.segments import DEFAULT_LIMITS, Arc, Bend, MotionLimits, SCurve, Segment, Slide, Spin, Stop, Straight


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


CART_II_TURN_RATE_RADPS = np.radians(40.0)  # experiment II's cart turns twice as fast: see path_cart_ii


def path_cart_ii() -> list[Segment]:
    """Experiment II: the same, faster and smoother (the paper: 19.27 m at 0.294 m/s, "more regular and smoother"
    movements than I's): 19.4 m at 0.294 m/s on average. Turning at 20 deg/s, as I does, a cart whose turns take
    most of its time averages at most about 0.23 m/s however fast it rolls; turning at up to 40 deg/s
    (``CART_II_TURN_RATE_RADPS``) and rolling at 0.55 m/s, it averages the paper's speed."""
    return random_cart(19.0, 0.55, seed=2, max_rate_radps=CART_II_TURN_RATE_RADPS)


CORRIDOR_SPEED_MPS = 0.305  # experiment III's cart rolls at this along the corridor: 0.30 m/s on average, its start too


def path_corridor_iii() -> list[Segment]:
    """Experiment III: the three-wheeled cart pushed along a raised-floor corridor, 14.48 m at about 0.30 m/s (the
    paper: 14.48 m at 0.302 m/s): down the corridor, drifting 0.3 m across it and back as a hand-pushed cart does, a
    90 degree left bend into the next corridor, and on."""
    v = CORRIDOR_SPEED_MPS
    return [
        Straight(3.0, v),
        SCurve(2.5, 0.3, v),
        Straight(2.0, v),
        Bend(np.pi / 2, 2.0, v),
        Straight(1.5, v),
        SCurve(2.0, -0.3, v),
        Straight(1.48, v),
    ]


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
    "corridor-iii": path_corridor_iii,
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
