"""gpo.experiments.table4 against numbers computed here: the table's final errors are those of the tracking camera, a
fresh floor run and its EKF (and, for the floor run, those of a hand-made association and first-pose placement); its
text names every row and path; a kept floor run (gpo.experiments.runs) is what a fresh run computes; and each config
is kept in its own file. On the sample recording, so that it runs in seconds."""

import numpy as np
import pytest

from gpo.experiments import runs
from gpo.experiments.runs import floor_run, route_config
from gpo.experiments.table4 import PAPER_TABLE4, ROWS, Row, format_fusion_accuracy, reproduce_table4
from gpo.fusion import fuse
from gpo.io import cache
from gpo.io.bag import Recording
from gpo.metrics import MAX_STAMP_DIFFERENCE_S, final_error
from gpo.pipeline.config import load_config
from gpo.pipeline.run import tracking_path
from gpo.sim.record import GROUND_TRUTH_TOPIC, recording

CAMERA, FLOOR, FUSED = Row("camera"), Row("floor", "gpo-exact", "analytic"), Row("fused", "gpo-exact", "analytic")


@pytest.fixture(scope="module")
def sample():
    """(bag, truth, the tracking camera's base_link path) of the sample recording."""
    bag = recording("sample", progress=False)
    with Recording(bag) as recorded:
        return bag, recorded.trajectory(GROUND_TRUTH_TOPIC), tracking_path(recorded, load_config().fusion)


@pytest.fixture(scope="module")
def table(sample):
    return reproduce_table4(paths=("sample",), rows=(CAMERA, FLOOR, FUSED))


@pytest.fixture
def empty_cache(tmp_path, monkeypatch):
    """Floor runs kept in an empty cache folder (the sample recording's path was found before)."""
    monkeypatch.setenv(cache.ENVIRONMENT_VARIABLE, str(tmp_path))
    return tmp_path / "runs"


def _kept_files(folder):
    return sorted(path.name for path in folder.rglob("*.npz"))


def test_each_row_holds_the_final_error_of_the_run_made_here(sample, table):
    bag, truth, tracking = sample
    floor = floor_run(bag, route_config("gpo-exact", "analytic"), cache=False)  # computed now, not read back
    fused = fuse(floor.trajectory, floor.inliers, tracking, load_config().fusion, floor.spread_px).trajectory
    # The table's floor run is a kept one, which make test's runs on other floating-point paths (.ci/fp-path) read
    # from the machine's own path: there the two differ by 1 micrometre and 4.5 microradians on this path of 3.26 m
    # (OpenCV's SIMD width moves the tracks in their last bits); a row mixed up with another is millimetres off.
    for row, estimate in ((CAMERA, tracking), (FLOOR, floor.trajectory), (FUSED, fused)):
        expected, found = final_error(estimate, truth), table.evaluations[row]["sample"].final
        assert found.position_m == pytest.approx(expected.position_m, abs=1e-5), row.label
        assert found.heading_rad == pytest.approx(expected.heading_rad, abs=1e-5), row.label
        assert found.distance_m == pytest.approx(expected.distance_m, abs=1e-12), row.label
        assert found.poses == expected.poses, row.label
    metres = table.translation_errors_m()
    assert metres.shape == (3, 1)
    assert metres[1, 0] == pytest.approx(final_error(floor.trajectory, truth).position_m, abs=1e-5)


def test_the_floor_rows_final_error_by_hand(sample, table):
    """Nearest truth stamp for each estimate stamp within 5 ms, the first pose placed on the truth's, the distance of
    the last positions: the first paper's translation error without evo."""
    bag, truth, _ = sample
    estimate = floor_run(bag, route_config("gpo-exact", "analytic")).trajectory
    nearest = np.abs(truth.times[None, :] - estimate.times[:, None]).argmin(axis=1)
    close = np.abs(truth.times[nearest] - estimate.times) <= MAX_STAMP_DIFFERENCE_S
    positions, yaw = estimate.positions[close], estimate.yaw[close]
    true_positions, true_yaw = truth.positions[nearest[close]], truth.yaw[nearest[close]]
    turn = true_yaw[0] - yaw[0]
    rotation = np.array([[np.cos(turn), -np.sin(turn)], [np.sin(turn), np.cos(turn)]])
    placed = (positions[:, :2] - positions[0, :2]) @ rotation.T + true_positions[0, :2]
    distance = np.linalg.norm(np.diff(true_positions, axis=0), axis=1).sum()
    final = table.evaluations[FLOOR]["sample"].final
    assert final.poses == close.sum() > 400
    assert final.position_m == pytest.approx(np.linalg.norm(placed[-1] - true_positions[-1, :2]), abs=1e-9)
    assert final.distance_m == pytest.approx(distance, abs=1e-9)
    assert final.percent == pytest.approx(100 * final.position_m / distance, abs=1e-9)
    assert final.heading_rad == pytest.approx(np.angle(np.exp(1j * (yaw[-1] + turn - true_yaw[-1]))), abs=1e-9)
    mean = np.linalg.norm(placed - true_positions[:, :2], axis=1).mean()  # the suite's APE mean along the path
    assert table.ape_means_m()[1, 0] == pytest.approx(mean, abs=1e-9)
    assert f"{mean:9.3f}{mean:9.3f}{final.position_m:25.3f}" in table.format_ape_mean().splitlines()[2]


def test_the_text_names_every_row_and_path_with_its_numbers(table):
    text, averaged = table.format(), table.format_measures()
    distance = table.evaluations[CAMERA]["sample"].final.distance_m
    assert f"sample ({distance:.1f} m)" in text.splitlines()[0] and "mean" in text.splitlines()[0]
    assert "mean over sample" in averaged.splitlines()[0]
    lines = text.splitlines()[1:]
    assert len(lines) == 3
    for row, line, metres, share in zip(
        table.rows, lines, table.translation_errors_m()[:, 0], table.percent()[:, 0], strict=True
    ):
        cell = f"{metres:>8.3f} ({share:5.2f} %)"
        assert line == f"{row.label:<38}{cell}{cell}"  # one path: its mean is itself
        assert any(line.startswith(row.label) for line in averaged.splitlines())
    assert len({row.label for row in ROWS}) == len(ROWS)  # every row of the full table tells itself apart


def test_a_kept_floor_run_is_what_a_fresh_run_computes(sample, empty_cache, monkeypatch):
    bag = sample[0]
    config = route_config("gpo-exact", "analytic")
    fresh = floor_run(bag, config, cache=False)
    assert _kept_files(empty_cache) == []  # cache=False keeps nothing
    written = floor_run(bag, config)
    assert len(_kept_files(empty_cache)) == 1

    def no_run(*args, **kwargs):
        raise AssertionError("the kept run should have been read back, not computed")

    monkeypatch.setattr(runs, "run", no_run)
    read = floor_run(bag, config)
    for kept in (written, read):
        np.testing.assert_array_equal(kept.trajectory.stamps_ns, fresh.trajectory.stamps_ns)
        np.testing.assert_allclose(kept.trajectory.positions, fresh.trajectory.positions, rtol=0, atol=1e-12)
        np.testing.assert_allclose(np.angle(np.exp(1j * (kept.trajectory.yaw - fresh.trajectory.yaw))), 0, atol=1e-12)
        np.testing.assert_array_equal(kept.inliers, fresh.inliers)
    assert read.frames_per_second == written.frames_per_second  # the run's own speed, kept with it
    assert fresh.inliers.max() > 0 and fresh.inliers[0] == 0  # the first frame has no step


def test_each_config_is_kept_in_its_own_file(sample, empty_cache):
    bag = sample[0]
    exact = route_config("gpo-exact", "analytic")
    floor_run(bag, exact)
    floor_run(bag, exact)
    assert len(_kept_files(empty_cache)) == 1
    floor_run(bag, route_config("gpo-rigid", "analytic"))
    floor_run(bag, exact.replace(max_gap_s=0.25))  # the same method and route, another parameter
    names = _kept_files(empty_cache)
    assert len(names) == 3
    assert sum("-gpo-exact-analytic-" in name for name in names) == 2
    assert sum("-gpo-rigid-analytic-" in name for name in names) == 1


def test_a_drifted_tracking_camera_is_the_bags_own_for_the_bags_drift(sample):
    """``drifted_tracking`` makes the recording's tracking stream without rendering: for the preset's own drift and
    seed it is the bag's, to the nanometre."""
    from gpo.sim.drift import T265_DRIFT
    from gpo.sim.record import PRESETS

    _, _, tracking = sample
    again = runs.drifted_tracking("sample", T265_DRIFT, PRESETS["sample"].seed)
    np.testing.assert_array_equal(again.stamps_ns, tracking.stamps_ns)
    np.testing.assert_allclose(again.positions, tracking.positions, rtol=0, atol=1e-9)


def test_the_fusion_accuracy_text_gives_each_presets_median_and_worst_and_the_outage_count():
    runs = [
        {"preset": preset, "floor_final_percent": floor, "camera_final_percent": camera, "fused_final_percent": fused}
        for preset, floor, camera, fused in (
            ("long1", 0.04, 1.0, 0.03), ("long1", 0.04, 3.0, 0.05), ("long1", 0.04, 2.0, 0.04),
            ("long1-outages", 16.0, 1.0, 0.10), ("long1-outages", 16.0, 2.0, 0.40),
        )
    ]
    summary = {"runs_within": "3/3", "worst_ratio": 1.25, "worst_excess_percent": 0.01}
    text = format_fusion_accuracy({"runs": runs, "summary": summary})
    lines = text.splitlines()
    assert lines[1].split() == ["long1", "3", "0.04", "2.00", "0.040", "0.050"]
    assert lines[2].split() == ["long1-outages", "2", "16.00", "1.50", "0.250", "0.400"]
    assert "in 3/3 runs (worst 1.250 x" in text
    assert lines[-1] == "with floor outages, fused at most 0.400 % (target 0.3 %: met in 1 of 2 runs)"
    outages_only = format_fusion_accuracy({"runs": runs, "summary": summary}, outages_only=True)
    assert "long1 " not in outages_only and "1.1 x" not in outages_only


def test_the_papers_table4_is_every_row_and_test_it_prints():
    """Five rows (its T265 row serves both images) by three tests; each printed average within a ten-thousandth of its
    tests' mean; the same layout as the suite's table, the tests' lengths in the header."""
    errors = PAPER_TABLE4.translation_errors_m()
    assert errors.shape == (len(PAPER_TABLE4.rows), len(PAPER_TABLE4.paths)) == (5, 3)
    np.testing.assert_allclose(errors.mean(axis=1), PAPER_TABLE4.printed_means_m, rtol=0, atol=1e-4)
    header, *lines = PAPER_TABLE4.format().splitlines()
    assert "Test4 (12.8 m)" in header and "Test6 (17.0 m)" in header
    assert [line[:38].strip() for line in lines] == [row.label for row in PAPER_TABLE4.rows]
    assert "0.1195 ( 0.81 %)" in lines[1]  # GPO on the GPI: the printed average, the mean of its tests' per cent


def test_the_paper_rows_are_ranked_by_their_means_in_the_paper_and_here():
    """A made-up run of the paper's five rows whose means are the paper's but for the two GPO rows, swapped: those two
    ranks are marked as differing, the others not; each rank is that of the mean printed beside it."""
    from gpo.experiments.table4 import Table4

    means = dict(zip(PAPER_TABLE4.rows, PAPER_TABLE4.printed_means_m, strict=True))
    gpi, ortho = Row("floor", "gpo", "gpi"), Row("floor", "gpo", "ortho-gpi")
    means[gpi], means[ortho] = means[ortho], means[gpi]

    class Final:  # what format_ranks reads of an evaluation
        def __init__(self, metres):
            self.final = type("FinalError", (), {"position_m": metres})()

    rows = PAPER_TABLE4.rows
    table = Table4(rows, ("a",), {row: {"a": Final(means[row])} for row in rows}, {})
    header, *lines = table.format_ranks().splitlines()
    assert "the paper" in header and "here" in header
    differing = {line[:38].strip() for line in lines if line.endswith("rank differs")}
    assert differing == {gpi.label, ortho.label}
    paper_ranks = [int(line[38:44]) for line in lines]
    assert paper_ranks == [5, 4, 3, 2, 1]  # the paper: T265 worst, then GPO on the GPI, ..., the EKF on the ortho-GPI
