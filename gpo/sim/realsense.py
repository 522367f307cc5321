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
down, another lens). ``simulate_realsense`` renders one of them along a named path of ``gpo.sim.motion``;
``realsense_recording`` caches it.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation
from tqdm.auto import tqdm

from gpo.cameras import KB4
from gpo.cameras.rig import OPTICAL_IN_BODY, CameraMount, Rig
from gpo.io import cache
from gpo.io.bag_writer import BagWriter
from gpo.io.fingerprint import sources
from gpo.sim.drift import T265_DRIFT, tracking_odometry
from gpo.sim.floors import make_floor
from gpo.sim.paths import named_plan
from gpo.sim.record import FLOOR_MARGIN_M, GROUND_TRUTH_TOPIC, ODOMETRY_TOPIC, START_NS, TEXEL_M
from gpo.sim.record import floor_extent as _floor_extent
from gpo.sim.render import FloorRenderer

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


RIGS = {
    "t265": RealsenseRig("t265", T265_FACTORY_LIKE, (0.60, -0.032, 0.12), (1.5, 6.0, 0.0)),
    "t265-high": RealsenseRig(
        "t265-high",
        KB4(281.2, 282.0, 421.7, 403.1, -0.0051, 0.0391, -0.0379, 0.0069, 848, 800),
        (0.45, 0.02, 0.18),
        (-1.0, 10.0, 1.0),
    ),
}


def simulate_realsense(rig_name: str, path: str, out, format: str = "ros1", seed: int = 5, progress: bool = True):
    """Render ``RIGS[rig_name]`` along the named ``path`` over a raised floor into a realsense-ros shaped bag at
    ``out`` (``format`` ros1, ros2 or ros2-mcap); ``seed`` sets the floor's texture and the tracking's drift."""
    chosen = RIGS[rig_name]
    rig, plan = chosen.rig(), named_plan(path)
    floor = make_floor("raised", _floor_extent(plan, rig, FLOOR_MARGIN_M["t265"]), TEXEL_M["t265"], seed)
    renderer = FloorRenderer(rig, floor)
    pose_position, pose_rotation = chosen.pose_in_base
    with BagWriter(out, format) as bag:
        bag.add_static_transform("base_link", POSE_FRAME, pose_position, pose_rotation.as_quat(), START_NS)
        bag.add_static_transform(POSE_FRAME, LINK_FRAME, np.zeros(3), [0.0, 0.0, 0.0, 1.0], START_NS)
        bag.add_static_transform(LINK_FRAME, FISHEYE_FRAME, FISHEYE1_IN_POSE, [0.0, 0.0, 0.0, 1.0], START_NS)
        bag.add_static_transform(FISHEYE_FRAME, OPTICAL_FRAME, np.zeros(3), OPTICAL_IN_BODY.as_quat(), START_NS)
        bag.add_trajectory(GROUND_TRUTH_TOPIC, plan.ground_truth(120.0, START_NS), msgtype="pose")
        odometry = tracking_odometry(plan, (pose_position, pose_rotation), 200.0, T265_DRIFT, seed, START_NS)
        bag.add_trajectory(ODOMETRY_TOPIC, odometry)
        times = np.arange(0.0, plan.duration_s, 1.0 / rig.rate_hz)
        for index, time_s in enumerate(tqdm(times, desc=f"rendering {rig_name} {path}", disable=not progress)):
            state = plan.sample(np.array([time_s]))
            image = renderer.render(np.array([state.x[0], state.y[0], state.yaw[0]]), frame_seed=(seed, index))
            stamp_ns = START_NS + round(time_s * 1e9)
            bag.add_image(IMAGE_TOPIC, stamp_ns, image, OPTICAL_FRAME)
            bag.add_camera_info(INFO_TOPIC, stamp_ns, rig.camera, OPTICAL_FRAME)
    return Path(out)


def realsense_recording(rig_name: str = "t265", path: str = "test", format: str = "ros1", seed: int = 5) -> Path:
    """The cached bag of ``simulate_realsense`` (made on first use; its key hashes this module and the simulator's
    sources)."""
    if rig_name not in RIGS:
        raise ValueError(f"unknown realsense rig {rig_name!r}; the rigs are {', '.join(RIGS)}")
    key = cache.key(asdict(RIGS[rig_name]), path, format, seed, sources=sources(__name__))
    target = cache.path("recordings", f"realsense-{rig_name}-{path}", key, ".bag" if format == "ros1" else "")
    if not target.exists():
        cache.write(target, lambda partial: simulate_realsense(rig_name, path, partial, format, seed, progress=False))
    return target
