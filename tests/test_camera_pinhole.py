"""Pinhole + radial-tangential distortion against OpenCV's own implementation."""

import cv2
import numpy as np
import pytest

from gpo.cameras import Pinhole

DOWNWARD = Pinhole(
    fx=600.0, fy=601.5, cx=376.2, cy=239.7, dist=(-0.28, 0.09, 0.0012, -0.0008, -0.01), width=752, height=480
)


def points_in_view(rng, n):
    xy = rng.uniform(-0.6, 0.6, (n, 2))
    z = rng.uniform(0.1, 5.0, n)
    return np.column_stack([xy * z[:, None], z])


@pytest.mark.parametrize("dist", [(0.0, 0.0, 0.0, 0.0), (-0.28, 0.09, 0.0012, -0.0008), DOWNWARD.dist])
def test_projection_equals_cv2_project_points(dist):
    camera = Pinhole(fx=600.0, fy=601.5, cx=376.2, cy=239.7, dist=dist, width=752, height=480)
    points = points_in_view(np.random.default_rng(0), 5_000)
    uv, valid = camera.project(points)
    expected, _ = cv2.projectPoints(points, np.zeros(3), np.zeros(3), camera.camera_matrix, np.array(dist))
    assert valid.all()
    np.testing.assert_allclose(uv, expected.reshape(-1, 2), atol=1e-9)


def test_unproject_project_round_trip_over_every_pixel():
    pixels = DOWNWARD.pixel_grid()
    rays, valid = DOWNWARD.unproject(pixels)
    back, valid_back = DOWNWARD.project(rays)
    assert valid.all() and valid_back.all()
    assert np.max(np.abs(back - pixels)) < 1e-6


def test_rays_match_cv2_undistort_points():
    pixels = np.random.default_rng(1).uniform([0, 0], [751, 479], (1_000, 2))
    rays, valid = DOWNWARD.unproject(pixels)
    criteria = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 200, 1e-14)
    normalised = cv2.undistortPoints(
        pixels.reshape(-1, 1, 2), DOWNWARD.camera_matrix, np.array(DOWNWARD.dist), criteria=criteria
    ).reshape(-1, 2)
    assert valid.all()
    np.testing.assert_allclose(rays[:, :2] / rays[:, 2:], normalised, atol=1e-9)


def test_beyond_the_monotonic_radius_is_invalid():
    # r (1 + k1 r^2) with k1 = -0.25 stops growing at r^2 = 1 / (3 * 0.25)
    camera = Pinhole(fx=100.0, fy=100.0, cx=50.0, cy=50.0, dist=(-0.25, 0.0, 0.0, 0.0), width=100, height=100)
    assert camera.max_radius == pytest.approx(np.sqrt(4.0 / 3.0))
    r = np.array([1.0, 1.15, 1.16, 2.0])
    uv, valid = camera.project(np.column_stack([r, np.zeros(4), np.ones(4)]))
    np.testing.assert_array_equal(valid, [True, True, False, False])
    assert np.isnan(uv[2:]).all()


def test_points_behind_and_nan_are_invalid():
    uv, valid = DOWNWARD.project([[0.0, 0.0, -1.0], [0.0, 0.0, 0.0], [np.nan, 0.0, 1.0], [0.1, 0.1, 1.0]])
    np.testing.assert_array_equal(valid, [False, False, False, True])
    assert np.isnan(uv[:3]).all()


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"fx": 0.0}, "fx must be > 0"),
        ({"dist": (0.1, 0.2, 0.3)}, r"dist must be \(k1, k2, p1, p2\)"),
        ({"dist": (0.1, np.inf, 0.0, 0.0)}, "k2 must be a finite number"),
        ({"width": -5}, "width must be a positive whole number"),
    ],
)
def test_invalid_parameters_raise_naming_them(change, message):
    params = {"fx": 600.0, "fy": 600.0, "cx": 376.0, "cy": 240.0, "dist": (0.0,) * 4, "width": 752, "height": 480}
    params.update(change)
    with pytest.raises(ValueError, match=message):
        Pinhole(**params)


def test_field_of_view_of_an_undistorted_pinhole_is_the_arctangent_sum():
    camera = Pinhole(fx=500.0, fy=400.0, cx=300.0, cy=200.0, dist=(0.0,) * 4, width=640, height=480)
    horizontal, vertical, diagonal = camera.field_of_view()
    assert horizontal == pytest.approx(np.arctan(300 / 500) + np.arctan(339 / 500), abs=1e-12)
    assert vertical == pytest.approx(np.arctan(200 / 400) + np.arctan(279 / 400), abs=1e-12)
    assert diagonal == pytest.approx(
        np.arctan(np.hypot(300 / 500, 200 / 400)) + np.arctan(np.hypot(339 / 500, 279 / 400)), abs=1e-12
    )
