"""The odometry EKF against exact motions: velocity measurements, frames, consistency, bad input."""

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from scipy.stats import chi2

from gpo.fusion import FilterDiverged, OdometryFusion, ProcessNoise, velocity_measurement
from gpo.kinematics import arc_increment


@given(st.floats(-1.0, 1.0), st.floats(-2.0, 2.0), st.floats(0.005, 0.1))
def test_velocity_measurement_inverts_an_arc(v, omega, dt):
    measured = velocity_measurement(arc_increment(v, omega, dt), dt)
    expected = [v if abs(v) > 1e-12 else 0.0, omega]
    np.testing.assert_allclose(measured, expected, atol=1e-9)


def _drive(seconds=6.0, rate_hz=30.0, v=0.4, omega=0.3, sigma=(0.02, 0.02), seed=0):
    """A constant arc measured by one noisy (v, omega) source; the filter and the true final pose."""
    rng = np.random.default_rng(seed)
    dt = 1.0 / rate_hz
    fusion = OdometryFusion(0.0, ProcessNoise())
    covariance = np.diag(np.square(sigma))
    for k in range(1, round(seconds * rate_hz) + 1):
        measured = np.array([v, omega]) + rng.standard_normal(2) * sigma
        fusion.add(k * dt, arc_increment(*measured, dt), dt, covariance)
    return fusion, arc_increment(v, omega, seconds)


def test_a_constant_arc_is_followed():
    fusion, truth = _drive()
    assert np.hypot(*(fusion.state[:2] - truth[:2])) < 0.02
    assert abs(fusion.state[2] - truth[2]) < 0.02
    np.testing.assert_allclose(fusion.state[3:], [0.4, 0.3], atol=0.02)


def test_the_filter_is_consistent_over_many_runs():
    """The pose error's NEES averaged over 40 runs lies within the 99 % band of chi-square with 3 x 40 dof."""
    nees = []
    for seed in range(40):
        fusion, truth = _drive(seed=seed)
        error = fusion.state[:3] - truth
        nees.append(error @ np.linalg.solve(fusion.covariance[:3, :3], error))
    low, high = chi2.ppf([0.005, 0.995], 3 * 40) / 40
    assert low < np.mean(nees) < high


def test_two_sources_at_different_rates_beat_either():
    rng = np.random.default_rng(1)
    v, omega, seconds = 0.3, -0.2, 5.0
    sources = {"floor": (30.0, 0.03), "camera": (200.0, 0.08)}
    errors = {}
    for used in (("floor",), ("camera",), ("floor", "camera")):
        events = sorted((k / rate, name) for name in used for k in range(1, round(seconds * sources[name][0]) + 1)
                        for rate in [sources[name][0]])
        fusion = OdometryFusion(0.0)
        for time_s, name in events:
            rate, sigma = sources[name]
            measured = np.array([v, omega]) + rng.standard_normal(2) * sigma
            fusion.add(time_s, arc_increment(*measured, 1 / rate), 1 / rate, np.eye(2) * sigma**2)
        fusion.predict(seconds)
        errors[used] = np.hypot(*(fusion.state[:2] - arc_increment(v, omega, seconds)[:2]))
    assert errors["floor", "camera"] < min(errors["floor",], errors["camera",]) * 1.2


def test_bad_measurements_are_refused():
    fusion, _ = _drive(seconds=1.0)
    with pytest.raises(ValueError, match="back in time"):
        fusion.add(0.5, [0.01, 0.0, 0.0], 1 / 30, np.eye(2) * 1e-4)
    with pytest.raises(ValueError, match="finite"):
        fusion.add(1.1, [np.nan, 0.0, 0.0], 1 / 30, np.eye(2) * 1e-4)
    assert not fusion.add(1.2, [1.0, 0.0, 0.0], 1 / 30, np.eye(2) * 1e-4)  # 30 m/s: an outlier
    assert fusion.refused == 1


def test_a_broken_covariance_is_reported_not_carried_on():
    fusion = OdometryFusion(0.0)
    fusion._filter.P[3, 3] = np.nan
    with pytest.raises(FilterDiverged):
        fusion.predict(0.1)
