"""The second paper's Table 2 under its own definitions (``gpo.metrics.paper_table2``), against sums computed here."""

import numpy as np
import pytest

from gpo.io.trajectory import Trajectory
from gpo.metrics import paper_table2

STAMPS = np.arange(101, dtype=np.int64) * 100_000_000  # 10 Hz for 10 s


def straight_run(scale=1.01, heading_drift_rad=0.02):
    """The truth drives 1 m along x; the estimate reads every step ``scale`` times too long and drifts in heading."""
    x = np.linspace(0.0, 1.0, len(STAMPS))
    truth = Trajectory.from_planar(STAMPS, x, np.zeros_like(x), np.zeros_like(x))
    yaw = np.linspace(0.0, heading_drift_rad, len(STAMPS))
    estimate = Trajectory.from_planar(STAMPS, scale * x, np.zeros_like(x), yaw, frame_id="odom")
    return estimate, truth, x, yaw


def test_every_column_is_the_printed_definition_on_a_continuous_truth():
    estimate, truth, x, yaw = straight_run()
    row = paper_table2(estimate, truth)
    errors = 0.01 * x  # metres, the estimate's overshoot at each sample
    assert row.distance_m == pytest.approx(1.0)
    assert row.positioning_rmse_mm == pytest.approx(1e3 * np.sqrt(np.mean(errors**2)))
    assert row.heading_rmse_deg == pytest.approx(np.degrees(np.sqrt(np.mean(yaw**2))))
    assert row.final_error_mm == pytest.approx(10.0)
    assert row.final_error_percent == pytest.approx(1.0)
    assert row.final_heading_deg == pytest.approx(np.degrees(0.02))
    assert row.relative_error_percent == pytest.approx(1.0)  # every 10 mm step read 0.1 mm long
    assert row.samples == len(STAMPS)


def test_with_the_end_alone_the_relative_error_is_the_final_error_in_percent():
    """As the paper prints for its VI, VIII and IX, whose ground truth was the run's end."""
    estimate, truth, *_ = straight_run(scale=1.0)
    shifted = Trajectory.from_planar(STAMPS, estimate.positions[:, 0], np.linspace(0, 0.004, len(STAMPS)),
                                     np.zeros(len(STAMPS)), frame_id="odom")
    row = paper_table2(shifted, truth, samples_ns=np.zeros(0, np.int64))
    assert row.samples == 2
    assert np.isnan(row.positioning_rmse_mm) and np.isnan(row.heading_rmse_deg)  # the paper's dashes
    assert row.relative_error_percent == pytest.approx(row.final_error_percent)
    assert row.final_error_percent == pytest.approx(0.4)


def test_step_samples_give_the_error_per_step_over_the_step():
    """Ten steps of 0.1 m, the estimate 2 mm long on every second one: relative error = mean of (2 or 0) / 100 mm."""
    _, truth, x, _ = straight_run(scale=1.0)
    step_errors = np.where(np.arange(10) % 2 == 1, 0.002, 0.0)
    at_samples = x[::10] + np.concatenate([[0.0], np.cumsum(step_errors)])
    wrong_x = np.interp(x, x[::10], at_samples)
    wrong = Trajectory.from_planar(STAMPS, wrong_x, np.zeros_like(x), np.zeros_like(x), frame_id="odom")
    row = paper_table2(wrong, truth, samples_ns=STAMPS[::10])
    assert row.samples == 11
    assert row.relative_error_percent == pytest.approx(100 * np.mean(step_errors / 0.1))  # 1 %


def test_a_closed_loop_measured_at_its_end_divides_by_the_distance_travelled():
    """The AGV returns to its start: the displacement is nil, the paper's percentage is of the distance."""
    angle = np.linspace(0.0, 2 * np.pi, len(STAMPS))
    truth = Trajectory.from_planar(STAMPS, np.sin(angle), 1 - np.cos(angle), angle)
    estimate = Trajectory.from_planar(STAMPS, np.sin(angle) + 0.003 * angle / (2 * np.pi), 1 - np.cos(angle), angle,
                                      frame_id="odom")
    row = paper_table2(estimate, truth, samples_ns=np.zeros(0, np.int64))
    assert row.final_error_mm == pytest.approx(3.0, abs=1e-6)
    assert row.relative_error_percent == pytest.approx(100 * 0.003 / row.distance_m)


def test_a_truth_that_never_moves_has_no_relative_error():
    still = Trajectory.from_planar(STAMPS, np.zeros(len(STAMPS)), np.zeros(len(STAMPS)), np.linspace(0, 1, len(STAMPS)))
    with pytest.raises(ValueError, match="never moves"):
        paper_table2(still, still)
