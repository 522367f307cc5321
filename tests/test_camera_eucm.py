"""EUCM against independent truth: round trips, the unified (Mei) model, finite differences."""

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from gpo.cameras import EUCM

T265_LIKE = EUCM(fx=286.0, fy=286.2, cx=424.3, cy=400.1, alpha=0.6, beta=1.1, width=848, height=800)


def random_points(rng, n, max_angle_deg=150.0):
    """Points at random directions up to ``max_angle_deg`` off the optical axis, 0.05-20 m away."""
    theta = np.radians(max_angle_deg) * np.sqrt(rng.uniform(0, 1, n))
    phi = rng.uniform(-np.pi, np.pi, n)
    rays = np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], axis=-1)
    return rays * rng.uniform(0.05, 20.0, (n, 1))


def test_unproject_project_round_trip_over_every_pixel():
    pixels = T265_LIKE.pixel_grid()
    rays, valid_rays = T265_LIKE.unproject(pixels)
    back, valid_back = T265_LIKE.project(rays)
    assert valid_rays.all() and valid_back.all()
    np.testing.assert_allclose(np.linalg.norm(rays, axis=-1), 1.0, atol=1e-12)
    assert np.max(np.abs(back - pixels)) < 1e-6


def test_project_unproject_round_trip_on_random_points():
    # alpha = 0.6, beta = 1.1 sees up to 133 degrees off the optical axis
    points = random_points(np.random.default_rng(0), 20_000, max_angle_deg=125.0)
    uv, valid = T265_LIKE.project(points)
    rays, valid_rays = T265_LIKE.unproject(uv)
    assert valid.all() and valid_rays.all()
    directions = points / np.linalg.norm(points, axis=-1, keepdims=True)
    np.testing.assert_allclose(rays, directions, atol=1e-9)


def unified_model_project(points, f, cx, cy, xi):
    """Mei's unified model, written from its definition: the point on the unit sphere, seen from
    a pinhole shifted by xi along the optical axis, with focal length gamma = f * (1 + xi)."""
    sphere = points / np.linalg.norm(points, axis=-1, keepdims=True)
    x, y, z = sphere.T
    return np.stack([f * x / (z + xi) + cx, f * y / (z + xi) + cy], axis=-1)


@pytest.mark.parametrize("alpha", [0.0, 0.3, 0.5, 0.62, 0.8])
def test_beta_one_is_the_unified_model(alpha):
    f, cx, cy = 250.0, 320.0, 240.0
    camera = EUCM(fx=f, fy=f, cx=cx, cy=cy, alpha=alpha, beta=1.0, width=640, height=480)
    xi = alpha / (1.0 - alpha)
    points = random_points(np.random.default_rng(1), 2_000, max_angle_deg=80.0)
    uv, valid = camera.project(points)
    assert valid.all()
    np.testing.assert_allclose(uv, unified_model_project(points, f * (1.0 + xi), cx, cy, xi), rtol=1e-12)


def test_point_jacobian_matches_finite_differences():
    points = random_points(np.random.default_rng(2), 500, max_angle_deg=100.0)
    j_point, _ = T265_LIKE.project_jacobians(points)
    h = 1e-6
    for axis in range(3):
        step = np.zeros(3)
        step[axis] = h
        numeric = (T265_LIKE.project(points + step)[0] - T265_LIKE.project(points - step)[0]) / (2 * h)
        np.testing.assert_allclose(j_point[:, :, axis], numeric, rtol=1e-5, atol=1e-4)


def test_parameter_jacobian_matches_finite_differences():
    points = random_points(np.random.default_rng(3), 500, max_angle_deg=100.0)
    _, j_params = T265_LIKE.project_jacobians(points)
    params = T265_LIKE.params
    for index in range(6):
        h = 1e-7 * max(1.0, abs(params[index]))
        plus, minus = params.copy(), params.copy()
        plus[index] += h
        minus[index] -= h
        numeric = (
            EUCM.from_params(plus, 848, 800).project(points)[0] - EUCM.from_params(minus, 848, 800).project(points)[0]
        ) / (2 * h)
        np.testing.assert_allclose(j_params[:, :, index], numeric, rtol=1e-5, atol=1e-4)


def test_projection_validity_boundary():
    # alpha = 0.6 > 0.5: w = (1 - alpha) / alpha; a ray at angle theta off the axis is valid iff
    # cos(theta) > -w * sqrt(beta sin^2(theta) + cos^2(theta)).
    camera = T265_LIKE
    w = (1 - camera.alpha) / camera.alpha
    theta = np.radians(np.linspace(60.0, 179.0, 2_000))
    rays = np.stack([np.sin(theta), np.zeros_like(theta), np.cos(theta)], axis=-1)
    expected = np.cos(theta) > -w * np.sqrt(camera.beta * np.sin(theta) ** 2 + np.cos(theta) ** 2)
    uv, valid = camera.project(rays)
    np.testing.assert_array_equal(valid, expected)
    assert 0 < expected.sum() < len(theta)
    assert np.isnan(uv[~valid]).all() and np.isfinite(uv[valid]).all()


def test_unprojection_validity_boundary():
    camera = EUCM(fx=100.0, fy=100.0, cx=0.0, cy=0.0, alpha=0.8, beta=1.5, width=2000, height=2000)
    r_max = 1.0 / np.sqrt(camera.beta * (2 * camera.alpha - 1))
    radii = np.array([0.5, 0.999, 1.001, 2.0]) * r_max
    rays, valid = camera.unproject(np.stack([radii * camera.fx, np.zeros(4)], axis=-1))
    np.testing.assert_array_equal(valid, [True, True, False, False])
    assert np.isnan(rays[2:]).all()


def test_bad_input_gives_nan_and_false_mask_or_a_clear_error():
    uv, valid = T265_LIKE.project([[0.0, 0.0, 1.0], [np.nan, 0.0, 1.0], [0.0, 0.0, -1.0], [np.inf, 0, 1]])
    np.testing.assert_array_equal(valid, [True, False, False, False])
    assert np.isnan(uv[1:]).all()
    rays, valid = T265_LIKE.unproject([[np.nan, 3.0]])
    assert not valid[0] and np.isnan(rays).all()
    with pytest.raises(ValueError, match=r"shape \(\.\.\., 3\)"):
        T265_LIKE.project(np.zeros((5, 2)))
    with pytest.raises(ValueError, match=r"shape \(\.\.\., 2\)"):
        T265_LIKE.unproject(np.zeros((5, 3)))


def test_shapes_broadcast_over_leading_axes():
    grid = T265_LIKE.pixel_grid()[::100, ::100]
    rays, valid = T265_LIKE.unproject(grid)
    assert rays.shape == (*grid.shape[:-1], 3) and valid.shape == grid.shape[:-1]
    uv, valid = T265_LIKE.project([0.1, 0.2, 1.0])
    assert uv.shape == (2,) and valid.shape == ()


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"fx": 0.0}, "fx must be > 0"),
        ({"fy": -3.0}, "fy must be > 0"),
        ({"alpha": 1.2}, r"alpha must lie in \[0, 1\]"),
        ({"alpha": -0.1}, r"alpha must lie in \[0, 1\]"),
        ({"beta": 0.0}, "beta must be > 0"),
        ({"cx": np.nan}, "cx must be a finite number"),
        ({"width": 0}, "width must be a positive whole number"),
        ({"height": 10.5}, "height must be a positive whole number"),
    ],
)
def test_invalid_parameters_raise_naming_them(change, message):
    params = {"fx": 286.0, "fy": 286.0, "cx": 424.0, "cy": 400.0, "alpha": 0.6, "beta": 1.1, "width": 848}
    params["height"] = 800
    params.update(change)
    with pytest.raises(ValueError, match=message):
        EUCM(**params)


eucm_cameras = st.builds(
    lambda f, aspect, alpha, beta: EUCM(
        fx=f, fy=f * aspect, cx=320.0, cy=240.0, alpha=alpha, beta=beta, width=640, height=480
    ),
    f=st.floats(50.0, 1000.0),
    aspect=st.floats(0.9, 1.1),
    alpha=st.floats(0.0, 0.95),
    beta=st.floats(0.2, 5.0),
)


@given(camera=eucm_cameras, u=st.floats(0.0, 639.0), v=st.floats(0.0, 479.0))
def test_property_every_valid_pixel_round_trips(camera, u, v):
    rays, valid = camera.unproject([u, v])
    if valid:
        back, valid_back = camera.project(rays)
        assert valid_back
        np.testing.assert_allclose(back, [u, v], atol=1e-6)
    else:
        assert np.isnan(rays).all()


@given(
    camera=eucm_cameras,
    theta=st.floats(0.0, 3.1),
    phi=st.floats(-np.pi, np.pi),
    distance=st.floats(1e-3, 1e3),
)
def test_property_every_valid_point_round_trips(camera, theta, phi, distance):
    direction = np.array([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)])
    uv, valid = camera.project(direction * distance)
    if valid:
        rays, valid_rays = camera.unproject(uv)
        assert valid_rays
        np.testing.assert_allclose(rays, direction, atol=1e-6)
    else:
        assert np.isnan(uv).all()


@given(alpha=st.one_of(st.floats(1.0001, 10.0), st.floats(-10.0, -0.0001)))
def test_property_alpha_outside_unit_interval_raises(alpha):
    with pytest.raises(ValueError, match="alpha"):
        EUCM(fx=1.0, fy=1.0, cx=0.0, cy=0.0, alpha=alpha, beta=1.0, width=10, height=10)
