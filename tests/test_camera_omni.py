"""Omni (Mei's unified model + radial-tangential distortion) against independent truth: Mei's equations with OpenCV's
distortion and undistortion, EUCM, Pinhole, round trips, and the edges of its valid region."""

import dataclasses
import math

import cv2
import numpy as np
import pytest
import yaml
from hypothesis import given
from hypothesis import strategies as st
from scipy.optimize import brentq

from gpo.cameras import EUCM, Omni, Pinhole
from gpo.cameras.files import load_kalibr, save_kalibr

# like the front camera of Kalibr's car (xi > 1: the fold at s_z = -1/xi lies inside the image)
FRONT_LIKE = Omni(
    fx=1291.5, fy=1293.3, cx=668.5, cy=407.0, xi=2.087, dist=(-0.987, 0.919, -0.0043, 0.0001), width=1280, height=800
)
# xi < 1: every pixel has a ray
WIDE = Omni(fx=300.0, fy=301.0, cx=320.5, cy=239.5, xi=0.8, dist=(-0.05, 0.01, 0.001, -0.0005), width=640, height=480)


def fold_angle(xi: float) -> float:
    """Angle off the optical axis, radians, where the image radius sin(t) / (cos(t) + xi) stops growing (xi > 1)
    or the point reaches the projection centre's plane (xi <= 1)."""
    return math.acos(-1.0 / xi) if xi > 1.0 else math.acos(-xi)


def random_points(rng, n, max_angle):
    """Points at random directions up to ``max_angle`` radians off the optical axis, 0.05-20 m away."""
    theta = max_angle * np.sqrt(rng.uniform(0, 1, n))
    phi = rng.uniform(-np.pi, np.pi, n)
    rays = np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], axis=-1)
    return rays * rng.uniform(0.05, 20.0, (n, 1))


def in_plane(theta):
    """Unit points ``theta`` radians off the optical axis, towards +x."""
    theta = np.asarray(theta, dtype=float)
    return np.stack([np.sin(theta), np.zeros_like(theta), np.cos(theta)], axis=-1)


def mei_then_opencv(camera: Omni, points: np.ndarray) -> np.ndarray:
    """Mei's projection written from its definition (onto the unit sphere, then the normalised plane of a centre
    xi behind the sphere's centre), distorted and scaled by OpenCV's ``projectPoints``."""
    sphere = points / np.linalg.norm(points, axis=-1, keepdims=True)
    normalised = sphere[:, :2] / (sphere[:, 2:] + camera.xi)
    matrix = np.array([[camera.fx, 0.0, camera.cx], [0.0, camera.fy, camera.cy], [0.0, 0.0, 1.0]])
    on_plane = np.column_stack([normalised, np.ones(len(points))])
    uv, _ = cv2.projectPoints(on_plane, np.zeros(3), np.zeros(3), matrix, np.array(camera.dist))
    return uv.reshape(-1, 2)


@pytest.mark.parametrize(("camera", "max_angle_deg"), [(FRONT_LIKE, 118.0), (WIDE, 100.0)])
def test_projection_is_the_unit_sphere_then_opencv_radtan(camera, max_angle_deg):
    points = random_points(np.random.default_rng(0), 5_000, np.radians(max_angle_deg))
    uv, valid = camera.project(points)
    assert valid.all()
    np.testing.assert_allclose(uv, mei_then_opencv(camera, points), atol=1e-9)


@pytest.mark.parametrize(("camera", "valid_fraction"), [(FRONT_LIKE, 0.78), (WIDE, 1.0)])
def test_unproject_project_round_trip_over_every_pixel(camera, valid_fraction):
    pixels = camera.pixel_grid()
    rays, valid = camera.unproject(pixels)
    back, valid_back = camera.project(rays)
    assert valid.mean() >= valid_fraction and (valid_back == valid).all()
    np.testing.assert_allclose(np.linalg.norm(rays[valid], axis=-1), 1.0, atol=1e-12)
    assert np.max(np.abs(back[valid] - pixels[valid])) < 1e-6
    assert np.isnan(rays[~valid]).all()


@pytest.mark.parametrize(
    ("camera", "max_angle"), [(FRONT_LIKE, fold_angle(FRONT_LIKE.xi) - 1e-3), (WIDE, np.radians(100))]
)
def test_project_unproject_round_trip_on_random_points(camera, max_angle):
    points = random_points(np.random.default_rng(1), 20_000, max_angle)
    uv, valid = camera.project(points)
    rays, valid_rays = camera.unproject(uv)
    assert valid.all() and valid_rays.all()
    np.testing.assert_allclose(rays, points / np.linalg.norm(points, axis=-1, keepdims=True), atol=1e-9)


def well_conditioned_radius(k1: float, k2: float, limit: float = 1.5) -> float:
    """Normalised radius up to which Newton's method from the distorted point converges within 20 steps: where
    the radial map r (1 + k1 r^2 + k2 r^4) keeps a slope above 0.2 (it flattens towards where it folds over),
    and at most ``limit`` (beyond, a strong k2 puts the distorted starting point far from the solution)."""
    r = np.linspace(0.0, limit, 1501)
    flat = 1.0 + 3.0 * k1 * r**2 + 5.0 * k2 * r**4 < 0.2
    return float(r[np.argmax(flat)]) if flat.any() else limit


@given(
    xi=st.floats(0.0, 3.0),
    k1=st.floats(-0.5, 0.0, allow_subnormal=False),
    k2=st.floats(-0.2, 0.5, allow_subnormal=False),  # np.roots overflows on subnormal ones
    p1=st.floats(-0.005, 0.005),
    p2=st.floats(-0.005, 0.005),
    seed=st.integers(0, 2**32 - 1),
)
def test_round_trip_for_any_barrel_distortion_where_it_is_well_conditioned(xi, k1, k2, p1, p2, seed):
    camera = Omni(fx=400.0, fy=410.0, cx=320.0, cy=240.0, xi=xi, dist=(k1, k2, p1, p2), width=640, height=480)
    points = random_points(np.random.default_rng(seed), 200, min(fold_angle(xi) - 1e-3, np.radians(100.0)))
    sphere = points / np.linalg.norm(points, axis=-1, keepdims=True)
    radius = np.linalg.norm(sphere[:, :2] / (sphere[:, 2:] + xi), axis=-1)
    sphere = sphere[radius < well_conditioned_radius(k1, k2)]
    uv, valid = camera.project(sphere)
    rays, valid_rays = camera.unproject(uv)
    assert valid.all() and valid_rays.all()
    np.testing.assert_allclose(rays, sphere, atol=1e-8)


@pytest.mark.parametrize("xi", [0.0, 0.4, 1.0, 1.6, 2.2])
def test_without_distortion_omni_is_eucm_with_alpha_xi_over_one_plus_xi(xi):
    f, cx, cy = 700.0, 640.0, 400.0
    omni = Omni(fx=f, fy=f, cx=cx, cy=cy, xi=xi, dist=(0.0,) * 4, width=1280, height=800)
    eucm = EUCM(fx=f / (1 + xi), fy=f / (1 + xi), cx=cx, cy=cy, alpha=xi / (1 + xi), beta=1.0, width=1280, height=800)
    points = random_points(np.random.default_rng(2), 20_000, np.pi)
    uv, valid = omni.project(points)
    uv_eucm, valid_eucm = eucm.project(points)
    np.testing.assert_array_equal(valid, valid_eucm)
    np.testing.assert_allclose(uv[valid], uv_eucm[valid], rtol=1e-12, atol=1e-9)
    rays, valid_rays = omni.unproject(omni.pixel_grid())
    rays_eucm, valid_rays_eucm = eucm.unproject(omni.pixel_grid())
    np.testing.assert_array_equal(valid_rays, valid_rays_eucm)
    np.testing.assert_allclose(rays[valid_rays], rays_eucm[valid_rays], atol=1e-12)
    np.testing.assert_allclose(omni.field_of_view(), eucm.field_of_view(), atol=1e-12)


@pytest.mark.parametrize("dist", [(0.0, 0.0, 0.0, 0.0), (-0.28, 0.09, 0.0012, -0.0008)])
def test_xi_zero_is_the_pinhole_with_the_same_distortion(dist):
    omni = Omni(fx=600.0, fy=601.5, cx=376.2, cy=239.7, xi=0.0, dist=dist, width=752, height=480)
    pinhole = Pinhole(fx=600.0, fy=601.5, cx=376.2, cy=239.7, dist=dist, width=752, height=480)
    points = random_points(np.random.default_rng(3), 20_000, np.pi)
    uv, valid = omni.project(points)
    uv_pinhole, valid_pinhole = pinhole.project(points)
    np.testing.assert_array_equal(valid, valid_pinhole)
    np.testing.assert_allclose(uv[valid], uv_pinhole[valid], rtol=1e-12)
    in_view = points[valid & (np.abs(uv[:, 0] - 376) < 2000) & (np.abs(uv[:, 1] - 240) < 2000)]
    expected, _ = cv2.projectPoints(in_view, np.zeros(3), np.zeros(3), pinhole.camera_matrix, np.array(dist))
    np.testing.assert_allclose(omni.project(in_view)[0], expected.reshape(-1, 2), atol=1e-8)
    rays, valid_rays = omni.unproject(omni.pixel_grid())
    rays_pinhole, valid_rays_pinhole = pinhole.unproject(omni.pixel_grid())
    assert valid_rays.all() and valid_rays_pinhole.all()
    np.testing.assert_allclose(rays, rays_pinhole, atol=1e-12)


def opencv_then_mei(camera: Omni, pixels: np.ndarray) -> np.ndarray:
    """Mei's unprojection written from its definition: OpenCV's ``undistortPoints`` (its own iteration, run to
    convergence) gives the undistorted point m on the normalised plane; the ray from the projection centre (0, 0, -xi)
    through (m, 1 - xi) meets the unit sphere at the far root t of |(0, 0, -xi) + t (m, 1)| = 1."""
    matrix = np.array([[camera.fx, 0.0, camera.cx], [0.0, camera.fy, camera.cy], [0.0, 0.0, 1.0]])
    converged = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 200, 1e-15)
    m = cv2.undistortPoints(pixels.reshape(-1, 1, 2), matrix, np.array(camera.dist), criteria=converged).reshape(-1, 2)
    squared = 1.0 + np.sum(m * m, axis=-1)  # |(m, 1)|^2
    with np.errstate(invalid="ignore"):  # no root: the pixel lies beyond the fold
        t = (camera.xi + np.sqrt(camera.xi**2 - squared * (camera.xi**2 - 1.0))) / squared
    return np.column_stack([t[:, None] * m, t - camera.xi])


@pytest.mark.parametrize("camera", [FRONT_LIKE, WIDE])
def test_unprojection_is_opencv_undistortion_then_the_unit_sphere(camera):
    """A second implementation of the inverse, beside the round trips: OpenCV's undistortion, then Mei's lift. (OpenCV's
    own omnidirectional module, cv2.omnidir, is only in opencv-contrib, which the suite does not install.)"""
    pixels = camera.pixel_grid().reshape(-1, 2)[::7]
    rays, valid = camera.unproject(pixels)
    expected = opencv_then_mei(camera, pixels)
    np.testing.assert_array_equal(valid, np.isfinite(expected[:, 2]))  # a ray exactly where the sphere has a point
    assert valid.mean() > (0.78 if camera is FRONT_LIKE else 0.99)  # xi > 1 folds the rim away: 78.5 % remain
    np.testing.assert_allclose(rays[valid], expected[valid], rtol=0, atol=1e-12)  # measured 1.6e-13 at most


@pytest.mark.parametrize("xi", [0.0, 0.5, 0.8, 1.25, 2.0, 3.0])
def test_points_are_valid_up_to_the_fold_and_invalid_beyond(xi):
    camera = Omni(fx=300.0, fy=300.0, cx=320.0, cy=240.0, xi=xi, dist=(0.0,) * 4, width=640, height=480)
    # in front of the projection centre (s_z > -xi), and for xi > 1 before the fold s_z = -1/xi
    edge = fold_angle(xi)
    uv, valid = camera.project(in_plane([edge - 1e-7, edge + 1e-7]))
    np.testing.assert_array_equal(valid, [True, False])
    assert np.isfinite(uv[0]).all() and np.isnan(uv[1]).all()


def test_the_image_radius_grows_up_to_the_fold_and_would_shrink_beyond():
    xi = 2.0
    camera = Omni(fx=300.0, fy=300.0, cx=320.0, cy=240.0, xi=xi, dist=(0.0,) * 4, width=640, height=480)
    theta = np.linspace(0.0, np.pi, 100_001)
    uv, valid = camera.project(in_plane(theta))
    assert np.all(np.diff(uv[valid, 0]) > 0)
    unrestricted_radius = np.sin(theta) / (np.cos(theta) + xi)  # without the fold two rays would share a pixel
    first_invalid = theta[np.argmin(valid)]
    assert first_invalid == pytest.approx(theta[np.argmax(unrestricted_radius)], abs=2 * np.pi / 100_000)
    assert first_invalid == pytest.approx(np.radians(120.0), abs=np.pi / 100_000)


def test_xi_one_sees_everything_but_straight_back():
    camera = Omni(fx=300.0, fy=300.0, cx=320.0, cy=240.0, xi=1.0, dist=(0.0,) * 4, width=640, height=480)
    _, valid = camera.project([[0.0, 0.0, -1.0], [1e-3, 0.0, -1.0], [1.0, 0.0, 0.0]])
    np.testing.assert_array_equal(valid, [False, True, True])


def test_beyond_the_monotonic_radius_of_the_distortion_is_invalid():
    # r (1 + k1 r^2) with k1 = -0.25 stops growing at r^2 = 1 / (3 * 0.25), r = |(mx, my)| on the normalised plane
    xi = 0.5
    camera = Omni(fx=100.0, fy=100.0, cx=50.0, cy=50.0, xi=xi, dist=(-0.25, 0.0, 0.0, 0.0), width=100, height=100)
    assert camera.max_radius == pytest.approx(np.sqrt(4.0 / 3.0))
    radii = (1.0, 1.15, 1.16, 2.0)
    angles = [brentq(lambda t, r=r: np.sin(t) / (np.cos(t) + xi) - r, 0.0, fold_angle(xi) - 1e-6) for r in radii]
    uv, valid = camera.project(in_plane(angles))
    np.testing.assert_array_equal(valid, [True, True, False, False])
    assert np.isnan(uv[2:]).all()


def test_valid_pixels_are_exactly_those_inside_the_image_circle():
    camera = dataclasses.replace(FRONT_LIKE, dist=(-0.987, 0.919, 0.0, 0.0))
    # the fold s_z = -1/xi lies at the normalised radius r = 1/sqrt(xi^2 - 1); with radial distortion only, the
    # valid pixels fill the circle of the distorted radius on the normalised plane
    r = 1.0 / math.sqrt(camera.xi**2 - 1.0)
    circle = r * (1.0 - 0.987 * r**2 + 0.919 * r**4)
    pixels = camera.pixel_grid()
    radius = np.hypot((pixels[..., 0] - camera.cx) / camera.fx, (pixels[..., 1] - camera.cy) / camera.fy)
    _, valid = camera.unproject(pixels)
    clear = np.abs(radius - circle) > 1e-6
    np.testing.assert_array_equal(valid[clear], radius[clear] < circle)
    assert 0.7 < valid.mean() < 0.9


def test_invalid_points_and_pixels_give_nan():
    uv, valid = FRONT_LIKE.project([[0.0, 0.0, 0.0], [np.nan, 0.0, 1.0], [np.inf, 0.0, 1.0], [0.0, 0.0, -1.0]])
    assert not valid.any() and np.isnan(uv).all()
    rays, valid = FRONT_LIKE.unproject([[np.nan, 400.0], [0.0, np.inf], [-1e6, 400.0]])
    assert not valid.any() and np.isnan(rays).all()


def test_any_leading_shape_works_and_a_wrong_last_axis_raises():
    point = np.array([0.1, -0.2, 1.0])
    uv, valid = FRONT_LIKE.project(point)
    assert uv.shape == (2,) and valid.shape == () and valid
    uv_grid, valid_grid = FRONT_LIKE.project(np.broadcast_to(point, (4, 5, 3)))
    assert uv_grid.shape == (4, 5, 2) and valid_grid.all()
    np.testing.assert_array_equal(uv_grid[3, 2], uv)
    rays, valid = FRONT_LIKE.unproject(np.broadcast_to(uv, (2, 3, 2)))
    assert rays.shape == (2, 3, 3) and valid.all()
    with pytest.raises(ValueError, match=r"points must have shape \(\.\.\., 3\)"):
        FRONT_LIKE.project([1.0, 2.0])
    with pytest.raises(ValueError, match=r"pixels must have shape \(\.\.\., 2\)"):
        FRONT_LIKE.unproject([1.0, 2.0, 3.0])


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"xi": -0.1}, "xi must be >= 0"),
        ({"xi": np.nan}, "xi must be a finite number"),
        ({"fx": 0.0}, "fx must be > 0"),
        ({"fy": -1.0}, "fy must be > 0"),
        ({"cx": np.inf}, "cx must be a finite number"),
        ({"dist": (0.1, 0.2, 0.0, 0.0, 0.1)}, r"dist must be \(k1, k2, p1, p2\), got 5 values"),
        ({"dist": (0.1, 0.2, np.nan, 0.0)}, "p1 must be a finite number"),
        ({"height": 0}, "height must be a positive whole number"),
    ],
)
def test_invalid_parameters_raise_naming_them(change, message):
    params = {"fx": 600.0, "fy": 600.0, "cx": 640.0, "cy": 400.0, "xi": 1.5, "dist": (0.0,) * 4}
    params |= {"width": 1280, "height": 800} | change
    with pytest.raises(ValueError, match=message):
        Omni(**params)


def test_kalibr_camchain_round_trip(tmp_path):
    path = save_kalibr(tmp_path / "camchain.yaml", {"cam0": FRONT_LIKE, "cam1": WIDE})
    document = yaml.safe_load(path.read_text())
    assert document["cam0"]["camera_model"] == "omni" and document["cam0"]["distortion_model"] == "radtan"
    assert document["cam0"]["intrinsics"] == [2.087, 1291.5, 1293.3, 668.5, 407.0]
    assert document["cam0"]["distortion_coeffs"] == [-0.987, 0.919, -0.0043, 0.0001]
    assert load_kalibr(path) == {"cam0": FRONT_LIKE, "cam1": WIDE}


def test_kalibr_omni_without_distortion_reads_as_zero_distortion(tmp_path):
    entry = {"camera_model": "omni", "intrinsics": [2.0, 800, 801, 640, 400], "distortion_model": "none"}
    path = tmp_path / "omni.yaml"
    path.write_text(yaml.safe_dump({"cam0": entry | {"resolution": [1280, 800]}}))
    assert load_kalibr(path)["cam0"] == Omni(800, 801, 640, 400, 2.0, (0.0, 0.0, 0.0, 0.0), 1280, 800)
