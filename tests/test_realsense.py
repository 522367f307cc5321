"""Simulated realsense-ros T265 bags, and ``gpo run`` on them with no config, ROS1 and ROS2, against the truth.

The truth: each rig's lens and mount (``gpo.sim.realsense.RIGS``) and the path's ground truth in the bag.
"""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from gpo.cameras.rig import OPTICAL_IN_BODY
from gpo.cli import main
from gpo.io.bag import Recording
from gpo.io.trajectory import Trajectory
from gpo.metrics import evaluate
from gpo.sim.realsense import FISHEYE1_IN_POSE, RIGS, realsense_recording
from gpo.sim.record import GROUND_TRUTH_TOPIC

TOPICS = {
    "/camera/fisheye1/image_raw": "sensor_msgs/msg/Image",
    "/camera/fisheye1/camera_info": "sensor_msgs/msg/CameraInfo",
    "/camera/odom/sample": "nav_msgs/msg/Odometry",
    "/tf_static": "tf2_msgs/msg/TFMessage",
    GROUND_TRUTH_TOPIC: "geometry_msgs/msg/PoseStamped",
}


@pytest.mark.parametrize("format", ["ros1", "ros2"])
def test_the_bag_has_realsense_ros_topics_frames_and_the_factory_lens(format):
    chosen = RIGS["t265"]
    with Recording(realsense_recording("t265", "test", format)) as bag:
        assert {t.name: t.msgtype for t in bag.topics()} == TOPICS
        lens = bag.camera_info("/camera/fisheye1/camera_info")
        np.testing.assert_array_equal(lens.params, chosen.lens.params)
        # each link of the T265's static tree, composed by hand: base_link -> optical = the rig's fisheye mount
        links = [
            ("base_link", "camera_pose_frame"),
            ("camera_pose_frame", "camera_link"),
            ("camera_link", "camera_fisheye1_frame"),
            ("camera_fisheye1_frame", "camera_fisheye1_optical_frame"),
        ]
        rotation, position = Rotation.identity(), np.zeros(3)
        for parent, child in links:
            translation, quaternion = bag.static_transform(parent, child)
            position, rotation = position + rotation.apply(translation), rotation * Rotation.from_quat(quaternion)
        pose_position, pose_rotation = chosen.pose_in_base
        np.testing.assert_allclose(position, pose_position + pose_rotation.apply(FISHEYE1_IN_POSE), atol=1e-12)
        assert (rotation.inv() * pose_rotation * OPTICAL_IN_BODY).magnitude() < 1e-9
        tracking = bag.trajectory("/camera/odom/sample")
        assert (tracking.frame_id, tracking.child_frame_id) == ("camera_odom_frame", "camera_pose_frame")


@pytest.mark.parametrize(("rig_name", "format"), [("t265", "ros1"), ("t265-high", "ros2")])
def test_run_with_no_config_reads_everything_from_the_bag(rig_name, format, tmp_path, capsys):
    bag = realsense_recording(rig_name, "test", format)
    for method in ("gpo-exact", "fused"):
        out = tmp_path / f"{method}.tum"
        assert main(["run", str(bag), "--method", method, "--out", str(out)]) == 0
        printed = capsys.readouterr().out
        assert "config: proposed from the bag" in printed
        assert "the bag's /camera/fisheye1/camera_info (the driver's factory calibration, KB4)" in printed
        assert "the bag's /tf_static: base_link -> camera_pose_frame -> camera_link" in printed
        with Recording(bag) as recording:
            truth = recording.trajectory(GROUND_TRUTH_TOPIC)
        evaluation = evaluate(Trajectory.read_tum(out), truth)
        # measured 0.039 % (t265) and 0.025 % (t265-high) for gpo-exact, 0.033 and 0.023 % fused, the same on the
        # avx2 and sse4 paths (.ci/fp-path): a bound of twice the worst
        assert evaluation.final.percent < 0.078, evaluation.final
        assert abs(np.degrees(evaluation.final.heading_rad)) < 0.051, evaluation.final  # measured 0.0253 deg at most
