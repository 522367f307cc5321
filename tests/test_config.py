"""Rig configs: a rig written and read back is the same rig; a camchain file can stand in for the camera; every number
held to the range a real rig can have, which admits what the presets and chapters use."""

import re
from pathlib import Path

import numpy as np
import pytest
import yaml

import gpo
from gpo.cameras.files import save_kalibr
from gpo.cameras.rig import CameraMount
from gpo.fusion import FusionSettings
from gpo.pipeline.config import load_config
from gpo.pipeline.schema import load_rig, save_rig
from gpo.sim.rigs import downward_rig, t265_rig


@pytest.mark.parametrize("make_rig", [t265_rig, downward_rig])
def test_rig_round_trip(tmp_path, make_rig):
    rig = make_rig()
    again = load_rig(save_rig(tmp_path / "rig.yaml", rig))
    assert again.camera == rig.camera
    np.testing.assert_array_equal(again.mount.position, rig.mount.position)
    assert np.allclose(again.mount.rotation.as_matrix(), rig.mount.rotation.as_matrix(), atol=1e-15)
    assert (again.name, again.rate_hz, again.image_topic, again.info_topic, again.frame_id) == (
        rig.name,
        rig.rate_hz,
        rig.image_topic,
        rig.info_topic,
        rig.frame_id,
    )


def test_the_saved_mount_is_the_simulators_position_and_roll_pitch_yaw(tmp_path):
    document = yaml.safe_load(save_rig(tmp_path / "rig.yaml", t265_rig()).read_text())
    assert set(document["mount"]) == {"position_m", "rpy_deg"}
    np.testing.assert_allclose(document["mount"]["position_m"], [0.6, 0.0, 0.12], atol=1e-12)
    np.testing.assert_allclose(document["mount"]["rpy_deg"], [1.5, 6.0, 0.0], atol=1e-9)


def write_mount(tmp_path, mount: dict):
    document = yaml.safe_load(save_rig(tmp_path / "rig.yaml", t265_rig()).read_text())
    document["mount"] = mount
    (tmp_path / "rig.yaml").write_text(yaml.safe_dump(document))
    return tmp_path / "rig.yaml"


def test_rpy_deg_is_the_body_frame_in_base_link_as_rep_103_has_it(tmp_path):
    # yawed 90 degrees to the left and pitched 30 degrees down: the optical axis points left and down
    rig = load_rig(write_mount(tmp_path, {"position_m": [0.1, 0.2, 0.3], "rpy_deg": [0.0, 30.0, 90.0]}))
    optical_axis = rig.mount.rotation.apply([0.0, 0.0, 1.0])
    np.testing.assert_allclose(optical_axis, [0.0, np.cos(np.radians(30)), -np.sin(np.radians(30))], atol=1e-12)
    # rolled 10 degrees: the image's right (optical x) tips down, as the camera's left side lifts
    rig = load_rig(write_mount(tmp_path, {"position_m": [0.1, 0.2, 0.3], "rpy_deg": [10.0, 0.0, 0.0]}))
    assert rig.mount.rotation.apply([1.0, 0.0, 0.0])[2] == pytest.approx(-np.sin(np.radians(10.0)))
    forward = CameraMount.forward(0.1, 0.2, 0.3, np.radians(6.0), np.radians(1.5))
    rpy = CameraMount.from_rpy([0.1, 0.2, 0.3], np.radians(1.5), np.radians(6.0), 0.0)
    np.testing.assert_allclose(rpy.rotation.as_matrix(), forward.rotation.as_matrix(), atol=1e-15)
    np.testing.assert_allclose(np.degrees(forward.body_rpy), [1.5, 6.0, 0.0], atol=1e-12)


def test_the_optical_quaternion_is_still_read_alone_or_beside_a_consistent_rpy(tmp_path):
    rig = t265_rig()
    quaternion = rig.mount.rotation.as_quat().tolist()
    position = rig.mount.position.tolist()
    for mount in (
        {"position_m": position, "quaternion_xyzw": quaternion},
        {"position_m": position, "quaternion_xyzw": quaternion, "rpy_deg": [1.5, 6.0, 0.0]},
    ):
        again = load_rig(write_mount(tmp_path, mount)).mount
        np.testing.assert_allclose(again.rotation.as_matrix(), rig.mount.rotation.as_matrix(), atol=1e-12)


def test_an_rpy_and_a_quaternion_that_disagree_are_shown_both_as_roll_pitch_yaw(tmp_path):
    rig = t265_rig()
    mount = {"position_m": [0.6, 0.0, 0.12], "quaternion_xyzw": rig.mount.rotation.as_quat().tolist()}
    path = write_mount(tmp_path, mount | {"rpy_deg": [1.5, 8.0, 0.0]})
    disagree = r"rig\.yaml: mount rpy_deg and quaternion_xyzw disagree by 2\.000 degrees"
    with pytest.raises(ValueError, match=disagree) as error:
        load_rig(path)
    assert "rpy_deg is [1.500, 8.000, 0.000] and quaternion_xyzw is [1.500, 6.000, 0.000]" in str(error.value)
    for bad, message in (
        ({"rpy_deg": [1.0, 2.0]}, r"mount\.rpy_deg\.2: missing"),
        ({"quaternion_xyzw": [0, 0, 0, 0]}, "quaternion cannot be all zeros"),
    ):
        with pytest.raises(ValueError, match=message):
            load_rig(write_mount(tmp_path, {"position_m": [0.6, 0.0, 0.12]} | bad))


def test_camera_from_a_camchain_file(tmp_path):
    rig = t265_rig()
    save_kalibr(tmp_path / "camchain.yaml", {"cam0": rig.camera})
    document = yaml.safe_load(save_rig(tmp_path / "rig.yaml", rig).read_text())
    del document["camera"]
    document["camchain"] = "camchain.yaml"
    (tmp_path / "rig.yaml").write_text(yaml.safe_dump(document))
    assert load_rig(tmp_path / "rig.yaml").camera == rig.camera
    document["camchain_camera"] = "cam3"
    (tmp_path / "rig.yaml").write_text(yaml.safe_dump(document))
    with pytest.raises(ValueError, match=r"camchain_camera 'cam3' is not in camchain\.yaml"):
        load_rig(tmp_path / "rig.yaml")


def test_missing_fields_are_named(tmp_path):
    document = yaml.safe_load(save_rig(tmp_path / "rig.yaml", t265_rig()).read_text())
    del document["mount"]["rpy_deg"]
    (tmp_path / "rig.yaml").write_text(yaml.safe_dump(document))
    with pytest.raises(ValueError, match=r"mount: .*no orientation: give rpy_deg: \[roll, pitch, yaw\]"):
        load_rig(tmp_path / "rig.yaml")
    document = yaml.safe_load(save_rig(tmp_path / "rig.yaml", t265_rig()).read_text())
    del document["camera"]
    (tmp_path / "rig.yaml").write_text(yaml.safe_dump(document))
    with pytest.raises(ValueError, match="give either 'camera'"):
        load_rig(tmp_path / "rig.yaml")


def test_the_ranges_admit_what_the_presets_and_chapters_use():
    """The shipped configs, the values of chapter 07's fusion sliders at both ends, and its tracking camera that is not
    to be trusted (walks of 5 m/sqrt(s) and 1 rad/sqrt(s)) all lie in the ranges a real rig can have; one step beyond
    each bound is refused with the key, the range and its unit."""
    from gpo.book.ch07_ekf_fusion import FUSION_SLIDERS

    for name in ("sim_t265.yaml", "sim_downward.yaml"):
        load_config(Path(gpo.__file__).parent / "configs" / name)
    for field, (_, low, high) in FUSION_SLIDERS.items():
        for exponent in (low, high):
            FusionSettings(**{field: 10.0**exponent})
    FusionSettings(tracking_position_walk_m_per_sqrt_s=5.0, tracking_yaw_walk_rad_per_sqrt_s=1.0)
    with pytest.raises(
        ValueError,
        match=r"^tracking_position_walk_m_per_sqrt_s must be a number from 0 to 10 "
        r"m/sqrt\(s\), got 10\.5$",
    ):
        FusionSettings(tracking_position_walk_m_per_sqrt_s=10.5)
    with pytest.raises(ValueError, match=r"^accel_mps2 must be a number from 0 to 100 m/s\^2 per sqrt\(Hz\), got -0\."):
        FusionSettings(accel_mps2=-0.1)


@pytest.mark.parametrize(
    ("key", "value", "message"),
    [
        ("rate_hz", 0.0, r"rate_hz must be a number over 0 to 1000 Hz, got 0\.0"),
        ("rate_hz", 1000.5, r"rate_hz must be a number over 0 to 1000 Hz, got 1000\.5"),
        (
            "mount",
            {"position_m": [0.6, 0.0, 5.5], "rpy_deg": [0, 6, 0]},
            r"mount\.position_m\.2 must be a number "
            r"over 0 to 5 m above the floor, got 5\.5",
        ),
        (
            "mount",
            {"position_m": [-50.5, 0.0, 0.1], "rpy_deg": [0, 6, 0]},
            r"mount\.position_m\.0 must be a number "
            r"from -50 to 50 m, got -50\.5",
        ),
        (
            "mount",
            {"position_m": [0.6, 0.0, 0.1], "rpy_deg": [0, 361, 0]},
            r"mount\.rpy_deg\.1 must be a number from "
            r"-360 to 360 deg, got 361",
        ),
    ],
)
def test_a_value_just_beyond_its_range_is_refused_with_key_value_range_and_unit(tmp_path, key, value, message):
    document = yaml.safe_load(save_rig(tmp_path / "rig.yaml", t265_rig()).read_text()) | {key: value}
    (tmp_path / "rig.yaml").write_text(yaml.safe_dump(document))
    with pytest.raises(ValueError, match=rf"rig\.yaml: {message}$"):
        load_rig(tmp_path / "rig.yaml")
    load_rig(save_rig(tmp_path / "again.yaml", t265_rig()))  # and the rig itself, in range, is read


def _document(tmp_path, edit) -> Path:
    """The shipped T265 config with ``edit(document)`` applied, written to ``tmp_path / rig.yaml``."""
    document = yaml.safe_load((Path(gpo.__file__).parent / "configs" / "sim_t265.yaml").read_text())
    edit(document)
    path = tmp_path / "rig.yaml"
    path.write_text(yaml.safe_dump(document, sort_keys=False))
    return path


@pytest.mark.parametrize(
    ("section", "key", "value"),
    [
        ("klt", "overview_scale", False),  # read as 0, it turned the whole-view check off
        ("keyframe", "min_overlap", True),  # read as 1.0
        ("features", "contrast_threshold", True),
        ("klt", "max_corners", True),
        ("fusion", "tracking_max_gap_s", False),
        (None, "rate_hz", True),
    ],
)
def test_a_flag_is_not_a_number(tmp_path, section, key, value):
    path = _document(tmp_path, lambda document: (document[section] if section else document).update({key: value}))
    name = re.escape(f"{section}.{key}" if section else key)
    expected = rf"rig\.yaml: {name}(: expected a (whole )?number \(got {value}\)| must be a .*number .*, got {value})"
    with pytest.raises(ValueError, match=expected):
        load_config(path)


@pytest.mark.parametrize(
    ("where", "edit"),
    [
        ("mount.position_m.0", lambda document: document["mount"].update(position_m=[True, 0.0, 0.12])),
        ("camera.resolution.0", lambda document: document["camera"].update(resolution=[True, 800])),
        ("features.keyframe.min_overlap", lambda document: document["features"].update(keyframe={"min_overlap": True})),
    ],
)
def test_a_flag_is_not_a_number_in_a_list_or_a_nested_section(tmp_path, where, edit):
    refused = r"(: expected a (whole )?number \(got True\)| must be a .*number .*, got True)"
    with pytest.raises(ValueError, match=rf"rig\.yaml: {re.escape(where)}{refused}"):
        load_config(_document(tmp_path, edit))


@pytest.mark.parametrize("value", [1, 0, "yes", "true", 1.0])
@pytest.mark.parametrize(("section", "key"), [("klt", "normalise_brightness"), ("features", "cross_check")])
def test_a_number_or_a_word_is_not_a_flag(tmp_path, section, key, value):
    path = _document(tmp_path, lambda document: document[section].update({key: value}))
    with pytest.raises(ValueError, match=rf"rig\.yaml: {section}\.{key}: expected true or false \(got {value!r}\)"):
        load_config(path)


def test_a_number_written_as_text_is_refused(tmp_path):
    path = _document(tmp_path, lambda document: document["klt"].update(quality_level="0.01"))
    with pytest.raises(ValueError, match=r"rig\.yaml: klt\.quality_level: expected a number \(got '0\.01'\)"):
        load_config(path)


@pytest.mark.parametrize(
    ("resolution", "message"),
    [
        ([848, 8.0e32], r"resolution\.1 must be a whole number from 1 to 20000 px, got 8e\+32"),
        ([True, 800], r"resolution\.0 must be a whole number from 1 to 20000 px, got True"),
    ],
)
def test_a_camchain_a_config_names_is_held_to_the_ranges_of_a_camera_written_inline(tmp_path, resolution, message):
    rig = t265_rig()
    camchain = yaml.safe_load(save_kalibr(tmp_path / "camchain.yaml", {"cam0": rig.camera}).read_text())
    inline = _document(tmp_path, lambda document: document["camera"].update(resolution=resolution))
    with pytest.raises(ValueError, match=rf"rig\.yaml: camera\.{message}"):
        load_config(inline)
    camchain["cam0"]["resolution"] = resolution
    (tmp_path / "camchain.yaml").write_text(yaml.safe_dump(camchain))

    def by_file(document):
        del document["camera"]
        document["camchain"] = "camchain.yaml"

    with pytest.raises(ValueError, match=rf"rig\.yaml: camchain camchain\.yaml, cam0: {message}"):
        load_config(_document(tmp_path, by_file))


def test_a_camchain_whose_cameras_are_named_by_numbers_is_named(tmp_path):
    """A camchain whose cameras are keyed by numbers, not the camera the config names (the campaign, seeds
    48707-48909: a TypeError joining the names)."""
    camchain = yaml.safe_load(save_kalibr(tmp_path / "camchain.yaml", {"cam0": t265_rig().camera}).read_text())
    (tmp_path / "camchain.yaml").write_text(yaml.safe_dump({2561302: camchain["cam0"]}))

    def by_file(document):
        del document["camera"]
        document.update(camchain="camchain.yaml", camchain_camera="cam0")

    with pytest.raises(ValueError, match=r"rig\.yaml: camchain_camera 'cam0' is not in camchain\.yaml \(2561302\)"):
        load_config(_document(tmp_path, by_file))


def test_a_wheelbase_shorter_than_the_reference_point_s_distance_names_the_file(tmp_path):
    """The campaign (seeds 48707-48909) cut the wheelbase to 8e-91 m: in range, but shorter than l_r = 0.8 m."""
    path = _document(tmp_path, lambda document: document["kinematics"].update(wheelbase_m=8e-91))
    with pytest.raises(
        ValueError, match=r"rig\.yaml: rear_to_reference_m \(l_r\) must lie between 0 and the wheelbase"
    ):
        load_config(path)
