"""Every model's analytic Jacobians (``project_jacobians``) against central finite differences."""

import numpy as np
import pytest

from gpo.cameras import EUCM, KB4, DoubleSphere, Omni

CAMERAS = [
    EUCM(286.0, 286.2, 424.3, 400.1, alpha=0.6, beta=1.1, width=848, height=800),
    KB4(286.6, 286.5, 422.3, 395.2, k1=-0.0068, k2=0.045, k3=-0.0435, k4=0.0084, width=848, height=800),
    DoubleSphere(158.3, 158.27, 254.96, 256.89, xi=-0.172, alpha=0.593, width=512, height=512),
    Omni(398.8, 398.8, 319.2, 319.7, xi=1.13, dist=(-0.25, 0.0097, 1e-3, -2e-3), width=640, height=720),
]


def points_up_to(max_angle_deg, n=400, seed=0):
    rng = np.random.default_rng(seed)
    theta = np.radians(max_angle_deg) * np.sqrt(rng.uniform(0, 1, n))
    phi = rng.uniform(-np.pi, np.pi, n)
    rays = np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], axis=-1)
    return rays * rng.uniform(0.2, 5.0, (n, 1))


@pytest.mark.parametrize("camera", CAMERAS, ids=lambda camera: type(camera).__name__)
def test_point_jacobian_matches_finite_differences(camera):
    points = points_up_to(95.0)
    j_point, _ = camera.project_jacobians(points)
    assert j_point.shape == (len(points), 2, 3) and np.isfinite(j_point).all()
    h = 1e-6
    for axis in range(3):
        step = np.zeros(3)
        step[axis] = h
        numeric = (camera.project(points + step)[0] - camera.project(points - step)[0]) / (2 * h)
        np.testing.assert_allclose(j_point[:, :, axis], numeric, rtol=1e-5, atol=1e-4)


@pytest.mark.parametrize("camera", CAMERAS, ids=lambda camera: type(camera).__name__)
def test_parameter_jacobian_matches_finite_differences(camera):
    points = points_up_to(95.0, seed=1)
    _, j_params = camera.project_jacobians(points)
    params = camera.params
    assert j_params.shape == (len(points), 2, len(params)) == (len(points), 2, len(camera.PARAMETER_NAMES))
    for index in range(len(params)):
        h = 1e-7 * max(1.0, abs(params[index]))
        plus, minus = params.copy(), params.copy()
        plus[index] += h
        minus[index] -= h
        shifted = [type(camera).from_params(p, camera.width, camera.height).project(points)[0] for p in (plus, minus)]
        np.testing.assert_allclose(j_params[:, :, index], (shifted[0] - shifted[1]) / (2 * h), rtol=1e-5, atol=1e-4)


@pytest.mark.parametrize("camera", CAMERAS, ids=lambda camera: type(camera).__name__)
def test_jacobians_on_the_optical_axis_and_nan_where_invalid(camera):
    j_point, j_params = camera.project_jacobians([[0.0, 0.0, 2.0], [np.nan, 0.0, 1.0], [0.0, 0.0, -1.0]])
    assert np.isfinite(j_point[0]).all() and np.isfinite(j_params[0]).all()
    assert np.isnan(j_point[1:]).all() and np.isnan(j_params[1:]).all()
    h = 1e-6
    numeric = (camera.project([h, 0.0, 2.0])[0] - camera.project([-h, 0.0, 2.0])[0]) / (2 * h)
    np.testing.assert_allclose(j_point[0, :, 0], numeric, rtol=1e-6, atol=1e-6)


@pytest.mark.parametrize("camera", CAMERAS, ids=lambda camera: type(camera).__name__)
def test_params_round_trip_and_a_wrong_length_is_refused(camera):
    assert type(camera).from_params(camera.params, camera.width, camera.height) == camera
    with pytest.raises(ValueError, match="parameters must be"):
        type(camera).from_params(camera.params[:-1], camera.width, camera.height)
