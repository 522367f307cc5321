"""Simulated recordings made on a Dask cluster: the presets a sweep names, and a population of drawn worlds.

``render(client, presets)`` renders (or finds in the cache, ``gpo.sim.record.recording``) every (preset, seed) pair
on the cluster's workers at once and returns their bags' paths. On a cluster of several machines the cache
(``GPO_CACHE_DIR``) must be a folder every worker and the client see under the same path.

``draw(seed)`` draws a world no method was tuned on (a ``Draw``): even seeds a forward-looking fisheye of the T265's
family (``FISHEYE``: its EUCM perturbed, mounted at any height, pitch, roll and lever in the ranges) with a drifting
tracking camera (``DRIFT``), odd seeds a downward pinhole camera of another focal length, height, tilt and place on
the robot (``DOWNWARD``); a floor of one kind or a mix of kinds, its grain from other photographs, glossy or matte
(``GLOSSY_SHARE``: polished screed mostly, lacquered wood and sealed tiles sometimes); a hall's ceiling of 2.5-12 m
with a drawn grid of lamps that a glossy floor mirrors (``CEILING``); a path of the papers' lengths
(``PATH_LENGTH_M``: 4-16 m for the fisheye, 4-20 m for the downward camera) in a room of ``ROOM_M`` (forward and
reverse legs, arcs and bends, spins on the spot, and for the downward camera's omnidirectional robot sideways and
diagonal slides and quarter turns). ``render_draws(client, draws)``
renders them as ``render`` does presets. The same seed draws the same world on every machine; ``matte(draw)`` is
that world with its floor's glossy sheen taken off.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from gpo.cameras import EUCM, Pinhole
from gpo.cameras.rig import CameraMount, Rig
from gpo.sim.ceiling import Ceiling
from gpo.sim.drift import TrackingDrift
from gpo.sim.floors import DEFAULT_PHOTOS, FLOOR_KINDS, PHOTOS, FloorDesign
from gpo.sim.plans import MotionPlan
from gpo.sim.record import Setup, preset, recording
from gpo.sim.rigs import downward_rig, t265_rig
from gpo.sim.segments import Arc, Bend, Segment, Slide, Spin, Stop, Straight

# the ranges draws are uniform in: (low, high)
FISHEYE = {
    "height_m": (0.08, 0.30),
    "pitch_deg": (0.0, 15.0),
    "roll_deg": (-2.0, 2.0),
    "lever_m": (0.3, 0.9),  # the camera ahead of the rear axle
    "side_m": (-0.05, 0.05),  # and to its left
    "f_px": (274.0, 298.0),  # EUCM focal length (fy within 0.3 % of fx), T265 units differ by a few per cent
    "centre_px": (-6.0, 6.0),  # principal point about the image centre's (424, 400)
    "alpha": (0.56, 0.64),
    "beta": (0.95, 1.25),
}
DOWNWARD = {
    "f_px": (400.0, 900.0),  # another lens on the same 752 x 480 sensor
    "height_m": (0.15, 0.40),  # at least MIN_FOOTPRINT_M * f: a pixel covers no less than that much floor
    "tilt_deg": (-3.0, 3.0),  # about base_link's x and y, each
    "x_m": (-0.2, 0.2),
    "y_m": (-0.1, 0.1),
    "k1": (-0.40, 0.0),  # barrel distortion, up to a wide-angle lens's (a constant keypoint offset turns the path)
    "k2": (0.0, 0.2),  # from 0.6 k1^2 on, which keeps the lens's radial map growing (``_downward``)
    "p_px": (-5e-4, 5e-4),  # p1, p2
    "centre_px": (-8.0, 8.0),
}
MIN_FOOTPRINT_M = 3.5e-4  # the floor texture's texels are 0.5 mm; a pixel's footprint keeps above 0.35 mm
DRIFT = {  # the tracking camera's drift about gpo.sim.drift.T265_DRIFT's
    "scale_error": (-0.03, 0.03),
    "yaw_bias_radps": (-2e-3, 2e-3),
    "yaw_walk_rad_per_sqrt_s": (0.5e-3, 2e-3),
    "position_walk_m_per_sqrt_s": (2.5e-3, 7.5e-3),
}
PATH_LENGTH_M = {"fisheye": (4.0, 16.0), "downward": (4.0, 20.0)}  # the papers' paths: 2-17 m and 4-20 m
ROOM_M = {"fisheye": 4.0, "downward": 3.0}  # base_link stays within a square room this wide, centred on the start
SPEED_MPS = {"fisheye": (0.25, 0.5), "downward": (0.25, 0.5)}
SPIN_RATE_RADPS = (0.35, 0.7)
SPIN_DEG = {"fisheye": (45.0, 180.0), "downward": (90.0, 90.0)}  # the omnidirectional robot turns quarter turns
MIX_SHARE = 0.4  # the share of floors mixing two kinds
OTHER_PHOTOS_SHARE = 0.5  # the share of floors whose grain comes from other photographs than the presets'
SEGMENT_WEIGHTS = {  # kind -> weight; slides only for the omnidirectional robot of the downward camera
    "straight": 0.32, "reverse": 0.12,
    "arc": 0.14,
    "bend": 0.16,
    "spin": 0.14,
    "stop": 0.04,
    "slide": 0.12,
}
MOST_PER_M = {"spin": 1 / 4, "stop": 1 / 8}  # at most 1 + this many per metre of a kind (time, not distance)
FISHEYE_FLOOR_MARGIN_M = 1.0  # floor beyond the path: the fisheye's far view beyond it shows the room's walls
DOWNWARD_FLOOR_MARGIN_M = 0.5
TEXEL_M = {"fisheye": 1e-3, "downward": 5e-4}
GLOSSY_SHARE = {"industrial": 0.8, "wood": 0.2, "raised": 0.2}  # screed is mostly polished; lacquer, sealed tiles
CEILING = {  # the hall above the floor: its height and its lamps (gpo.sim.ceiling.Ceiling), uniform in the ranges
    "height_m": (2.5, 12.0),
    "pitch_m": (1.5, 4.0),  # along and across, each
    "lamp_length_m": (0.6, 1.5),  # at most 0.8 of the pitch
    "lamp_width_m": (0.1, 0.6),  # at most 0.8 of the pitch
    "yaw_deg": (0.0, 180.0),
    "reflection": (25.0, 90.0),  # grey levels a mirrored lamp adds on a glossy floor (the presets': 60)
    "softness_m": (0.1, 0.4),
}


@dataclass(frozen=True, eq=False)
class Draw:
    """One drawn world: its ``seed``, the ``kind`` of rig (fisheye or downward), the ``setup`` a recording renders
    and the drawn ``parameters`` in people's units (for reports)."""

    seed: int
    kind: str
    setup: Setup
    parameters: dict

    @property
    def label(self) -> str:
        return f"draw{self.seed:03d}-{self.kind}"


def draw(seed: int) -> Draw:
    """The world of ``seed`` (an integer >= 0): a fisheye rig for even seeds, a downward camera for odd ones."""
    if int(seed) != seed or seed < 0:
        raise ValueError(f"a draw's seed is an integer >= 0, got {seed!r}")
    rng = np.random.default_rng([int(seed), 21])
    kind = "fisheye" if seed % 2 == 0 else "downward"
    rig, rig_parameters = (_fisheye if kind == "fisheye" else _downward)(rng)
    floor = _floor(rng)
    segments = draw_path(rng, kind, length_m=float(rng.uniform(*PATH_LENGTH_M[kind])))
    drift, drift_parameters = _drift(rng) if kind == "fisheye" else (None, {})
    ceiling, ceiling_parameters = _ceiling(rng)
    setup = Setup(
        rig,
        MotionPlan(segments),
        floor,
        int(seed),
        drift,
        TEXEL_M[kind],
        FISHEYE_FLOOR_MARGIN_M if kind == "fisheye" else DOWNWARD_FLOOR_MARGIN_M,
        ceiling=ceiling,
    )
    parameters = {
        **rig_parameters,
        "floor": "+".join(floor.kinds),
        "photos": "+".join(floor.photos),
        "sheen": "on" if floor.sheen else "off",
        "path_m": round(setup.plan.distance_m, 3),
        "path": _path_summary(segments),
        **drift_parameters,
        **ceiling_parameters,
    }
    return Draw(int(seed), kind, setup, parameters)


def matte(chosen: Draw) -> Draw:
    """``chosen``'s world with its floor's reflective sheen taken off (``FloorDesign.sheen``): the same rig, path,
    drift and texture, so that the difference between the two is what a glossy floor's reflections cost."""
    floor = replace(chosen.setup.floor, sheen=False)
    return replace(chosen, setup=replace(chosen.setup, floor=floor), parameters={**chosen.parameters, "sheen": "off"})


def _fisheye(rng: np.random.Generator) -> tuple[Rig, dict]:
    """A T265-like fisheye with drawn intrinsics at a drawn place on the robot, looking forward."""
    ranges = {name: rng.uniform(*bounds) for name, bounds in FISHEYE.items()}
    fy = ranges["f_px"] * rng.uniform(0.997, 1.003)
    camera = EUCM(
        fx=ranges["f_px"],
        fy=fy,
        cx=424.0 + ranges["centre_px"],
        cy=400.0 + rng.uniform(*FISHEYE["centre_px"]),
        alpha=ranges["alpha"],
        beta=ranges["beta"],
        width=848,
        height=800,
    )
    mount = CameraMount.forward(
        ranges["lever_m"],
        ranges["side_m"],
        ranges["height_m"],
        math.radians(ranges["pitch_deg"]),
        math.radians(ranges["roll_deg"]),
    )
    shipped = t265_rig()
    rig = Rig("fisheye", camera, mount, shipped.rate_hz, shipped.image_topic, shipped.info_topic, shipped.frame_id)
    shown = ("height_m", "pitch_deg", "roll_deg", "lever_m", "f_px", "alpha", "beta")
    return rig, {name: round(float(ranges[name]), 4) for name in shown}


def _downward(rng: np.random.Generator) -> tuple[Rig, dict]:
    """A pinhole camera of another lens on the shipped rig's sensor, looking down from a drawn height and place."""
    focal = rng.uniform(*DOWNWARD["f_px"])
    height = rng.uniform(max(DOWNWARD["height_m"][0], MIN_FOOTPRINT_M * focal), DOWNWARD["height_m"][1])
    tilt_x, tilt_y = rng.uniform(*DOWNWARD["tilt_deg"], size=2)
    x, y = rng.uniform(*DOWNWARD["x_m"]), rng.uniform(*DOWNWARD["y_m"])
    # the radial map r (1 + k1 r^2 + k2 r^4) keeps growing, so that every pixel sees one ray: its slope
    # 1 + 3 k1 r^2 + 5 k2 r^4 is least, 1 - 9 k1^2 / (20 k2), at r^2 = -3 k1 / (10 k2), and k2 >= 0.6 k1^2 keeps
    # that at least a quarter of the slope at the centre
    k1 = rng.uniform(*DOWNWARD["k1"])
    k2 = rng.uniform(max(DOWNWARD["k2"][0], 0.6 * k1**2), DOWNWARD["k2"][1])
    p1, p2 = rng.uniform(*DOWNWARD["p_px"], size=2)
    shift_x, shift_y = rng.uniform(*DOWNWARD["centre_px"], size=2)
    shipped = downward_rig()
    camera = Pinhole(
        fx=focal,
        fy=focal,
        cx=shipped.camera.cx + shift_x,
        cy=shipped.camera.cy + shift_y,
        dist=(k1, k2, p1, p2, 0.0),
        width=shipped.camera.width,
        height=shipped.camera.height,
    )
    mount = CameraMount.downward(x, y, height, math.radians(tilt_x), math.radians(tilt_y))
    rig = Rig("downward", camera, mount, shipped.rate_hz, shipped.image_topic, shipped.info_topic, shipped.frame_id)
    parameters = {
        "height_m": height, "f_px": focal, "tilt_x_deg": tilt_x, "tilt_y_deg": tilt_y, "x_m": x, "y_m": y,
        "k1": k1, "k2": k2,
    }
    return rig, {name: round(float(value), 4) for name, value in parameters.items()}


def _floor(rng: np.random.Generator) -> FloorDesign:
    """One kind, or two mixed in patches of 0.5-2 m; the presets' grain or that of one or two other photographs;
    glossy (it mirrors the ceiling's lamps) with the ``GLOSSY_SHARE`` of its first kind."""
    count = 2 if rng.random() < MIX_SHARE else 1
    kinds = tuple(str(kind) for kind in rng.choice(FLOOR_KINDS, size=count, replace=False))
    photos = DEFAULT_PHOTOS
    if rng.random() < OTHER_PHOTOS_SHARE:
        photos = tuple(str(p) for p in rng.choice(PHOTOS, size=int(rng.integers(1, 3)), replace=False))
    patch = float(rng.uniform(0.5, 2.0))
    return FloorDesign(kinds, photos, patch, sheen=bool(rng.random() < GLOSSY_SHARE[kinds[0]]))


def _ceiling(rng: np.random.Generator) -> tuple[Ceiling, dict]:
    """A hall's ceiling drawn in the ``CEILING`` ranges: its height, its lamps' grid, size, turn and place, and how
    bright and blurred a glossy floor mirrors them."""
    values = {name: rng.uniform(*bounds) for name, bounds in CEILING.items() if name != "pitch_m"}
    pitch = tuple(float(v) for v in rng.uniform(*CEILING["pitch_m"], size=2))
    lamp = (min(values["lamp_length_m"], 0.8 * pitch[0]), min(values["lamp_width_m"], 0.8 * pitch[1]))
    ceiling = Ceiling(
        height_m=float(values["height_m"]),
        pitch_m=pitch,
        lamp_m=(float(lamp[0]), float(lamp[1])),
        yaw_rad=math.radians(values["yaw_deg"]),
        offset_m=tuple(float(v) for v in rng.uniform(0.0, 1.0, size=2) * pitch),
        reflection=float(values["reflection"]),
        softness_m=float(values["softness_m"]),
    )
    shown = {"ceiling_m": ceiling.height_m, "lamp_pitch_m": min(pitch), "reflection": ceiling.reflection}
    return ceiling, {name: round(float(value), 3) for name, value in shown.items()}


def _drift(rng: np.random.Generator) -> tuple[TrackingDrift, dict]:
    values = {name: float(rng.uniform(*bounds)) for name, bounds in DRIFT.items()}
    return TrackingDrift(**values), {f"drift_{name}": round(value, 6) for name, value in values.items()}


def draw_path(rng: np.random.Generator, kind: str, length_m: float) -> list[Segment]:
    """Segments drawn by ``SEGMENT_WEIGHTS`` for a rig of ``kind`` (fisheye or downward; slides only for the
    downward camera's omnidirectional robot) until ``length_m`` metres are driven, each at a speed drawn from
    ``SPEED_MPS``; a segment that would take base_link out of the kind's ``ROOM_M`` room is drawn again; a kind of
    segment drawn 1 + ``MOST_PER_M`` per metre times is not drawn again. Straights run 0.4-2.5 m, reverse legs
    0.3-1.2 m; spins turn ``SPIN_DEG`` either way at ``SPIN_RATE_RADPS``; arcs 30-120 degrees on 0.5-1.5 m,
    forwards or in reverse; bends 30-90 degrees over 1-2.5 m."""
    holonomic, room, speeds = kind == "downward", ROOM_M[kind], SPEED_MPS[kind]
    kinds = [k for k in SEGMENT_WEIGHTS if holonomic or k != "slide"]
    most = {k: 1 + math.floor(per_m * length_m) for k, per_m in MOST_PER_M.items()}
    drawn = dict.fromkeys(kinds, 0)
    segments: list[Segment] = []
    pose, driven = (0.0, 0.0, 0.0), 0.0
    while driven < length_m:
        weights = np.array([SEGMENT_WEIGHTS[k] * (drawn[k] < most.get(k, math.inf)) for k in kinds])
        chosen = kinds[rng.choice(len(kinds), p=weights / weights.sum())]
        speed = float(rng.uniform(*speeds))
        side = float(rng.choice([-1.0, 1.0]))
        if chosen == "straight":
            candidate = Straight(float(rng.uniform(0.4, 2.5)), speed)
        elif chosen == "reverse":
            candidate = Straight(-float(rng.uniform(0.3, 1.2)), min(speed, 0.3))
        elif chosen == "arc":
            direction = 1.0 if rng.random() < 0.75 else -1.0
            angle = side * math.radians(rng.uniform(30.0, 120.0))
            candidate = Arc(float(rng.uniform(0.5, 1.5)), angle, direction * min(speed, 0.35))
        elif chosen == "bend":
            candidate = Bend(side * math.radians(rng.uniform(30.0, 90.0)), float(rng.uniform(1.0, 2.5)), speed)
        elif chosen == "spin":
            angle = side * math.radians(rng.uniform(*SPIN_DEG[kind]))
            candidate = Spin(angle, float(rng.uniform(*SPIN_RATE_RADPS)))
        elif chosen == "stop":
            candidate = Stop(float(rng.uniform(0.3, 1.0)))
        else:
            candidate = Slide(float(rng.uniform(-0.5, 0.5)), side * float(rng.uniform(0.3, 1.0)), speed)
        plan = MotionPlan([candidate], pose)
        state = plan.sample(np.linspace(0.0, plan.duration_s, 25))
        if (np.abs(state.x) <= room / 2).all() and (np.abs(state.y) <= room / 2).all():
            segments.append(candidate)
            drawn[chosen] += 1
            pose = (float(state.x[-1]), float(state.y[-1]), float(state.yaw[-1]))
            driven += plan.distance_m
    return segments


def _path_summary(segments: Sequence[Segment]) -> str:
    """The path in short, e.g. ``straight reverse spin(-90) slide``."""
    words = []
    for segment in segments:
        if isinstance(segment, Spin):
            words.append(f"spin({math.degrees(segment.angle_rad):+.0f})")
        elif isinstance(segment, Straight):
            words.append("straight" if segment.distance_m > 0 else "reverse")
        else:
            reverse = getattr(segment, "speed_mps", 1.0) < 0
            words.append(type(segment).__name__.lower() + ("(reverse)" if reverse else ""))
    return " ".join(words)


def render(client, presets: Sequence[tuple[str, int | None]]) -> dict[tuple[str, int | None], Path]:
    """The bag of each (preset name, seed or None for the preset's own) in ``presets``, rendered on ``client``'s
    workers when not cached. Raises ValueError for an unknown preset before anything is rendered."""
    pairs = list(dict.fromkeys(presets))
    for name, _ in pairs:
        preset(name)
    names, seeds = [name for name, _ in pairs], [seed for _, seed in pairs]
    return dict(zip(pairs, _recordings(client, names, seeds, [None] * len(pairs)), strict=True))


def render_draws(client, draws: Sequence[Draw]) -> dict[str, Path]:
    """The bag of each of ``draws`` by its label, rendered on ``client``'s workers when not cached."""
    setups, labels = [d.setup for d in draws], [d.label for d in draws]
    return dict(zip(labels, _recordings(client, setups, [None] * len(draws), labels), strict=True))


def _recordings(client, whats: list, seeds: list, labels: list) -> list[Path]:
    """``gpo.sim.record.recording`` of each (what, seed, label) on the workers, in order."""
    if not whats:
        return []
    formats, quiet, jobs = ["ros1"] * len(whats), [False] * len(whats), [1] * len(whats)
    return [
        Path(p) for p in client.gather(client.map(recording, whats, formats, quiet, seeds, jobs, labels, pure=False))
    ]
