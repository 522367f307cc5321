"""Odometry from bags: accuracy against the simulator's truth, every bag format, and bad input."""

import dataclasses

import numpy as np
import pytest
import yaml

from gpo.cli import main
from gpo.experiments.runs import route_config
from gpo.io.bag import Recording
from gpo.io.bag_writer import BagWriter
from gpo.io.trajectory import Trajectory
from gpo.metrics import final_error
from gpo.odometry.kinematics import compose
from gpo.pipeline.config import load_config, save_config
from gpo.pipeline.odometer import FloorOdometer, FrameRecord
from gpo.pipeline.run import OdometryResult, run, tracking_path
from gpo.sim.record import FLOOR_BOARDS, GROUND_TRUTH_TOPIC, floor_board_path, recording
from gpo.sim.rigs import t265_rig

FRAMES = 60  # two seconds of the sample recording: straight ahead at up to 0.5 m/s


@pytest.fixture(scope="module")
def sample():
    """The sample recording's path, its first frames and its ground truth."""
    path = recording("sample")
    with Recording(path) as bag:
        frames = [frame for _, frame in zip(range(FRAMES), bag.frames(progress=False), strict=False)]
        truth = bag.trajectory(GROUND_TRUTH_TOPIC)
    return path, frames, truth


def _final_error(trajectory, truth) -> tuple[float, float, float]:
    """Final position error (m), heading error (rad) and distance (m) after placing the estimate on the truth."""
    index = np.searchsorted(truth.stamps_ns, trajectory.stamps_ns)
    assert np.all(truth.stamps_ns[index] == trajectory.stamps_ns)
    true = np.column_stack([truth.positions[index, :2], np.unwrap(truth.yaw[index])])
    estimate = compose(true[0], np.column_stack([trajectory.positions[:, :2], np.unwrap(trajectory.yaw)]))
    error = estimate[-1] - true[-1]
    distance = float(np.linalg.norm(np.diff(true[:, :2], axis=0), axis=1).sum())
    return float(np.hypot(*error[:2])), float(error[2]), distance


def test_exact_and_rigid_follow_the_sample_with_its_reverse_and_spin(sample):
    """Bounds of twice the measured final error (the same on the avx2 and sse4 paths, .ci/fp-path): gpo-exact 0.023 %
    and 0.088 deg, gpo-rigid 0.137 % and 0.50 deg on the sample's 3.26 m."""
    path, _, truth = sample
    for method, bound_percent, bound_deg in (("gpo-exact", 0.05, 0.2), ("gpo-rigid", 0.3, 1.0)):
        result = run(path, load_config().replace(method=method), progress=False)
        position, heading, distance = _final_error(result.trajectory, truth)
        assert 100 * position / distance < bound_percent, method
        assert abs(np.degrees(heading)) < bound_deg, method
        assert result.summary()["frames_measured"] == len(result.records) - 1


def test_the_papers_model_reads_reverse_driving_as_forward(sample):
    path, _, truth = sample
    result = run(path, load_config().replace(method="gpo"), progress=False)
    assert result.error is None and result.summary()["frames_measured"] == len(result.records) - 1
    position, _, distance = _final_error(result.trajectory, truth)
    assert position / distance > 0.1  # the sample's reverse leg and spin are read wrongly: measured 32 %


def _write(path, frames, stamps, images=None, format="ros1"):
    rig = t265_rig()
    with BagWriter(path, format) as bag:
        for index, (frame, stamp) in enumerate(zip(frames, stamps, strict=True)):
            image = frame.image if images is None else images[index]
            bag.add_image(rig.image_topic, int(stamp), image, rig.frame_id)
    return path


@pytest.mark.parametrize("format", ["ros1", "ros2", "ros2-mcap"])
def test_every_bag_format_gives_the_same_trajectory(sample, tmp_path, format):
    _, frames, _ = sample
    name = "short.bag" if format == "ros1" else "short"
    bag = _write(tmp_path / name, frames, [f.stamp_ns for f in frames], format=format)
    result = run(bag, progress=False)
    reference = run(_write(tmp_path / "reference.bag", frames, [f.stamp_ns for f in frames]), progress=False)
    np.testing.assert_array_equal(result.trajectory.positions, reference.trajectory.positions)
    assert result.trajectory.path_length > 0.3  # measured 0.67 m: a path, not one left standing


def test_duplicates_gaps_and_a_floor_without_texture_are_flagged_and_the_run_goes_on(sample, tmp_path):
    _, frames, truth = sample
    stamps = [f.stamp_ns for f in frames]
    stamps[40:] = [s + 3_000_000_000 for s in stamps[40:]]  # a 3 s gap before frame 40
    stamps[20] = stamps[19]  # frame 20 repeats frame 19's stamp
    images = [f.image for f in frames]
    images[30:33] = [np.full_like(images[0], 90)] * 3  # three frames of a blank floor
    result = run(_write(tmp_path / "bad.bag", frames, stamps, images), progress=False)
    summary = result.summary()
    assert summary["frames"] == FRAMES
    assert summary["frames_skipped"] == 1
    assert summary["frames_held"] == 1
    # three blank frames, and the one after them has nothing to start from
    assert summary["frames_coasted"] == 4
    assert summary["flags"] == {"no texture": 4, "stamp out of order": 1, "frame gap": 1}
    assert "frames_slower_layer" not in summary  # the sample's wood floor has one layer
    # coasting over the blank frames (four frames, 6 cm of travel while speeding up) costs under a centimetre
    before_gap = result.trajectory
    position, _, _ = _final_error(
        type(before_gap)(before_gap.stamps_ns[:38], before_gap.positions[:38], before_gap.quaternions[:38]), truth
    )
    assert position < 0.01


def test_frames_out_of_order_are_skipped(sample):
    _, frames, _ = sample
    odometer = FloorOdometer(load_config())
    records = [odometer.step(frames[i].stamp_ns, frames[i].image) for i in (0, 1, 2, 1, 3)]
    assert [r.status for r in records] == ["first", "measured", "measured", "skipped", "measured"]
    assert "0.033 s before" in records[3].flag


def test_missing_topic_and_wrong_image_size_are_clear_errors(sample, tmp_path):
    _, frames, _ = sample
    bag = _write(tmp_path / "ok.bag", frames[:3], [f.stamp_ns for f in frames[:3]])
    with pytest.raises(ValueError, match="/camera/fisheye1/image_raw"):
        run(bag, topic="/camera/fisheye2/image_raw", progress=False)
    small = [f.image[:400, :424] for f in frames[:3]]
    with pytest.raises(ValueError, match=r"424 x 400 pixels, but the camera of the config's rig 't265' is 848 x 800"):
        run(_write(tmp_path / "small.bag", frames[:3], [f.stamp_ns for f in frames[:3]], small), progress=False)


def test_a_run_that_stops_early_keeps_and_writes_what_it_computed(sample, tmp_path, monkeypatch, capsys):
    path, frames, _ = sample

    def broken(self, *args, **kwargs):
        yield from frames[:10]
        raise ValueError("message 10 is damaged")

    monkeypatch.setattr(Recording, "frames", broken)
    assert main(["run", str(path), "--out", str(tmp_path / "traj.tum")]) == 1
    assert "stopped early after 10 frames: message 10 is damaged" in capsys.readouterr().err
    assert len((tmp_path / "traj.tum").read_text().splitlines()) == 11  # a header and ten poses
    assert "stopped_early: 'after 10 frames" in (tmp_path / "traj.summary.yaml").read_text()


def test_config_round_trip_and_the_default(tmp_path):
    config = load_config()
    rig = t265_rig()
    assert config.rig.camera == rig.camera
    np.testing.assert_allclose(config.rig.mount.position, rig.mount.position)
    np.testing.assert_allclose(config.rig.mount.rotation.as_matrix(), rig.mount.rotation.as_matrix(), atol=1e-15)
    changed = config.replace(method="gpo-rigid", vector="mean")
    again = load_config(save_config(tmp_path / "rig.yaml", changed))
    assert (again.method, again.vector, again.klt, again.model) == ("gpo-rigid", "mean", config.klt, config.model)
    assert again.fusion == config.fusion
    np.testing.assert_array_equal(again.floor.affine, config.floor.affine)
    text = (tmp_path / "rig.yaml").read_text().replace("max_corners", "corners")
    (tmp_path / "bad.yaml").write_text(text)
    with pytest.raises(ValueError, match=r"bad\.yaml: klt\.corners: unknown key; did you mean max_corners\?"):
        load_config(tmp_path / "bad.yaml")
    with pytest.raises(ValueError, match="unknown method"):
        config.replace(method="magic")


def test_a_config_without_a_floor_patch_gets_the_shipped_configs(tmp_path):
    document = yaml.safe_load(save_config(tmp_path / "rig.yaml", load_config()).read_text())
    document["floor_image"] = {"route": "analytic"}
    (tmp_path / "bare.yaml").write_text(yaml.safe_dump(document))
    bare, shipped = load_config(tmp_path / "bare.yaml").floor, load_config().floor
    assert (bare.width, bare.height) == (shipped.width, shipped.height) == (200, 200)
    np.testing.assert_array_equal(bare.affine, shipped.affine)


def test_cli_run_writes_trajectory_and_summary_and_a_bag_with_the_estimate(sample, tmp_path, capsys):
    path, _, _ = sample
    out, copy = tmp_path / "t.tum", tmp_path / "with_estimate.bag"
    arguments = ["run", str(path), "--out", str(out), "--method", "gpo-exact", "--write-bag", str(copy)]
    assert main(arguments) == 0
    printed = capsys.readouterr().out
    assert "frames/s" in printed and "distance travelled" in printed and "/gpo/odom" in printed
    assert (tmp_path / "t.summary.yaml").exists()
    written = Trajectory.read_tum(out)
    with Recording(copy) as copied, Recording(path) as original:
        estimate = copied.trajectory("/gpo/odom")
        counts = {t.name: t.count for t in original.topics()}
        assert {t.name: t.count for t in copied.topics() if t.name != "/gpo/odom"} == counts
    np.testing.assert_array_equal(estimate.stamps_ns, written.stamps_ns)
    np.testing.assert_allclose(estimate.positions, written.positions, atol=1e-9)


# bounds of twice the measured final error, worst of the machine's, avx2 and sse4 paths (.ci/fp-path), measured
# from keyframes: the ortho-GPI 0.026 % and 0.145 deg, the plain GPI (metric near its corners) 0.134 % and 0.393 deg
@pytest.mark.parametrize(("route", "bound_percent", "bound_deg"), [("ortho-gpi", 0.053, 0.29), ("gpi", 0.27, 0.79)])
def test_the_chessboard_routes_follow_the_sample(sample, route, bound_percent, bound_deg):
    path, _, truth = sample
    result = run(path, route_config("gpo-exact", route), progress=False)
    position, heading, distance = _final_error(result.trajectory, truth)
    assert result.config.route == route
    assert 100 * position / distance < bound_percent and abs(np.degrees(heading)) < bound_deg


def test_a_chessboard_route_needs_a_readable_board_image(tmp_path):
    config = load_config()
    with pytest.raises(ValueError, match="unknown route"):
        config.replace(route="magic")
    with pytest.raises(ValueError, match="needs board_image"):
        config.replace(route="gpi")
    missing = config.replace(route="gpi", board_image=tmp_path / "none.png", board=FLOOR_BOARDS["t265"])
    with pytest.raises(ValueError, match=r"none\.png"):
        FloorOdometer(missing)
    again = load_config(save_config(tmp_path / "rig.yaml", route_config("gpo", "ortho-gpi")))
    expected = ("ortho-gpi", FLOOR_BOARDS["t265"], floor_board_path("t265"))
    assert (again.route, again.board, again.board_image) == expected


def test_fused_runs_the_floor_odometry_and_the_tracking_camera_through_the_ekf(sample, tmp_path):
    path, frames, truth = sample
    config = load_config()
    exact = config.replace(method="fused", fusion=dataclasses.replace(config.fusion, floor_method="gpo-exact"))
    result = run(path, exact, progress=False)
    np.testing.assert_array_equal(result.trajectory.stamps_ns, result.floor_trajectory.stamps_ns)
    with Recording(path) as recorded:
        tracking = tracking_path(recorded, config.fusion)
    fused, _, _ = _final_error(result.trajectory, truth)
    camera = final_error(tracking, truth).position_m
    # the floor's exact arcs pull the camera's 2 % scale error in: measured 0.64 mm against the camera's 13.3 mm
    assert fused < 0.1 * camera
    bag = _write(tmp_path / "no-odometry.bag", frames[:5], [f.stamp_ns for f in frames[:5]])
    with pytest.raises(ValueError, match="/camera/odom/sample"):
        run(bag, config.replace(method="fused"), progress=False)


def test_a_runs_floor_run_is_what_the_filter_reads_of_its_frames():
    """``OdometryResult.floor_run``: the frames not skipped, each step's inliers (0 where not measured) and spread."""
    nan = float("nan")
    records = [
        FrameRecord(0, (0.0, 0.0, 0.0), 0, 0, 0, nan, "first"),
        FrameRecord(100_000_000, (0.01, 0.0, 0.0), 50, 40, 30, 0.5, "measured"),
        FrameRecord(200_000_000, (0.01, 0.0, 0.0), 0, 0, 0, nan, "skipped", "unreadable"),
        FrameRecord(300_000_000, (0.02, 0.0, 0.001), 45, 20, 12, 1.25, "coasted", "too few tracks"),
        FrameRecord(400_000_000, (0.03, 0.001, 0.002), 60, 50, 44, 0.25, "measured"),
    ]
    floor = OdometryResult(records, 2.5, load_config(), "a.bag", "/camera").floor_run
    np.testing.assert_array_equal(floor.trajectory.stamps_ns, [0, 100_000_000, 300_000_000, 400_000_000])
    np.testing.assert_allclose(floor.trajectory.positions[:, :2], [[0, 0], [0.01, 0], [0.02, 0], [0.03, 0.001]])
    assert floor.inliers.tolist() == [0, 30, 0, 44]
    np.testing.assert_array_equal(floor.spread_px, [nan, 0.5, 1.25, 0.25])
    assert floor.frames_per_second == 2.0  # five frames read in 2.5 s


def test_the_summary_counts_the_frames_whose_flow_held_a_slower_layer():
    """A tenth or more of a frame's kept vectors in a slower layer (``gpo.motion.layers.slower_layer``) counts the
    frame."""
    nan = float("nan")
    records = [
        FrameRecord(0, (0.0, 0.0, 0.0), 0, 0, 0, nan, "first"),
        FrameRecord(100_000_000, (0.01, 0.0, 0.0), 50, 40, 30, 0.5, "measured", None, 4),  # a tenth: counted
        FrameRecord(200_000_000, (0.02, 0.0, 0.0), 50, 40, 30, 0.5, "measured", None, 3),  # under a tenth
        FrameRecord(300_000_000, (0.03, 0.0, 0.0), 50, 40, 36, 0.5, "measured", None, 0),
        FrameRecord(400_000_000, (0.04, 0.0, 0.0), 50, 10, 9, 0.5, "measured", None, 5),  # half: counted
    ]
    assert OdometryResult(records, 1.0, load_config(), "a.bag", "/camera").summary()["frames_slower_layer"] == 2


def test_a_runs_cautions_name_each_cause_behind_a_tenth_of_its_steps():
    """Steps not measured, steps holding a slower layer and increments the filter refused: each named once it is
    behind ``CAUTION_SHARE`` (a tenth) of the steps, and not before."""
    nan = float("nan")

    def records(slower: int, coasted: int, plain: int) -> list[FrameRecord]:
        first = [FrameRecord(0, (0.0, 0.0, 0.0), 0, 0, 0, nan, "first")]
        kinds = [("measured", None, 8)] * slower + [("coasted", "too few tracks kept (3 of 60)", 0)] * coasted
        kinds += [("measured", None, 0)] * plain
        return first + [
            FrameRecord((k + 1) * 10**8, (0.01 * k, 0.0, 0.0), 60, 40, 30, 0.5, status, flag, layer)
            for k, (status, flag, layer) in enumerate(kinds)
        ]

    def cautions(slower: int, coasted: int, plain: int, refused: int | None = None) -> list[str]:
        fusion = None if refused is None else {"refused_by_nis_gate": refused}
        return OdometryResult(records(slower, coasted, plain), 1.0, load_config(), "a", "/c", fusion=fusion).cautions

    assert cautions(9, 9, 82) == [] and cautions(9, 9, 82, refused=9) == []  # under a tenth of 100 steps each
    found = cautions(10, 10, 80, refused=10)
    assert found[0] == "10 of 100 steps not measured: mostly too few tracks kept"
    assert found[1].startswith("10 of 100 steps held a second, slower layer of motion")
    assert found[2].startswith("the filter refused 10 increments in 100 steps")
    result = OdometryResult(records(0, 10, 90), 1.0, load_config(), "a", "/c")
    assert result.summary()["cautions"] == result.cautions and not result.flagged  # a caution is not a flag
    overview = records(0, 0, 100)
    overview[1:11] = [dataclasses.replace(r, overview=True) for r in overview[1:11]]
    result = OdometryResult(overview, 1.0, load_config(), "a", "/c")
    assert result.cautions == ["10 of 100 steps measured on the whole view, the tracks disagreeing with it (a glossy "
                               "floor's reflections?)"] and result.summary()["frames_overview"] == 10
