"""The renderer against independent truth: chessboard corners found by OpenCV lie where the camera
model projects the board's true corners, for both rigs, on the floor and held in front of the camera."""

import cv2
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from gpo.sim.boardviews import CALIBRATION_BOARD, board_views
from gpo.sim.floors import FLOOR_KINDS, make_floor
from gpo.sim.render import FloorRenderer, camera_pose_in_world, render_board_view
from gpo.sim.rigs import downward_rig, t265_rig
from gpo.targets import Chessboard, FloorBoard

RIGS = {"t265": t265_rig(), "downward": downward_rig()}


def corner_errors(image: np.ndarray, board: Chessboard, truth: np.ndarray) -> np.ndarray:
    """Distance from each true corner to the nearest corner OpenCV finds, pixels."""
    found, corners = cv2.findChessboardCornersSB(image, board.pattern_size, flags=cv2.CALIB_CB_ACCURACY)
    assert found, "OpenCV did not find the chessboard"
    distances = np.linalg.norm(corners.reshape(-1, 1, 2) - truth[None], axis=-1)
    assert len(set(distances.argmin(axis=0))) == len(truth), "true corners must match distinct detections"
    return distances.min(axis=0)


@pytest.mark.parametrize("rig_name", RIGS)
@pytest.mark.parametrize(
    ("euler", "position"),
    [
        ([0.2, -0.3, 0.1], [-0.10, -0.08, 0.35]),
        ([0.0, 0.0, 0.0], [-0.12, -0.09, 0.40]),
        ([-0.3, 0.35, 0.2], [-0.10, -0.07, 0.45]),
    ],
)
def test_board_held_in_front_of_the_camera_lands_where_the_model_projects(rig_name, euler, position):
    camera = RIGS[rig_name].camera
    board = Chessboard((8, 6), 0.03, 0.03)
    rotation = Rotation.from_euler("xyz", euler)
    image = render_board_view(camera, board, (rotation, np.array(position)), seed=1)
    truth, valid = camera.project(rotation.apply(board.inner_corners()) + position)
    assert valid.all()
    assert np.median(corner_errors(image, board, truth)) < 0.3


@pytest.mark.parametrize(("rig_name", "board_x", "texel"), [("t265", 0.78, 1e-3), ("downward", -0.08, 5e-4)])
def test_board_lying_on_the_floor_lands_where_the_model_projects(rig_name, board_x, texel):
    rig = RIGS[rig_name]
    renderer = FloorRenderer(rig, make_floor("raised", (-0.5, 1.2, -0.5, 0.5), texel=texel, seed=1))
    on_floor = FloorBoard(Chessboard((8, 6), 0.02, 0.02), board_x, -0.05, 0.1)
    pose = np.array([0.0, 0.0, 0.0])
    image = renderer.render(pose, frame_seed=2, boards=(on_floor,))
    rotation, centre = camera_pose_in_world(rig, pose)
    truth, valid = rig.camera.project(rotation.inv().apply(on_floor.corners_world() - centre))
    assert valid.all()
    assert np.median(corner_errors(image, on_floor.board, truth)) < 0.3


@pytest.mark.parametrize("rig_name", RIGS)
def test_each_floor_pixel_sees_its_floor_point(rig_name):
    """The precomputed floor point of a pixel, taken back into the camera frame, projects onto that pixel."""
    rig = RIGS[rig_name]
    renderer = FloorRenderer(rig, make_floor("industrial", (-0.5, 0.5, -0.5, 0.5), texel=2e-3, seed=0))
    rows, cols = np.nonzero(renderer.hits_floor)
    pick = np.random.default_rng(0).choice(len(rows), 2000, replace=False)
    floor_base = np.column_stack([renderer.floor_points[rows[pick], cols[pick]], np.zeros(2000)])
    in_camera = rig.mount.rotation.inv().apply(floor_base - rig.mount.position)
    pixels, valid = rig.camera.project(in_camera)
    assert valid.all()
    np.testing.assert_allclose(pixels, np.column_stack([cols[pick], rows[pick]]), atol=1e-6)


def test_rendering_is_deterministic_and_the_noise_is_per_frame():
    renderer = FloorRenderer(RIGS["downward"], make_floor("wood", (-0.5, 0.5, -0.5, 0.5), texel=5e-4, seed=4))
    first = renderer.render([0.01, 0.02, 0.3], frame_seed=(7, 1))
    assert np.array_equal(first, renderer.render([0.01, 0.02, 0.3], frame_seed=(7, 1)))
    other = renderer.render([0.01, 0.02, 0.3], frame_seed=(7, 2))
    difference = first.astype(float) - other
    assert 0.5 < np.std(difference) < 10.0  # noise and flicker only: same scene


def test_floor_kinds_order_by_texture_strength():
    """Wood has the strongest fine texture, then the raised floor, then the industrial floor (as in the paper)."""
    strength = {}
    for kind in FLOOR_KINDS:
        texture = make_floor(kind, (0.0, 0.6, 0.0, 0.6), texel=1e-3, seed=5).levels[0].astype(np.float32)
        strength[kind] = cv2.Laplacian(cv2.GaussianBlur(texture, (0, 0), 1.0), cv2.CV_32F).std()
    assert strength["wood"] > strength["raised"] > strength["industrial"]


def test_floor_is_deterministic_and_rejects_unknown_kinds():
    a = make_floor("raised", (0.0, 0.3, 0.0, 0.2), texel=1e-3, seed=9)
    b = make_floor("raised", (0.0, 0.3, 0.0, 0.2), texel=1e-3, seed=9)
    assert all(np.array_equal(x, y) for x, y in zip(a.levels, b.levels, strict=True))
    with pytest.raises(ValueError, match="unknown floor kind 'carpet'"):
        make_floor("carpet", (0.0, 1.0, 0.0, 1.0))


@pytest.mark.parametrize("rig_name", RIGS)
def test_calibration_views_fill_the_image_and_their_corners_are_true(rig_name):
    camera = RIGS[rig_name].camera
    views = board_views(camera, 4, seed=3)
    assert all(((v.corners >= 20) & (v.corners <= [camera.width - 20, camera.height - 20])).all() for v in views)
    for view in views:
        assert np.median(corner_errors(view.image, CALIBRATION_BOARD, view.corners)) < 0.3
    assert np.array_equal(board_views(camera, 1, seed=3)[0].image, views[0].image)
