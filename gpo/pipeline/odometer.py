"""Frame by frame: a camera frame in, the robot's pose out (``FloorOdometer.step``), each frame's record beside it."""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from enum import StrEnum

import cv2
import numpy as np

from gpo.floor_image.analytic import analytic_table
from gpo.floor_image.gpi import ground_plane_image
from gpo.floor_image.image import GroundImageError, RemapTable
from gpo.floor_image.ortho import ortho_rectify
from gpo.motion.following import FollowFrame, KeypointFollower
from gpo.motion.keyframes import FRAME_TO_FRAME
from gpo.motion.keypoints import FeatureMatches, FeatureTracker, Keypoints, detect
from gpo.motion.klt import FloorFlow, FlowFrame, FlowMeasurement
from gpo.odometry.estimators import FloorGeometry
from gpo.odometry.kinematics import between, compose
from gpo.pipeline.config import OdometryConfig, Route


class Status(StrEnum):
    """What became of a frame: its motion measured, the robot coasted or held across it, the frame skipped, or the
    first frame."""

    MEASURED = "measured"
    COASTED = "coasted"
    HELD = "held"
    SKIPPED = "skipped"
    FIRST = "first"


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


@dataclass(frozen=True)
class Unreadable:
    """A frame that could not be read, in its image's place: ``reason`` says why (``FloorOdometer.step`` skips it)."""

    reason: str


@dataclass(frozen=True)
class OtherSize(Unreadable):
    """A frame whose ``size`` (width, height) is not the calibration's: skipped, or refused when it is the first."""

    size: tuple[int, int] = (0, 0)


@dataclass(frozen=True)
class FrameRecord:
    """One frame: header stamp (ns), base_link's ``pose`` (x, y, theta) in odom after it, the flow's counts
    (tracked, kept, inliers, spread in pixels), ``status`` (measured, coasted, held, skipped, first), the
    ``flag`` saying why when not measured, ``slower``: the kept vectors in a slower layer (``gpo.motion.klt``),
    ``overview``: whether the whole-view check measured the frame (``gpo.motion.overview``), and ``disagreed``:
    whether the tracks and that check disagreed, the frame's motion in doubt (``gpo.motion.klt.FlowQuality``)."""

    stamp_ns: int
    pose: tuple[float, float, float]
    tracked: int
    kept: int
    inliers: int
    spread_px: float
    status: Status
    flag: str | None = None
    slower: int = 0
    overview: bool = False
    disagreed: bool = False

    def __post_init__(self):
        object.__setattr__(self, "status", Status(self.status))  # a status given by its name, as a member

    @property
    def fused_inliers(self) -> int:
        """The inliers the fusion reads for the step into this frame: 0 (not fused) unless it was measured."""
        return self.inliers if self.status is Status.MEASURED else 0

    @property
    def fused_spread_px(self) -> float:
        """The spread the fusion reads for the step into this frame (pixels): infinite where its motion is in doubt
        (``disagreed``: the fusion then does not fuse it, ``gpo.fusion.streaming``), NaN where unknown."""
        return math.inf if self.disagreed else self.spread_px


class FloorOdometer:
    """Frame-by-frame odometry of one config: ``step(stamp_ns, image)`` returns that frame's ``FrameRecord``.

    The floor's motion comes from what the config's estimator reads (``FloorEstimator.MOTION``): the floor image's KLT
    flow (``gpo.motion.klt``) or matched keypoints (``gpo.motion.keypoints``); the estimator
    (``gpo.odometry.estimators``) turns it into the increment since the frame the motion was measured from, composed
    onto that frame's pose. For an estimator that reads ``KEYFRAMES``, that frame is the KLT flow's keyframe (the
    config's ``keyframe`` policy), so that the errors of the frames in between do not add up; else the previous
    frame. The keypoints are matched with their own keyframe (the ``features`` section's ``keyframe`` policy). A
    measurement made from the frame before instead (``from_previous``) is composed onto that frame's pose."""

    def __init__(self, config: OdometryConfig):
        self.config = config
        self.table = floor_table(config)
        keypoints_route = config.route is Route.KEYPOINTS
        geometry = FloorGeometry(None if keypoints_route else config.floor, config.rig.camera, config.rig.mount)
        self.estimator = config.estimator(config, geometry)
        if self.estimator.MOTION == "keypoints":
            self._mask = None if keypoints_route else self.table.valid.astype(np.uint8)
            if config.features.follow == "lk":
                self.motion = KeypointFollower(config.features, config.klt, self._mask)
            else:
                self.motion = FeatureTracker(config.features)
        else:
            policy = config.keyframe if self.estimator.KEYFRAMES else FRAME_TO_FRAME
            self.motion = FloorFlow(config.klt, mask=self.table.valid, keyframe=policy)
        self._overview_table = self._overview(config)
        self.pose = np.zeros(3)
        self._keyframe: tuple[int, np.ndarray] | None = None  # the stamp (ns) and pose the motion is measured from
        self._stamp_ns: int | None = None
        self._measured_ns: int | None = None
        self._velocity = np.zeros(3)  # the last measured increment per second (dx, dy, dtheta)

    def _overview(self, config: OdometryConfig) -> RemapTable | None:
        """The table of the wider view the estimator's flow is checked on (``gpo.motion.overview``), or None: the
        estimator takes no check, the config turns it off, or the wider view lies mostly outside the camera's."""
        if not (self.estimator.MOTION == "tracks" and self.estimator.OVERVIEW and config.klt.overview_scale):
            return None
        try:
            return floor_table(config.replace(floor=config.floor.widened(config.klt.overview_scale)))
        except GroundImageError:
            return None

    def floor_image(self, image: np.ndarray) -> np.ndarray:
        """The floor image (8-bit) of a grey frame (mono8, or mono16 taken to its upper 8 bits; ``Recording.frames``
        with ``gray=True`` turns colour to grey); for the ``keypoints`` route the 8-bit frame itself. A clear error
        when its size is not the calibration's."""
        if image.shape[:2] != self.frame_shape:
            raise ValueError(self._size_error(image.shape[1::-1]))
        if image.dtype == np.uint16:
            image = (image >> 8).astype(np.uint8)
        return image if self.config.route is Route.KEYPOINTS else self.table.apply(image)

    def _size_error(self, size: tuple[int, int]) -> str:
        height, width = self.frame_shape
        return (
            f"the images are {size[0]} x {size[1]} pixels, but the camera of the config's rig "
            f"'{self.config.rig.name}' is {width} x {height}: wrong --topic, or a config of another camera"
        )

    @property
    def frame_shape(self) -> tuple[int, int]:
        """(height, width) of the calibrated camera's frames, pixels."""
        width, height = self.table.source_size
        return height, width

    def refusal(self, image) -> str | None:
        """What makes ``image`` nothing ``step`` takes, in words ("expected ..., got ..."), or None. ``step`` takes a
        grey camera frame, a 2-D uint8 (or uint16: mono16) array of the calibration's size; what ``prepare`` makes of
        one for this odometer's method (a ``FlowFrame`` of the floor image's size for the KLT methods, ``Keypoints``
        for a keypoint method that matches them, a ``FollowFrame`` for one that follows them); or an ``Unreadable``
        frame, which it skips. (``step`` itself skips a frame of another size after the first, as a recording's reader
        flags one.)"""
        height, width = self.frame_shape
        frame = f"a grey camera frame, a 2-D uint8 (or uint16) array of {width} x {height} pixels (width x height)"
        if isinstance(image, Unreadable):
            return None
        if isinstance(image, np.ndarray):
            if image.ndim != 2 or image.dtype not in (np.uint8, np.uint16):
                return f"expected {frame}, got a {image.dtype} array of shape {image.shape}"
            if image.shape != (height, width):
                return f"expected {frame}, got {image.shape[1]} x {image.shape[0]}"
            return None
        kind, prepared = self._prepared_kind
        if isinstance(image, kind):
            return self._prepared_refusal(image)
        return f"expected {frame}, {prepared} (what prepare makes of one) or Unreadable, got {type(image).__name__}"

    @property
    def _prepared_kind(self) -> tuple[type, str]:
        """What ``prepare`` makes of a frame for this odometer's method, and its name in words."""
        if isinstance(self.motion, KeypointFollower):
            return FollowFrame, "a FollowFrame"
        if isinstance(self.motion, FeatureTracker):
            return Keypoints, "Keypoints"
        return FlowFrame, "a FlowFrame"

    def _prepared_refusal(self, prepared: FlowFrame | Keypoints | FollowFrame) -> str | None:
        """What makes ``prepared`` (of this odometer's kind) other than ``prepare`` makes it, or None."""
        if isinstance(prepared, Keypoints):
            counts = {len(prepared.points), len(prepared.descriptors), len(prepared.sizes)}
            if len(counts) == 1 and prepared.points.shape[1:] == (2,):
                return None
            return (
                f"expected Keypoints of as many points (N, 2) as descriptors and sizes, got points of shape "
                f"{prepared.points.shape}, {len(prepared.descriptors)} descriptors, {len(prepared.sizes)} sizes"
            )
        if isinstance(prepared, FollowFrame):
            shape = self.frame_shape if self.config.route is Route.KEYPOINTS else self.table.valid.shape
            if prepared.image.dtype == np.uint8 and prepared.image.shape == shape:
                return None
            got = f"a {prepared.image.dtype} one of shape {prepared.image.shape}"
            return f"expected a FollowFrame of a uint8 image of shape {shape}, got {got}"
        shape = self.table.valid.shape
        wide = None if self._overview_table is None else self._overview_table.valid.shape
        if prepared.image.dtype != np.uint8 or prepared.image.shape != shape:
            got = f"a {prepared.image.dtype} one of shape {prepared.image.shape}"
            return f"expected a FlowFrame of a uint8 floor image of shape {shape}, got {got}"
        if (None if prepared.overview is None else prepared.overview.shape) != wide:
            return f"expected a FlowFrame whose overview (the whole-view check's) is of shape {wide}"
        return None

    def keypoints(self, image: np.ndarray) -> Keypoints:
        """The keypoints of a camera frame as a keypoint estimator's tracker detects them (in the frame itself for the
        ``keypoints`` route, else in its floor image), to be given to ``step`` in the frame's place."""
        if self.estimator.MOTION != "keypoints":
            raise ValueError(f"keypoints are read by a keypoint method, this odometer's method is {self.config.method}")
        return detect(self.floor_image(image), self.config.features, self._mask)

    def prepare(self, image: np.ndarray | Unreadable) -> FlowFrame | Keypoints | FollowFrame | Unreadable:
        """What ``step`` does to a camera frame (H, W) before it tracks it, which depends on the frame alone: its floor
        image made ready for the KLT flow (``FlowFrame``), for a keypoint method that matches keypoints its
        ``keypoints``, for one that follows them the image with its pyramid (``FollowFrame``); a frame of another size
        than the calibration's as ``OtherSize``. Frames can so be prepared ahead, in another thread,
        while the odometer steps through earlier ones (``gpo.pipeline.run.odometry`` with ``threads``)."""
        if not isinstance(image, np.ndarray):
            return image  # unreadable, or prepared already
        if image.shape[:2] != self.frame_shape:
            size = image.shape[1::-1]
            return OtherSize(f"{size[0]} x {size[1]} pixels, not the calibration's", size)
        if isinstance(self.motion, KeypointFollower):
            return self.motion.prepare(self.floor_image(image))
        if self.estimator.MOTION == "keypoints":
            return self.keypoints(image)
        wide = None if self._overview_table is None else functools.partial(self._overview_table.apply, image)
        return self.motion.prepare(self.floor_image(image), wide)  # the wider view made when the check needs it

    def step(self, stamp_ns: int, image: np.ndarray | FlowFrame | Keypoints | FollowFrame | Unreadable) -> FrameRecord:
        """Take one camera frame (H, W) in stamp order, or what ``prepare`` made of it; return its record. A frame that
        cannot be read (``Unreadable``), or after the first one whose size is not the calibration's, is skipped and
        flagged with the reason."""
        previous = self._stamp_ns
        if isinstance(image, np.ndarray):
            image = self.prepare(image)
        if isinstance(image, OtherSize) and previous is None:
            raise ValueError(self._size_error(image.size))
        if isinstance(image, Unreadable):
            return self._record(stamp_ns, None, Status.SKIPPED, f"unreadable frame: {image.reason}")
        if previous is not None and stamp_ns <= previous:
            problem = "repeats" if stamp_ns == previous else f"is {(previous - stamp_ns) * 1e-9:.3f} s before"
            return self._record(stamp_ns, None, Status.SKIPPED, f"stamp out of order: {problem} the previous; skipped")
        self._stamp_ns = stamp_ns
        if previous is None:
            self._track(image, stamp_ns)
            self._measured_ns = stamp_ns
            return self._record(stamp_ns, None, Status.FIRST)
        dt = (stamp_ns - previous) * 1e-9
        if dt > self.config.max_gap_s:
            self.motion.restart()
            self._track(image, stamp_ns)
            self._velocity[:] = 0.0
            return self._record(stamp_ns, None, Status.HELD, f"frame gap: {dt:.2f} s without frames, motion unknown")
        keyframe_ns, keyframe_pose = self._keyframe
        measurement = self._track(image, stamp_ns)
        if measurement.flag is not None:
            return self._coast(stamp_ns, dt, measurement, measurement.flag)
        if measurement.from_previous:  # measured from the frame before, not from the keyframe
            keyframe_ns, keyframe_pose = previous, self.pose
        increment, why = self.estimator.increment(measurement, (stamp_ns - keyframe_ns) * 1e-9)
        if increment is None:
            return self._coast(stamp_ns, dt, measurement, why)
        pose = compose(keyframe_pose, increment)
        step = increment if keyframe_ns == previous else between(self.pose, pose)
        self.pose, self._velocity = pose, step / dt
        self._measured_ns = stamp_ns
        return self._record(stamp_ns, measurement, Status.MEASURED)

    def _track(
        self, floor: FlowFrame | Keypoints | FollowFrame, stamp_ns: int
    ) -> FlowMeasurement | FeatureMatches | None:
        if isinstance(self.motion, FeatureTracker):
            return self.motion.follow(floor)
        if isinstance(floor, Keypoints):
            raise ValueError(f"the {self.config.method} method needs camera frames, not keypoints")
        return self.motion.track(floor, stamp_ns * 1e-9)

    def _coast(self, stamp_ns: int, dt: float, measurement, why: str) -> FrameRecord:
        if (stamp_ns - self._measured_ns) * 1e-9 <= self.config.max_gap_s:
            self.pose = compose(self.pose, self._velocity * dt)
            return self._record(stamp_ns, measurement, Status.COASTED, why)
        return self._record(stamp_ns, measurement, Status.HELD, why)

    def _record(self, stamp_ns, measurement, status, flag=None) -> FrameRecord:
        if status is not Status.SKIPPED and self.motion.keyframe_is_latest:  # the next frame is measured from this one
            self._keyframe = (int(stamp_ns), self.pose)  # step replaces the pose array, never changes it in place
        counts = (0, 0, 0, math.nan, 0, False, False) if measurement is None else measurement.counts
        pose = tuple(float(v) for v in self.pose)
        return FrameRecord(int(stamp_ns), pose, *counts[:4], status, flag, *counts[4:])
