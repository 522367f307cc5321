"""gpo.io.datasets: every registered file is found in a local copy and checks out; offline failures are clear and
fast."""

import hashlib
import re
from pathlib import Path

import pooch
import pytest
import requests

from gpo.io import datasets

BASALT_COMMIT = "0f3b2b52c807f70ff4e2973ce253c73329eea7bc"
SHARED = Path(__file__).resolve().parents[2] / "shared" / "real_data"


@pytest.fixture
def shared_data(monkeypatch) -> Path:
    """GPO_DATA_DIR pointed at ``../shared/real_data``; the test is skipped, with the reason, where it is absent."""
    if not SHARED.is_dir():
        pytest.skip(f"no local copy of the real data at {SHARED}")
    monkeypatch.setenv("GPO_DATA_DIR", str(SHARED))
    return SHARED


@pytest.fixture
def offline_cache(monkeypatch, tmp_path) -> Path:
    """GPO_DATA_DIR pointed at an empty folder, with every download failing at once as if offline."""

    def unreachable(self, url, output_file, pooch_object):
        raise requests.ConnectionError(f"Failed to resolve host of {url}")

    monkeypatch.setattr(pooch.HTTPDownloader, "__call__", unreachable)
    monkeypatch.setenv("GPO_DATA_DIR", str(tmp_path / "cache"))
    return tmp_path / "cache"


def sources_table(text: str) -> dict[str, str]:
    """SOURCES.md's file tables: ``"<repo-name>/<path>"`` -> git blob sha-1."""
    blobs, repository = {}, None
    for line in text.splitlines():
        # "### kalibr  (commit <sha>)" or "### boofcv-data — <owner/name>, commit <sha>"
        if heading := re.match(r"### (\S+)\s.*commit [0-9a-f]{40}", line):
            repository = heading[1]
        elif (row := re.match(r"\| (\S+) \| \d+ \| `?([0-9a-f]{40})`? \|", line)) and repository:
            blobs[f"{repository}/{row[1]}"] = row[2]
    return blobs


def test_every_registered_file_fetches_from_the_local_copy_with_its_hashes(shared_data):
    blobs = sources_table((shared_data / "SOURCES.md").read_text())
    assert datasets.names() == sorted(blobs)
    for name in datasets.names():
        path = datasets.fetch(name)  # pooch checks the registered sha256
        assert path == shared_data / name
        content = path.read_bytes()
        assert hashlib.sha1(b"blob %d\0" % len(content) + content).hexdigest() == blobs[name], name


def test_offline_fetch_names_the_file_the_url_the_cache_and_the_fix(offline_cache):
    name = "basalt/data/tumvi_512_eucm_calib.json"
    with pytest.raises(datasets.DatasetUnavailable) as caught:
        datasets.fetch(name)
    message = str(caught.value)
    assert name in message and str(offline_cache) in message and "GPO_DATA_DIR" in message
    assert (
        f"https://raw.githubusercontent.com/VladyslavUsenko/basalt/{BASALT_COMMIT}/{name.split('/', 1)[1]}" in message
    )
    assert not (offline_cache / name).exists()


def test_a_download_with_the_wrong_hash_is_refused(offline_cache, monkeypatch):
    def wrong_content(self, url, output_file, pooch_object):
        Path(output_file).write_text("not the file")

    monkeypatch.setattr(pooch.HTTPDownloader, "__call__", wrong_content)
    with pytest.raises(datasets.DatasetUnavailable, match="basalt/LICENSE"):
        datasets.fetch("basalt/LICENSE")
    assert not (offline_cache / "basalt" / "LICENSE").exists()


@pytest.mark.parametrize(
    ("name", "suggestion"),
    [
        ("basalt/tumvi_512_eucm_calib.json", "basalt/data/tumvi_512_eucm_calib.json"),
        ("im_rear.jpg", "kalibr/aslam_cv/aslam_cv_python/example/im_rear.jpg"),
    ],
)
def test_unknown_name_suggests_the_closest(name, suggestion):
    with pytest.raises(KeyError, match=f"did you mean .*{re.escape(suggestion)}"):
        datasets.fetch(name)


def test_image_loaders_return_the_published_sizes(shared_data):
    chart = datasets.tumvi_chart_image()
    assert chart.shape == (512, 512) and chart.dtype == "uint8" and chart.max() == 255
    cars = datasets.kalibr_car_images()
    assert sorted(cars) == ["front", "left", "rear", "right"]
    assert all(image.shape == (800, 1280) and image.dtype == "uint8" for image in cars.values())
    assert datasets.floor_checkerboard_image().shape == (960, 1280)


def test_path_loaders_point_into_the_cache(shared_data):
    assert datasets.tumvi_eucm_calibration().name == "tumvi_512_eucm_calib.json"
    assert "grobi_cvg_may2013_second" in datasets.kalibr_car_pipeline_info().read_text()
    trajectories = datasets.rpg_trajectories()
    assert sorted(trajectories) == ["estimate", "eval_cfg", "groundtruth"]
    assert all(path.is_relative_to(shared_data) and path.is_file() for path in trajectories.values())
