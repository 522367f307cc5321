"""Kalibr and Basalt calibration files: the real published files load, and round-trip unchanged."""

import json

import pytest
import yaml

from gpo.calibfiles import load_basalt, load_kalibr, save_basalt, save_kalibr
from gpo.camera import Pinhole

BASALT_EUCM_FILES = ["tumvi_512_eucm_calib.json", "euroc_eucm_calib.json"]


@pytest.mark.parametrize("name", BASALT_EUCM_FILES)
def test_basalt_files_load_with_their_published_values(fetch_or_skip, name):
    path = fetch_or_skip(f"basalt/data/{name}")
    published = json.loads(path.read_text())["value0"]
    cameras = load_basalt(path)
    assert len(cameras) == len(published["intrinsics"]) == 2
    for camera, entry, size in zip(cameras, published["intrinsics"], published["resolution"], strict=True):
        values = entry["intrinsics"]
        assert [camera.fx, camera.fy, camera.cx, camera.cy, camera.alpha, camera.beta] == [
            values[k] for k in ("fx", "fy", "cx", "cy", "alpha", "beta")
        ]
        assert [camera.width, camera.height] == size


@pytest.mark.parametrize("name", BASALT_EUCM_FILES)
def test_basalt_file_round_trips_unchanged_through_our_basalt_writer(fetch_or_skip, tmp_path, name):
    path = fetch_or_skip(f"basalt/data/{name}")
    original = json.loads(path.read_text())
    written = save_basalt(tmp_path / name, load_basalt(path), template=original)
    assert json.loads(written.read_text()) == original
    assert load_basalt(save_basalt(tmp_path / "bare.json", load_basalt(path))) == load_basalt(path)


@pytest.mark.parametrize("name", BASALT_EUCM_FILES)
def test_basalt_cameras_round_trip_unchanged_through_kalibr(fetch_or_skip, tmp_path, name):
    cameras = load_basalt(fetch_or_skip(f"basalt/data/{name}"))
    named = {f"cam{i}": camera for i, camera in enumerate(cameras)}
    written = save_kalibr(tmp_path / "camchain.yaml", named, rostopics={"cam0": "/cam0/image_raw"})
    assert load_kalibr(written) == named
    document = yaml.safe_load(written.read_text())
    assert document["cam0"]["intrinsics"] == [cameras[0].alpha, cameras[0].beta, *cameras[0].params[:4].tolist()]
    assert document["cam0"]["rostopic"] == "/cam0/image_raw" and "rostopic" not in document["cam1"]


def test_unsupported_basalt_model_is_named(fetch_or_skip):
    path = fetch_or_skip("basalt/data/t265_kb4_calib.json")
    with pytest.raises(ValueError, match=r"t265_kb4_calib\.json, camera 0: unsupported camera model 'kb4'"):
        load_basalt(path)


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
    path = tmp_path / "ds.yaml"
    path.write_text(
        yaml.safe_dump(
            {"cam0": {"camera_model": "ds", "intrinsics": [-0.2, 0.6, 350, 350, 640, 400], "resolution": [1280, 800]}}
        )
    )
    with pytest.raises(ValueError, match=r"ds\.yaml, cam0: unsupported camera model 'ds'"):
        load_kalibr(path)
    equidistant = {"camera_model": "pinhole", "intrinsics": [300, 300, 320, 240], "distortion_model": "equidistant"}
    path.write_text(yaml.safe_dump({"cam0": equidistant | {"distortion_coeffs": [0.1] * 4, "resolution": [640, 480]}}))
    with pytest.raises(ValueError, match=r"unsupported camera model 'pinhole' with distortion 'equidistant'"):
        load_kalibr(path)
    path.write_text(yaml.safe_dump({"cam0": {"camera_model": "eucm", "intrinsics": [0.6, 1.1, 1, 1, 0, 0]}}))
    with pytest.raises(ValueError, match="missing the field 'resolution'"):
        load_kalibr(path)
