"""The cubemap against truth written here independently: face rotations as matrices, each face as K = [[N/2, 0,
(N-1)/2], [0, N/2, (N-1)/2], [0, 0, 1]], 3-D points and lines, and the simulator's floor chessboard."""

import cv2
import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from gpo.cameras import EUCM, T265_LIKE
from gpo.floor_image.cubemap import CROSS_CELLS, FACE_NAMES, Cubemap
from gpo.sim.record import FLOOR_BOARDS, floor_board_image
from gpo.sim.render import camera_pose_in_world
from gpo.sim.rigs import t265_rig

# fisheye_optical <- face: the columns are the face's x (right), y (down) and z (viewing) axes in the fisheye frame
FACE_MATRICES = {
    "front": np.eye(3),
    "left": np.array([[0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]]),
    "right": np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]]),
    "bottom": np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]]),
    "top": np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]]),
}
N = 572  # the default face size of the T265-like camera: 2 * f, f = 286 px
CUBEMAP = Cubemap(T265_LIKE)
RNG_SEED = 5


def face_projection(points: np.ndarray, name: str, size: int = N) -> tuple[np.ndarray, np.ndarray]:
    """Face pixels (n, 2) of fisheye-frame points (n, 3) through the face's pinhole, and whether they lie on it."""
    in_face = points @ FACE_MATRICES[name]  # R^T p, row by row
    with np.errstate(invalid="ignore", divide="ignore"):
        uv = size / 2.0 * in_face[:, :2] / in_face[:, 2:] + (size - 1) / 2.0
    on_face = (in_face[:, 2] > 0) & np.all((uv >= -0.5) & (uv <= size - 0.5), axis=1)
    return uv, on_face


def line_residuals(points: np.ndarray) -> np.ndarray:
    """Distances (pixels) of 2-D points (n, 2) from their total-least-squares line."""
    centred = points - points.mean(axis=0)
    normal = np.linalg.svd(centred)[2][-1]
    return np.abs(centred @ normal)


def random_points(count: int, seed: int = RNG_SEED) -> np.ndarray:
    """Points (count, 3) in all directions, 0.1-5 m from the lens."""
    rng = np.random.default_rng(seed)
    directions = rng.standard_normal((count, 3))
    return directions / np.linalg.norm(directions, axis=1, keepdims=True) * rng.uniform(0.1, 5.0, (count, 1))


def test_faces_share_one_90_degree_intrinsic_and_the_written_rotations():
    assert CUBEMAP.face_size == N
    K = np.array([[N / 2, 0.0, (N - 1) / 2], [0.0, N / 2, (N - 1) / 2], [0.0, 0.0, 1.0]])
    assert set(CUBEMAP.faces) == set(FACE_NAMES) == set(FACE_MATRICES)
    for name, face in CUBEMAP.faces.items():
        assert face.name == name and face.size == N
        np.testing.assert_array_equal(face.K, K)
        np.testing.assert_allclose(face.rotation.as_matrix(), FACE_MATRICES[name], atol=1e-15)
    # the outer edges of a face's edge pixels are 45 degrees off its axis
    edge_ray = np.linalg.inv(K) @ [N - 0.5, (N - 1) / 2, 1.0]
    assert np.degrees(np.arctan2(edge_ray[0], edge_ray[2])) == pytest.approx(45.0, abs=1e-12)
    assert Cubemap(T265_LIKE, 100).faces["top"].K[0, 0] == 50.0


def test_the_bottom_face_looks_at_the_floor_on_the_robot():
    rig = t265_rig()
    axis_in_base = (rig.mount.rotation * CUBEMAP.faces["bottom"].rotation).apply([0.0, 0.0, 1.0])
    assert axis_in_base[2] < -0.99  # straight down but for the camera's 6 degree pitch and 1.5 degree roll
    front_axis = (rig.mount.rotation * CUBEMAP.faces["front"].rotation).apply([0.0, 0.0, 1.0])
    assert front_axis[0] > 0.99


def test_fisheye_to_face_agrees_with_each_faces_own_pinhole():
    points = random_points(40_000)
    fisheye_uv, seen = T265_LIKE.project(points)
    seen &= T265_LIKE.in_image(fisheye_uv)
    for name in FACE_NAMES:
        expected, on_face = face_projection(points, name)
        face_uv, valid = CUBEMAP.fisheye_to_face(name, fisheye_uv)
        np.testing.assert_array_equal(valid, on_face & seen)
        assert valid.sum() > 1000
        assert np.abs(face_uv[valid] - expected[valid]).max() < 1e-6
        assert np.isnan(face_uv[~valid]).all()
        back, back_valid = CUBEMAP.face_to_fisheye(name, expected[valid])
        assert back_valid.all() and np.abs(back - fisheye_uv[valid]).max() < 1e-6


def test_round_trip_over_every_face_pixel_centre_and_random_subpixels():
    rng = np.random.default_rng(RNG_SEED)
    for name in FACE_NAMES:
        centres = CUBEMAP.faces[name].pinhole.pixel_grid().reshape(-1, 2)
        uv = np.concatenate([centres, rng.uniform(-0.49, N - 0.51, (20_000, 2))])
        fisheye_uv, valid = CUBEMAP.face_to_fisheye(name, uv)
        back, back_valid = CUBEMAP.fisheye_to_face(name, fisheye_uv[valid])
        assert back_valid.all()
        assert np.abs(back - uv[valid]).max() < 1e-6
        assert valid.mean() > (0.99 if name == "front" else 0.5)


@given(
    name=st.sampled_from(FACE_NAMES),
    u=st.floats(-0.49, N - 0.51),
    v=st.floats(-0.49, N - 0.51),
)
def test_round_trip_of_any_face_point(name, u, v):
    fisheye_uv, valid = CUBEMAP.face_to_fisheye(name, [u, v])
    if valid:
        back, back_valid = CUBEMAP.fisheye_to_face(name, fisheye_uv)
        assert back_valid and np.abs(back - [u, v]).max() < 1e-6
    else:
        assert np.isnan(fisheye_uv).all()


def test_faces_tile_every_direction_the_fisheye_sees_but_the_back():
    directions = random_points(200_000)
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    fisheye_uv, seen = T265_LIKE.project(directions)
    seen &= T265_LIKE.in_image(fisheye_uv)
    magnitudes = np.sort(np.abs(directions), axis=1)
    off_edges = magnitudes[:, 2] - magnitudes[:, 1] > 1e-9  # not on an edge between two faces
    back = (directions[:, 2] < 0) & (-directions[:, 2] == magnitudes[:, 2])
    counts = sum(CUBEMAP.fisheye_to_face(name, fisheye_uv)[1].astype(int) for name in FACE_NAMES)
    chosen = seen & off_edges
    np.testing.assert_array_equal(counts[chosen], np.where(back[chosen], 0, 1))
    assert counts[~seen].max() == 0
    assert chosen.sum() > 100_000


def test_no_direction_falls_between_two_faces():
    t = np.linspace(-0.95, 0.95, 39)
    one = np.ones_like(t)
    edges = [  # directions exactly on the edges the front face shares, and on the edges between side faces
        np.column_stack(axes)
        for axes in [(one, t, one), (-one, t, one), (t, one, one), (t, -one, one), (one, one, t), (-one, -one, t)]
    ]
    directions = np.concatenate(edges)
    fisheye_uv, seen = T265_LIKE.project(directions)
    seen &= T265_LIKE.in_image(fisheye_uv)
    counts = sum(CUBEMAP.fisheye_to_face(name, fisheye_uv)[1].astype(int) for name in FACE_NAMES)
    assert seen.sum() > 150
    assert (counts[seen] == 2).all()  # on a seam, both faces hold the direction: no cracks


def test_straight_lines_in_space_are_straight_in_every_face():
    rng = np.random.default_rng(RNG_SEED)
    checked = 0
    for name in FACE_NAMES:
        for _ in range(20):
            start = FACE_MATRICES[name] @ np.array([*rng.uniform(-1.0, 1.0, 2), 1.0]) * rng.uniform(0.3, 3.0)
            end = start + rng.standard_normal(3)
            points = start + np.linspace(0.0, 1.0, 200)[:, None] * (end - start)
            fisheye_uv, _ = T265_LIKE.project(points)
            face_uv, valid = CUBEMAP.fisheye_to_face(name, fisheye_uv)
            if valid.sum() < 20:
                continue
            assert line_residuals(face_uv[valid]).max() < 1e-6
            checked += 1
    assert checked > 60
    # the fisheye itself bends lines: a row of points 1 m ahead, seen across the image
    row = np.column_stack([np.linspace(-2.0, 2.0, 50), np.full(50, 0.5), np.ones(50)])
    assert line_residuals(T265_LIKE.project(row)[0]).max() > 20.0


def test_lines_on_the_floor_are_straight_in_the_bottom_face():
    mount = t265_rig().mount
    for y in (-0.1, -0.05, 0.0, 0.05, 0.1):  # lines along the robot's x axis, in base_link, on the floor
        floor = np.column_stack([np.linspace(0.5, 0.75, 100), np.full(100, y), np.zeros(100)])
        optical = mount.rotation.inv().apply(floor - mount.position)
        face_uv, valid = CUBEMAP.fisheye_to_face("bottom", T265_LIKE.project(optical)[0])
        assert valid.sum() > 30
        assert line_residuals(face_uv[valid]).max() < 1e-6


@pytest.fixture(scope="module")
def floor_board_fisheye() -> np.ndarray:
    """The T265-like rig's rendered view of its 20 mm floor chessboard, the robot at the world origin."""
    return floor_board_image("t265")


def test_the_floor_chessboard_comes_out_straight_where_it_lies(floor_board_fisheye):
    board = FLOOR_BOARDS["t265"]
    rotation, centre = camera_pose_in_world(t265_rig(), np.zeros(3))
    corners_optical = rotation.inv().apply(board.corners_world() - centre)
    columns, rows = board.board.pattern_size
    bent = T265_LIKE.project(corners_optical)[0].reshape(rows, columns, 2).transpose(1, 0, 2)
    assert max(line_residuals(line).max() for line in bent) > 1.0  # the fisheye bends the lines across the robot

    face = CUBEMAP.face_image(floor_board_fisheye, "front")
    found, corners = cv2.findChessboardCorners(face, (columns, rows))
    assert found
    criteria = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 50, 1e-4)
    corners = cv2.cornerSubPix(face, corners, (5, 5), (-1, -1), criteria).reshape(rows, columns, 2)
    assert max(line_residuals(row).max() for row in corners) < 0.3
    assert max(line_residuals(column).max() for column in corners.transpose(1, 0, 2)) < 0.3

    truth, on_face = face_projection(corners_optical, "front")
    assert on_face.all()
    detected = corners.reshape(-1, 2)
    distances = np.linalg.norm(detected[:, None, :] - truth[None, :, :], axis=2).min(axis=1)
    assert np.median(distances) < 0.5 and distances.max() < 1.0


def test_cross_lays_out_the_five_faces_with_continuous_seams(floor_board_fisheye):
    image = floor_board_fisheye
    colour = np.dstack([image, 255 - image, image // 2])
    cross = CUBEMAP.cross(colour)
    assert cross.shape == (3 * N, 3 * N, 3) and cross.dtype == np.uint8
    for name, (row, column) in CROSS_CELLS.items():
        cell = cross[row * N : (row + 1) * N, column * N : (column + 1) * N]
        np.testing.assert_array_equal(cell, CUBEMAP.face_image(colour, name))
    for row, column in [(0, 0), (0, 2), (2, 0), (2, 2)]:
        assert not cross[row * N : (row + 1) * N, column * N : (column + 1) * N].any()
    # across each seam, neighbouring cross pixels show neighbouring fisheye pixels
    middle = np.arange(200, N - 200, dtype=float)
    first, last = np.zeros_like(middle), np.full_like(middle, N - 1.0)
    seams = {  # face: (its pixels on the seam, the front face's pixels on the other side)
        "left": (np.column_stack([last, middle]), np.column_stack([first, middle])),
        "right": (np.column_stack([first, middle]), np.column_stack([last, middle])),
        "top": (np.column_stack([middle, last]), np.column_stack([middle, first])),
        "bottom": (np.column_stack([middle, first]), np.column_stack([middle, last])),
    }
    for name, (face_uv, front_uv) in seams.items():
        across, valid = CUBEMAP.face_to_fisheye(name, face_uv)
        front, front_valid = CUBEMAP.face_to_fisheye("front", front_uv)
        assert valid.all() and front_valid.all()
        assert np.linalg.norm(across - front, axis=1).max() < 1.0


def test_tables_are_computed_once_and_match_the_point_mapping():
    tables = CUBEMAP.maps("bottom")
    assert Cubemap(T265_LIKE).maps("bottom") is tables
    assert tables.map_x.dtype == tables.map_y.dtype == np.float32 and tables.map_x.shape == (N, N)
    assert not tables.map_x.flags.writeable
    fisheye_uv, valid = CUBEMAP.face_to_fisheye("bottom", CUBEMAP.faces["bottom"].pinhole.pixel_grid())
    np.testing.assert_array_equal(tables.valid, valid)
    np.testing.assert_allclose(tables.map_x[valid], fisheye_uv[valid][:, 0], atol=1e-4)
    np.testing.assert_allclose(tables.map_y[valid], fisheye_uv[valid][:, 1], atol=1e-4)
    assert np.isnan(tables.map_x[~valid]).all() and np.isnan(tables.map_y[~valid]).all()


def masked_faces(camera: EUCM, size: int = 64) -> dict[str, tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """Face name -> (face image of a uniform grey-200 fisheye frame, valid, unit rays of the pixel centres)."""
    cubemap = Cubemap(camera, size)
    frame = np.full((camera.height, camera.width), 200, np.uint8)
    grid = cubemap.faces["front"].pinhole.pixel_grid().reshape(-1, 2)
    faces = {}
    for name in FACE_NAMES:
        rays = np.column_stack([(grid - (size - 1) / 2.0) / (size / 2.0), np.ones(len(grid))]) @ FACE_MATRICES[name].T
        rays /= np.linalg.norm(rays, axis=1, keepdims=True)
        faces[name] = (cubemap.face_image(frame, name), cubemap.maps(name).valid, rays.reshape(size, size, 3))
    return faces


def test_a_narrow_lens_leaves_the_side_faces_partly_masked():
    narrow = EUCM(fx=286.0, fy=286.0, cx=424.0, cy=400.0, alpha=0.1, beta=1.0, width=848, height=800)
    for name, (image, valid, rays) in masked_faces(narrow).items():
        fisheye_uv, seen = narrow.project(rays)
        np.testing.assert_array_equal(valid, seen & narrow.in_image(fisheye_uv))
        assert (image[valid] == 200).all() and (image[~valid] == 0).all()
        if name == "front":
            assert valid.all()
        else:
            assert 0.05 < valid.mean() < 0.6


def test_rays_beyond_the_lens_valid_region_are_masked_inside_the_image():
    # alpha > 0.5, beta = 1: the lens sees rays up to arccos(-w), w = (1 - alpha) / alpha = 0.25, i.e. 104.5 degrees
    # off its axis; that border lies 1.29 fx = 258 px from the centre, well inside the image
    wide = EUCM(fx=200.0, fy=200.0, cx=424.0, cy=400.0, alpha=0.8, beta=1.0, width=848, height=800)
    for name, (image, valid, rays) in masked_faces(wide).items():
        inside_lens = rays[..., 2] > -0.25
        clear = np.abs(rays[..., 2] + 0.25) > 1e-9
        np.testing.assert_array_equal(valid[clear], inside_lens[clear])
        assert (image[valid] == 200).all() and (image[~valid] == 0).all()
        assert valid.all() if name == "front" else 0.6 < valid.mean() < 0.95


def test_bad_input_gets_clear_errors():
    with pytest.raises(ValueError, match=r"640x480.*848x800"):
        CUBEMAP.face_image(np.zeros((480, 640), np.uint8), "front")
    with pytest.raises(ValueError, match=r"800x848.*848x800"):
        CUBEMAP.cross(np.zeros((848, 800), np.uint8))
    with pytest.raises(ValueError, match="uint8"):
        CUBEMAP.face_image(np.zeros((800, 848), np.float32), "front")
    for size in (7, 0, -4, 7.5, True):
        with pytest.raises(ValueError, match="face_size"):
            Cubemap(T265_LIKE, size)
    with pytest.raises(ValueError, match=r"back.*front, left, right, bottom, top"):
        CUBEMAP.maps("back")
    with pytest.raises(ValueError, match=r"shape \(\.\.\., 2\)"):
        CUBEMAP.fisheye_to_face("front", np.zeros((4, 3)))
    with pytest.raises(ValueError, match=r"shape \(\.\.\., 3\)"):
        CUBEMAP.faces["front"].pixels(np.zeros((4, 2)))
