"""Kalibr, Basalt and camera_info forms: the real published files load, and round-trip unchanged; files of the wrong
form are refused naming the file and the field."""

import json
import re

import pytest
import yaml

from gpo.cameras import EUCM, KB4, DoubleSphere, Omni, Pinhole
from gpo.cameras.files import (
    camera_from_camera_info,
    camera_info_distortion,
    load_basalt,
    load_boofcv,
    load_kalibr,
    save_basalt,
    save_kalibr,
)

BASALT_EUCM_FILES = ["tumvi_512_eucm_calib.json", "euroc_eucm_calib.json"]
BASALT_FILES = {
    "tumvi_512_eucm_calib.json": EUCM,
    "euroc_eucm_calib.json": EUCM,
    "t265_kb4_calib.json": KB4,
    "euroc_ds_calib.json": DoubleSphere,
    "tumvi_512_ds_calib.json": DoubleSphere,
}


@pytest.mark.parametrize("name", BASALT_FILES)
def test_basalt_files_load_with_their_published_values(fetch_or_skip, name):
    path = fetch_or_skip(f"basalt/data/{name}")
    published = json.loads(path.read_text())["value0"]
    cameras = load_basalt(path)
    assert len(cameras) == len(published["intrinsics"]) == 2
    for camera, entry, size in zip(cameras, published["intrinsics"], published["resolution"], strict=True):
        assert type(camera) is BASALT_FILES[name]
        values = entry["intrinsics"]
        assert sorted(values) == sorted(camera.PARAMETER_NAMES)
        assert {key: getattr(camera, key) for key in values} == values
        assert [camera.width, camera.height] == size


@pytest.mark.parametrize("name", BASALT_FILES)
def test_basalt_file_round_trips_unchanged_through_our_basalt_writer(fetch_or_skip, tmp_path, name):
    path = fetch_or_skip(f"basalt/data/{name}")
    original = json.loads(path.read_text())
    written = save_basalt(tmp_path / name, load_basalt(path), template=original)
    assert json.loads(written.read_text()) == original
    assert load_basalt(save_basalt(tmp_path / "bare.json", load_basalt(path))) == load_basalt(path)


@pytest.mark.parametrize("name", BASALT_FILES)
def test_basalt_cameras_round_trip_unchanged_through_kalibr(fetch_or_skip, tmp_path, name):
    cameras = load_basalt(fetch_or_skip(f"basalt/data/{name}"))
    named = {f"cam{i}": camera for i, camera in enumerate(cameras)}
    written = save_kalibr(tmp_path / "camchain.yaml", named, rostopics={"cam0": "/cam0/image_raw"})
    assert load_kalibr(written) == named


@pytest.mark.parametrize("name", BASALT_EUCM_FILES)
def test_kalibr_writes_eucm_intrinsics_in_kalibrs_order(fetch_or_skip, tmp_path, name):
    cameras = load_basalt(fetch_or_skip(f"basalt/data/{name}"))
    named = {f"cam{i}": camera for i, camera in enumerate(cameras)}
    written = save_kalibr(tmp_path / "camchain.yaml", named, rostopics={"cam0": "/cam0/image_raw"})
    document = yaml.safe_load(written.read_text())
    assert document["cam0"]["intrinsics"] == [cameras[0].alpha, cameras[0].beta, *cameras[0].params[:4].tolist()]
    assert document["cam0"]["rostopic"] == "/cam0/image_raw" and "rostopic" not in document["cam1"]


def test_kalibr_writes_ds_and_kb4_in_kalibrs_forms(tmp_path):
    ds = DoubleSphere(fx=349.7, fy=348.7, cx=365.9, cy=249.3, xi=-0.24, alpha=0.567, width=752, height=480)
    kb4 = KB4(286.6, 286.5, 422.3, 395.2, k1=-0.0068, k2=0.045, k3=-0.0435, k4=0.0084, width=848, height=800)
    document = yaml.safe_load(save_kalibr(tmp_path / "camchain.yaml", {"cam0": ds, "cam1": kb4}).read_text())
    assert document["cam0"]["camera_model"] == "ds" and document["cam0"]["distortion_model"] == "none"
    assert document["cam0"]["intrinsics"] == [-0.24, 0.567, 349.7, 348.7, 365.9, 249.3]
    assert document["cam1"]["camera_model"] == "pinhole" and document["cam1"]["distortion_model"] == "equidistant"
    assert document["cam1"]["intrinsics"] == [286.6, 286.5, 422.3, 395.2]
    assert document["cam1"]["distortion_coeffs"] == [-0.0068, 0.045, -0.0435, 0.0084]


def test_unsupported_basalt_model_is_named(tmp_path):
    path = tmp_path / "fov_calib.json"
    entry = {"camera_type": "fov", "intrinsics": {"fx": 1.0, "fy": 1.0, "cx": 0.0, "cy": 0.0, "w": 0.9}}
    path.write_text(json.dumps({"value0": {"intrinsics": [entry], "resolution": [[640, 480]]}}))
    with pytest.raises(ValueError, match=r"fov_calib\.json, camera 0: unsupported camera model 'fov'"):
        load_basalt(path)
    with pytest.raises(TypeError, match="camera 0: Basalt files hold EUCM, DoubleSphere, KB4 cameras, not a Pinhole"):
        save_basalt(tmp_path / "x.json", [Pinhole(1.0, 1.0, 0.0, 0.0, (0.0,) * 4, 4, 4)])


def test_kalibr_pinhole_radtan_round_trip(tmp_path):
    camera = Pinhole(fx=600.0, fy=601.0, cx=376.0, cy=240.0, dist=(-0.28, 0.09, 1e-3, -8e-4), width=752, height=480)
    path = save_kalibr(tmp_path / "camchain.yaml", {"cam0": camera})
    document = yaml.safe_load(path.read_text())
    assert document["cam0"]["distortion_model"] == "radtan"
    assert document["cam0"]["distortion_coeffs"] == [-0.28, 0.09, 1e-3, -8e-4]
    assert load_kalibr(path) == {"cam0": camera}


def test_kalibr_refuses_what_it_cannot_hold(tmp_path):
    with_k3 = Pinhole(fx=1.0, fy=1.0, cx=0.0, cy=0.0, dist=(0.0, 0.0, 0.0, 0.0, 0.1), width=4, height=4)
    with pytest.raises(ValueError, match="no k3"):
        save_kalibr(tmp_path / "x.yaml", {"cam0": with_k3})
    path = tmp_path / "fov.yaml"
    path.write_text(
        yaml.safe_dump(
            {"cam0": {"camera_model": "pinhole", "intrinsics": [350, 350, 640, 400], "distortion_model": "fov",
                      "distortion_coeffs": [0.9], "resolution": [1280, 800]}}
        )
    )
    with pytest.raises(ValueError, match=r"fov\.yaml, cam0: unsupported camera model 'pinhole' with distortion 'fov'"):
        load_kalibr(path)
    equidistant = {"camera_model": "pinhole", "intrinsics": [300, 300, 320, 240], "distortion_model": "equidistant"}
    path.write_text(yaml.safe_dump({"cam0": equidistant | {"distortion_coeffs": [0.1] * 3, "resolution": [640, 480]}}))
    with pytest.raises(ValueError, match=r"equidistant needs 4 distortion_coeffs \[k1, k2, k3, k4\], got 3"):
        load_kalibr(path)
    path.write_text(yaml.safe_dump({"cam0": {"camera_model": "eucm", "intrinsics": [0.6, 1.1, 1, 1, 0, 0]}}))
    with pytest.raises(ValueError, match="missing the field 'resolution'"):
        load_kalibr(path)


CAMERA_INFO_CAMERAS = [
    EUCM(fx=286.0, fy=286.2, cx=424.3, cy=400.1, alpha=0.6, beta=1.1, width=848, height=800),
    DoubleSphere(fx=158.3, fy=158.27, cx=254.96, cy=256.89, xi=-0.172, alpha=0.593, width=512, height=512),
    KB4(fx=286.6, fy=286.5, cx=422.3, cy=395.2, k1=-0.0068, k2=0.045, k3=-0.0435, k4=0.0084, width=848, height=800),
    Pinhole(fx=600.0, fy=601.0, cx=376.0, cy=240.0, dist=(-0.28, 0.09, 1e-3, -8e-4, 0.01), width=752, height=480),
]


@pytest.mark.parametrize("camera", CAMERA_INFO_CAMERAS, ids=lambda camera: type(camera).__name__)
def test_camera_info_round_trip(camera):
    model, d = camera_info_distortion(camera)
    k = [camera.fx, 0.0, camera.cx, 0.0, camera.fy, camera.cy, 0.0, 0.0, 1.0]
    assert camera_from_camera_info(model, d, k, camera.width, camera.height, "info") == camera


def test_camera_info_reads_realsense_ros_equidistant_with_a_fifth_zero_and_refuses_the_rest():
    k = [286.6, 0.0, 422.3, 0.0, 286.5, 395.2, 0.0, 0.0, 1.0]
    camera = camera_from_camera_info("equidistant", [-0.0068, 0.045, -0.0435, 0.0084, 0.0], k, 848, 800, "t265")
    assert isinstance(camera, KB4) and camera.dist == (-0.0068, 0.045, -0.0435, 0.0084)
    with pytest.raises(ValueError, match=r"t265: distortion model 'equidistant' with 3 coefficients"):
        camera_from_camera_info("equidistant", [0.1, 0.2, 0.3], k, 848, 800, "t265")
    with pytest.raises(ValueError, match=r"t265: distortion model 'kannala' with 4 coefficients"):
        camera_from_camera_info("kannala", [0.1, 0.2, 0.3, 0.4], k, 848, 800, "t265")
    with pytest.raises(TypeError, match="Omni has no camera_info distortion model"):
        camera_info_distortion(Omni(400.0, 400.0, 320.0, 320.0, 1.1, (0.0,) * 4, 640, 640))


EUCM_ENTRY = {"camera_model": "eucm", "intrinsics": [0.6, 1.1, 286.0, 286.0, 424.0, 400.0], "resolution": [848, 800]}


@pytest.mark.parametrize(
    ("entry", "words"),
    [
        ([1, 2], "cam0: expected a mapping with the field 'camera_model', got [1, 2]"),
        (EUCM_ENTRY | {"intrinsics": "0.6 1.1"}, "cam0, intrinsics: expected a list, got '0.6 1.1'"),
        (EUCM_ENTRY | {"intrinsics": [0.6, [1.1], 286, 286, 424, 400]}, "cam0, intrinsics: expected a number, got [1."),
        (EUCM_ENTRY | {"intrinsics": [0.6, True, 286, 286, 424, 400]}, "cam0, intrinsics: expected a number, got Tr"),
        (EUCM_ENTRY | {"resolution": 848}, "cam0, resolution: expected a list of 2, got 848"),
        (EUCM_ENTRY | {"intrinsics": [2.0, 1.1, 286, 286, 424, 400]}, "cam0: alpha must lie in [0, 1], got 2.0"),
        (EUCM_ENTRY | {"resolution": [848, -800]}, "cam0: height must be a positive whole number of pixels"),
    ],
)
def test_a_kalibr_entry_of_the_wrong_form_is_named_with_its_field(tmp_path, entry, words):
    path = tmp_path / "camchain.yaml"
    path.write_text(yaml.safe_dump({"cam0": entry}))
    with pytest.raises(ValueError) as refused:
        load_kalibr(path)
    assert str(refused.value).startswith(f"{path}, {words}")


def test_basalt_and_boofcv_files_of_the_wrong_form_name_the_file_and_field(tmp_path):
    basalt = tmp_path / "calib.json"
    for document, words in [
        ([1, 2], "expected a mapping with the field 'value0', got [1, 2]"),
        ({"value0": {"intrinsics": {}, "resolution": []}}, "value0, intrinsics: expected a list, got {}"),
        ({"value0": {"intrinsics": [{"camera_type": "eucm", "intrinsics": {"fx": "x"}}], "resolution": [[8, 8]]}},
         "camera 0, fx: expected a number, got 'x'"),
    ]:
        basalt.write_text(json.dumps(document))
        with pytest.raises(ValueError, match=re.escape(f"{basalt}, {words}") + "|" + re.escape(f"{basalt}: {words}")):
            load_basalt(basalt)
    basalt.write_bytes(b"\xff\xfe{}")
    with pytest.raises(ValueError, match=re.escape(f"{basalt} is not a text file (UTF-8)")):
        load_basalt(basalt)
    boofcv = tmp_path / "boofcv.yaml"
    boofcv.write_text("model: omnidirectional_universal\npinhole: [1, 2]\n")
    with pytest.raises(ValueError, match=re.escape(f"{boofcv}, pinhole: expected a mapping, got [1, 2]")):
        load_boofcv(boofcv)


@pytest.mark.parametrize(
    ("text", "words"),
    [
        ("cam0: " + "[" * 5000 + "]" * 5000 + "\n", "line 1, column 107: not valid YAML: lists or mappings nested"),
        ("cam0: \x1d\n", "not valid YAML: unacceptable character #x001d"),
        ("!!float", "not valid YAML: a value tagged !!int, !!float, !!bool or !!timestamp is empty"),
        ("cam0:\n  camera_model: !!bool\n", "not valid YAML: a value tagged"),
        ("cam0:\n  resolution: [848, !!int +]\n", "not valid YAML: a value tagged"),
        ("cam0: !!timestamp tomorrow\n", "not valid YAML: a value tagged"),
        ("\n".join([f"l0: &l0 [{', '.join(['x'] * 10)}]"] + [f"l{k}: &l{k} [{', '.join([f'*l{k - 1}'] * 10)}]"
                                                           for k in range(1, 7)]), "aliases expand to more than"),
    ],
    ids=["nested 5000 deep", "a control character", "an empty !!float", "an empty !!bool", "!!int +",
         "a !!timestamp that is none", "an alias bomb"],
)
def test_a_calibration_is_read_as_safely_as_a_config(tmp_path, text, words):
    """Each refused at once, naming the file (before, PyYAML's own error, or seconds of work, or memory)."""
    path = tmp_path / "camchain.yaml"
    path.write_text(text)
    with pytest.raises(ValueError, match=re.escape(str(path)) + ".*" + re.escape(words)):
        load_kalibr(path)
