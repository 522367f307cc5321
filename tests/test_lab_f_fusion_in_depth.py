"""Lab F's helpers: the arc's own Jacobian and the filter run with it, the noise settings' variants, the NEES of a
fused path, and the saved acceptance runs drawn."""

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import gpo.fusion.ekf
from gpo.book.lab_f_fusion_in_depth import (
    arc_jacobian,
    arc_jacobian_in_filter,
    draw_acceptance,
    noise_variants,
    pose_nees,
    scaled_process_noise,
)
from gpo.fusion import FusedPath, FusionSettings
from gpo.fusion.ekf import motion_jacobian
from gpo.io.trajectory import Trajectory
from gpo.odometry.kinematics import arc_increment

pytestmark = pytest.mark.usefixtures("close_figures")  # conftest.py


def _arc_motion(state: np.ndarray, dt: float) -> np.ndarray:
    """The state moved ``dt`` seconds along the arc of its (v, omega), as the filter predicts it."""
    step = arc_increment(float(state[3]), float(state[4]), dt)
    cos, sin = math.cos(state[2]), math.sin(state[2])
    return np.array(
        [
            state[0] + cos * step[0] - sin * step[1],
            state[1] + sin * step[0] + cos * step[1],
            state[2] + step[2],
            state[3],
            state[4],
        ]
    )


@given(
    st.floats(-3.0, 3.0),
    st.floats(-1.0, 1.0),
    st.one_of(st.floats(-3.0, 3.0), st.floats(-1e-5, 1e-5), st.just(0.0)),
)
def test_the_arc_jacobian_is_the_arcs(theta, v, omega):
    state, dt, step = np.array([0.3, -0.2, theta, v, omega]), 1 / 30, 1e-6
    numeric = np.column_stack(
        [(_arc_motion(state + step * e, dt) - _arc_motion(state - step * e, dt)) / (2 * step) for e in np.eye(5)]
    )
    np.testing.assert_allclose(arc_jacobian(state, dt), numeric, atol=1e-8)


def test_the_first_order_jacobian_leaves_out_what_omega_does_to_the_position():
    """Straight ahead at v, the arc's Jacobian moves the position sideways by v dt^2 / 2 per rad/s of omega; eq. 34's
    (the filter's) does not; the rest agrees."""
    state, dt = np.array([0.0, 0.0, 0.0, 0.45, 0.0]), 1 / 30
    arc, first_order = arc_jacobian(state, dt), motion_jacobian(state, dt)
    np.testing.assert_allclose(arc[:2, 4], [0.0, 0.45 * dt**2 / 2], atol=1e-15)
    np.testing.assert_array_equal(first_order[:2, 4], 0.0)
    np.testing.assert_allclose(arc[:, :4], first_order[:, :4], atol=1e-15)


def test_the_filter_runs_with_the_arcs_jacobian_only_inside_the_block():
    original = gpo.fusion.ekf.motion_jacobian
    with arc_jacobian_in_filter():
        assert gpo.fusion.ekf.motion_jacobian is arc_jacobian
        fusion = gpo.fusion.ekf.OdometryFusion(0.0, sources=("floor",), calibrated=None)
        fusion._filter.x[3:5] = [0.4, 0.3]
        fusion.predict(0.1)
    assert gpo.fusion.ekf.motion_jacobian is original
    with pytest.raises(RuntimeError), arc_jacobian_in_filter():
        raise RuntimeError("stop")
    assert gpo.fusion.ekf.motion_jacobian is original


def test_the_variants_change_what_they_say_and_nothing_else():
    settings = FusionSettings()
    variants = noise_variants(settings)
    assert variants["default"] is settings
    assert variants["floor sigmas x 3"].floor_speed_sigma_mps == pytest.approx(3 * settings.floor_speed_sigma_mps)
    assert variants["no bias states"].tracking_scale_sigma == 0.0
    assert variants["trust the camera only"].tracking_yaw_bias_sigma_radps == 0.0
    assert variants["trust the floor only"].tracking_jitter_m == pytest.approx(1000 * settings.tracking_jitter_m)
    assert variants["process noise x 10"] == scaled_process_noise(settings, 10.0)
    assert variants["process noise / 10"].angular_accel_radps2 == pytest.approx(0.1 * settings.angular_accel_radps2)
    assert variants["process noise / 10"].floor_speed_sigma_mps == settings.floor_speed_sigma_mps


def test_pose_nees_is_the_errors_over_the_covariance():
    stamps = np.array([0, 1, 2]) * 10**8
    truth = Trajectory.from_planar(
        np.arange(0, 3 * 10**8, 10**7), np.linspace(0, 0.29, 30), np.zeros(30), np.zeros(30), frame_id="odom"
    )
    estimate = Trajectory.from_planar(stamps, [0.0, 0.11, 0.2], [0.0, 0.0, -0.02], [0.0, 0.0, 0.01], frame_id="odom")
    covariances = np.tile(np.diag([1e-4, 4e-4, 1e-4, 1, 1, 1, 1]), (3, 1, 1))
    fused = FusedPath(estimate, covariances, np.zeros((3, 2)), 0, {})
    np.testing.assert_allclose(pose_nees(fused, truth), [0.01**2 / 1e-4, 0.02**2 / 4e-4 + 0.01**2 / 1e-4], atol=1e-9)
    np.testing.assert_allclose(pose_nees(fused, truth, block=(1,)), [0.0, 1.0], atol=1e-9)


def test_the_saved_runs_are_drawn():
    runs = [
        {"preset": "long1", "floor_final_percent": 0.04, "camera_final_percent": 1.0, "fused_final_percent": 0.05},
        {"preset": "long1", "floor_final_percent": 0.04, "camera_final_percent": 0.5, "fused_final_percent": 0.03},
        {
            "preset": "long1-outages",
            "floor_final_percent": 15.0,
            "camera_final_percent": 1.0,
            "fused_final_percent": 0.1,
        },
    ]
    left, right = draw_acceptance({"runs": runs})
    np.testing.assert_allclose(left.lines[0].get_xydata(), [[0.04, 0.05], [0.04, 0.03]])
    assert [line.get_ydata()[0] for line in right.lines[:3]] == [15.0, 1.0, 0.1]
    assert [tick.get_text() for tick in right.get_xticklabels()] == ["long1-outages"]
