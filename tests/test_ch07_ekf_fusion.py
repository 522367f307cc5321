"""Chapter 07's helpers: ellipses that hold what they claim, robots drawn from the filter's own model, the gate's log,
a relocalised camera, and the figures drawn from them."""

import math

import matplotlib.pyplot as plt
import numpy as np
import pytest
from scipy.stats import chi2

import gpo.fusion.ekf
from gpo.book.ch07_ekf_fusion import (
    covariance_ellipse,
    draw_bias_estimates,
    draw_clouds,
    draw_lag,
    draw_nis,
    draw_quality,
    ellipse_scale,
    final_offset,
    gate_log,
    inside_ellipse,
    model_draws,
    relocalised,
    step_errors,
)
from gpo.fusion import FusionSettings, fuse
from gpo.fusion.ekf import ProcessNoise, motion_jacobian, process_covariance
from gpo.io.trajectory import Trajectory
from gpo.odometry.kinematics import arc_increment, compose, integrate

pytestmark = pytest.mark.usefixtures("close_figures")  # conftest.py


def _arc(rate_hz: float, seconds: float = 3.0, sigma=(0.0, 0.0), seed: int = 0) -> Trajectory:
    """A 0.4 m/s, 0.3 rad/s arc sampled at ``rate_hz``, each step's (v, omega) with white noise ``sigma``."""
    rng = np.random.default_rng(seed)
    steps = round(seconds * rate_hz)
    velocities = np.array([0.4, 0.3]) + rng.standard_normal((steps, 2)) * sigma
    increments = arc_increment(velocities[:, 0], velocities[:, 1], 1 / rate_hz)
    stamps = np.round(np.arange(steps + 1) / rate_hz * 1e9).astype(np.int64)
    return Trajectory.from_planar(stamps, *integrate(increments).T, frame_id="odom")


def _measured(floor: Trajectory) -> np.ndarray:
    inliers = np.full(len(floor), 100)
    inliers[0] = 0
    return inliers


def test_an_ellipse_reaches_its_confidence():
    covariance = np.array([[4.0, 1.5], [1.5, 1.0]])
    _, ax = plt.subplots()
    patch = covariance_ellipse(ax, np.array([1.0, 2.0]), covariance, 0.95)
    values = np.linalg.eigvalsh(covariance)
    assert patch.width == pytest.approx(2 * ellipse_scale(0.95) * math.sqrt(values[1]))
    assert patch.height == pytest.approx(2 * ellipse_scale(0.95) * math.sqrt(values[0]))
    assert ellipse_scale(0.95) == pytest.approx(math.sqrt(chi2.ppf(0.95, 2)))
    # points on the long axis's end are on the boundary; the share of Gaussian draws inside is the confidence
    rng = np.random.default_rng(3)
    draws = rng.multivariate_normal([1.0, 2.0], covariance, 20000)
    assert inside_ellipse(draws, [1.0, 2.0], covariance, 0.95).mean() == pytest.approx(0.95, abs=0.01)


def test_an_ellipse_keeps_its_centre_when_the_callers_array_moves_on():
    centre = np.array([0.5, -0.5])
    _, ax = plt.subplots()
    patch = covariance_ellipse(ax, centre, np.eye(2))
    centre[:] = 9.0
    assert tuple(patch.center) == (0.5, -0.5)


def test_clouds_count_the_points_inside_each_ellipse():
    _, ax = plt.subplots()
    points = np.array([[0.0, 0.0], [0.001, 0.0], [0.1, 0.0]])  # metres; the ellipse's reach is 2.45 mm
    draw_clouds({"filter": (points, 1e-6 * np.eye(2))}, ax=ax)
    assert ax.lines[0].get_label() == "filter: 2 of 3 inside"
    np.testing.assert_allclose(ax.lines[0].get_xydata(), 1e3 * points)


def test_drawn_robots_spread_as_the_filters_prediction_says():
    """Robots drawn from the process model end, on average, on the held arc, and their scatter is what the filter's
    own prediction (F P F' + Q, step by step) says, to the linearisation's few per cent."""
    state, noise, dt = np.array([0.0, 0.0, 0.0, 0.45, 0.56]), ProcessNoise(), 1 / 30
    draws = model_draws(state, noise, dt, 30, 4000, seed=2)
    assert draws.shape == (30, 4000, 3)
    np.testing.assert_array_equal(draws, model_draws(state, noise, dt, 30, 4000, seed=2))
    x, covariance = state.copy(), np.zeros((5, 5))
    for _ in range(30):
        jacobian = motion_jacobian(x, dt)
        covariance = jacobian @ covariance @ jacobian.T + process_covariance(x, dt, noise)
        x[:3] = compose(x[:3], arc_increment(x[3], x[4], dt))
    ends = draws[-1]
    np.testing.assert_allclose(ends.mean(axis=0), x[:3], atol=0.003)
    np.testing.assert_allclose(np.cov(ends[:, :2].T), covariance[:2, :2], rtol=0.1, atol=1e-7)


def test_the_gate_log_records_every_step_offered_and_restores_the_filter():
    floor, tracking = _arc(30.0, sigma=(0.004, 0.02), seed=1), _arc(200.0, sigma=(0.02, 0.02), seed=2)
    jumped = relocalised(tracking, 1.5, (0.2, -0.15))
    with gate_log() as log:
        gated = fuse(floor, _measured(floor), jumped, FusionSettings())
    assert gated.refused == 1
    refused = [entry for entry in log if not entry[3]]
    assert len(refused) == 1 and refused[0][1] == "tracking" and refused[0][0] == pytest.approx(1.5, abs=0.01)
    assert refused[0][2] > gpo.fusion.ekf.MAX_NIS
    assert {entry[1] for entry in log} == {"floor", "tracking"}
    assert len(log) == 2 * (len(floor) - 1)  # each floor frame: one floor step and one rate-matched camera step
    with gate_log(math.inf) as open_log:
        ungated = fuse(floor, _measured(floor), jumped, FusionSettings())
    assert ungated.refused == 0 and all(entry[3] for entry in open_log)
    # after the blocks the package is its own again: the same result as a run never logged
    assert gpo.fusion.ekf.MAX_NIS == 50.0
    again = fuse(floor, _measured(floor), jumped, FusionSettings())
    np.testing.assert_array_equal(again.trajectory.positions, gated.trajectory.positions)


def test_the_gate_log_restores_the_filter_after_an_error():
    add, nis = gpo.fusion.ekf.OdometryFusion.add, gpo.fusion.ekf._nis
    with pytest.raises(RuntimeError), gate_log(1.0):
        raise RuntimeError("stop")
    assert gpo.fusion.ekf.OdometryFusion.add is add and gpo.fusion.ekf._nis is nis and gpo.fusion.ekf.MAX_NIS == 50.0


def test_a_relocalised_path_jumps_once():
    path = _arc(200.0, seconds=1.0)
    jumped = relocalised(path, 0.5, (0.2, -0.15))
    moved = jumped.positions - path.positions
    after = path.times - path.times[0] >= 0.5
    np.testing.assert_allclose(moved[after], np.tile([0.2, -0.15, 0.0], (after.sum(), 1)))
    np.testing.assert_array_equal(moved[~after], 0.0)
    np.testing.assert_array_equal(jumped.quaternions, path.quaternions)


def test_a_path_against_itself_has_no_error():
    truth = _arc(120.0)
    path = _arc(30.0)
    np.testing.assert_allclose(final_offset(path, truth), 0.0, atol=1e-6)
    read, exact = step_errors(path, truth)
    np.testing.assert_allclose(read, exact, atol=1e-5)
    assert read[:, 0] == pytest.approx(0.4, abs=1e-3)


def test_the_figures_draw_what_they_are_given():
    _, ax = plt.subplots()
    draw_nis([(0.1, "floor", 1.0, True), (0.2, "tracking", 80.0, False)], ax=ax)
    assert {line.get_label() for line in ax.lines} >= {"floor steps", "tracking steps", "refused", "the gate, 50"}
    _, ax = plt.subplots()
    draw_quality(np.array([0.01, 0.1]), np.array([0.001, -0.002]), 6e-4, 0.04, ax=ax)
    np.testing.assert_allclose(ax.lines[0].get_ydata(), [1.0, -2.0])
    axes = draw_bias_estimates([[0.01, 1e-3]], [[0.012, 0.9e-3]], [[0.004, 0.3e-3]])
    assert axes[0].get_xlabel() == "the simulator's scale error [%]"
    _, bottom = draw_lag(np.array([0.0, 1.0]), np.array([0.0, 0.5]), {"late": np.array([0.0, 0.008])}, 1 / 30)
    np.testing.assert_allclose(bottom.lines[0].get_ydata(), [0.0, 8.0])
