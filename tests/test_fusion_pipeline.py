"""The fused route of ``gpo.pipeline``: the tracking camera's mount from /tf_static or the config, checked before any
frame; a tracking stream that cannot be fused leaves the floor odometry as the result."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import gpo.pipeline.run
from gpo.fusion import FusionSettings, TrackingMount
from gpo.io.bag import Recording
from gpo.io.bag_writer import BagWriter
from gpo.io.trajectory import Trajectory
from gpo.pipeline.config import load_config, save_config
from gpo.pipeline.run import run, tracking_mount, tracking_path

MOUNT = TrackingMount((0.6, 0.0, 0.12), (0.0, -6.0, 0.0))  # ahead of the rear axle, pitched 6 deg down


def _bag(tmp_path, tf_static=True, odometry=True, nan=False, name="fused.bag"):
    """A 0.5 s bag of the T265 rig: five noise frames, and the tracking camera's odometry at 200 Hz driving 0.4 m/s
    straight (its pose frame where ``MOUNT`` says, in /tf_static when ``tf_static``)."""
    config = load_config()
    rig = config.rig
    rng = np.random.default_rng(0)
    out = tmp_path / name
    rotation = Rotation.from_euler("xyz", MOUNT.rpy_deg, degrees=True)
    with BagWriter(out, "ros1") as bag:
        if tf_static:
            bag.add_static_transform("base_link", "camera_pose_frame", MOUNT.position_m, rotation.as_quat(), 0)
        if odometry:
            times = np.arange(101) / 200
            positions = rotation.inv().apply(np.column_stack([0.4 * times, 0 * times, 0 * times]))
            if nan:
                positions[40] = np.nan
            stamps = np.round(times * 1e9).astype(np.int64) + 1
            quaternions = np.tile([0.0, 0.0, 0.0, 1.0], (len(times), 1))
            if nan:
                for k in range(len(times)):
                    bag.add_odometry("/camera/odom/sample", int(stamps[k]), positions[k], quaternions[k],
                                     "camera_odom_frame", "camera_pose_frame")
            else:
                bag.add_trajectory("/camera/odom/sample", Trajectory(stamps, positions, quaternions,
                                                                     "camera_odom_frame", "camera_pose_frame"))
        for k in range(5):
            stamp = round(k / 10 * 1e9) + 1
            image = rng.integers(0, 255, (800, 848), dtype=np.uint8)
            bag.add_image(rig.image_topic, stamp, image, rig.frame_id)
    return out


def _fused_config(mount=None):
    config = load_config()
    fusion = FusionSettings(tracking_mount=mount)
    return config.replace(method="fused", fusion=fusion)


def test_the_mount_comes_from_tf_static_or_the_config(tmp_path):
    with Recording(_bag(tmp_path)) as recording:
        (_, position), note = tracking_mount(recording, FusionSettings())
        assert note is None
        np.testing.assert_allclose(position, MOUNT.position_m)
        (_, _), agreeing = tracking_mount(recording, FusionSettings(tracking_mount=MOUNT))
        assert agreeing is None
        moved = TrackingMount((0.6, 0.002, 0.12), (0.0, -6.0, 0.0))
        (_, position), note = tracking_mount(recording, FusionSettings(tracking_mount=moved))
        assert "2.0 mm" in note and "/tf_static's is used" in note
        np.testing.assert_allclose(position, MOUNT.position_m)
        turned = TrackingMount((0.6, 0.0, 0.12), (0.0, -6.0, 0.2))
        assert "0.20 deg" in tracking_mount(recording, FusionSettings(tracking_mount=turned))[1]
        from_static = tracking_path(recording, FusionSettings())
    with Recording(_bag(tmp_path, tf_static=False, name="no_tf.bag")) as recording:
        (_, position), note = tracking_mount(recording, FusionSettings(tracking_mount=MOUNT))
        assert note == "config"
        from_config = tracking_path(recording, FusionSettings(tracking_mount=MOUNT))
        with pytest.raises(ValueError, match=r"one of two ways.*/tf_static.*fusion: tracking_mount"):
            tracking_mount(recording, FusionSettings())
    np.testing.assert_allclose(from_config.positions, from_static.positions, atol=1e-12)
    np.testing.assert_allclose(from_static.positions[-1], [0.2, 0.0, 0.0], atol=1e-9)  # base_link drove 0.2 m ahead


def test_a_missing_mount_or_topic_is_an_error_before_any_frame(tmp_path):
    with pytest.raises(ValueError, match="one of two ways"):
        run(_bag(tmp_path, tf_static=False), _fused_config(), progress=False)
    with pytest.raises(ValueError, match=r"no topic /camera/odom/sample .*fusion.tracking_topic"):
        run(_bag(tmp_path, odometry=False, name="no_odometry.bag"), _fused_config(), progress=False)


def test_the_fused_route_runs_with_the_config_mount_and_reports_it(tmp_path):
    result = run(_bag(tmp_path, tf_static=False), _fused_config(MOUNT), progress=False)
    assert result.fused is not None and len(result.trajectory) == 5
    # the floor measures nothing on the noise frames, so the path is the tracking camera's: base_link drove 0.4 m/s
    # straight ahead (measured 13 micrometres short at most, the filter starting from rest; .ci/fp-path's too)
    trajectory = result.trajectory
    np.testing.assert_allclose(trajectory.positions[:, 0], 0.4 * trajectory.times, rtol=0, atol=3e-5)
    np.testing.assert_allclose(trajectory.positions[:, 1:], 0.0, rtol=0, atol=1e-9)
    np.testing.assert_allclose(trajectory.yaw, 0.0, rtol=0, atol=1e-9)
    summary = result.summary()
    assert summary["fusion"]["mount"] == "config (fusion.tracking_mount)"
    assert summary["fusion"]["refused_by_nis_gate"] == 0


def test_unreadable_tracking_poses_are_refused_before_the_first_frame(tmp_path, monkeypatch):
    monkeypatch.setattr(gpo.pipeline.run, "odometry", lambda *a, **k: pytest.fail("frames were read"))
    with pytest.raises(ValueError, match=r"tracking camera's odometry on /camera/odom/sample cannot be read: .*finite"):
        run(_bag(tmp_path, nan=True), _fused_config(), progress=False)


def test_the_tracking_mount_goes_through_the_config_file_and_bad_ones_are_refused(tmp_path):
    config = _fused_config(MOUNT)
    again = load_config(save_config(tmp_path / "with_mount.yaml", config))
    assert again.fusion.tracking_mount == MOUNT and again.fusion == config.fusion
    with pytest.raises(ValueError, match=r"fusion\.tracking_mount needs position_m and rpy_deg"):
        FusionSettings(tracking_mount={"position_m": [0.6, 0.0, 0.12]})
    with pytest.raises(ValueError, match=r"fusion.tracking_mount.rpy_deg must be 3 finite numbers"):
        FusionSettings(tracking_mount={"position_m": [0.6, 0.0, 0.12], "rpy_deg": [0.0, float("nan"), 0.0]})
