"""A run config's odometry as a robot's node or a notebook runs it: messages in as they arrive, poses out.

    odometer = LiveOdometer(load_config("robot.yaml"), on_fused=publish)
    record = odometer.step(stamp_ns, image)         # each camera frame: the floor odometry's pose, now
    odometer.track(stamp_ns, position, orientation)  # with ``fused``, each tracking camera message

``step`` runs the config's ``FloorOdometer`` on the frame and returns its ``FrameRecord``. With the method ``fused``
the floor odometry of ``fusion.floor_method`` and the tracking camera's own odometry go through the same
``gpo.fusion.StreamingFusion`` that ``gpo.pipeline.run`` uses on a recording, so a live run and a recorded one give
the same fused path. A frame's fused pose is settled once the tracking camera has a message after it (at 200 Hz,
within 5 ms): each settled ``FusedPose`` goes to ``on_fused`` as it comes, and ``latest`` holds the newest. Nothing
grows with the run's length.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy.spatial.transform import Rotation

from gpo.fusion import FusedPose, StreamingFusion
from gpo.io.trajectory import Trajectory, base_from_sensor_odometry
from gpo.motion.keypoints import Keypoints
from gpo.motion.klt import FlowFrame
from gpo.pipeline.config import FUSED, OdometryConfig
from gpo.pipeline.odometer import FloorOdometer, FrameRecord, Status, Unreadable


class LiveOdometer:
    """The odometry of ``config``, one message at a time.

    ``tracking_mount``: for ``fused``, the tracking camera's pose frame in base_link (rotation, translation in metres,
    as a bag's /tf_static gives it); default the config's ``fusion.tracking_mount``. Without either, a ValueError.
    ``on_fused``: called with each ``FusedPose`` as it is settled, in the frames' order.
    """

    def __init__(
        self,
        config: OdometryConfig,
        tracking_mount: tuple[Rotation, np.ndarray] | None = None,
        on_fused: Callable[[FusedPose], object] | None = None,
    ):
        self.config = config
        fused = config.method == FUSED
        self.floor = FloorOdometer(config.replace(method=config.fusion.floor_method) if fused else config)
        self.fusion = StreamingFusion(config.fusion) if fused else None
        self.latest: FusedPose | None = None
        self._on_fused = on_fused
        if fused and tracking_mount is None:
            if config.fusion.tracking_mount is None:
                raise ValueError(
                    "the fused method needs the tracking camera's mount: give tracking_mount (rotation, translation of "
                    "its pose frame in base_link), or fusion: tracking_mount: {position_m: [x, y, z], rpy_deg: [roll, "
                    "pitch, yaw]} in the config"
                )
            tracking_mount = config.fusion.tracking_mount.transform
        self._mount = tracking_mount

    def step(self, stamp_ns: int, image: np.ndarray | FlowFrame | Keypoints | Unreadable) -> FrameRecord:
        """One camera frame (H, W) in stamp order, or what ``FloorOdometer.prepare`` made of it: the floor odometry's
        record. With ``fused``, the frames this settles go to ``on_fused``."""
        record = self.floor.step(stamp_ns, image)
        if self.fusion is not None and record.status is not Status.SKIPPED:
            self._keep(self.fusion.add_floor(stamp_ns * 1e-9, record.pose, record.fused_inliers,
                                             record.fused_spread_px))
        return record

    def track(self, stamp_ns: int, position, orientation) -> None:
        """One message of the tracking camera's odometry (``fused`` only): its pose frame's ``position`` (x, y, z m)
        and ``orientation`` (quaternion x, y, z, w) in its odometry frame at header stamp ``stamp_ns``. The floor
        frames it settles (usually none or one) go to ``on_fused``."""
        if self.fusion is None:
            raise ValueError(f"the fused method fuses tracking messages; this odometer's is {self.config.method}")
        base = base_from_sensor_odometry(
            Trajectory(np.array([stamp_ns]), np.array([position], dtype=float), np.array([orientation], dtype=float)),
            self._mount,
            (Rotation.identity(), np.zeros(3)),
        )
        self._keep(self.fusion.add_tracking(stamp_ns * 1e-9, (*base.positions[0, :2], base.yaw[0])))

    def finish(self) -> None:
        """At the end of a stream: the frames still waiting for a tracking message after them are settled with the
        messages so far, and go to ``on_fused``."""
        if self.fusion is not None:
            self._keep(self.fusion.finish())

    def _keep(self, settled: list[FusedPose]) -> None:
        for pose in settled:
            self.latest = pose
            if self._on_fused is not None:
                self._on_fused(pose)
