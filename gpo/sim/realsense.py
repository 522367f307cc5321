"""Recordings shaped like a realsense-ros T265 bag: what a user with a T265 on a robot records.

realsense-ros (ros1 branch, ``rs_t265.launch``) publishes the fisheye images on ``/camera/fisheye1/image_raw``
with their ``/camera/fisheye1/camera_info`` (the factory calibration, ``distortion_model: equidistant``, i.e.
Kannala-Brandt KB4), the tracking odometry on ``/camera/odom/sample`` (``camera_pose_frame`` in
``camera_odom_frame``) and its static frames on ``/tf_static``: ``camera_pose_frame -> camera_link`` (the same
place), ``camera_link -> camera_fisheye1_frame`` (the left lens, x forward, y left, z up) and
``camera_fisheye1_frame -> camera_fisheye1_optical_frame`` (x right, y down, z forward). The robot adds
``base_link -> camera_pose_frame``, where the T265 sits on it. ``/mocap/base_link`` holds the ground truth.

``RealsenseRig`` is a T265 on a robot: its fisheye lens (``KB4``), where its pose frame sits (``CameraMount``
of the fisheye's optical frame follows from ``FISHEYE1_IN_POSE``). ``RIGS`` holds the shipped T265 rig's place with
a factory-like lens (``t265``) and one the shipped configs do not describe (``t265-high``: higher, pitched further
down, another lens). ``RealsenseRig.setup`` is a ``gpo.sim.record.Setup`` of one of them along a named path of
``gpo.sim.paths``, its frames laid out by ``realsense_static_tree``; ``gpo.sim.record`` renders and caches it like any
setup (``realsense_recording``). What is realsense-ros's here is the names of the topics and frames, the static
tree, and the lens: a ``KB4`` camera, which the bag writer puts in camera_info as ``equidistant``.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from gpo.cameras import KB4
from gpo.cameras.rig import OPTICAL_IN_BODY, CameraMount, Rig
from gpo.sim.drift import T265_DRIFT
from gpo.sim.floors import FloorDesign
from gpo.sim.paths import named_plan
from gpo.sim.record import FLOOR_MARGIN_M, TEXEL_M, Setup, StaticTransform, recording

IMAGE_TOPIC = "/camera/fisheye1/image_raw"
INFO_TOPIC = "/camera/fisheye1/camera_info"
POSE_FRAME = "camera_pose_frame"
LINK_FRAME = "camera_link"
FISHEYE_FRAME = "camera_fisheye1_frame"
OPTICAL_FRAME = "camera_fisheye1_optical_frame"
FISHEYE1_IN_POSE = np.array([0.0, 0.032, 0.0])
"""The left fisheye's centre in the T265's pose frame (x forward, y left, z up), metres: half the 64 mm baseline."""
T265_FACTORY_LIKE = KB4(284.9, 286.1, 425.2, 398.3, -0.0073, 0.0442, -0.0417, 0.0078, 848, 800)
"""A KB4 lens with numbers like a T265's factory calibration of its left fisheye (848 x 800 pixels)."""


@dataclass(frozen=True)
class RealsenseRig:
    """A T265 on a robot: the ``lens``, its pose frame at ``position_m`` in base_link turned by ``rpy_deg`` (roll,
    pitch, yaw of the body frame, REP-103), 30 frames per second."""

    name: str
    lens: KB4
    position_m: tuple[float, float, float]
    rpy_deg: tuple[float, float, float]
    rate_hz: float = 30.0

    @property
    def pose_in_base(self) -> tuple[np.ndarray, Rotation]:
        """(position m, rotation base <- camera_pose_frame)."""
        return np.array(self.position_m, dtype=float), Rotation.from_euler("ZYX", np.radians(self.rpy_deg[::-1]))

    def rig(self) -> Rig:
        """The fisheye's ``gpo.cameras.rig.Rig``: its optical frame's mount in base_link, the realsense-ros names."""
        position, rotation = self.pose_in_base
        mount = CameraMount(position + rotation.apply(FISHEYE1_IN_POSE), rotation * OPTICAL_IN_BODY)
        return Rig(self.name, self.lens, mount, self.rate_hz, IMAGE_TOPIC, INFO_TOPIC, OPTICAL_FRAME)

    def setup(self, path: str, seed: int) -> Setup:
        """This T265 driving the named ``path`` over a raised floor, its tracking odometry drifting as
        ``T265_DRIFT`` from its pose frame; ``seed`` sets the floor's texture, the sensor's noise and the drift."""
        return Setup(
            self.rig(),
            named_plan(path),
            FloorDesign(("raised",)),
            seed,
            T265_DRIFT,
            TEXEL_M["t265"],
            FLOOR_MARGIN_M["t265"],
            tracking_mount=self.pose_in_base,
            static_tree=realsense_static_tree,
        )


def realsense_static_tree(setup: Setup) -> list[StaticTransform]:
    """realsense-ros's static frames of a T265 at ``setup.tracking_body()``: ``base_link -> camera_pose_frame`` (where
    the robot holds it), ``-> camera_link`` (the same place), ``-> camera_fisheye1_frame`` (the left lens,
    ``FISHEYE1_IN_POSE`` metres; x forward, y left, z up) ``-> camera_fisheye1_optical_frame`` (x right, y down,
    z forward)."""
    position, rotation = setup.tracking_body()
    identity = Rotation.identity().as_quat()
    return [
        StaticTransform("base_link", POSE_FRAME, position, rotation.as_quat()),
        StaticTransform(POSE_FRAME, LINK_FRAME, np.zeros(3), identity),
        StaticTransform(LINK_FRAME, FISHEYE_FRAME, FISHEYE1_IN_POSE, identity),
        StaticTransform(FISHEYE_FRAME, OPTICAL_FRAME, np.zeros(3), OPTICAL_IN_BODY.as_quat()),
    ]


RIGS = {
    "t265": RealsenseRig("t265", T265_FACTORY_LIKE, (0.60, -0.032, 0.12), (1.5, 6.0, 0.0)),
    "t265-high": RealsenseRig(
        "t265-high",
        KB4(281.2, 282.0, 421.7, 403.1, -0.0051, 0.0391, -0.0379, 0.0069, 848, 800),
        (0.45, 0.02, 0.18),
        (-1.0, 10.0, 1.0),
    ),
}


def realsense_recording(
    rig_name: str = "t265", path: str = "test", format: str = "ros1", seed: int = 5, jobs: int = 1
) -> Path:
    """The bag of ``RIGS[rig_name].setup(path, seed)`` (``format``: ros1, ros2 or ros2-mcap), rendered on first use by
    ``jobs`` processes and cached by ``gpo.sim.record.recording`` as ``realsense-<rig>-<path>``."""
    if rig_name not in RIGS:
        raise ValueError(f"unknown realsense rig {rig_name!r}; the rigs are {', '.join(RIGS)}")
    setup = RIGS[rig_name].setup(path, seed)
    return recording(setup, format, progress=False, jobs=jobs, label=f"realsense-{rig_name}-{path}")
