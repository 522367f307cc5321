"""The metrics against cases worked by hand, against evo's own command line on the same files, and against
rpg_trajectory_evaluation's posyaw formula."""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from evo.core.trajectory import PoseTrajectory3D
from evo.tools import file_interface
from scipy.spatial.transform import Rotation

from gpo.io import datasets
from gpo.io.trajectory import Trajectory
from gpo.metrics import (
    MAX_STAMP_DIFFERENCE_S,
    associate,
    evaluate,
    final_error,
    paper_table2,
    place_on_truth,
    to_evo,
    truth_poses,
)


def _planar(stamps_s, x, y, yaw):
    return Trajectory.from_planar(np.round(np.asarray(stamps_s) * 1e9).astype(np.int64), x, y, yaw)


def _arc(yaw_drift_rad_per_s: float = 0.0) -> Trajectory:
    """20 s along a circle of radius 3 m at 10 Hz (9 m), heading along the path plus ``yaw_drift_rad_per_s`` * t."""
    t = np.linspace(0.0, 20.0, 201)
    angle = 0.15 * t
    return _planar(t, 3.0 * np.sin(angle), 3.0 * (1.0 - np.cos(angle)), angle + yaw_drift_rad_per_s * t)


def _moved(trajectory: Trajectory, yaw_deg: float, shift) -> Trajectory:
    """``trajectory`` in a frame turned by ``yaw_deg`` about z and shifted by ``shift`` (metres)."""
    return trajectory.compose((Rotation.from_euler("z", yaw_deg, degrees=True), np.asarray(shift, dtype=float)))


def test_final_error_places_the_first_pose_then_compares_the_last():
    t = np.linspace(0.0, 10.0, 101)
    truth = _planar(t, t, np.zeros_like(t), np.zeros_like(t))  # 10 m straight along x
    # the estimate starts elsewhere, turned by 90 degrees, and covers 2 % too much ground, ending 1 degree off
    estimate = _planar(t, 5.0 + 0 * t, 1.02 * t, np.pi / 2 + np.radians(1.0) * t / 10)
    error = final_error(estimate, truth)
    assert error.position_m == pytest.approx(0.2, abs=1e-9)
    assert error.percent == pytest.approx(2.0, abs=1e-7)
    assert np.degrees(error.heading_rad) == pytest.approx(1.0, abs=1e-9)
    assert error.poses == 101


def test_placing_on_the_truth_undoes_a_rigid_move_and_keeps_the_shared_stamps():
    truth = _arc()
    moved = _moved(truth, 37.0, [2.0, -1.0, 0.0])
    shorter = Trajectory(moved.stamps_ns[50:], moved.positions[50:], moved.quaternions[50:], "odom")
    placed, associated = place_on_truth(shorter, truth)
    np.testing.assert_array_equal(placed.stamps_ns, truth.stamps_ns[50:])
    np.testing.assert_array_equal(associated.stamps_ns, truth.stamps_ns[50:])
    np.testing.assert_allclose(placed.positions, truth.positions[50:], rtol=0, atol=1e-9)
    np.testing.assert_allclose(np.angle(np.exp(1j * (placed.yaw - truth.yaw[50:]))), 0.0, atol=1e-9)
    last = np.hypot(*(placed.positions[-1, :2] - associated.positions[-1, :2]))
    assert last == pytest.approx(final_error(shorter, truth).position_m, abs=1e-12)  # the same placing


def test_truth_poses_interpolate_between_poses_and_hold_at_the_ends():
    truth = _arc()  # 10 Hz: 0.15 rad/s of heading, the position on a circle
    poses = truth_poses(truth, [0.05, 10.0, -1.0, 25.0])
    np.testing.assert_allclose(poses[0], [*truth.positions[:2, :2].mean(axis=0), 0.0075], atol=1e-12)
    np.testing.assert_allclose(poses[1], [*truth.positions[100, :2], 1.5], atol=1e-12)
    np.testing.assert_allclose(poses[2], [0.0, 0.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(poses[3], [*truth.positions[-1, :2], 3.0], atol=1e-12)


def test_final_error_refuses_trajectories_apart_in_time():
    t = np.linspace(0.0, 1.0, 11)
    truth = _planar(t, t, 0 * t, 0 * t)
    with pytest.raises(ValueError, match="match in time"):
        final_error(_planar(t + 100.0, t, 0 * t, 0 * t), truth)


# --- cases worked by hand ---------------------------------------------------------------------------------------


@pytest.mark.parametrize("align", ["origin", "se2", "se3", "posyaw"])
def test_a_rigid_offset_leaves_no_error_after_alignment(align):
    truth = _arc()
    evaluation = evaluate(_moved(truth, 30.0, [2.0, -1.0, 0.0]), truth, align)
    assert evaluation.ape_m.max < 1e-9
    assert evaluation.rpe_m.max < 1e-9
    assert evaluation.final.position_m < 1e-9 and abs(evaluation.final.heading_rad) < 1e-9
    assert evaluation.heading_rmse_deg < 1e-7


def test_without_alignment_the_offset_is_the_error():
    truth = _arc()
    rotation, shift = Rotation.from_euler("z", 30.0, degrees=True), np.array([2.0, -1.0, 0.0])
    evaluation = evaluate(_moved(truth, 30.0, shift), truth, "none")
    offsets = np.linalg.norm(rotation.apply(truth.positions) + shift - truth.positions, axis=1)
    assert evaluation.ape_m.rmse == pytest.approx(np.sqrt(np.mean(offsets**2)), abs=1e-12)
    assert evaluation.ape_m.max == pytest.approx(offsets.max(), abs=1e-12)
    assert evaluation.final.position_m == pytest.approx(offsets[-1], abs=1e-12)  # the offset lies in the plane
    assert evaluation.heading_rmse_deg == pytest.approx(30.0, abs=1e-9)
    assert np.degrees(evaluation.final.heading_rad) == pytest.approx(30.0, abs=1e-9)
    assert evaluation.rpe_m.max < 1e-9  # the relative motion is untouched


def test_posyaw_removes_a_height_offset_that_se2_keeps():
    truth = _arc()
    estimate = _moved(truth, -40.0, [0.5, 1.0, 0.25])
    assert evaluate(estimate, truth, "posyaw").ape_m.max < 1e-9
    se2 = evaluate(estimate, truth, "se2")
    assert se2.ape_m.rmse == pytest.approx(0.25, abs=1e-9) and se2.ape_m.max == pytest.approx(0.25, abs=1e-9)
    assert se2.final.position_m < 1e-9  # the final error is measured in the floor plane


def test_se2_and_posyaw_agree_for_a_path_on_the_floor():
    truth = _arc()
    noise = np.random.default_rng(7).normal(0.0, 0.002, (len(truth), 3))  # 2 mm, in z too
    drifted = _arc(np.radians(0.1)).positions * 1.01 + noise
    estimate = Trajectory(truth.stamps_ns, drifted, _arc(np.radians(0.1)).quaternions)
    se2, posyaw = evaluate(estimate, truth, "se2"), evaluate(estimate, truth, "posyaw")
    assert se2.ape_m.rmse > 0.01
    assert posyaw.ape_m.rmse == pytest.approx(se2.ape_m.rmse, abs=1e-5)
    assert posyaw.final == se2.final and posyaw.heading_rmse_deg == se2.heading_rmse_deg


def test_a_scale_error_gives_its_final_error_percent():
    stamps = np.arange(81) * 0.1
    x = np.arange(81) * 0.125  # 10 m straight ahead in steps that add up to whole metres exactly
    truth = _planar(stamps, x, 0 * x, 0 * x)
    estimate = _planar(stamps, 1.03 * x, 0 * x, 0 * x)  # 3 % too long
    evaluation = evaluate(estimate, truth, "origin")
    assert evaluation.final.position_m == pytest.approx(0.3, abs=1e-12)
    assert evaluation.final.percent == pytest.approx(3.0, abs=1e-10)
    assert evaluation.rpe_m.max == pytest.approx(0.03, abs=1e-12) and evaluation.rpe_m.mean == pytest.approx(0.03)
    assert evaluation.drift_percent_per_m == pytest.approx(3.0, abs=1e-10)
    assert evaluation.ape_m.max == pytest.approx(0.3, abs=1e-12)
    assert final_error(estimate, truth).position_m == pytest.approx(0.3, abs=1e-12)  # the first paper's Table 4
    measures = evaluation.measures()
    assert measures["final_error_mm"] == pytest.approx(300.0) and measures["final_error_percent"] == pytest.approx(3.0)
    assert measures["ape_rmse_m"] == pytest.approx(0.03 * np.sqrt(np.mean(x**2)), abs=1e-12)
    assert measures["drift_percent_per_m"] == pytest.approx(3.0) and measures["heading_rmse_deg"] == 0.0
    # with a truth at every pose, the second paper's positioning RMSE and final error are the same numbers
    paper = paper_table2(estimate, truth)
    assert paper.positioning_rmse_mm == pytest.approx(1e3 * measures["ape_rmse_m"], abs=1e-9)
    assert paper.final_error_mm == pytest.approx(measures["final_error_mm"], abs=1e-9)


def test_a_straight_path_aligns_in_the_plane_but_not_in_space():
    t = np.linspace(0.0, 5.0, 51)
    truth = _planar(t, t, 0 * t, 0 * t)
    assert evaluate(_moved(truth, 10.0, [1.0, 2.0, 0.0]), truth, "se2").ape_m.max < 1e-9
    with pytest.raises(ValueError, match="cannot align by se3"):
        evaluate(truth, truth, "se3")


def test_a_yaw_drift_gives_known_heading_errors():
    rate = np.radians(0.2)  # rad/s, so 4 degrees after 20 s
    truth, estimate = _arc(), _arc(rate)
    evaluation = evaluate(estimate, truth, "origin")
    t = truth.times - truth.times[0]
    assert evaluation.heading_rmse_deg == pytest.approx(np.degrees(rate * np.sqrt(np.mean(t**2))), abs=1e-9)
    assert np.degrees(evaluation.final.heading_rad) == pytest.approx(4.0, abs=1e-9)
    np.testing.assert_allclose(evaluation.heading_errors_rad, rate * t, atol=1e-12)
    assert evaluation.ape_m.max < 1e-12 and evaluation.final.position_m < 1e-12


def test_the_table_shows_every_number():
    text = str(evaluate(_moved(_arc(), 0.0, [0.0, 0.01, 0.0]), _arc(), "none"))
    assert "alignment               none" in text
    assert "APE position [mm]           10.00    10.00    10.00    10.00" in text
    assert "final position error    10.0 mm" in text and "heading (yaw) error     rmse 0.000 deg" in text


# --- bad input -------------------------------------------------------------------------------------------------


def test_trajectories_without_overlap_are_refused_with_both_time_ranges():
    t = np.linspace(0.0, 1.0, 11)
    with pytest.raises(
        ValueError, match=r"do not overlap: the estimate spans 100\.000 \.\. 101\.000 s, the truth 0\.000"
    ):
        associate(_planar(t + 100.0, t, 0 * t, 0 * t), _planar(t, t, 0 * t, 0 * t))


def test_too_few_matching_stamps_are_refused_with_how_many():
    t = np.linspace(0.0, 1.0, 11)
    estimate_t = np.array([0.0, 0.55, 0.65, 0.75])  # only the first within 5 ms of a truth stamp
    with pytest.raises(ValueError, match=r"only 1 pose\(s\) of the estimate match the truth in time within 0.005 s"):
        associate(_planar(estimate_t, estimate_t, 0 * estimate_t, 0 * estimate_t), _planar(t, t, 0 * t, 0 * t))


@pytest.mark.parametrize("which", ["estimate", "truth"])
def test_nan_is_refused_naming_the_trajectory(which):
    good = to_evo(_arc())
    positions = good.positions_xyz.copy()
    positions[3, 1] = np.nan
    bad = PoseTrajectory3D(positions, good.orientations_quat_wxyz, good.timestamps)
    pair = (bad, good) if which == "estimate" else (good, bad)
    with pytest.raises(ValueError, match=f"the {which} has NaN or infinite numbers in 1 pose\\(s\\), first at pose 3"):
        associate(*pair)


def test_an_unknown_alignment_is_refused_with_the_choices():
    with pytest.raises(ValueError, match="unknown alignment 'sim3': expected one of none, origin, se2, se3, posyaw"):
        evaluate(_arc(), _arc(), "sim3")


# --- the same numbers as evo's command line and as rpg_trajectory_evaluation -------------------------------------

EVO_ALIGN_FLAGS = {"none": [], "origin": ["--align_origin"], "se3": ["--align"]}


def _written_pair(folder: Path) -> tuple[Path, Path]:
    """TUM files of a truth at 100 Hz, a little off the floor, and a drifting, noisy estimate at 30 Hz 1 ms later."""
    t = np.arange(0.0, 15.0, 0.01)
    angle = 0.2 * t
    positions = np.column_stack([4.0 * np.sin(angle), 2.0 * (1 - np.cos(angle)), 0.05 * np.sin(t)])
    rotations = Rotation.from_euler("ZYX", np.column_stack([angle, 0.02 * np.sin(t), 0.01 * np.cos(t)]))
    truth = Trajectory(np.round((1.7e9 + t) * 1e9).astype(np.int64), positions, rotations.as_quat())
    rng = np.random.default_rng(3)
    chosen = np.arange(0, len(t), 3)
    drift = Rotation.from_euler("z", 0.002 * t[chosen, None]) * Rotation.from_rotvec(
        rng.normal(0, 0.005, (len(chosen), 3))
    )
    estimate = Trajectory(
        truth.stamps_ns[chosen] + 1_000_000,
        1.02 * positions[chosen] + rng.normal(0.0, 0.01, (len(chosen), 3)) + [0.3, -0.2, 0.1],
        (drift * rotations[chosen]).as_quat(),
    )
    return estimate.write_tum(folder / "estimate.tum"), truth.write_tum(folder / "truth.tum")


@pytest.fixture(params=["rpg_trajectory_evaluation", "written"])
def tum_pair(request, tmp_path) -> tuple[Path, Path]:
    """(estimate, truth) TUM files: a real VI-SLAM run on EuRoC V1_02, or two small files written here."""
    if request.param == "written":
        return _written_pair(tmp_path)
    try:
        paths = datasets.rpg_trajectories()
    except datasets.DatasetUnavailable as error:
        pytest.skip(str(error))
    return paths["estimate"], paths["groundtruth"]


def _evo(tool: str, estimate: Path, truth: Path, flags: list[str], out: Path) -> dict:
    """The statistics ``evo_ape``/``evo_rpe`` save for ``truth`` (reference) and ``estimate``, associated as ours."""
    command = [str(Path(sys.executable).parent / tool), "tum", str(truth), str(estimate), *flags]
    command += ["--t_max_diff", str(MAX_STAMP_DIFFERENCE_S), "--save_results", str(out), "--no_warnings"]
    subprocess.run(command, check=True, capture_output=True, text=True)
    return file_interface.load_res_file(out).stats


def _statistics(statistics) -> dict:
    return {name: getattr(statistics, name) for name in ("rmse", "mean", "median", "max")}


@pytest.mark.parametrize("align", sorted(EVO_ALIGN_FLAGS))
def test_ape_equals_evo_ape_on_the_same_files(tum_pair, align, tmp_path):
    estimate, truth = tum_pair
    expected = _evo("evo_ape", estimate, truth, EVO_ALIGN_FLAGS[align], tmp_path / "ape.zip")
    ours = evaluate(Trajectory.read_tum(estimate), Trajectory.read_tum(truth), align)
    for name, value in _statistics(ours.ape_m).items():
        assert value == pytest.approx(expected[name], abs=1e-6), name


def test_rpe_equals_evo_rpe_on_the_same_files(tum_pair, tmp_path):
    estimate, truth = tum_pair
    flags = ["--delta", "1", "--delta_unit", "m", "--pairs_from_reference"]
    expected = _evo("evo_rpe", estimate, truth, flags, tmp_path / "rpe.zip")
    ours = evaluate(Trajectory.read_tum(estimate), Trajectory.read_tum(truth))
    assert ours.rpe_delta_m == 1.0
    for name, value in _statistics(ours.rpe_m).items():
        assert value == pytest.approx(expected[name], abs=1e-6), name


def test_posyaw_is_rpg_trajectory_evaluations(tum_pair):
    """Its align_umeyama(gt, est, known_scale=True, yaw_only=True): the yaw from get_best_yaw's closed form."""
    estimate, truth = (Trajectory.read_tum(path) for path in tum_pair)
    estimated, reference = associate(estimate, truth)
    p_es, p_gt = estimated.positions_xyz, reference.positions_xyz
    c = (p_es - p_es.mean(0)).T @ (p_gt - p_gt.mean(0))
    theta = np.pi / 2 - np.arctan2(c[0, 0] + c[1, 1], c[0, 1] - c[1, 0])
    rotation = Rotation.from_euler("z", theta).as_matrix()
    aligned = p_es @ rotation.T + (p_gt.mean(0) - rotation @ p_es.mean(0))
    errors = np.linalg.norm(aligned - p_gt, axis=1)
    ours = evaluate(estimate, truth, "posyaw")
    np.testing.assert_allclose(ours.estimate.positions, aligned, atol=1e-9)
    assert ours.ape_m.rmse == pytest.approx(np.sqrt(np.mean(errors**2)), abs=1e-9)
    assert ours.ape_m.max == pytest.approx(errors.max(), abs=1e-9)
