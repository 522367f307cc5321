"""A config in, a trajectory out: the one place where the stages meet.

Long (about 730 lines) because all that joins the stages is here: the config read into stages, the odometer's step
for every method and route, the run over a bag and its result; each stage itself lives in its own module.

``run(bag, config)`` streams a recording's camera frames through the floor image's one remap table
(``gpo.ground``), the frame-to-frame floor flow (``gpo.flow``) and a motion estimator (``gpo.kinematics``), and
integrates the pose of ``base_link`` in ``odom`` (the pose at the first frame is the origin). The estimators
(``METHODS``):

- ``gpo``: the first paper's Ground Plane Odometry: the median motion vector read as the motion of a virtual
  front wheel a wheelbase L ahead of the rear axle, through the paper's bicycle model (eqs. 25-34, Euler step).
  The vector is the motion of the floor where the tracks are, and tracks drift towards the robot between
  re-detections, so the wheel is placed at the tracks' median each frame (about L; l_r keeps its ratio to L).
  Left at the fixed L, every turn read 5 % short on the ``long1`` path;
- ``gpo-exact``: the same vector, of the floor's own tracks (on a glossy floor not its reflections':
  ``gpo.flow.floor_layer``), turned into the exact circular arc of a rigid robot that does not slide at its rear
  axle (reverse driving and turning on the spot included);
- ``gpo-rigid``: no kinematic model: the rigid 2-D motion of the kept tracks (RANSAC, then least squares) is the
  frame's increment;
- ``fused``: one of those (``FusionSettings.floor_method``) and the tracking camera's own odometry from the same
  bag, fused by the EKF of ``gpo.fusion``.

Every frame gets a ``FrameRecord``. A frame that cannot be measured is flagged with the reason and the robot
**coasts** across it at the last measured velocity, for at most ``max_gap_s``; beyond that it is held still.
Frames whose stamp repeats or goes backwards are skipped; a gap longer than ``max_gap_s`` between frames is
flagged, the pose held across it and tracking restarted after it. A frame that cannot be read (a corrupt JPEG, a
short buffer, another size) is skipped and flagged with the reason, and the frames after it are read. ``run``
returns what it computed when reading stops early, at Ctrl-C, or when the fusion fails (the result says which).
"""

from __future__ import annotations

import math
import time
import warnings
from collections import Counter
from dataclasses import dataclass, field, fields
from enum import StrEnum
from importlib import resources
from pathlib import Path

import cv2
import numpy as np
import yaml
from scipy.spatial.transform import Rotation

from gpo.bag import Recording, StampWarning
from gpo.config import FloorImageSection, read_config, rig_from_config, rig_to_dict
from gpo.features import FeatureMatches, FeatureParameters, FeatureTracker, Keypoints, degenerate, detect, refit
from gpo.flow import FloorFlow, FlowMeasurement, KLTParameters, floor_layer, slower_layer
from gpo.fusion import FilterDiverged, FusionSettings, TrackingMount, fuse
from gpo.ground import (
    FLOOR_METRES_PER_PIXEL,
    FLOOR_X_RANGE_M,
    FLOOR_Y_RANGE_M,
    FloorImage,
    RemapTable,
    analytic_table,
    ground_plane_image,
    ortho_rectify,
    pixels_to_floor,
)
from gpo.kinematics import (
    PaperBicycle,
    compose,
    increment_from_point_motion,
    increment_from_point_pairs,
)
from gpo.outputs import write_text, write_with
from gpo.rig import Rig
from gpo.targets import Chessboard, FloorBoard
from gpo.trajectory import Trajectory, base_from_sensor_odometry


class Method(StrEnum):
    """The motion estimators (the module docstring says what each does); each is its name in configs."""

    GPO = "gpo"
    GPO_EXACT = "gpo-exact"
    GPO_RIGID = "gpo-rigid"
    FEATURES = "features"
    FUSED = "fused"


class Route(StrEnum):
    """How a camera frame becomes what the motion is measured on (``OdometryConfig`` says what each does)."""

    ANALYTIC = "analytic"
    ORTHO_GPI = "ortho-gpi"
    GPI = "gpi"
    KEYPOINTS = "keypoints"


class Status(StrEnum):
    """What became of a frame: its motion measured, the robot coasted or held across it, the frame skipped, or the
    first frame."""

    MEASURED = "measured"
    COASTED = "coasted"
    HELD = "held"
    SKIPPED = "skipped"
    FIRST = "first"


METHODS = tuple(Method)
FLOOR_METHODS = tuple(method for method in Method if method is not Method.FUSED)
ROUTES = tuple(Route)
VECTORS = ("median", "mean")
RANSAC_THRESHOLD_PX = 1.0  # a track fits the rigid motion when it lands this close to where the motion puts it
DEFAULT_CONFIG = "sim_t265.yaml"


@dataclass(frozen=True, eq=False)
class OdometryConfig:
    """Everything a run needs: the ``rig``, the ``floor`` image, the KLT ``klt`` parameters, the paper's bicycle
    ``model``, the ``method`` (one of ``METHODS``), the ``vector`` statistic (median or mean; for ``gpo`` and
    ``gpo-exact``), ``max_gap_s``, the longest time the robot coasts or a frame gap is bridged, seconds, the
    ``fusion`` settings of the ``fused`` method, and the ``route`` that makes the floor image (``floor_table``):

    - ``analytic``: each floor point projected through the calibrated camera from the rig's mount (no chessboard);
    - ``ortho-gpi``: the first paper's chessboard route, fisheye -> cubemap -> GPI -> ortho-GPI, calibrated on
      ``board_image``, a frame of the chessboard ``board`` lying on the floor where ``board`` says;
    - ``gpi``: the plain GPI of the same frame, its own approximate scale and place taken for true;
    - ``keypoints``: no floor image; the ``features`` method detects keypoints in the camera image and turns each
      into a floor point (``gpo.ground.pixels_to_floor``: undistortion, the mount's tilt, its height), the second
      paper's way.

    ``features``: the keypoint detector, matching and filters of the ``features`` method (``gpo.features``)."""

    rig: Rig
    floor: FloorImage
    klt: KLTParameters = field(default_factory=KLTParameters)
    model: PaperBicycle | None = None
    method: Method = Method.GPO_EXACT
    vector: str = "median"
    max_gap_s: float = 0.5
    fusion: FusionSettings = field(default_factory=FusionSettings)
    route: Route = Route.ANALYTIC
    board_image: Path | None = None
    board: FloorBoard | None = None
    features: FeatureParameters = field(default_factory=FeatureParameters)

    def __post_init__(self):
        if self.route not in ROUTES:
            raise ValueError(f"unknown route {self.route!r}; the routes are {', '.join(ROUTES)}")
        if self.method not in METHODS:
            raise ValueError(f"unknown method {self.method!r}; the methods are {', '.join(METHODS)}")
        object.__setattr__(self, "route", Route(self.route))  # a name from a file or the command line, as a member
        object.__setattr__(self, "method", Method(self.method))
        if self.route in (Route.ORTHO_GPI, Route.GPI) and (self.board_image is None or self.board is None):
            raise ValueError(f"the {self.route} route needs board_image (a frame of the floor board) and board")
        if self.fusion.floor_method not in FLOOR_METHODS:
            floor_method = self.fusion.floor_method
            raise ValueError(f"fusion.floor_method must be one of {', '.join(FLOOR_METHODS)}, got {floor_method!r}")
        floor_method = self.fusion.floor_method if self.method is Method.FUSED else self.method
        if self.route is Route.KEYPOINTS and floor_method != Method.FEATURES:
            raise ValueError(
                f"the keypoints route corrects keypoints: it needs the features method, not {floor_method}"
            )
        if self.vector not in VECTORS:
            raise ValueError(f"unknown vector {self.vector!r}; use {' or '.join(VECTORS)}")
        if not self.max_gap_s > 0:
            raise ValueError(f"max_gap_s must be positive, got {self.max_gap_s!r}")
        if self.model is None:
            centre = float(np.mean(self.floor.extent[:2]))
            object.__setattr__(self, "model", PaperBicycle(centre, centre))

    def replace(self, **changes) -> OdometryConfig:
        """A copy with ``changes`` (any field, e.g. method="gpo")."""
        values = {f.name: getattr(self, f.name) for f in fields(self)}
        return OdometryConfig(**{**values, **changes})


def load_config(path=None) -> OdometryConfig:
    """The run config of a config YAML (checked by ``gpo.config.read_config``) with the sections ``floor_image``,
    ``klt``, ``kinematics``, ``odometry``, ``fusion`` and ``features``; None loads the shipped default for the
    simulated T265 rig. Errors name the file and the key."""
    if path is None:
        with resources.as_file(resources.files("gpo") / "configs" / DEFAULT_CONFIG) as default:
            return load_config(default)
    path = Path(path)
    document = read_config(path)
    rig = rig_from_config(document, path)
    kinematics = document.kinematics
    model = None if kinematics is None else PaperBicycle(kinematics.wheelbase_m, kinematics.rear_to_reference_m)
    odometry = document.odometry.model_dump(exclude_none=True)
    try:
        floor = _floor_image(document.floor_image)
        return OdometryConfig(
            rig, floor, document.klt, model, **odometry, fusion=document.fusion, features=document.features,
            **_route(document.floor_image, path),
        )
    except ValueError as error:
        raise ValueError(f"{path}: {error}") from None


def config_to_dict(config: OdometryConfig) -> dict:
    """The YAML document of ``config`` (``load_config`` reads it back)."""
    x_min, x_max, y_min, y_max = config.floor.extent
    return {
        **rig_to_dict(config.rig),
        "floor_image": {
            "x_range_m": [round(x_min, 9), round(x_max, 9)],
            "y_range_m": [round(y_min, 9), round(y_max, 9)],
            "metres_per_pixel": round(config.floor.metres_per_pixel, 12),
            **_route_to_dict(config),
        },
        "klt": {f.name: getattr(config.klt, f.name) for f in fields(config.klt)},
        "kinematics": {
            "wheelbase_m": config.model.wheelbase_m,
            "rear_to_reference_m": config.model.rear_to_reference_m,
        },
        "odometry": {"method": str(config.method), "vector": config.vector, "max_gap_s": config.max_gap_s},
        "fusion": config.fusion.to_dict(),
        "features": {f.name: getattr(config.features, f.name) for f in fields(config.features)},
    }


def save_config(path, config: OdometryConfig) -> Path:
    """Write ``config`` as YAML (through a temporary name); return the path."""
    header = "# gpo run config: the rig (camera, mount, topics), the floor image, KLT, the bicycle model, the method\n"
    return write_text(path, header + yaml.safe_dump(config_to_dict(config), sort_keys=False, default_flow_style=None))


def _floor_image(section: FloorImageSection) -> FloorImage:
    try:
        return FloorImage.top_view(
            section.x_range_m or FLOOR_X_RANGE_M,
            section.y_range_m or FLOOR_Y_RANGE_M,
            section.metres_per_pixel or FLOOR_METRES_PER_PIXEL,
        )
    except ValueError as error:
        raise ValueError(f"floor_image: {error}") from None


def _route(section: FloorImageSection, path: Path) -> dict:
    """The floor image's ``route`` and, for the chessboard routes, ``board_image`` (relative to the config file)
    and ``board`` (where it lay in base_link)."""
    route = {"route": section.route}
    if section.board_image is not None:
        route["board_image"] = path.parent / section.board_image
    if section.board is not None:
        board = section.board
        chessboard = Chessboard(board.squares, board.square_m, board.margin_m)
        route["board"] = FloorBoard(chessboard, board.x_m, board.y_m, math.radians(board.yaw_deg))
    return route


def _route_to_dict(config: OdometryConfig) -> dict:
    if config.route in (Route.ANALYTIC, Route.KEYPOINTS):
        return {} if config.route is Route.ANALYTIC else {"route": str(config.route)}
    board = config.board
    return {
        "route": str(config.route),
        "board_image": str(config.board_image),
        "board": {
            "squares": list(board.board.squares),
            "square_m": board.board.square,
            "margin_m": board.board.margin,
            "x_m": board.x,
            "y_m": board.y,
            "yaw_deg": math.degrees(board.yaw),
        },
    }


def floor_table(config: OdometryConfig) -> RemapTable:
    """The one remap table from the camera to ``config.floor`` along ``config.route`` (up to half of the floor
    image may lie outside the view; those pixels are masked); the ``keypoints`` route, which makes no floor image,
    has the analytic one, for people to look at."""
    camera, floor = config.rig.camera, config.floor
    if config.route in (Route.ANALYTIC, Route.KEYPOINTS):
        return analytic_table(camera, config.rig.mount, floor, max_outside=0.5)
    image = cv2.imread(str(config.board_image), cv2.IMREAD_GRAYSCALE)
    if image is None:
        raise ValueError(f"cannot read the floor board's image {config.board_image} (the {config.route} route)")
    gpi = ground_plane_image(image, camera, config.board)
    if config.route is Route.GPI:
        return gpi.resampled(floor, max_outside=0.5)
    return ortho_rectify(gpi, gpi.table.apply(image), config.board, floor, max_outside=0.5).table


# ----------------------------------------------------------------------------------------------- running


@dataclass(frozen=True)
class Unreadable:
    """A frame that could not be read, in its image's place: ``reason`` says why (``FloorOdometer.step`` skips it)."""

    reason: str


@dataclass(frozen=True)
class FrameRecord:
    """One frame: header stamp (ns), base_link's ``pose`` (x, y, theta) in odom after it, the flow's counts
    (tracked, kept, inliers, spread in pixels), ``status`` (measured, coasted, held, skipped, first), the
    ``flag`` saying why when not measured, and ``slower``: the kept vectors in a slower layer (``gpo.flow``)."""

    stamp_ns: int
    pose: tuple[float, float, float]
    tracked: int
    kept: int
    inliers: int
    spread_px: float
    status: Status
    flag: str | None = None
    slower: int = 0

    def __post_init__(self):
        object.__setattr__(self, "status", Status(self.status))  # a status given by its name, as a member


class FloorOdometer:
    """Frame-by-frame odometry of one config: ``step(stamp_ns, image)`` returns that frame's ``FrameRecord``.
    The floor's motion comes from KLT flow (``gpo.flow``) or, for the ``features`` method, from matched keypoints
    (``gpo.features``)."""

    def __init__(self, config: OdometryConfig):
        self.config = config
        self.table = floor_table(config)
        if config.method is Method.FEATURES:
            self.motion = FeatureTracker(config.features)
            self._mask = None if config.route is Route.KEYPOINTS else self.table.valid.astype(np.uint8)
        else:
            self.motion = FloorFlow(config.klt, mask=self.table.valid)
        estimators = {
            Method.GPO: self._paper_increment,
            Method.GPO_EXACT: self._exact_increment,
            Method.GPO_RIGID: self._rigid_step,
            Method.FEATURES: self._feature_increment,
        }
        if config.method not in estimators:
            raise ValueError(f"a floor odometer runs one of {', '.join(FLOOR_METHODS)}, not {config.method}")
        self._estimate = estimators[config.method]  # (measurement, dt) -> (the frame's increment or None, why)
        affine = config.floor.affine
        self._to_metres = affine[:, :2].T.copy(), affine[:, 2].copy()
        self._nadir_px = np.linalg.solve(affine[:, :2], config.rig.mount.position[:2] - affine[:, 2])
        self.pose = np.zeros(3)
        self._stamp_ns: int | None = None
        self._measured_ns: int | None = None
        self._velocity = np.zeros(3)  # the last measured increment per second (dx, dy, dtheta)

    def floor_image(self, image: np.ndarray) -> np.ndarray:
        """The floor image (8-bit) of a grey frame (mono8, or mono16 taken to its upper 8 bits; ``Recording.frames``
        with ``gray=True`` turns colour to grey); for the ``keypoints`` route the 8-bit frame itself. A clear error
        when its size is not the calibration's."""
        if image.shape[:2] != self._frame_shape:
            height, width = self._frame_shape
            raise ValueError(
                f"the images are {image.shape[1]} x {image.shape[0]} pixels, but the camera of the config's rig "
                f"'{self.config.rig.name}' is {width} x {height}: wrong --topic, or a config of another camera"
            )
        if image.dtype == np.uint16:
            image = (image >> 8).astype(np.uint8)
        return image if self.config.route is Route.KEYPOINTS else self.table.apply(image)

    @property
    def _frame_shape(self) -> tuple[int, int]:
        """(height, width) of the calibrated camera's frames."""
        width, height = self.table.source_size
        return height, width

    def keypoints(self, image: np.ndarray) -> Keypoints:
        """The keypoints of a camera frame as the ``features`` method detects them (in the frame itself for the
        ``keypoints`` route, else in its floor image), to be given to ``step`` in the frame's place."""
        if self.config.method is not Method.FEATURES:
            raise ValueError(f"keypoints are the features method's, this odometer's method is {self.config.method}")
        return detect(self.floor_image(image), self.config.features, self._mask)

    def step(self, stamp_ns: int, image: np.ndarray | Keypoints) -> FrameRecord:
        """Take one camera frame (H, W) in stamp order, or for the ``features`` method its ``keypoints``; return
        its record. A frame that cannot be read (``Unreadable``), or after the first one whose size is not the
        calibration's, is skipped and flagged with the reason."""
        previous = self._stamp_ns
        if isinstance(image, np.ndarray) and previous is not None and image.shape[:2] != self._frame_shape:
            image = Unreadable(f"{image.shape[1]} x {image.shape[0]} pixels, not the calibration's")
        if isinstance(image, Unreadable):
            return self._record(stamp_ns, None, Status.SKIPPED, f"unreadable frame: {image.reason}")
        if previous is not None and stamp_ns <= previous:
            problem = "repeats" if stamp_ns == previous else f"is {(previous - stamp_ns) * 1e-9:.3f} s before"
            return self._record(stamp_ns, None, Status.SKIPPED, f"stamp out of order: {problem} the previous; skipped")
        floor = image if isinstance(image, Keypoints) else self.floor_image(image)
        self._stamp_ns = stamp_ns
        if previous is None:
            self._track(floor, stamp_ns)
            self._measured_ns = stamp_ns
            return self._record(stamp_ns, None, Status.FIRST)
        dt = (stamp_ns - previous) * 1e-9
        if dt > self.config.max_gap_s:
            self.motion.restart()
            self._track(floor, stamp_ns)
            self._velocity[:] = 0.0
            return self._record(stamp_ns, None, Status.HELD, f"frame gap: {dt:.2f} s without frames, motion unknown")
        measurement = self._track(floor, stamp_ns)
        flag = measurement.flag if isinstance(measurement, FeatureMatches) else measurement.quality.flag
        if flag is not None:
            return self._coast(stamp_ns, dt, measurement, flag)
        increment, why = self._estimate(measurement, dt)
        if increment is None:
            return self._coast(stamp_ns, dt, measurement, why)
        self.pose = compose(self.pose, increment)
        self._velocity = increment / dt
        self._measured_ns = stamp_ns
        return self._record(stamp_ns, measurement, Status.MEASURED)

    def _track(self, floor: np.ndarray | Keypoints, stamp_ns: int) -> FlowMeasurement | FeatureMatches | None:
        if isinstance(self.motion, FeatureTracker):
            return self.motion.follow(floor) if isinstance(floor, Keypoints) else self.motion.track(floor, self._mask)
        if isinstance(floor, Keypoints):
            raise ValueError(f"the {self.config.method} method needs camera frames, not keypoints")
        return self.motion.track(floor, stamp_ns * 1e-9)

    def _coast(self, stamp_ns: int, dt: float, measurement, why: str) -> FrameRecord:
        if (stamp_ns - self._measured_ns) * 1e-9 <= self.config.max_gap_s:
            self.pose = compose(self.pose, self._velocity * dt)
            return self._record(stamp_ns, measurement, Status.COASTED, why)
        return self._record(stamp_ns, measurement, Status.HELD, why)

    def _metres(self, uv: np.ndarray) -> np.ndarray:
        matrix, offset = self._to_metres
        return uv @ matrix + offset

    def _vector_motion(self, measurement: FlowMeasurement, tracks: np.ndarray | None = None):
        """The floor point the vector statistic measures (the median start of the kept tracks, or of those the mask
        ``tracks`` picks) and its displacement, both in base_link, metres."""
        starts, vectors = measurement.start, measurement.vectors
        if tracks is not None:
            starts, vectors = starts[tracks], vectors[tracks]
        statistic = np.median if self.config.vector == "median" else np.mean
        return self._metres(np.median(starts, axis=0)), self._to_metres[0].T @ statistic(vectors, axis=0)

    def _paper_increment(self, measurement: FlowMeasurement, dt: float):
        """``gpo``: the paper's bicycle model on the vector, its virtual wheel at the measured point."""
        where, moved = self._vector_motion(measurement)
        return self._virtual_wheel_at(where[0]).step(np.zeros(3), -moved, dt), None  # from the origin

    def _exact_increment(self, measurement: FlowMeasurement, dt: float):
        """``gpo-exact``: the exact arc that moves the measured point by the vector of the floor's own tracks, not
        a reflection's (``gpo.flow.floor_layer``)."""
        where, moved = self._vector_motion(measurement, floor_layer(measurement.start, measurement.end, self._nadir_px))
        return increment_from_point_motion(where, where + moved), None

    def _rigid_step(self, measurement: FlowMeasurement, dt: float):
        """``gpo-rigid``: the rigid motion of the kept tracks."""
        increment = self._rigid_increment(measurement)
        return increment, None if increment is not None else "rigid fit: too few tracks agree"

    def _virtual_wheel_at(self, wheelbase_m: float) -> PaperBicycle:
        """The configured bicycle model with its virtual front wheel moved to ``wheelbase_m``, l_r in proportion."""
        model = self.config.model
        return PaperBicycle(wheelbase_m, min(wheelbase_m, wheelbase_m * model.rear_to_reference_m / model.wheelbase_m))

    def _rigid_increment(self, measurement: FlowMeasurement) -> np.ndarray | None:
        start, end = self._metres(measurement.start), self._metres(measurement.end)
        threshold = RANSAC_THRESHOLD_PX * self.config.floor.metres_per_pixel
        _, inliers = cv2.estimateAffinePartial2D(
            start, end, method=cv2.RANSAC, ransacReprojThreshold=threshold, maxIters=200, confidence=0.995
        )
        if inliers is None or inliers.sum() < self.config.klt.min_tracks:
            return None
        chosen = inliers.ravel().astype(bool)
        return increment_from_point_pairs(start[chosen], end[chosen])

    def _feature_increment(self, matches: FeatureMatches, dt: float) -> tuple[np.ndarray | None, str | None]:
        """``features``: the rigid 2-D transform of the kept matches in metres (the second paper's (theta, Tx, Ty))
        as the robot's increment, fitted again on every match it explains to ``refit_px``; None when the points are
        collinear."""
        parameters = self.config.features
        start, end, on_floor = self._feature_metres(*matches.matched)  # every match once, kept or not
        kept = matches.kept & on_floor
        if kept.sum() < parameters.min_matches or degenerate(matches.start):
            return None, f"degenerate: {kept.sum()} kept matches on the floor, (nearly) on one line"
        increment = increment_from_point_pairs(start[kept], end[kept])
        if parameters.refit_px > 0:
            tolerance = parameters.refit_px * self._feature_pixel_m
            increment = refit(start[on_floor], end[on_floor], increment, tolerance, parameters.min_matches)
        return increment, None

    def _feature_metres(self, start_px: np.ndarray, end_px: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Matched pixels as floor points of base_link (metres), and which pairs reach the floor at both ends."""
        if self.config.route is not Route.KEYPOINTS:
            return self._metres(start_px), self._metres(end_px), np.ones(len(start_px), dtype=bool)
        camera, mount = self.config.rig.camera, self.config.rig.mount
        (start, seen_start), (end, seen_end) = (pixels_to_floor(camera, mount, p) for p in (start_px, end_px))
        return start, end, seen_start & seen_end

    @property
    def _feature_pixel_m(self) -> float:
        """About how far on the floor one pixel of the image the keypoints come from reaches, metres."""
        if self.config.route is not Route.KEYPOINTS:
            return self.config.floor.metres_per_pixel
        return self.config.rig.mount.height / self.config.rig.camera.fx

    def _record(self, stamp_ns, measurement, status, flag=None) -> FrameRecord:
        slower = 0
        if isinstance(measurement, FeatureMatches):
            counts = (len(measurement.pairs), int(measurement.kept.sum()), int(measurement.kept.sum()), math.nan)
        elif measurement is not None:
            quality = measurement.quality
            counts, slower = (quality.tracked, quality.kept, quality.inliers, quality.spread_px), quality.slower
        else:
            counts = (0, 0, 0, math.nan)
        return FrameRecord(int(stamp_ns), tuple(float(v) for v in self.pose), *counts, status, flag, slower)


@dataclass(frozen=True)
class FloorRun:
    """A floor run's path of base_link in odom (``trajectory``) at every frame not skipped, the flow's inlier tracks
    behind each of its steps (``inliers``: 0 where the step was coasted, held or first), the run's frames per second,
    and the inliers' spread behind each step (``spread_px``, pixels: NaN where unknown; None when not kept)."""

    trajectory: Trajectory
    inliers: np.ndarray
    frames_per_second: float
    spread_px: np.ndarray | None = None


@dataclass
class OdometryResult:
    """A run's frames and timing: ``records`` (one per frame read), ``seconds`` of wall time, the ``config``,
    the recording's ``source`` and ``topic``, ``error``: why the run stopped early or its fusion failed, or None,
    and whether it was ``interrupted`` (Ctrl-C, SIGTERM) before the end."""

    records: list[FrameRecord]
    seconds: float
    config: OdometryConfig
    source: str
    topic: str
    error: str | None = None
    fused: Trajectory | None = None
    fusion: dict | None = None  # the fused route's own summary: the mount's source, refused and dropped measurements
    interrupted: bool = False

    @property
    def flagged(self) -> bool:
        """Whether the result is short of what was asked: stopped early, interrupted, or not fused."""
        return self.error is not None or self.interrupted

    @property
    def trajectory(self) -> Trajectory:
        """base_link in odom at every frame that was not skipped (for ``fused``, the EKF's path)."""
        return self.fused if self.fused is not None else self.floor_trajectory

    @property
    def floor_trajectory(self) -> Trajectory:
        """The floor odometry's own path of base_link in odom, at every frame that was not skipped."""
        kept = [r for r in self.records if r.status is not Status.SKIPPED]
        poses = np.array([r.pose for r in kept]).reshape(-1, 3)
        stamps = np.array([r.stamp_ns for r in kept], dtype=np.int64)
        return Trajectory.from_planar(stamps, poses[:, 0], poses[:, 1], poses[:, 2], frame_id="odom")

    @property
    def frames_per_second(self) -> float:
        return len(self.records) / self.seconds if self.seconds > 0 else math.nan

    @property
    def floor_run(self) -> FloorRun:
        """The floor odometry as the EKF reads it (``gpo.fusion.fuse``): its path, each step's inliers and spread."""
        kept = [r for r in self.records if r.status is not Status.SKIPPED]
        inliers = np.array([r.inliers if r.status is Status.MEASURED else 0 for r in kept])
        spread = np.array([r.spread_px for r in kept])
        return FloorRun(self.floor_trajectory, inliers, self.frames_per_second, spread)

    def summary(self) -> dict:
        """Plain numbers for people and files: distance, frames by status, flags by reason, speed, and (when any)
        the frames whose flow held a slower layer (``gpo.flow``: reflections on a glossy floor)."""
        statuses = Counter(r.status for r in self.records)
        slower = sum(slower_layer(r.slower, r.kept) for r in self.records)
        reasons = Counter(_reason(r.flag) for r in self.records if r.flag)
        unreadable = [f"{r.stamp_ns}: {r.flag}" for r in self.records if r.flag and r.flag.startswith("unreadable")]
        trajectory = self.trajectory
        return {
            "source": self.source,
            "topic": self.topic,
            "method": str(self.config.method),
            "vector": self.config.vector,
            "frames": len(self.records),
            **{f"frames_{status}": statuses.get(status, 0) for status in Status if status is not Status.FIRST},
            "flags": dict(reasons.most_common()),
            **({"frames_slower_layer": slower} if slower else {}),
            "distance_m": round(trajectory.path_length, 4),
            "duration_s": round(float(np.ptp(trajectory.times)), 3) if len(trajectory) else 0.0,
            "frames_per_second": round(self.frames_per_second, 1),
            "stopped_early": self.error,
            **({"unreadable": unreadable} if unreadable else {}),
            **({"interrupted": True} if self.interrupted else {}),
            **({"fusion": self.fusion} if self.fusion is not None else {}),
        }

    def write(self, tum_path) -> tuple[Path, Path]:
        """Write the trajectory as TUM and the summary as YAML beside it (``summary_path``), each through a
        temporary name (``gpo.outputs``); return both paths."""
        tum_path = Path(tum_path)
        summary_path = write_text(summary_path_of(tum_path), yaml.safe_dump(self.summary(), sort_keys=False))
        return write_with(tum_path, self.trajectory.write_tum), summary_path


def summary_path_of(tum_path) -> Path:
    """Where ``OdometryResult.write`` puts the summary of the TUM file ``tum_path``: ``.summary.yaml`` beside it."""
    return Path(tum_path).with_suffix(".summary.yaml")


def _reason(flag: str) -> str:
    """A flag's kind, without its numbers: the text before the first colon."""
    return flag.split(":")[0].split("(")[0].strip()


def run(bag, config: OdometryConfig | None = None, topic: str | None = None, progress: bool = True) -> OdometryResult:
    """Odometry of the camera frames of ``bag`` (``topic``: default the rig's image topic when the bag has it,
    else its only image topic). The topic, and for ``fused`` the tracking camera's odometry and mount, are checked
    before the first frame. Returns what was computed even when reading stops early, is interrupted (Ctrl-C) or
    the fusion fails: then ``error`` or ``interrupted`` say so (nothing is raised, so that the partial result, or
    the floor odometry alone, can be written). Unreadable frames are skipped and flagged."""
    config = config or load_config()
    with Recording(bag) as recording, warnings.catch_warnings():
        warnings.simplefilter("ignore", StampWarning)  # each such frame is flagged in its record instead
        topic = _choose_topic(recording, topic, config.rig)
        if config.method is Method.FUSED:  # the tracking camera's topic, odometry and mount, before any frame
            _check_tracking_topic(recording, config.fusion)
            tracking = tracking_path(recording, config.fusion)
            _, note = tracking_mount(recording, config.fusion)
        started = time.perf_counter()
        frames = (
            (frame.stamp_ns, frame.image if frame.problem is None else Unreadable(frame.problem))
            for frame in recording.frames(topic, gray=True, progress=progress, flag_unreadable=True)
        )
        try:
            result = odometry(frames, config, str(bag), topic)
        except ValueError as error:
            raise ValueError(f"{bag}, topic {topic}: {error}") from None
        if config.method is Method.FUSED and not result.interrupted:
            _fuse_into(result, tracking, config.fusion, note)
            result.seconds = time.perf_counter() - started
    return result


def _fuse_into(result: OdometryResult, tracking: Trajectory, settings: FusionSettings, note: str | None) -> None:
    """Add the EKF's path from the floor odometry of ``result`` and the tracking camera's path of base_link
    (``tracking_path``) to ``result``; when the tracking stream cannot be fused, say why in ``result.error`` and
    leave the floor odometry as the result."""
    floor = result.floor_run
    mount = "config (fusion.tracking_mount)" if note == "config" else "/tf_static"
    result.fusion = {"mount": mount, **({"note": note} if note not in (None, "config") else {})}
    try:
        fused = fuse(floor.trajectory, floor.inliers, tracking, settings, floor.spread_px)
    except (ValueError, FilterDiverged) as failure:
        reason = f"fusion failed, the floor odometry is the result: {failure}"
        result.error = reason if result.error is None else f"{result.error}; {reason}"
        return
    result.fused = fused.trajectory
    result.fusion.update(refused_by_nis_gate=fused.refused, dropped=fused.dropped)


def odometry(frames, config: OdometryConfig, source: str = "frames", topic: str = "") -> OdometryResult:
    """Floor odometry of ``frames``: (stamp_ns, image) pairs in stamp order, each image a grey camera frame or, for
    the ``features`` method, its ``FloorOdometer.keypoints``, so that runs differing only in the matching and the
    filters can share one detection. For ``fused`` the floor method's odometry (``run`` adds the filter). Stops at
    the first frame that cannot be read (an error of reading ``frames``) and says why in ``error``, and at Ctrl-C
    (KeyboardInterrupt), keeping the frames before and marking the result ``interrupted``."""
    fused = config.method is Method.FUSED
    odometer = FloorOdometer(config.replace(method=config.fusion.floor_method) if fused else config)
    records: list[FrameRecord] = []
    started = time.perf_counter()
    error, interrupted = None, False
    try:
        for stamp_ns, image in frames:
            records.append(odometer.step(stamp_ns, image))
    except (ValueError, KeyError, OSError) as failure:
        if not records:
            raise
        error = f"after {len(records)} frames: {failure}"
    except KeyboardInterrupt:
        interrupted = True
    if records and all(r.flag and r.flag.startswith("unreadable") for r in records):
        raise ValueError(f"none of the {len(records)} frames could be read; the first: {records[0].flag}")
    seconds = time.perf_counter() - started
    return OdometryResult(records, seconds, config, source, topic, error, interrupted=interrupted)


def tracking_path(recording: Recording, settings: FusionSettings) -> Trajectory:
    """The recording's tracking-camera odometry as the path of base_link in odom (the origin at its first pose)."""
    try:
        odometry = recording.trajectory(settings.tracking_topic)
    except ValueError as error:
        topic = settings.tracking_topic
        raise ValueError(f"the tracking camera's odometry on {topic} cannot be read: {error}") from None
    mount, _ = tracking_mount(recording, settings)
    return base_from_sensor_odometry(odometry, mount, (Rotation.identity(), np.zeros(3)))


MOUNT_TOLERANCE = (1e-3, 0.1)  # metres, degrees: a configured mount further than this from /tf_static's is reported


def tracking_mount(recording: Recording, settings: FusionSettings) -> tuple[tuple[Rotation, np.ndarray], str | None]:
    """The tracking camera's pose frame in base_link (rotation, translation m) and where it came from: /tf_static's
    base_link -> ``tracking_frame`` when the bag has it (then None, or a sentence when ``fusion.tracking_mount``
    disagrees by more than ``MOUNT_TOLERANCE``), else ``fusion.tracking_mount`` (then "config"). Neither: a
    ValueError naming both ways."""
    configured = settings.tracking_mount
    try:
        translation, quaternion = recording.static_transform("base_link", settings.tracking_frame)
    except ValueError as missing:
        if configured is None:
            raise ValueError(
                f"{missing}. The tracking camera's mount is needed one of two ways: a /tf_static transform "
                f"base_link -> {settings.tracking_frame} in the bag, or fusion: tracking_mount: "
                f"{{position_m: [x, y, z], rpy_deg: [roll, pitch, yaw]}} in the config (its pose frame, x forward, "
                "y left, z up, in base_link)"
            ) from None
        return _configured_mount(configured), "config"
    static = (Rotation.from_quat(quaternion), np.asarray(translation, dtype=float))
    if configured is None:
        return static, None
    rotation, position = _configured_mount(configured)
    moved = float(np.linalg.norm(position - static[1]))
    turned = float(np.degrees((rotation.inv() * static[0]).magnitude()))
    if moved > MOUNT_TOLERANCE[0] or turned > MOUNT_TOLERANCE[1]:
        return static, (
            f"fusion.tracking_mount is {1e3 * moved:.1f} mm and {turned:.2f} deg from /tf_static's base_link -> "
            f"{settings.tracking_frame}; /tf_static's is used"
        )
    return static, None


def _configured_mount(mount: TrackingMount) -> tuple[Rotation, np.ndarray]:
    return Rotation.from_euler("xyz", mount.rpy_deg, degrees=True), np.array(mount.position_m)


def _check_tracking_topic(recording: Recording, settings: FusionSettings) -> None:
    topics = {t.name: t for t in recording.topics()}
    if settings.tracking_topic not in topics:
        raise ValueError(
            f"{recording.path}: no topic {settings.tracking_topic} for the tracking camera's odometry "
            f"(fusion.tracking_topic); the bag has {', '.join(sorted(topics))}"
        )


def _choose_topic(recording: Recording, topic: str | None, rig: Rig) -> str:
    if topic is not None:
        return recording.image_topic(topic)
    if rig.image_topic in {t.name for t in recording.topics()}:
        return recording.image_topic(rig.image_topic)
    return recording.image_topic()
