"""Recordings of the simulated rigs, written as ROS bags the way a real robot's would be.

A ``Preset`` names a rig, a path, a floor and a seed, and what disturbs the camera's view of the floor
(``gpo.sim.disturbances.Disturbances``: sheets dragged across it, glints). It stands for a ``Setup``, which holds the
things themselves (the rig, the motion plan, the floor's design, the tracking camera's drift), so that a
recording of any rig, path or floor (``gpo.sim.population`` draws them) is rendered the same way.
``simulate`` drives the path, renders every camera frame and writes one bag holding:

- the camera images (``sensor_msgs/Image``, mono8) and ``camera_info`` on the rig's topics;
- ``/mocap/base_link`` (``geometry_msgs/PoseStamped``, 120 Hz): ground truth of ``base_link`` in
  ``world``, as a motion-capture system would give it;
- for a rig with a tracking camera (the fisheye rig: its camera is the T265's), ``/camera/odom/sample``
  (``nav_msgs/Odometry``, 200 Hz): the tracking camera's own drifting odometry, ``camera_pose_frame`` in
  ``camera_odom_frame``, as realsense-ros publishes it;
- ``/tf_static``: the setup's ``static_tree``; gpo's own (``gpo_static_tree``) puts the camera's optical frame
  (and the tracking camera's body frame) straight in ``base_link``, ``gpo.sim.realsense`` lays out a T265's frames
  as realsense-ros does.

``recording(name)`` is the one call the notebooks make: it generates the preset's (or setup's) bag on first
use and returns the cached file. Generation is deterministic, so the bag is the same file byte for
byte every time; the cache key holds a hash of the simulator's own source, so a changed simulator
makes a new file.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Iterator
from concurrent.futures import ProcessPoolExecutor
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import NamedTuple

import cv2
import numpy as np
from scipy.spatial.transform import Rotation
from tqdm.auto import tqdm

from gpo.cameras.files import camera_to_kalibr
from gpo.cameras.rig import Rig
from gpo.cameras.targets import Chessboard, FloorBoard
from gpo.io import cache
from gpo.io.bag_writer import BagWriter
from gpo.io.fingerprint import sources
from gpo.io.trajectory import Trajectory
from gpo.sim.ceiling import DEFAULT_CEILING, Ceiling
from gpo.sim.disturbances import Disturbances
from gpo.sim.drift import T265_DRIFT, TrackingDrift, tracking_odometry
from gpo.sim.floors import VERY_LOW_CONTRAST, FloorDesign, make_floor
from gpo.sim.outages import Outage, apply_outage, outage_at
from gpo.sim.paths import named_plan
from gpo.sim.plans import MotionPlan
from gpo.sim.render import FloorRenderer
from gpo.sim.rigs import RIGS

START_NS = 1_700_000_000 * 1_000_000_000  # 2023-11-14 22:13:20 UTC: the first stamp of every recording
GROUND_TRUTH_TOPIC = "/mocap/base_link"
ODOMETRY_TOPIC = "/camera/odom/sample"
AVERAGE_REFLECTION = dataclasses.replace(DEFAULT_CEILING, reflection=DEFAULT_CEILING.reflection / 2)
"""The room of an averagely reflective floor (the second paper's raised floor): its mirrored lamps half as bright
as the glossy screed's."""
TEXEL_M = {"t265": 1e-3, "downward": 5e-4}  # floor texture resolution per rig: finer than a pixel's footprint
FLOOR_MARGIN_M = {"t265": 2.5, "downward": 0.5}  # textured floor beyond the path, metres


@dataclass(frozen=True)
class Preset:
    """A recording: ``rig`` (``t265`` or ``downward``), a named ``path`` of ``gpo.sim.paths``, a floor kind.

    ``exposure_s`` > 0 blurs each frame over that exposure (``blur_samples`` poses averaged).
    ``disturbances`` put moving sheets and glints in the camera's view (none by default).
    ``outages`` (``gpo.sim.outages.Outage``) are stretches where the floor cannot be measured (none by default).
    ``contrast`` and ``sheen``: the floor's (``gpo.sim.floors.FloorDesign``: its texture's contrast, 1 as the kind
    has it; None: the kind's own sheen); ``ceiling``: the room's, whose lamps a glossy floor mirrors.
    """

    rig: str
    path: str
    floor: str
    seed: int
    description: str
    exposure_s: float = 0.0
    blur_samples: int = 3
    disturbances: Disturbances = field(default_factory=Disturbances)
    outages: tuple[Outage, ...] = ()
    contrast: float = 1.0
    sheen: bool | None = None
    ceiling: Ceiling = DEFAULT_CEILING

    def setup(self) -> Setup:
        """What this preset shows: its rig, path, floor and seed; the fisheye rig's T265 drifts as ``T265_DRIFT``."""
        return Setup(
            RIGS[self.rig](),
            named_plan(self.path),
            FloorDesign((self.floor,), sheen=self.sheen, contrast=self.contrast),
            self.seed,
            T265_DRIFT if self.rig == "t265" else None,
            TEXEL_M[self.rig],
            FLOOR_MARGIN_M[self.rig],
            self.exposure_s,
            self.blur_samples,
            self.disturbances,
            self.outages,
            ceiling=self.ceiling,
        )


class StaticTransform(NamedTuple):
    """A transform a recording puts on ``/tf_static``: frame ``child`` at ``position_m`` (3,) metres in frame
    ``parent``, turned by the unit quaternion ``quaternion_xyzw`` (rotation parent <- child)."""

    parent: str
    child: str
    position_m: np.ndarray
    quaternion_xyzw: np.ndarray


def gpo_static_tree(setup: Setup) -> list[StaticTransform]:
    """gpo's own static frames: the camera's optical frame (``Rig.frame_id``: x right, y down, z forward) in
    ``base_link``, and for a setup with a tracking camera its body frame ``camera_pose_frame`` (x forward, y left,
    z up; ``Setup.tracking_body``) in ``base_link``."""
    mount = setup.rig.mount
    tree = [StaticTransform("base_link", setup.rig.frame_id, mount.position, mount.rotation.as_quat())]
    if setup.drift is not None:
        position, rotation = setup.tracking_body()
        tree.append(StaticTransform("base_link", "camera_pose_frame", position, rotation.as_quat()))
    return tree


@dataclass(frozen=True, eq=False)
class Setup:
    """Everything a recording shows: the ``rig`` driving ``plan`` over a ``floor`` made at ``texel_m`` metres per
    texel, ``floor_margin_m`` beyond the path of the robot and its camera; the ``seed`` of the floor's texture, the
    sensor's noise and the tracking camera's drift; ``drift``: how the tracking camera's odometry drifts, or None for a
    rig without one; the exposure, disturbances and outages as ``Preset`` has them.

    ``tracking_mount``: where the tracking camera's body frame ``camera_pose_frame`` (x forward, y left, z up) sits,
    (position (3,) metres in ``base_link``, rotation base_link <- body); None puts it at the rig's camera's own body
    frame (as gpo's fisheye rig is the T265's fisheye standing for the whole T265). ``ceiling``: the room's ceiling
    and its lamps, which a glossy floor mirrors (``gpo.sim.ceiling``). ``static_tree``: the frames the
    bag's ``/tf_static`` holds, computed from the setup: ``gpo_static_tree`` (gpo's own) or a driver's
    (``gpo.sim.realsense.realsense_static_tree``). The rig names the image and camera_info topics and the optical
    frame, and its camera model gives the camera_info's distortion model.
    """

    rig: Rig
    plan: MotionPlan
    floor: FloorDesign
    seed: int
    drift: TrackingDrift | None = None
    texel_m: float = 1e-3
    floor_margin_m: float = 2.5
    exposure_s: float = 0.0
    blur_samples: int = 3
    disturbances: Disturbances = field(default_factory=Disturbances)
    outages: tuple[Outage, ...] = ()
    tracking_mount: tuple[np.ndarray, Rotation] | None = None
    ceiling: Ceiling = DEFAULT_CEILING
    static_tree: Callable[[Setup], list[StaticTransform]] = gpo_static_tree

    def tracking_body(self) -> tuple[np.ndarray, Rotation]:
        """The tracking camera's body frame in ``base_link``: (position (3,) metres, rotation base_link <- body)."""
        mount = self.rig.mount
        return (mount.position, mount.body_rotation) if self.tracking_mount is None else self.tracking_mount

    def description(self) -> dict:
        """The setup in plain numbers and names (what the recording cache's key hashes)."""
        rig, plan = self.rig, self.plan
        tracking_position, tracking_rotation = self.tracking_body()
        return {
            "rig": {
                "name": rig.name,
                "camera": camera_to_kalibr(rig.camera, rig.name),
                "position_m": [float(v) for v in rig.mount.position],
                "quaternion_xyzw": [float(v) for v in rig.mount.rotation.as_quat()],
                "rate_hz": rig.rate_hz,
                "names": [rig.image_topic, rig.info_topic, rig.frame_id],
            },
            "plan": {
                "segments": [[type(segment).__name__, asdict(segment)] for segment in plan.segments],
                "start": list(plan.start), "limits": asdict(plan.limits),
            },
            "floor": asdict(self.floor),
            "ceiling": asdict(self.ceiling),
            "seed": self.seed,
            "drift": None if self.drift is None else asdict(self.drift),
            "texel_m": self.texel_m,
            "floor_margin_m": self.floor_margin_m,
            "exposure_s": self.exposure_s,
            "blur_samples": self.blur_samples,
            "disturbances": asdict(self.disturbances),
            "outages": [asdict(outage) for outage in self.outages],
            "tracking_body": {
                "position_m": [float(v) for v in tracking_position],
                "quaternion_xyzw": [float(v) for v in tracking_rotation.as_quat()],
            },
            "static_tree": f"{self.static_tree.__module__}.{self.static_tree.__qualname__}",
        }


PRESETS = {
    "sample": Preset("t265", "sample", "raised", 1, "the fisheye rig on a raised floor, ~13 s: the notebooks' sample"),
    "test": Preset("t265", "test", "raised", 2, "the fisheye rig, ~3 s: for the tests"),
    **{
        f"short{k}": Preset(
            "t265",
            f"short{k}",
            "raised",
            10 + k,
            f"the fisheye rig, 2-5 m path {k} (Test{k}), with sheets dragged across the floor and a lamp's glint",
            disturbances=Disturbances(sheets=sheets, glints=1, seed=10 + k),
        )
        for k, sheets in ((1, 5), (2, 8), (3, 7))  # a sheet in the GPI's floor patch in 40-50 % of the frames
    },
    "glossy": Preset(
        "t265", "short2", "industrial", 60, "the fisheye rig over polished screed mirroring the ceiling's lamps, 4.5 m"
    ),
    **{
        f"long{k}": Preset(
            "t265", f"long{k}", "raised", 20 + k, f"the fisheye rig, 12-17 m path {k} (Test{k + 3})", exposure_s=0.006
        ) for k in (1, 2, 3)
    },
    **{
        f"downward-{kind}": Preset(
            "downward", "downward-short", kind, 30 + k, f"the downward camera over a {kind} floor, 4.3 m"
        ) for k, kind in enumerate(("wood", "raised", "industrial"))
    },
    "downward-long": Preset("downward", "downward-long", "wood", 33, "the downward camera over a wood floor, 16.5 m"),
    # the second paper's experiments in its conditions (its Tables 1 and 2): the downward camera on the three-wheeled
    # cart over wood (I-II, low reflectivity, high texture) and along a raised-floor corridor (III, average both), on
    # the linear and rotational stages over the industrial floor (IV-VIII, high reflectivity: the screed mirrors the
    # ceiling's lamps; low texture for IV and VI, very low for V, VII and VIII) and on the omnidirectional AGV (IX)
    **{
        f"paper2-{number}": Preset("downward", path, floor, seed, f"experiment {number.upper()}: {text}", **conditions)
        for number, path, floor, seed, text, conditions in (
            ("i", "cart-i", "wood", 41, "a cart pushed at random over a wood floor, 18 m at 0.16 m/s", {}),
            ("ii", "cart-ii", "wood", 42, "the same, faster, 19.4 m at 0.294 m/s", {}),
            ("iii", "corridor-iii", "raised", 43, "a cart along a raised-floor corridor, 14.48 m at 0.30 m/s",
             {"sheen": True, "ceiling": AVERAGE_REFLECTION}),
            ("iv", "stage-iv", "industrial", 44, "50 steps of 10 mm on a linear stage, 0.5 m, low texture", {}),
            ("v", "stage-v", "industrial", 45, "100 steps of 5-20 mm on a linear stage, 1.24 m, very low texture",
             {"contrast": VERY_LOW_CONTRAST}),
            ("vi", "stage-vi", "industrial", 46, "along a linear stage at 0.12 m/s, 3.18 m, low texture", {}),
            ("vii", "rotation-vii", "industrial", 47, "a 90 degree rotation in 1 degree steps, very low texture",
             {"contrast": VERY_LOW_CONTRAST}),
            ("viii", "rotation-viii", "industrial", 48, "a 180 degree rotation at 20 deg/s, very low texture",
             {"contrast": VERY_LOW_CONTRAST}),
            ("ix", "agv-ix", "industrial", 49, "the omnidirectional AGV, 81 m with sideways and diagonal moves", {}),
        )
    },
}
# Floor outages: the long paths again (same motion, floor, seed and tracking camera), with four stretches where the
# floor cannot be measured, 6 s in all (12-14 % of the frames)
FLOOR_OUTAGES = (
    Outage("textureless", 6.0, 3.0),
    Outage("glare", 16.0, 1.5),
    Outage("fast", 27.0, 0.5),
    Outage("lifted", 37.0, 1.0),
)
PRESETS.update(
    {
        f"long{k}-outages": dataclasses.replace(
            PRESETS[f"long{k}"],
            description=f"long{k}, the floor unmeasurable 4 times, 6 s in all (no texture, glare, too fast, lifted)",
            outages=FLOOR_OUTAGES,
        )
        for k in (1, 2, 3)
    }
)


def preset(name: str) -> Preset:
    """The preset called ``name``; a clear error listing the presets otherwise."""
    if name not in PRESETS:
        raise ValueError(f"unknown preset {name!r}; the presets are {', '.join(PRESETS)}")
    return PRESETS[name]


def setup_of(what: str | Setup, seed: int | None = None) -> tuple[Setup, str]:
    """The setup of ``what`` (a preset's name, with ``seed`` in place of its own when given, or a setup, then
    ``seed`` None) and the label its recording is cached under."""
    if isinstance(what, Setup):
        if seed is not None:
            raise ValueError("a seed replaces a preset's; a setup holds its own")
        return what, f"{what.rig.name}-setup"
    chosen = preset(what) if seed is None else dataclasses.replace(preset(what), seed=seed)
    return chosen.setup(), what if chosen.seed == preset(what).seed else f"{what}-seed{seed}"


def floor_extent(plan: MotionPlan, rig: Rig, margin: float) -> tuple[float, float, float, float]:
    """(x_min, x_max, y_min, y_max) metres covering the path of the robot and of its camera, plus ``margin``."""
    state = plan.sample(np.linspace(0.0, plan.duration_s, 400))
    ahead = np.hypot(*rig.mount.position[:2])
    x = np.concatenate([state.x - ahead, state.x + ahead])
    y = np.concatenate([state.y - ahead, state.y + ahead])
    return x.min() - margin, x.max() + margin, y.min() - margin, y.max() + margin


@dataclass(frozen=True, eq=False)
class Scene:
    """What ``setup`` shows: the ``renderer`` of its floor (with its disturbances) and the ``frame_times``
    (seconds) of its camera frames."""

    setup: Setup
    renderer: FloorRenderer
    frame_times: np.ndarray

    @classmethod
    def of(cls, what: str | Setup, seed: int | None = None) -> Scene:
        """The scene of ``what``: a preset's name (``seed`` replaces the preset's: its floor's texture and the
        tracking camera's drift) or a setup."""
        setup, _ = setup_of(what, seed)
        rig, plan = setup.rig, setup.plan
        floor = setup.floor.texture(floor_extent(plan, rig, setup.floor_margin_m), setup.texel_m, setup.seed)
        frame_times = np.arange(0.0, plan.duration_s, 1.0 / rig.rate_hz)
        path = plan.sample(frame_times)
        disturbances = setup.disturbances
        renderer = FloorRenderer(
            rig,
            floor,
            ceiling=setup.ceiling,
            sheets=disturbances.place_sheets(frame_times, np.column_stack([path.x, path.y, path.yaw])),
            glints=disturbances.place_glints(),
        )
        return cls(setup, renderer, frame_times)

    @property
    def rig(self) -> Rig:
        return self.setup.rig

    @property
    def plan(self) -> MotionPlan:
        return self.setup.plan

    def frame(self, index: int) -> np.ndarray:
        """Camera frame ``index`` (uint8), the same whoever renders it and in whatever order."""
        times, poses = _exposure(self.setup, self.frame_times[index])
        image = self.renderer.render(poses, frame_seed=(self.setup.seed, index), times_s=times)
        outage = outage_at(self.setup.outages, self.frame_times[index])
        return image if outage is None else apply_outage(outage.kind, image)


def simulate(
    what: str | Setup, out, format: str = "ros1", progress: bool = True, seed: int | None = None, jobs: int = 1
) -> Path:
    """Render ``what`` (a preset's name or a ``Setup``) into a new bag at ``out`` (``format``: ros1, ros2 or
    ros2-mcap); return its path.

    ``seed`` replaces a preset's (its floor's texture and the tracking camera's drift). ``jobs`` > 1 renders the
    frames in that many processes (the bag is the same, byte for byte).
    """
    if jobs < 1:
        raise ValueError(f"jobs must be at least 1, not {jobs}")
    scene = Scene.of(what, seed)
    setup, rig, plan = scene.setup, scene.rig, scene.plan
    with BagWriter(out, format) as bag:
        for transform in setup.static_tree(setup):
            bag.add_static_transform(*transform, START_NS)
        bag.add_trajectory(GROUND_TRUTH_TOPIC, plan.ground_truth(120.0, START_NS), msgtype="pose")
        if setup.drift is not None:
            odometry = tracking_odometry(plan, setup.tracking_body(), 200.0, setup.drift, setup.seed, START_NS)
            bag.add_trajectory(ODOMETRY_TOPIC, odometry)
        frames = _frames(setup, scene, jobs)
        name = what if isinstance(what, str) else rig.name
        counted = tqdm(frames, desc=f"rendering {name}", total=len(scene.frame_times), disable=not progress)
        for time_s, image in zip(scene.frame_times, counted, strict=True):
            stamp_ns = START_NS + round(time_s * 1e9)
            bag.add_image(rig.image_topic, stamp_ns, image, rig.frame_id)
            bag.add_camera_info(rig.info_topic, stamp_ns, rig.camera, rig.frame_id)
    return Path(out)


FRAMES_PER_TASK = 16  # frames a rendering process renders at a time
_WORKER_SCENE: dict[str, Scene] = {}  # in a rendering process: the scene it renders


def _frames(setup: Setup, scene: Scene, jobs: int) -> Iterator[np.ndarray]:
    """The frames of ``scene`` (of ``setup``) in order, rendered here or by ``jobs`` processes."""
    count = len(scene.frame_times)
    if jobs == 1:
        yield from (scene.frame(index) for index in range(count))
        return
    tasks = [range(start, min(start + FRAMES_PER_TASK, count)) for start in range(0, count, FRAMES_PER_TASK)]
    _WORKER_SCENE["scene"] = scene  # a process forked from this one starts with it, floor texture and all
    try:
        with ProcessPoolExecutor(jobs, initializer=_start_rendering, initargs=(setup,)) as pool:
            for images in pool.map(_render, tasks):
                yield from images
    finally:
        _WORKER_SCENE.clear()


def _start_rendering(setup: Setup) -> None:
    """In a rendering process: set up the scene of ``setup`` once, unless it was forked with it."""
    if "scene" not in _WORKER_SCENE:
        _WORKER_SCENE["scene"] = Scene.of(setup)


def _render(indices: range) -> list[np.ndarray]:
    """In a rendering process: the frames ``indices`` of its scene."""
    return [_WORKER_SCENE["scene"].frame(index) for index in indices]


def _exposure(setup: Setup, time_s: float) -> tuple[np.ndarray, np.ndarray]:
    """Times (K,) seconds and poses (K, 3) over the exposure centred on ``time_s``, kept inside the plan."""
    plan = setup.plan
    if setup.exposure_s <= 0:
        times = np.array([time_s])
    else:
        half = 0.5 * setup.exposure_s
        times = np.clip(np.linspace(time_s - half, time_s + half, setup.blur_samples), 0.0, plan.duration_s)
    state = plan.sample(times)
    return times, np.column_stack([state.x, state.y, state.yaw])


def recording(
    what: str | Setup = "sample",
    format: str = "ros1",
    progress: bool = True,
    seed: int | None = None,
    jobs: int = 1,
    label: str | None = None,
) -> Path:
    """The bag of ``what``: a preset's name (with ``seed`` in place of its own, when given) or a ``Setup``;
    generated on first use, then read from the cache (``gpo.io.cache``, ``recordings``, named ``label``: by default
    the preset's name, or the rig's for a setup).

    Its key holds the setup (``Setup.description``), the format and the simulator's sources
    (``gpo.io.fingerprint.sources`` of this module and of the module of the setup's ``static_tree``: the simulator
    and what it runs). Each process renders into a file of its own and renames it into place when complete,
    so processes that want the same recording at once never read one another's half-written bag (the files are
    identical). A kept bag is checked against its seal (``gpo.io.cache.intact``) before its path is returned: one
    cut short or corrupted since it was made is rendered again. ``jobs``: processes rendering its frames.
    """
    path = recording_path(what, format, seed, label)
    if not cache.intact(path):  # missing, or cut short or corrupted since it was made
        cache.write(path, lambda partial: simulate(what, partial, format, progress, seed, jobs))
    return path


def recording_path(
    what: str | Setup = "sample", format: str = "ros1", seed: int | None = None, label: str | None = None
) -> Path:
    """Where ``recording`` keeps the bag of ``what`` (see there), whether or not it has been made."""
    setup, own_label = setup_of(what, seed)
    key = cache.key(setup.description(), format, sources=sources(__name__, setup.static_tree.__module__))
    return cache.path("recordings", label or own_label, key, ".bag" if format == "ros1" else "")


FLOOR_BOARDS = {
    # a board of 20.0 mm squares (the first paper's Table 1) lying on the floor, in base_link with the robot at rest
    "t265": FloorBoard(Chessboard((8, 6), 0.020, 0.015), x=0.74, y=-0.06, yaw=0.0),
    "downward": FloorBoard(Chessboard((8, 6), 0.020, 0.015), x=0.06, y=-0.08, yaw=np.pi / 2),
}


def floor_board_image(rig_name: str, seed: int = 0) -> np.ndarray:
    """The rig's camera image (uint8) of ``FLOOR_BOARDS[rig_name]`` on a raised floor, the robot at the world origin:
    rendered once, then read from the cache (``floor_board_path``); on a full disk rendered and not kept."""
    path = _floor_board_cached(rig_name, seed)
    if cache.intact(path):
        return cv2.imread(str(path), cv2.IMREAD_GRAYSCALE)
    image = _render_floor_board(rig_name, seed)
    cache.keep(path, lambda partial: cv2.imwrite(str(partial), image))
    return image


def floor_board_path(rig_name: str, seed: int = 0) -> Path:
    """The PNG of ``floor_board_image(rig_name, seed)`` in the cache (``recordings``), written on first use and keyed by
    the simulator's sources like the recordings."""
    path = _floor_board_cached(rig_name, seed)
    if not cache.intact(path):
        cache.write(path, lambda partial: cv2.imwrite(str(partial), _render_floor_board(rig_name, seed)))
    return path


def _floor_board_cached(rig_name: str, seed: int) -> Path:
    key = cache.key(rig_name, seed, sources=sources(__name__))
    return cache.path("recordings", f"floor_board_{rig_name}", key, ".png")


def _render_floor_board(rig_name: str, seed: int) -> np.ndarray:
    rig = RIGS[rig_name]()
    floor = make_floor("raised", (-1.0, 2.0, -1.5, 1.5), TEXEL_M[rig_name], seed)
    return FloorRenderer(rig, floor).render(np.zeros(3), frame_seed=seed, boards=(FLOOR_BOARDS[rig_name],))


def _rounded(trajectory: Trajectory) -> Trajectory:
    """``trajectory`` to the nanometre and 1e-12 of a quaternion, so that its file is the same on every machine
    (vectorised maths may differ in the last bit from one CPU to another)."""
    return dataclasses.replace(
        trajectory, positions=np.round(trajectory.positions, 9), quaternions=np.round(trajectory.quaternions, 12)
    )


def write_sample_data(folder) -> list[Path]:
    """Write the small sample files kept in the repository's ``data/``; return their paths.

    ``sample_groundtruth.tum`` and ``sample_tracking_odometry.tum``: the sample preset's ground
    truth (base_link in world, 120 Hz) and the tracking camera's odometry (200 Hz), without
    rendering the images; ``floor_board_t265.png`` and ``floor_board_downward.png``: each rig's
    view of a 20 mm chessboard lying on the floor, placed as ``FLOOR_BOARDS`` says.
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    chosen = preset("sample")
    plan = named_plan(chosen.path)
    rig = RIGS[chosen.rig]()
    written = [
        _rounded(plan.ground_truth(120.0, START_NS)).write_tum(folder / "sample_groundtruth.tum"),
        _rounded(tracking_odometry(plan, rig.mount, 200.0, T265_DRIFT, chosen.seed, START_NS)).write_tum(
            folder / "sample_tracking_odometry.tum"
        ),
    ]
    for rig_name in FLOOR_BOARDS:
        path = folder / f"floor_board_{rig_name}.png"
        cv2.imwrite(str(path), floor_board_image(rig_name), [cv2.IMWRITE_PNG_COMPRESSION, 9])
        written.append(path)
    return written
