"""A run config's odometry as a robot's node or a notebook runs it: messages in as they arrive, poses out.

    odometer = LiveOdometer(load_config("robot.yaml"), on_fused=publish)
    record = odometer.step(stamp_ns, image)         # each camera frame: the floor odometry's pose, now
    odometer.track(stamp_ns, position, orientation)  # with ``fused``, each tracking camera message

``step`` runs the config's ``FloorOdometer`` on the frame and returns its ``FrameRecord``. With the method ``fused``
the floor odometry of ``fusion.floor_method`` and the tracking camera's own odometry go through the same
``gpo.fusion.StreamingFusion`` that ``gpo.pipeline.run`` uses on a recording, so a live run and a recorded one give
the same fused path. The floor feature odometer following its keypoints between keyframes (``features.follow:
lk``, ``gpo.motion.following``) does so here as on a recording: a frame costs a Lucas-Kanade search, a keyframe a
detection. A frame's fused pose is settled once the tracking camera has a message after it (at 200 Hz,
within 5 ms): each settled ``FusedPose`` goes to ``on_fused`` as it comes, and ``latest`` holds the newest. Nothing
grows with the run's length.

Every public method checks its arguments before it changes anything, and refuses what it cannot take with
``RefusedMessage``, naming the argument, what was expected and what it got; the odometer is then exactly as it was
before the call, and the stream goes on with the next message.
"""

from __future__ import annotations

import numbers
from collections.abc import Callable

import numpy as np
from scipy.spatial.transform import Rotation

from gpo.fusion import FusedPose, StreamingFusion
from gpo.io.trajectory import NS_PER_S, Trajectory, base_from_sensor_odometry
from gpo.motion.following import FollowFrame
from gpo.motion.keypoints import Keypoints
from gpo.motion.klt import FlowFrame
from gpo.pipeline.config import FUSED, OdometryConfig
from gpo.pipeline.odometer import FloorOdometer, FrameRecord, Status, Unreadable

MAX_STAMP_STEP_NS = 86_400 * NS_PER_S
"""A message stamped more than a day from the last one (either way) is refused: a clock gone wrong, not a stream."""
LATEST_NS = 2**63 - 1
"""The last nanosecond a stamp may name (int64, as a bag's)."""


class RefusedMessage(ValueError):
    """An argument ``LiveOdometer`` refused: the message names it, what was expected and what it got. The odometer is
    as it was before the call."""


class LiveOdometer:
    """The odometry of ``config``, one message at a time.

    ``tracking_mount``: for ``fused``, the tracking camera's pose frame in base_link (rotation, translation in metres,
    as a bag's /tf_static gives it); default the config's ``fusion.tracking_mount``. Without either, a
    ``RefusedMessage``. ``on_fused``: called with each ``FusedPose`` as it is settled, in the frames' order.
    """

    def __init__(
        self,
        config: OdometryConfig,
        tracking_mount: tuple[Rotation, np.ndarray] | None = None,
        on_fused: Callable[[FusedPose], object] | None = None,
    ):
        if not isinstance(config, OdometryConfig):
            raise RefusedMessage(
                f"config: expected an OdometryConfig (gpo.pipeline.config.load_config), got {type(config).__name__}"
            )
        if on_fused is not None and not callable(on_fused):
            raise RefusedMessage(f"on_fused: expected a callable or None, got {type(on_fused).__name__}")
        fused = config.method == FUSED
        if fused and tracking_mount is None:
            if config.fusion.tracking_mount is None:
                raise RefusedMessage(
                    "tracking_mount: the fused method needs the tracking camera's mount: give tracking_mount "
                    "(rotation, translation of its pose frame in base_link), or fusion: tracking_mount: {position_m: "
                    "[x, y, z], rpy_deg: [roll, pitch, yaw]} in the config"
                )
            tracking_mount = config.fusion.tracking_mount.transform
        self._mount = None if tracking_mount is None else _mount(tracking_mount)
        self.config = config
        self.floor = FloorOdometer(config.replace(method=config.fusion.floor_method) if fused else config)
        self.fusion = StreamingFusion(config.fusion) if fused else None
        self.latest: FusedPose | None = None
        self._on_fused = on_fused
        self._last_ns: int | None = None  # the stamp of the last message taken, of either stream

    def step(self, stamp_ns: int, image: np.ndarray | FlowFrame | Keypoints | FollowFrame | Unreadable) -> FrameRecord:
        """One camera frame in stamp order: ``stamp_ns`` its header stamp (whole nanoseconds), ``image`` the grey
        frame (H, W) of the calibration's size, 8-bit (16-bit is read as its upper 8 bits), or what
        ``FloorOdometer.prepare`` made of it (``FloorOdometer.refusal`` says what is taken); the floor odometry's
        record. A frame stamped at or before the last one is skipped (its record says so). With ``fused``, the frames
        this settles go to ``on_fused``."""
        stamp_ns = self._stamp(stamp_ns)
        problem = self.floor.refusal(image)
        if problem:
            raise RefusedMessage(f"image: {problem}")
        record = self.floor.step(stamp_ns, image)
        self._last_ns = stamp_ns if self._last_ns is None else max(self._last_ns, stamp_ns)
        if self.fusion is not None and record.status is not Status.SKIPPED:
            self._keep(
                self.fusion.add_floor(stamp_ns * 1e-9, record.pose, record.fused_inliers, record.fused_spread_px)
            )
        return record

    def track(self, stamp_ns: int, position, orientation) -> None:
        """One message of the tracking camera's odometry (``fused`` only): its pose frame's ``position`` (x, y, z m)
        and ``orientation`` (quaternion x, y, z, w, of any length but zero) in its odometry frame at header stamp
        ``stamp_ns`` (whole nanoseconds). A pose that is not finite is dropped and counted (``fusion.dropped``). The
        floor frames it settles (usually none or one) go to ``on_fused``."""
        if self.fusion is None:
            raise RefusedMessage(f"the fused method fuses tracking messages; this odometer's is {self.config.method}")
        stamp_ns = self._stamp(stamp_ns)
        position = _numbers("position", position, 3, "x, y, z in metres")
        orientation = _numbers("orientation", orientation, 4, "a quaternion x, y, z, w")
        finite = bool(np.isfinite(position).all() and np.isfinite(orientation).all())
        if finite and not np.linalg.norm(orientation) > 0:
            raise RefusedMessage(f"orientation: expected a quaternion x, y, z, w of some length, got {orientation}")
        pose = np.full(3, np.nan)  # not finite: the filter drops and counts it
        if finite:
            base = base_from_sensor_odometry(
                Trajectory(np.array([stamp_ns]), position[None], orientation[None]),
                self._mount,
                (Rotation.identity(), np.zeros(3)),
            )
            pose = np.array([*base.positions[0, :2], base.yaw[0]])
        self._last_ns = stamp_ns if self._last_ns is None else max(self._last_ns, stamp_ns)
        self._keep(self.fusion.add_tracking(stamp_ns * 1e-9, pose))

    def finish(self) -> None:
        """At the end of a stream: the frames still waiting for a tracking message after them are settled with the
        messages so far, and go to ``on_fused``."""
        if self.fusion is not None:
            self._keep(self.fusion.finish())

    def _stamp(self, value) -> int:
        """``value`` as a stamp: whole nanoseconds from 0 to ``LATEST_NS``, within ``MAX_STAMP_STEP_NS`` of the last
        message taken; else a RefusedMessage."""
        whole = isinstance(value, numbers.Integral) or (isinstance(value, numbers.Real) and float(value).is_integer())
        if isinstance(value, bool) or not whole:
            raise RefusedMessage(f"stamp_ns: expected a whole number of nanoseconds, got {value!r}")
        if not 0 <= value <= LATEST_NS:
            raise RefusedMessage(f"stamp_ns: expected nanoseconds from 0 to {LATEST_NS} (int64), got {value!r}")
        stamp = int(value)
        if self._last_ns is not None and abs(stamp - self._last_ns) > MAX_STAMP_STEP_NS:
            raise RefusedMessage(
                f"stamp_ns: {stamp} is more than a day from the last message's, {self._last_ns}: a stamp within a "
                "day after the last message (a new stream needs a new LiveOdometer)"
            )
        return stamp

    def _keep(self, settled: list[FusedPose]) -> None:
        for pose in settled:
            self.latest = pose
            if self._on_fused is not None:
                self._on_fused(pose)


def _numbers(name: str, value, count: int, meaning: str) -> np.ndarray:
    """``value`` as ``count`` floats (a sequence of real numbers, no flags, no text); else a RefusedMessage naming
    ``name`` and its ``meaning``."""
    items = list(value) if isinstance(value, list | tuple | np.ndarray) and np.ndim(value) == 1 else None
    if (
        items is None
        or len(items) != count
        or not all(isinstance(item, numbers.Real) and not isinstance(item, bool | np.bool_) for item in items)
    ):
        raise RefusedMessage(f"{name}: expected {count} numbers, {meaning}, got {value!r}")
    return np.array(items, dtype=float)


def _mount(mount) -> tuple[Rotation, np.ndarray]:
    """A tracking camera's mount checked: (a scipy Rotation, 3 finite numbers in metres); else a RefusedMessage."""
    if not (isinstance(mount, tuple | list) and len(mount) == 2 and isinstance(mount[0], Rotation) and mount[0].single):
        raise RefusedMessage(
            f"tracking_mount: expected (rotation, translation): a scipy Rotation and 3 numbers in metres, got {mount!r}"
        )
    translation = _numbers("tracking_mount", mount[1], 3, "the translation x, y, z in metres")
    if not np.isfinite(translation).all():
        raise RefusedMessage(f"tracking_mount: expected a finite translation, got {translation}")
    return mount[0], translation
