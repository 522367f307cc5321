"""Frame by frame: a camera frame in, the robot's pose out (``FloorOdometer.step``), each frame's record beside it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import StrEnum

import cv2
import numpy as np

from gpo.floor_image.analytic import analytic_table, pixels_to_floor
from gpo.floor_image.gpi import ground_plane_image
from gpo.floor_image.image import RemapTable
from gpo.floor_image.ortho import ortho_rectify
from gpo.motion.keypoints import FeatureMatches, FeatureTracker, Keypoints, detect
from gpo.motion.klt import FloorFlow, FlowMeasurement
from gpo.motion.layers import floor_layer
from gpo.odometry.estimators.keypoints import degenerate, refit
from gpo.odometry.kinematics import (
    PaperBicycle,
    compose,
    increment_from_point_motion,
    increment_from_point_pairs,
)
from gpo.pipeline.config import FLOOR_METHODS, Method, OdometryConfig, Route


class Status(StrEnum):
    """What became of a frame: its motion measured, the robot coasted or held across it, the frame skipped, or the
    first frame."""

    MEASURED = "measured"
    COASTED = "coasted"
    HELD = "held"
    SKIPPED = "skipped"
    FIRST = "first"


RANSAC_THRESHOLD_PX = 1.0  # a track fits the rigid motion when it lands this close to where the motion puts it


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
class FrameRecord:
    """One frame: header stamp (ns), base_link's ``pose`` (x, y, theta) in odom after it, the flow's counts
    (tracked, kept, inliers, spread in pixels), ``status`` (measured, coasted, held, skipped, first), the
    ``flag`` saying why when not measured, and ``slower``: the kept vectors in a slower layer (``gpo.motion.klt``)."""

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
    The floor's motion comes from KLT flow (``gpo.motion.klt``) or, for the ``features`` method, from matched keypoints
    (``gpo.motion.keypoints``)."""

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
        a reflection's (``gpo.motion.layers.floor_layer``)."""
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
