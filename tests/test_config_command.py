"""``python -m gpo config``: a run config proposed from a bag, against the simulator's truth; and its bad input.

The truth: the simulated rigs' mounts and lenses (``gpo.sim.rigs``, ``gpo.sim.realsense``), which the bags carry on
camera_info and /tf_static; the floor region is checked against what the camera sees through the true mount.
"""

from types import SimpleNamespace

import numpy as np
import pytest
import yaml

import gpo.io.bag_writer
from gpo.cameras.files import save_kalibr
from gpo.cameras.rig import CameraMount
from gpo.cli import main
from gpo.io.bag_writer import BagWriter
from gpo.pipeline.config import load_config
from gpo.pipeline.propose import MARGIN_PX, check_region, floor_region, footprint
from gpo.sim.realsense import RIGS, realsense_recording
from gpo.sim.record import START_NS, recording
from gpo.sim.rigs import downward_rig, t265_rig


def test_config_from_a_realsense_bag_holds_its_lens_mount_topics_and_a_region_it_sees(tmp_path, capsys):
    bag, truth = realsense_recording("t265", "test"), RIGS["t265"].rig()
    out = tmp_path / "rig.yaml"
    assert main(["config", str(bag), "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "camera_pose_frame -> camera_link -> camera_fisheye1_frame -> camera_fisheye1_optical_frame" in printed
    text = out.read_text()
    assert "# floor_image: the camera looks ahead" in text and "# kinematics: the floor region's centre" in text
    config = load_config(out)
    rig = config.rig
    assert (rig.image_topic, rig.info_topic, rig.frame_id) == (truth.image_topic, truth.info_topic, truth.frame_id)
    np.testing.assert_allclose(rig.camera.params, truth.camera.params, rtol=1e-12)
    np.testing.assert_allclose(rig.mount.position, truth.mount.position, atol=1e-9)
    assert (rig.mount.rotation.inv() * truth.mount.rotation).magnitude() < 1e-9
    assert config.fusion.tracking_topic == "/camera/odom/sample" and config.fusion.tracking_frame == "camera_pose_frame"
    # the region: ahead of the camera, clear of the robot (0.8 heights ahead of the camera's foot), seen inside the
    # image through the true mount, its pixel the camera's footprint at its near edge, the lever at its centre
    x_min, x_max, y_min, y_max = config.floor.extent
    assert x_min >= truth.mount.position[0] + 0.8 * truth.mount.height - 2e-3
    corners = np.array([[x, y, 0.0] for x in (x_min, x_max) for y in (y_min, y_max)])
    pixels, valid = truth.camera.project(truth.mount.rotation.inv().apply(corners - truth.mount.position))
    assert valid.all() and (pixels >= MARGIN_PX).all() and (pixels[:, 0] < truth.camera.width - MARGIN_PX).all()
    centre = ((x_min + x_max) / 2, (y_min + y_max) / 2)
    near_edge = footprint(truth.camera, truth.mount, (x_min, centre[1]))
    assert config.floor.metres_per_pixel == pytest.approx(near_edge, abs=1e-4)
    assert config.model.wheelbase_m == pytest.approx(centre[0])
    assert abs(centre[1] - truth.mount.position[1]) < 0.01
    # the written file runs as it is
    assert main(["run", str(bag), "--config", str(out), "--out", str(tmp_path / "traj.tum")]) == 0


def test_run_without_a_config_keeps_the_shipped_one_for_its_own_rig(capsys, tmp_path):
    assert main(["run", str(recording("test")), "--out", str(tmp_path / "traj.tum")]) == 0
    assert "config: the shipped default (sim_t265.yaml): the bag's camera_info and /tf_static are its rig's" in (
        capsys.readouterr().out
    )


def test_a_downward_camera_gets_a_region_below_it_read_by_the_rigid_fit():
    rig = downward_rig()
    floor, how = floor_region(rig.camera, rig.mount)
    x_min, x_max, y_min, y_max = floor.extent
    axis = rig.mount.rotation.apply([0.0, 0.0, 1.0])
    axis_foot = rig.mount.position[:2] - rig.mount.height * axis[:2] / axis[2]
    assert x_min < axis_foot[0] < x_max and y_min < axis_foot[1] < y_max and "looks down" in how
    assert 0.1 < x_max - x_min < 0.31 and 0.1 < y_max - y_min < 0.5  # the image covers 0.31 x 0.2 m of floor


def _small_bag(path, info=None, transforms=(), camera=None):
    """A two-frame bag of the T265 rig's image size: images on /camera/fisheye1/image_raw, ``info`` (a camera) on
    /camera/fisheye1/camera_info, ``transforms`` (parent, child) on /tf_static."""
    rig = t265_rig()
    with BagWriter(path, "ros1") as bag:
        for parent, child in transforms:
            bag.add_static_transform(parent, child, [0.6, 0.0, 0.12], [0.5, -0.5, 0.5, -0.5], START_NS)
        for index in range(2):
            stamp = START_NS + index * 33_000_000
            bag.add_image(rig.image_topic, stamp, np.full((800, 848), 100, np.uint8), rig.frame_id)
            if info is not None:
                bag.add_camera_info(rig.info_topic, stamp, info, rig.frame_id)
    return path


def _fails(argv, capsys) -> str:
    assert main(argv) == 1
    error = capsys.readouterr().err
    assert "Traceback" not in error
    return error


def test_bad_bags_and_mounts_are_clear_errors_that_say_what_to_give(tmp_path, capsys, monkeypatch):
    rig = t265_rig()
    out = ["--out", str(tmp_path / "rig.yaml")]
    no_info = _small_bag(tmp_path / "no_info.bag", transforms=[("base_link", rig.frame_id)])
    assert "give the camera's calibration with --camera" in _fails(["config", str(no_info), *out], capsys)
    no_frame = _small_bag(tmp_path / "no_frame.bag", rig.camera, [("base_link", "camera_pose_frame")])
    error = _fails(["config", str(no_frame), *out], capsys)
    assert "does not lead from base_link to the camera's frame camera_fisheye1_optical_frame" in error
    assert "base_link -> camera_pose_frame" in error and "--mount" in error
    with monkeypatch.context() as patched:
        patched.setattr(gpo.io.bag_writer, "camera_info_distortion", lambda camera: ("fov", [0.92]))
        fov = _small_bag(tmp_path / "fov.bag", rig.camera, [("base_link", rig.frame_id)])
    error = _fails(["config", str(fov), *out], capsys)
    assert "distortion model 'fov'" in error and "--camera CALIB instead" in error
    with monkeypatch.context() as patched:
        patched.setattr(gpo.io.bag_writer, "camera_info_distortion", lambda camera: ("equidistant", [0.0] * 4))
        zeros = SimpleNamespace(fx=0.0, fy=0.0, cx=0.0, cy=0.0, width=848, height=800)
        zero = _small_bag(tmp_path / "zero.bag", zeros, [("base_link", rig.frame_id)])
    error = _fails(["config", str(zero), *out], capsys)
    assert "fx must" in error and "got 0.0" in error and "--camera CALIB instead" in error
    # with --camera and --mount the same bags give a config; a mount below the floor, pitched up, or ten times
    # higher than the bag's /tf_static (0.12 m, _small_bag) is refused
    calib = tmp_path / "calib.yaml"
    save_kalibr(calib, {"cam0": rig.camera})
    for name, position, rpy, expected in (
        ("good", [0.6, 0.0, 0.12], [1.5, 6.0, 0.0], None),
        ("below", [0.6, 0.0, -0.12], [1.5, 6.0, 0.0], "mount.position_m.2 must be a number over 0 to 5 m above the "
                                                      "floor, got -0.12"),
        ("up", [0.6, 0.0, 0.12], [0.0, -80.0, 0.0], "does not see the floor"),
        ("tall", [0.6, 0.0, 1.2], [1.5, 6.0, 0.0], f"--mount {tmp_path / 'tall.yaml'} puts the camera 1.200 m above "
                                                   f"the floor, {zero}'s /tf_static 0.120 m"),
    ):
        mount = tmp_path / f"{name}.yaml"
        mount.write_text(yaml.safe_dump({"mount": {"position_m": position, "rpy_deg": rpy}}))
        argv = ["config", str(zero), "--camera", str(calib), "--mount", str(mount), *out]
        if expected is None:
            assert main(argv) == 0
            assert load_config(tmp_path / "rig.yaml").rig.mount.height == pytest.approx(0.12)
        else:
            assert expected in _fails(argv, capsys)


def test_a_region_outside_the_image_is_refused():
    rig = t265_rig()
    tilted_up = CameraMount.forward(0.6, 0.0, 0.12, pitch=np.radians(-60.0))
    with pytest.raises(ValueError, match=r"beyond the lens's view|outside the image"):
        floor_region(rig.camera, tilted_up)
    with pytest.raises(ValueError, match="outside the image"):
        check_region(rig.camera, rig.mount, (0.3, 0.5), (-0.1, 0.1))  # behind the camera
