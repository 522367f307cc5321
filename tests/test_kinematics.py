"""The kinematics against independent truth: exact arcs, SE(2) round trips, OpenCV's rigid fit, the paper's cases."""

import cv2
import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from gpo.odometry.kinematics import (
    SMALL_ANGLE,
    PaperBicycle,
    arc_increment,
    between,
    compose,
    exact_velocities,
    increment_from_point_motion,
    increment_from_point_pairs,
    integrate,
    metres_per_pixel,
    paper_heading_rate_ratio,
    point_velocity_inputs,
    rigid_fit,
)

angles = st.floats(-3.0, 3.0)
lengths = st.floats(-2.0, 2.0)


def _moved(point, increment):
    """Where a static floor point seen at ``point`` is seen after the robot moved by ``increment``."""
    dx, dy, dtheta = increment
    cos, sin = np.cos(dtheta), np.sin(dtheta)
    rel = np.asarray(point) - [dx, dy]
    return np.array([cos * rel[..., 0] + sin * rel[..., 1], -sin * rel[..., 0] + cos * rel[..., 1]]).T


@given(lengths, lengths, angles, lengths, lengths, angles)
def test_between_inverts_compose(x, y, theta, dx, dy, dtheta):
    start = np.array([x, y, theta])
    end = compose(start, [dx, dy, dtheta])
    np.testing.assert_allclose(between(start, end), [dx, dy, np.angle(np.exp(1j * dtheta))], atol=1e-9)


def test_arc_increment_is_a_circle_and_a_line():
    # a quarter circle of radius 2 m to the left
    np.testing.assert_allclose(arc_increment(np.pi, np.pi / 2, 1.0), [2.0, 2.0, np.pi / 2], atol=1e-12)
    np.testing.assert_allclose(arc_increment(0.5, 0.0, 2.0), [1.0, 0.0, 0.0], atol=1e-15)
    # the series near zero turn meets the closed form
    below, above = arc_increment(1.0, SMALL_ANGLE * (1 - 1e-9), 1.0), arc_increment(1.0, SMALL_ANGLE * (1 + 1e-9), 1.0)
    np.testing.assert_allclose(below, above, rtol=1e-8, atol=1e-15)  # the turns differ by 2e-9 relative


def test_arc_increment_matches_fine_integration():
    v, omega, dt = 0.4, -0.7, 0.5
    steps = integrate(np.tile([v * dt / 20000, 0.0, omega * dt / 20000], (20000, 1)))
    np.testing.assert_allclose(arc_increment(v, omega, dt), steps[-1], atol=1e-5)


@given(st.floats(-0.03, 0.03), st.floats(-0.05, 0.05), st.floats(0.3, 1.2), st.floats(-0.2, 0.2))
def test_increment_from_point_motion_inverts_an_arc(distance, turn, cx, cy):
    increment = arc_increment(distance, turn, 1.0)
    point = np.array([cx, cy])
    np.testing.assert_allclose(increment_from_point_motion(point, _moved(point, increment)), increment, atol=1e-12)


def test_increment_from_point_motion_refuses_the_rear_axle():
    with pytest.raises(ValueError, match="rear axle"):
        increment_from_point_motion([0.0, 0.1], [0.0, 0.1])


@given(lengths, lengths, angles, st.integers(0, 2**31))
def test_rigid_fit_matches_opencv(tx, ty, angle, seed):
    rng = np.random.default_rng(seed)
    source = rng.uniform(-1, 1, (30, 2))
    rotation = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
    target = source @ rotation.T + [tx, ty] + 1e-3 * rng.standard_normal((30, 2))
    fitted_angle, translation = rigid_fit(source, target)
    affine, _ = cv2.estimateAffinePartial2D(source, target, method=cv2.LMEDS)
    # OpenCV also fits a scale; with a rigid truth it is 1 to the noise, and the rotations agree
    assert abs(np.angle(np.exp(1j * (fitted_angle - np.arctan2(affine[1, 0], affine[0, 0]))))) < 5e-3
    np.testing.assert_allclose(translation, affine[:, 2], atol=5e-3)


def test_rigid_fit_is_exact_without_noise_and_refuses_one_point():
    source = np.array([[0.7, 0.1], [0.9, -0.05], [0.8, 0.0]])
    increment = np.array([0.02, 0.001, 0.03])
    np.testing.assert_allclose(increment_from_point_pairs(source, _moved(source, increment)), increment, atol=1e-14)
    with pytest.raises(ValueError, match="distinct"):
        rigid_fit([[1.0, 2.0], [1.0, 2.0]], [[0.0, 0.0], [0.0, 0.0]])


def test_point_velocity_inputs_keep_reverse_and_spin():
    speed, steering = point_velocity_inputs([[-0.4, 0.0], [0.0, 0.3], [0.0, -0.3], [0.3, 0.3]])
    np.testing.assert_allclose(speed, [-0.4, 0.3, 0.3, np.hypot(0.3, 0.3)])
    np.testing.assert_allclose(steering, [0.0, np.pi / 2, -np.pi / 2, np.pi / 4], atol=1e-15)
    v, omega = exact_velocities(speed, steering, 0.8)
    np.testing.assert_allclose(v, [-0.4, 0.0, 0.0, 0.3], atol=1e-15)
    np.testing.assert_allclose(omega, [0.0, 0.3 / 0.8, -0.3 / 0.8, 0.3 / 0.8], atol=1e-15)


def _front_wheel_displacement(v, omega, dt, wheelbase):
    point = np.array([wheelbase, 0.0])
    return point - _moved(point, arc_increment(v, omega, dt))


def _paper_arc_error(rate_hz, v=0.4, omega=0.25, seconds=5.0):
    """Final pose error of the paper's model (l_r = L) driving a forward arc, and the true turn."""
    model, dt = PaperBicycle(0.8, 0.8), 1 / rate_hz
    pose = np.zeros(3)
    for _ in range(round(seconds * rate_hz)):
        pose = model.step(pose, _front_wheel_displacement(v, omega, dt, 0.8), dt)
    return pose - arc_increment(v, omega, seconds)


def test_paper_model_with_reference_at_the_wheel_converges_at_first_order():
    """l_r = L makes eq. 30 exact in continuous time; per frame, the chord read as eq. 26's direction lags the
    turn by half the frame's rotation, a heading-rate error of -v dt / (2 L): first order in dt."""
    errors = {rate: _paper_arc_error(rate) for rate in (30, 300, 3000)}
    assert errors[30][2] == pytest.approx(-0.4 / 30 / 1.6 * 1.25, rel=0.03)
    for slow, fast in ((30, 300), (300, 3000)):
        assert np.linalg.norm(errors[slow]) / np.linalg.norm(errors[fast]) == pytest.approx(10.0, rel=0.02)


def test_paper_model_heading_rate_off_by_the_ratio_when_reference_is_not_the_wheel():
    model, dt = PaperBicycle(0.8, 0.0), 1e-4
    v, omega = 0.4, 0.3
    speed, steering = model.inputs(_front_wheel_displacement(v, omega, dt, 0.8), dt)
    theta_dot = model.rates(speed, steering, 0.0)[2]
    assert theta_dot / omega == pytest.approx(paper_heading_rate_ratio(steering, 0.8, 0.0), rel=1e-3)
    assert paper_heading_rate_ratio(np.radians(24.0), 0.8, 0.0) == pytest.approx(1.0946, abs=1e-4)


def test_paper_model_reads_reverse_as_forward():
    model, dt = PaperBicycle(0.8, 0.8), 1 / 30
    pose = model.step(np.zeros(3), _front_wheel_displacement(-0.3, 0.0, dt, 0.8), dt)
    assert pose[0] == pytest.approx(+0.01, abs=1e-9)  # the truth is -0.01 m


def test_model_and_scale_checks():
    assert metres_per_pixel(0.25, 600.0) == pytest.approx(0.25 / 600)
    with pytest.raises(ValueError, match="height_m"):
        metres_per_pixel(-1.0, 600.0)
    with pytest.raises(ValueError, match="l_r"):
        PaperBicycle(0.8, 1.0)
    with pytest.raises(ValueError, match="L"):
        PaperBicycle(0.0, 0.0)
