"""Pinhole + radial-tangential distortion against OpenCV's own implementation."""

import cv2
import numpy as np
import pytest

from gpo.camera import Pinhole

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
