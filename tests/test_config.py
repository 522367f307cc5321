"""Rig configs: a rig written and read back is the same rig; a camchain file can stand in for the camera."""

import numpy as np
import pytest
import yaml

from gpo.calibfiles import save_kalibr
from gpo.config import load_rig, save_rig
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


def test_the_people_numbers_are_the_mount_of_the_simulator(tmp_path):
    document = yaml.safe_load(save_rig(tmp_path / "rig.yaml", t265_rig()).read_text())
    assert document["mount"]["height_m"] == pytest.approx(0.12)
    assert document["mount"]["pitch_deg"] == pytest.approx(6.0)
    assert document["mount"]["roll_deg"] == pytest.approx(1.5)


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
    del document["mount"]["quaternion_xyzw"]
    (tmp_path / "rig.yaml").write_text(yaml.safe_dump(document))
    with pytest.raises(ValueError, match=r"mount\.quaternion_xyzw: missing"):
        load_rig(tmp_path / "rig.yaml")
    document = yaml.safe_load(save_rig(tmp_path / "rig.yaml", t265_rig()).read_text())
    del document["camera"]
    (tmp_path / "rig.yaml").write_text(yaml.safe_dump(document))
    with pytest.raises(ValueError, match="give either 'camera'"):
        load_rig(tmp_path / "rig.yaml")
