"""The first paper's numbered equations (Ground Plane Odometry, eqs. 1-34), each computed by hand as printed and
compared with the package; where the package computes one otherwise, the test shows how the two relate."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from gpo.cameras import T265_LIKE
from gpo.floor_image.cubemap import FACE_ROTATIONS, Cubemap
from gpo.odometry.kinematics import PaperBicycle, metres_per_pixel

# eqs. 8-12 as the paper's text lists their nine entries, in the order it gives them
PRINTED_ENTRIES = {
    "front": [1, 0, 0, 0, 1, 0, 0, 0, 1],
    "left": [0, 0, 1, 0, 1, 0, -1, 0, 0],
    "right": [0, 0, -1, 0, 1, 0, 1, 0, 0],
    "bottom": [1, 0, 0, 0, 0, -1, 0, 1, 0],
    "top": [1, 0, 0, 0, 0, 1, 0, -1, 0],
}
FACING = {"front": (0, 0, 1), "left": (-1, 0, 0), "right": (1, 0, 0), "bottom": (0, 1, 0), "top": (0, -1, 0)}
"""Where each face looks in the optical frame (x right, y down, z forward)."""


def by_columns(entries):
    return np.array(entries, dtype=float).reshape(3, 3).T


def by_rows(entries):
    return np.array(entries, dtype=float).reshape(3, 3)


def eucm_by_hand(point, camera):
    """Eqs. 1-7 as printed: X -> rho -> (x_P, y_P) -> X_M -> X_I = K X_M."""
    x, y, z = point  # (1)
    rho = np.sqrt(camera.beta * (x**2 + y**2) + z**2)  # (2)
    denominator = camera.alpha * rho + (1 - camera.alpha) * z
    x_p, y_p = x / denominator, y / denominator  # (3)-(5)
    x_m = np.array([x_p, y_p, 1.0])  # (6)
    k = np.array([[camera.fx, 0, camera.cx], [0, camera.fy, camera.cy], [0, 0, 1]])
    return (k @ x_m)[:2]  # (7)


def test_eqs_1_to_7_are_the_eucm_projection():
    points = np.array([[0.0, 0.0, 1.0], [0.3, 0.12, 0.5], [1.0, 0.12, -0.3], [-0.7, -0.4, 0.2]])
    pixels, valid = T265_LIKE.project(points)
    assert valid.all()
    for point, pixel in zip(points, pixels, strict=True):
        np.testing.assert_allclose(pixel, eucm_by_hand(point, T265_LIKE), rtol=0, atol=1e-9)


def test_the_text_lists_matrices_column_by_column():
    # eq. 7's K is listed "fx 0 0, 0 fy 0, cx cy 1": read by columns it is the usual intrinsic matrix
    c = T265_LIKE
    k_listed = [c.fx, 0, 0, 0, c.fy, 0, c.cx, c.cy, 1]
    k = np.array([[c.fx, 0, c.cx], [0, c.fy, c.cy], [0, 0, 1]])
    np.testing.assert_array_equal(by_columns(k_listed), k)
    assert not np.array_equal(by_rows(k_listed), k)
    # eq. 21's H is listed "h11 h21 h31, h12 h22 h32, h13 h23 1"
    h_listed = ["h11", "h21", "h31", "h12", "h22", "h32", "h13", "h23", "1"]
    h = np.array(h_listed).reshape(3, 3).T
    assert h.tolist() == [["h11", "h12", "h13"], ["h21", "h22", "h23"], ["h31", "h32", "1"]]


@pytest.mark.parametrize("name", list(PRINTED_ENTRIES))
def test_eqs_8_to_12_read_by_columns_are_the_face_rotations(name):
    suite = FACE_ROTATIONS[name].as_matrix()
    np.testing.assert_allclose(by_columns(PRINTED_ENTRIES[name]), suite, atol=1e-12)
    # read by columns, each face looks where its name says
    np.testing.assert_allclose(by_columns(PRINTED_ENTRIES[name]) @ [0, 0, 1], FACING[name], atol=1e-12)


@pytest.mark.parametrize("name", ["left", "right", "bottom", "top"])
def test_eqs_9_to_12_read_by_rows_are_the_transposes(name):
    printed = by_rows(PRINTED_ENTRIES[name])
    suite = FACE_ROTATIONS[name].as_matrix()
    np.testing.assert_allclose(printed, suite.T, atol=1e-12)
    # and then each face looks the opposite way: the printed R_Bottom as rows is the package's R_top
    np.testing.assert_allclose(printed @ [0, 0, 1], -np.array(FACING[name]), atol=1e-12)
    opposite = {"left": "right", "right": "left", "bottom": "top", "top": "bottom"}[name]
    np.testing.assert_allclose(printed, FACE_ROTATIONS[opposite].as_matrix(), atol=1e-12)


@pytest.mark.parametrize("name", list(PRINTED_ENTRIES))
def test_eqs_13_to_18_then_6_7_by_hand(name):
    cubemap = Cubemap(T265_LIKE)
    face = cubemap.faces[name]
    rng = np.random.default_rng(7)
    uv = rng.uniform(0, face.size - 1, size=(50, 2))
    fisheye_uv, valid = cubemap.face_to_fisheye(name, uv)
    assert valid.any()
    r_face = by_columns(PRINTED_ENTRIES[name])
    k_face_inverse = np.linalg.inv(face.K)
    for pixel, expected, ok in zip(uv, fisheye_uv, valid, strict=True):
        x_ci = k_face_inverse @ [pixel[0], pixel[1], 1.0]  # (13), with the face's K^-1 the package adds
        x_c = r_face @ x_ci  # (14)-(15)
        if ok:  # (16)-(18), (6), (7) are eqs. 2-7 with X_C for X
            np.testing.assert_allclose(expected, eucm_by_hand(x_c, T265_LIKE), rtol=0, atol=1e-6)


def test_eq_13_without_k_inverse_is_not_a_ray():
    # the printed X_CI = (u, v, 1) in pixels rotated as it is does not give the face pixel's ray
    cubemap = Cubemap(T265_LIKE)
    face = cubemap.faces["front"]
    corner = np.array([0.0, 0.0])
    ray, _ = face.rays(corner)
    printed = np.array([corner[0], corner[1], 1.0])
    assert np.degrees(np.arccos(ray @ printed / np.linalg.norm(printed))) > 40.0


def test_eqs_23_24_the_scale():
    height, focal = 0.12, 286.0
    assert metres_per_pixel(height, focal) == pytest.approx(height / focal)  # (23)
    m = np.array([3.0, -16.5])
    np.testing.assert_allclose(metres_per_pixel(height, focal) * m, height / focal * m)  # (24)
    with pytest.raises(ValueError, match="positive"):
        metres_per_pixel(0.0, focal)


def paper_delta(dx, dy, two_argument):
    """Eq. 26 as printed, with the paper's (dx, dy) to the robot's right and forward."""
    angle = np.arctan2(dy, dx) if two_argument else np.arctan(dy / dx)
    return angle - np.pi / 2


@pytest.mark.parametrize("degrees", [-80.0, -30.0, -5.0, 5.0, 30.0, 80.0])
def test_eq_26_in_the_papers_axes(degrees):
    bicycle = PaperBicycle(0.8, 0.4)
    direction = np.radians(degrees)  # the wheel's direction in base_link, left positive
    d = 0.01 * np.array([np.cos(direction), np.sin(direction)])  # base_link: x forward, y left
    _, delta = bicycle.inputs(d, 1 / 30)
    assert delta == pytest.approx(direction)
    dx, dy = -d[1], d[0]  # the paper's axes: to the right, forward
    assert paper_delta(dx, dy, two_argument=True) == pytest.approx(delta)
    printed = paper_delta(dx, dy, two_argument=False)
    if degrees < 0:  # moving to the right: the one-argument arctan as printed agrees
        assert printed == pytest.approx(delta)
    else:  # moving to the left: it is half a turn off
        assert printed == pytest.approx(delta - np.pi)


def test_eqs_25_to_34_by_hand():
    wheelbase, lever, dt = 0.8, 0.3, 1 / 30
    bicycle = PaperBicycle(wheelbase, lever)
    d = np.array([0.015, 0.006])  # the front wheel's displacement in base_link
    dx, dy = -d[1], d[0]  # in the paper's axes
    V = np.sqrt(dx**2 + dy**2) / dt  # (25)
    delta = np.arctan2(dy, dx) - np.pi / 2  # (26), two-argument
    S = wheelbase / np.tan(delta)  # (27)
    beta = np.arctan(lever / S)  # (28)
    assert beta == pytest.approx(np.arctan(lever * np.tan(delta) / wheelbase))
    R = S / np.cos(beta)  # (29)
    theta_dot = V / R  # (30)
    assert theta_dot == pytest.approx(V * np.tan(delta) * np.cos(beta) / wheelbase)
    pose = np.array([1.0, -2.0, 0.4])  # base_link's pose
    reference = pose[:2] + lever * np.array([np.cos(pose[2]), np.sin(pose[2])])
    theta = pose[2]
    x_dot, y_dot = V * np.cos(theta + beta), V * np.sin(theta + beta)  # (32), (33)
    x, y = reference + np.array([x_dot, y_dot]) * dt  # (34)
    theta = theta + theta_dot * dt  # (31), eq. 34's third row
    expected_base = [x - lever * np.cos(theta), y - lever * np.sin(theta), theta]

    speed, steering = bicycle.inputs(d, dt)
    assert speed == pytest.approx(V) and steering == pytest.approx(delta)
    assert bicycle.instant_centre_distance(steering) == pytest.approx(S)
    assert bicycle.slip(steering) == pytest.approx(beta)
    assert bicycle.turning_radius(steering) == pytest.approx(R)
    np.testing.assert_allclose(bicycle.rates(speed, steering, pose[2]), [x_dot, y_dot, theta_dot])
    np.testing.assert_allclose(bicycle.step(pose, d, dt), expected_base, rtol=0, atol=1e-12)


def test_eq_27_29_straight_ahead_are_infinite():
    bicycle = PaperBicycle(0.8, 0.8)
    assert np.isinf(bicycle.instant_centre_distance(0.0))
    assert np.isinf(bicycle.turning_radius(0.0))
    assert bicycle.rates(0.5, 0.0, 0.0)[2] == 0.0


def test_face_rotations_are_quarter_turns_about_x_and_y():
    # the same matrices named by their axes, as the module docstring writes them
    expected = {
        "left": Rotation.from_euler("y", -90, degrees=True),
        "bottom": Rotation.from_euler("x", -90, degrees=True),
    }
    for name, rotation in expected.items():
        np.testing.assert_allclose(FACE_ROTATIONS[name].as_matrix(), rotation.as_matrix(), atol=1e-12)
