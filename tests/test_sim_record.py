"""Simulated recordings: what the bag holds equals the simulator's truth, generation is deterministic, and the
short presets' disturbances reach the floor patch the ortho-GPI shows."""

import hashlib
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import gpo
from gpo.io import cache
from gpo.io.bag import Recording
from gpo.io.fingerprint import sources
from gpo.sim.disturbances import GPI_PATCH_M
from gpo.sim.drift import T265_DRIFT, tracking_odometry
from gpo.sim.paths import named_plan
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
    folder = tmp_path_factory.mktemp("cache")
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv(cache.ENVIRONMENT_VARIABLE, str(folder))
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


def test_another_process_on_one_thread_renders_the_same_bytes(test_bag, tmp_path):
    """The noise comes from OpenCV's generator and the lookups from its threaded remap: neither depends on the
    process or on how many threads OpenCV runs."""
    out = tmp_path / "elsewhere.bag"
    environment = {**os.environ, "OPENCV_FOR_THREADS_NUM": "1"}
    command = [sys.executable, "-m", "gpo", "simulate", "--preset", "test", "--out", str(out)]
    subprocess.run(command, env=environment, capture_output=True, check=True)
    assert sha256(out) == sha256(test_bag)


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


def sheet_cover(sheets, time_s: float, pose: np.ndarray) -> float:
    """Fraction of the floor patch (a 41 x 41 grid of its points) that some sheet covers at ``time_s``."""
    x_min, x_max, y_min, y_max = GPI_PATCH_M
    ahead, left = np.meshgrid(np.linspace(x_min, x_max, 41), np.linspace(y_min, y_max, 41))
    x, y, yaw = pose
    world = np.stack([x + np.cos(yaw) * ahead - np.sin(yaw) * left, y + np.sin(yaw) * ahead + np.cos(yaw) * left], -1)
    covered = np.zeros(ahead.shape, bool)
    for sheet in sheets:
        sheet_x, sheet_y, sheet_yaw = sheet.pose(time_s)
        offset = world - [sheet_x, sheet_y]
        along = offset @ [np.cos(sheet_yaw), np.sin(sheet_yaw)]
        across = offset @ [-np.sin(sheet_yaw), np.cos(sheet_yaw)]
        covered |= (np.abs(along) <= sheet.size_m[0] / 2) & (np.abs(across) <= sheet.size_m[1] / 2)
    return float(covered.mean())


@pytest.mark.parametrize("name", ["short1", "short2", "short3"])
def test_short_presets_drag_sheets_across_the_floor_patch_and_light_a_glint_in_it(name):
    """A sheet covers 5-25 % of the patch in 40-50 % of the frames; the glint lies inside it in every frame."""
    chosen = preset(name)
    plan = named_plan(chosen.path)
    times = np.arange(0.0, plan.duration_s, 1.0 / t265_rig().rate_hz)
    state = plan.sample(times)
    poses = np.column_stack([state.x, state.y, state.yaw])
    sheets = chosen.disturbances.place_sheets(times, poses)
    assert sheets == chosen.disturbances.place_sheets(times, poses)  # seeded
    covers = np.array([sheet_cover(sheets, time_s, pose) for time_s, pose in zip(times, poses, strict=True)])
    present = covers > 0.01
    assert 0.35 <= present.mean() <= 0.55
    assert 0.05 <= np.median(covers[present]) <= 0.25
    (glint,) = chosen.disturbances.place_glints()
    x_min, x_max, y_min, y_max = GPI_PATCH_M
    assert x_min + glint.radius_m <= glint.centre_m[0] <= x_max - glint.radius_m
    assert y_min + glint.radius_m <= glint.centre_m[1] <= y_max - glint.radius_m


def test_only_the_short_presets_are_disturbed():
    disturbed = {name for name, chosen in PRESETS.items() if chosen.disturbances.sheets or chosen.disturbances.glints}
    assert disturbed == {"short1", "short2", "short3"}


def test_the_cache_key_hashes_every_module_a_recording_runs():
    """Every gpo module that importing the simulator loads is hashed, so no change to one reuses a stale bag; the
    method's pipeline, its tables and the book, which only read recordings, are not, so changing them re-renders
    nothing."""
    program = (
        "import sys, gpo.sim.record\n"
        "print(*(m.__file__ for m in list(sys.modules.values()) if m.__name__.startswith('gpo.')))"
    )
    loaded = subprocess.run([sys.executable, "-c", program], capture_output=True, text=True, check=True).stdout.split()
    hashed = {path.resolve() for path in sources("gpo.sim.record")}
    assert {Path(path).resolve() for path in loaded} <= hashed
    package = Path(gpo.__file__).resolve().parent
    assert not {path for path in hashed if path.relative_to(package).parts[0] in ("pipeline", "experiments", "book")}


def test_frames_rendered_by_two_processes_make_the_same_bag(test_bag, tmp_path):
    assert sha256(simulate("test", tmp_path / "parallel.bag", progress=False, jobs=2)) == sha256(test_bag)
    with pytest.raises(ValueError, match="jobs must be at least 1, not 0"):
        simulate("test", tmp_path / "none.bag", jobs=0)
