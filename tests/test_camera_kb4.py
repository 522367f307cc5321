"""Kannala-Brandt (KB4) against OpenCV's fisheye model, round trips over a real T265 calibration, validity."""

import cv2
import numpy as np
import pytest

from gpo.cameras import KB4

# Basalt's published calibration of a real T265's left fisheye (basalt/data/t265_kb4_calib.json, camera 0)
T265 = KB4(
    fx=286.60144163375526,
    fy=286.4617087423328,
    cx=422.2765876951761,
    cy=395.2246466040553,
    k1=-0.006762412326815424,
    k2=0.045170283325720005,
    k3=-0.043515167278210636,
    k4=0.008374959821591333,
    width=848,
    height=800,
)


def directions(rng, n, max_angle_deg):
    theta = np.radians(max_angle_deg) * np.sqrt(rng.uniform(0, 1, n))
    phi = rng.uniform(-np.pi, np.pi, n)
    return np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], axis=-1)


def test_projection_equals_cv2_fisheye_project_points():
    # OpenCV's fisheye model sees points in front of the lens only (it takes atan(r / z))
    points = directions(np.random.default_rng(0), 5_000, 89.0) * np.random.default_rng(1).uniform(0.05, 20, (5_000, 1))
    uv, valid = T265.project(points)
    matrix = np.array([[T265.fx, 0.0, T265.cx], [0.0, T265.fy, T265.cy], [0.0, 0.0, 1.0]])
    no_motion = np.zeros(3)
    expected, _ = cv2.fisheye.projectPoints(points.reshape(-1, 1, 3), no_motion, no_motion, matrix, np.array(T265.dist))
    assert valid.all()
    assert np.max(np.abs(uv - expected.reshape(-1, 2))) < 1e-9


def test_rays_equal_cv2_fisheye_undistort_points():
    pixels = T265.pixel_grid()[::40, ::40].reshape(-1, 2)
    rays, valid = T265.unproject(pixels)
    front = valid & (rays[:, 2] > 0.2)  # OpenCV returns points on the plane z = 1
    matrix = np.array([[T265.fx, 0.0, T265.cx], [0.0, T265.fy, T265.cy], [0.0, 0.0, 1.0]])
    criteria = (cv2.TERM_CRITERIA_COUNT + cv2.TERM_CRITERIA_EPS, 100, 1e-14)
    plane = cv2.fisheye.undistortPoints(pixels[front].reshape(-1, 1, 2), matrix, np.array(T265.dist), criteria=criteria)
    np.testing.assert_allclose(rays[front, :2] / rays[front, 2:], plane.reshape(-1, 2), atol=1e-7)


def test_unproject_project_round_trip_over_the_whole_t265_image():
    pixels = T265.pixel_grid()
    rays, valid_rays = T265.unproject(pixels)
    back, valid_back = T265.project(rays)
    assert valid_rays.all() and valid_back.all()
    np.testing.assert_allclose(np.linalg.norm(rays, axis=-1), 1.0, atol=1e-12)
    assert np.max(np.abs(back - pixels)) < 1e-6


def test_project_unproject_round_trip_up_to_straight_back():
    rng = np.random.default_rng(2)
    rays = directions(rng, 20_000, 179.0)
    uv, valid = T265.project(rays * rng.uniform(0.05, 20.0, (20_000, 1)))
    back, valid_back = T265.unproject(uv)
    assert valid.all() and valid_back.all()
    np.testing.assert_allclose(back, rays, atol=1e-9)


def test_equidistant_without_coefficients_maps_the_angle_linearly():
    camera = KB4(300.0, 300.0, 320.0, 240.0, 0.0, 0.0, 0.0, 0.0, 640, 480)
    theta = np.radians([0.0, 10.0, 45.0, 90.0, 135.0])
    uv, valid = camera.project(np.stack([np.sin(theta), np.zeros(5), np.cos(theta)], axis=-1))
    assert valid.all()
    np.testing.assert_allclose(uv[:, 0], 320.0 + 300.0 * theta, rtol=1e-14)
    np.testing.assert_allclose(uv[:, 1], 240.0, rtol=1e-14)


def test_beyond_the_fold_of_theta_d_is_invalid():
    # theta_d = theta (1 - 0.1 theta^2) grows up to theta^2 = 1 / 0.3
    camera = KB4(300.0, 300.0, 320.0, 240.0, -0.1, 0.0, 0.0, 0.0, 640, 480)
    assert camera.max_theta == pytest.approx(np.sqrt(1.0 / 0.3), rel=1e-12)
    theta = camera.max_theta + np.array([-1e-3, 1e-3])
    _, valid = camera.project(np.stack([np.sin(theta), np.zeros(2), np.cos(theta)], axis=-1))
    np.testing.assert_array_equal(valid, [True, False])
    edge = camera.project([np.sin(camera.max_theta), 0.0, np.cos(camera.max_theta)])[0]
    rays, valid = camera.unproject(edge + np.array([[-1.0, 0.0], [1.0, 0.0]]))
    np.testing.assert_array_equal(valid, [True, False])
    assert np.isnan(rays[1]).all()


def test_bad_points_and_pixels_give_nan_and_a_false_mask():
    uv, valid = T265.project([[0.0, 0.0, 1.0], [np.nan, 0.0, 1.0], [0.0, 0.0, -1.0], [np.inf, 0, 1], [0.0, 0.0, 0.0]])
    np.testing.assert_array_equal(valid, [True, False, False, False, False])
    np.testing.assert_allclose(uv[0], [T265.cx, T265.cy])
    assert np.isnan(uv[1:]).all()
    rays, valid = T265.unproject([[np.nan, 3.0], [T265.cx, T265.cy]])
    np.testing.assert_array_equal(valid, [False, True])
    assert np.isnan(rays[0]).all() and np.allclose(rays[1], [0.0, 0.0, 1.0])
    with pytest.raises(ValueError, match=r"shape \(\.\.\., 3\)"):
        T265.project(np.zeros((5, 2)))


@pytest.mark.parametrize(
    ("change", "message"),
    [({"fx": 0.0}, "fx must be > 0"), ({"k3": np.nan}, "k3 must be a finite number"), ({"width": 0.5}, "width")],
)
def test_invalid_parameters_raise_naming_them(change, message):
    params = dict(zip(KB4.PARAMETER_NAMES, T265.params, strict=True)) | {"width": 848, "height": 800} | change
    with pytest.raises(ValueError, match=message):
        KB4(**params)
