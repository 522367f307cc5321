"""A recording in, a trajectory out: ``run(bag, config)``.

``run`` streams a recording's camera frames through the config's ``FloorOdometer`` (``gpo.pipeline.odometer``: the
floor image's one remap table, the floor's motion, the config's floor estimator of ``gpo.odometry.estimators``) and
integrates the pose of ``base_link`` in ``odom`` (the pose at the first frame is the origin). With the method
``fused``, the floor odometry of ``fusion.floor_method`` and the tracking camera's own odometry from the same bag are
fused by the EKF of ``gpo.fusion``.

Every frame gets a ``FrameRecord``. A frame that cannot be measured is flagged with the reason and the robot
**coasts** across it at the last measured velocity, for at most ``max_gap_s``; beyond that it is held still.
Frames whose stamp repeats or goes backwards are skipped; a gap longer than ``max_gap_s`` between frames is
flagged, the pose held across it and tracking restarted after it. A frame that cannot be read (a corrupt JPEG, a
short buffer, another size) is skipped and flagged with the reason, and the frames after it are read. ``run``
returns what it computed when reading stops early, at Ctrl-C, or when the fusion fails (the result says which; a
``fused`` run interrupted is the floor odometry alone, its summary's ``fusion`` says it was not fused).
"""

from __future__ import annotations

import contextlib
import math
import time
import warnings
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
import yaml
from scipy.spatial.transform import Rotation

from gpo.cameras.rig import Rig
from gpo.fusion import FilterDiverged, FusionSettings, fuse
from gpo.io.ahead import read_ahead
from gpo.io.bag import Recording, StampWarning
from gpo.io.outputs import write_together
from gpo.io.trajectory import Trajectory, base_from_sensor_odometry
from gpo.motion.layers import slower_layer
from gpo.pipeline.config import FUSED, OdometryConfig, load_config
from gpo.pipeline.odometer import FloorOdometer, FrameRecord, Status, Unreadable


@dataclass(frozen=True)
class FloorRun:
    """A floor run's path of base_link in odom (``trajectory``) at every frame not skipped, the flow's inlier tracks
    behind each of its steps (``inliers``: 0 where the step was coasted, held or first), the run's frames per second,
    and the inliers' spread behind each step (``spread_px``, pixels: NaN where unknown, infinite where the step is in
    doubt, ``FrameRecord.fused_spread_px``; None when not kept)."""

    trajectory: Trajectory
    inliers: np.ndarray
    frames_per_second: float
    spread_px: np.ndarray | None = None


MEASURED_SHARE = 0.5  # a run that measured fewer than this share of its steps is a flagged result
CAUTION_SHARE = 0.1  # a doubtful cause behind at least this share of a run's steps is named (``cautions``)


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
        """Whether the result is short of what was asked: stopped early, interrupted, not fused, or mostly not
        measured (``shortfall``)."""
        return self.error is not None or self.interrupted or self.shortfall is not None

    @property
    def shortfall(self) -> str | None:
        """Why a run that read every frame is still a flagged result: it measured fewer than ``MEASURED_SHARE`` of
        its steps (the rest coasted, held or skipped: no texture, a black floor, the wrong topic), or None."""
        steps = len(self.records) - 1
        measured = sum(r.status is Status.MEASURED for r in self.records)
        if steps > 0 and measured < MEASURED_SHARE * steps:
            return f"measured {measured} of {steps} steps between frames"
        return None

    @property
    def cautions(self) -> list[str]:
        """The measured causes that make a finished run doubtful, each behind at least ``CAUTION_SHARE`` of its steps:
        steps not measured (coasted, held or skipped; by their most common reason), measured steps whose flow held a
        second, slower layer of motion (``gpo.motion.layers``: a glossy floor's reflections, which pull the floor's
        motion short), and for ``fused`` the increments the filter's NIS gate refused (the floor and the tracking
        camera disagreeing beyond their noise), and measured steps the whole-view check took over
        (``gpo.motion.overview``). Empty when nothing reaches it."""
        steps = len(self.records) - 1
        if steps <= 0:
            return []
        found = []
        measured = [r for r in self.records if r.status is Status.MEASURED]
        missed = steps - len(measured)
        if missed >= CAUTION_SHARE * steps:
            reasons = Counter(_reason(r.flag) for r in self.records if r.flag)
            why = f": mostly {reasons.most_common(1)[0][0]}" if reasons else ""
            found.append(f"{missed} of {steps} steps not measured{why}")
        overview = sum(r.overview for r in measured)
        if overview >= CAUTION_SHARE * steps:
            found.append(
                f"{overview} of {steps} steps measured on the whole view, the tracks disagreeing with it "
                "(a glossy floor's reflections?)"
            )
        slower = sum(slower_layer(r.slower, r.kept) for r in measured)
        if slower >= CAUTION_SHARE * steps:
            layer = "a second, slower layer of motion (a glossy floor's reflections)"
            found.append(f"{slower} of {steps} steps held {layer}")
        refused = (self.fusion or {}).get("refused_by_nis_gate", 0)
        if refused >= CAUTION_SHARE * steps:
            found.append(
                f"the filter refused {refused} increments in {steps} steps: the floor and the tracking camera "
                "disagree beyond their noise"
            )
        return found

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
        inliers = np.array([r.fused_inliers for r in kept])
        spread = np.array([r.fused_spread_px for r in kept])
        return FloorRun(self.floor_trajectory, inliers, self.frames_per_second, spread)

    def summary(self) -> dict:
        """Plain numbers for people and files: distance, frames by status, flags by reason, speed, and (when any)
        the frames whose flow held a slower layer (``gpo.motion.klt``: reflections on a glossy floor), those the
        whole-view check measured (``gpo.motion.overview``) and the run's ``cautions``."""
        statuses = Counter(r.status for r in self.records)
        slower = sum(slower_layer(r.slower, r.kept) for r in self.records)
        overview = sum(r.overview for r in self.records)
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
            **({"frames_overview": overview} if overview else {}),
            "distance_m": round(trajectory.path_length, 4),
            "duration_s": round(float(np.ptp(trajectory.times)), 3) if len(trajectory) else 0.0,
            "frames_per_second": round(self.frames_per_second, 1),
            "stopped_early": self.error,
            **({"flagged": self.shortfall} if self.shortfall else {}),
            **({"cautions": self.cautions} if self.cautions else {}),
            **({"unreadable": unreadable} if unreadable else {}),
            **({"interrupted": True} if self.interrupted else {}),
            **({"fusion": self.fusion} if self.fusion is not None else {}),
        }

    def files(self, tum_path) -> dict[Path, Callable[[Path], object]]:
        """The run's files by path, each with what writes it at a temporary path (``gpo.io.outputs.write_together``):
        the trajectory as TUM at ``tum_path`` and the summary as YAML beside it (``summary_path_of``)."""
        summary = yaml.safe_dump(self.summary(), sort_keys=False)
        return {
            Path(tum_path): self.trajectory.write_tum,
            summary_path_of(tum_path): lambda temporary: temporary.write_text(summary),
        }

    def write(self, tum_path) -> tuple[Path, Path]:
        """Write the trajectory and its summary (``files``) as one set: both replace the files there, or neither
        (``gpo.io.outputs.write_together``); return both paths."""
        trajectory, summary = write_together(self.files(tum_path))
        return trajectory, summary


def summary_path_of(tum_path) -> Path:
    """Where ``OdometryResult.write`` puts the summary of the TUM file ``tum_path``: ``.summary.yaml`` beside it."""
    return Path(tum_path).with_suffix(".summary.yaml")


def _reason(flag: str) -> str:
    """A flag's kind, without its numbers: the text before the first colon."""
    return flag.split(":")[0].split("(")[0].strip()


def run(
    bag,
    config: OdometryConfig | None = None,
    topic: str | None = None,
    progress: bool = True,
    threads: int | None = None,
) -> OdometryResult:
    """Odometry of the camera frames of ``bag`` (``topic``: default the rig's image topic when the bag has it,
    else its only image topic) on ``threads`` threads (``odometry``). The topic, and for ``fused`` the tracking
    camera's odometry and mount, are checked before the first frame. Returns what was computed even when reading
    stops early, is interrupted (Ctrl-C) or the fusion fails: then ``error`` or ``interrupted`` say so (nothing is
    raised, so that the partial result, or the floor odometry alone, can be written; a ``fused`` run interrupted is
    not fused, and ``fusion["not_fused"]`` says so). Unreadable frames are skipped and flagged."""
    config = config or load_config()
    with Recording(bag) as recording, warnings.catch_warnings():
        warnings.simplefilter("ignore", StampWarning)  # each such frame is flagged in its record instead
        topic = _choose_topic(recording, topic, config.rig)
        if config.method == FUSED:  # the tracking camera's topic, odometry and mount, before any frame
            _check_tracking_topic(recording, config.fusion)
            tracking = tracking_path(recording, config.fusion)
            _, note = tracking_mount(recording, config.fusion)
        started = time.perf_counter()
        frames = (
            (frame.stamp_ns, frame.image if frame.problem is None else Unreadable(frame.problem))
            for frame in recording.frames(topic, gray=True, progress=progress, flag_unreadable=True)
        )
        try:
            result = odometry(frames, config, str(bag), topic, threads)
        except ValueError as error:
            raise ValueError(f"{bag}, topic {topic}: {error}") from None
        if config.method == FUSED and result.interrupted:
            result.fusion = {
                "not_fused": f"interrupted before the fusion: the trajectory is the floor odometry of "
                f"{config.fusion.floor_method} alone, without the tracking camera"
            }
        elif config.method == FUSED:
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


def odometry(
    frames, config: OdometryConfig, source: str = "frames", topic: str = "", threads: int | None = None
) -> OdometryResult:
    """Floor odometry of ``frames``: (stamp_ns, image) pairs in stamp order, each image a grey camera frame or what
    ``FloorOdometer.prepare`` makes of it (for the ``features`` method its keypoints, so that runs differing only in
    the matching and the filters can share one detection). For ``fused`` the floor method's odometry (``run`` adds
    the filter). Stops at the first frame that cannot be read (an error of reading ``frames``) and says why in
    ``error``, and at Ctrl-C (KeyboardInterrupt), keeping the frames before and marking the result ``interrupted``.

    ``threads``: None works in the calling thread and leaves OpenCV's threads as they are. A number sets OpenCV's
    threads to it for the run; from 2 on, a second thread also reads and prepares the next frames while the odometer
    tracks the current one (``gpo.io.ahead``). The records are the same whatever the threads."""
    fused = config.method == FUSED
    odometer = FloorOdometer(config.replace(method=config.fusion.floor_method) if fused else config)
    ahead = None
    if threads is not None and threads >= 2:
        frames = ahead = read_ahead((stamp_ns, odometer.prepare(image)) for stamp_ns, image in frames)
    records: list[FrameRecord] = []
    started = time.perf_counter()
    error, interrupted = None, False
    try:
        with opencv_threads(threads):
            for stamp_ns, image in frames:
                records.append(odometer.step(stamp_ns, image))
    except (ValueError, KeyError, OSError) as failure:
        if not records:
            raise
        error = f"after {len(records)} frames: {failure}"
    except KeyboardInterrupt:
        interrupted = True
    finally:
        if ahead is not None:
            ahead.close()  # stops the reading thread
    if records and all(r.flag and r.flag.startswith("unreadable") for r in records):
        raise ValueError(f"none of the {len(records)} frames could be read; the first: {records[0].flag}")
    seconds = time.perf_counter() - started
    return OdometryResult(records, seconds, config, source, topic, error, interrupted=interrupted)


@contextlib.contextmanager
def opencv_threads(threads: int | None):
    """OpenCV's threads set to ``threads`` inside the block (None: left as they are), then set back."""
    if threads is None:
        yield
        return
    if threads < 1:
        raise ValueError(f"threads must be 1 or more, got {threads}")
    before = cv2.getNumThreads()
    cv2.setNumThreads(threads)
    try:
        yield
    finally:
        cv2.setNumThreads(before)


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
        return configured.transform, "config"
    static = (Rotation.from_quat(quaternion), np.asarray(translation, dtype=float))
    if configured is None:
        return static, None
    rotation, position = configured.transform
    moved = float(np.linalg.norm(position - static[1]))
    turned = float(np.degrees((rotation.inv() * static[0]).magnitude()))
    if moved > MOUNT_TOLERANCE[0] or turned > MOUNT_TOLERANCE[1]:
        return static, (
            f"fusion.tracking_mount is {1e3 * moved:.1f} mm and {turned:.2f} deg from /tf_static's base_link -> "
            f"{settings.tracking_frame}; /tf_static's is used"
        )
    return static, None


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
