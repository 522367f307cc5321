"""Simulated recordings: what the bag holds equals the simulator's truth, and generation is deterministic."""

import hashlib
from pathlib import Path

import numpy as np
import pytest

from gpo.bag import Recording
from gpo.sim.motion import T265_DRIFT, named_plan, tracking_odometry
from gpo.sim.record import (
    GROUND_TRUTH_TOPIC,
    ODOMETRY_TOPIC,
    PRESETS,
    START_NS,
    preset,
    recording,
    simulate,
    write_sample_data,
)
from gpo.sim.rigs import t265_rig

DATA = Path(__file__).resolve().parents[1] / "data"


def sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


@pytest.fixture(scope="module")
def test_bag(tmp_path_factory) -> Path:
    """The "test" preset, generated once through the cache, in a fresh cache folder."""
    cache = tmp_path_factory.mktemp("cache")
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("GPO_CACHE_DIR", str(cache))
        first = recording("test", progress=False)
        assert recording("test", progress=False) == first  # the second call reads the cache
    return first


def test_the_bag_holds_the_simulators_truth(test_bag):
    rig, chosen = t265_rig(), preset("test")
    plan = named_plan(chosen.path)
    with Recording(test_bag) as bag:
        assert bag.image_topic() == rig.image_topic
        frames = list(bag.frames(progress=False))
        truth = bag.trajectory(GROUND_TRUTH_TOPIC)
        odometry = bag.trajectory(ODOMETRY_TOPIC)
        assert bag.camera_info(rig.info_topic) == rig.camera
        translation, quaternion = bag.static_transform("base_link", rig.frame_id)
    assert len(frames) == int(np.ceil(plan.duration_s * rig.rate_hz))
    assert frames[0].image.shape == (800, 848) and frames[0].image.dtype == np.uint8
    assert frames[0].stamp_ns == START_NS and frames[1].stamp_ns - frames[0].stamp_ns == round(1e9 / 30)
    expected = plan.sample((truth.stamps_ns - START_NS) / 1e9)
    np.testing.assert_allclose(truth.positions[:, :2], np.column_stack([expected.x, expected.y]), atol=1e-12)
    expected_odometry = tracking_odometry(plan, rig.mount, 200.0, T265_DRIFT, chosen.seed, START_NS)
    np.testing.assert_array_equal(odometry.stamps_ns, expected_odometry.stamps_ns)
    np.testing.assert_allclose(odometry.positions, expected_odometry.positions, atol=1e-12)
    np.testing.assert_allclose(translation, rig.mount.position)
    assert abs(np.dot(quaternion, rig.mount.rotation.as_quat())) == pytest.approx(1.0)


def test_regenerating_a_recording_gives_the_same_bytes(test_bag, tmp_path):
    assert sha256(simulate("test", tmp_path / "again.bag", progress=False)) == sha256(test_bag)


def test_sample_data_regenerate_byte_for_byte(tmp_path):
    expected = dict(line.split()[::-1] for line in (DATA / "SHA256SUMS").read_text().splitlines())
    written = write_sample_data(tmp_path)
    assert sorted(path.name for path in written) == sorted(expected)
    for path in written:
        assert sha256(path) == expected[path.name], f"{path.name} differs from data/{path.name}"
        assert sha256(DATA / path.name) == expected[path.name], f"data/{path.name} does not match SHA256SUMS"


def test_unknown_preset_lists_the_presets():
    with pytest.raises(ValueError, match=r"unknown preset .tset.; the presets are sample"):
        preset("tset")
    assert {"sample", "test", "short1", "long3", "downward-industrial"} <= set(PRESETS)
