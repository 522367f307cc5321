"""The final error against cases worked by hand."""

import numpy as np
import pytest

from gpo.metrics import final_error
from gpo.trajectory import Trajectory


def _planar(stamps_s, x, y, yaw):
    return Trajectory.from_planar(np.round(np.asarray(stamps_s) * 1e9).astype(np.int64), x, y, yaw)


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


def test_final_error_refuses_trajectories_apart_in_time():
    t = np.linspace(0.0, 1.0, 11)
    truth = _planar(t, t, 0 * t, 0 * t)
    with pytest.raises(ValueError, match="match in time"):
        final_error(_planar(t + 100.0, t, 0 * t, 0 * t), truth)
