"""The renderer against independent truth: chessboard corners found by OpenCV lie where the camera
model projects the board's true corners, for both rigs, on the floor and held in front of the camera;
a moving sheet shows where its own trajectory puts it, a glint stays where the camera sees its floor point."""

import dataclasses

import cv2
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from gpo.cameras.targets import Chessboard, FloorBoard
from gpo.sim.boardviews import CALIBRATION_BOARD, board_views
from gpo.sim.ceiling import LIT, Ceiling
from gpo.sim.disturbances import GPI_PATCH_M, Disturbances, Glint, MovingSheet, print_sheet
from gpo.sim.floors import FLOOR_KINDS, make_floor
from gpo.sim.render import FloorRenderer, Sensor, camera_pose_in_world, render_board_view
from gpo.sim.rigs import downward_rig, t265_rig

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


# ------------------------------------------------------------------------------------------ disturbances

QUIET = Sensor(read_noise=0.0, shot_noise=0.0, flicker=0.0, vignetting=0.0)  # images differ only where the scene does
SHEET = MovingSheet((0.12, 0.085), (0.80, -0.02), 0.0, (0.04, 0.12), 0.3, 0.4, seed=5)
SHEET_TIMES = (0.0, 0.3)
SHEET_POSES = (np.array([0.0, 0.0, 0.0]), np.array([0.06, 0.0, 0.03]))  # the robot rolls 6 cm and turns


@pytest.fixture(scope="module")
def floor():
    return make_floor("raised", (-0.5, 1.6, -0.8, 0.8), texel=1e-3, seed=6)


def world_to_pixels(rig, pose, world_xy: np.ndarray) -> np.ndarray:
    """Camera pixels (N, 2) of floor points (N, 2) in world, with the robot at ``pose``."""
    rotation, centre = camera_pose_in_world(rig, pose)
    points = np.column_stack([world_xy, np.zeros(len(world_xy))])
    pixels, valid = rig.camera.project(rotation.inv().apply(points - centre))
    assert valid.all()
    return pixels


def outline_mask(rig, pose, corners_world: np.ndarray, grow_px: int) -> np.ndarray:
    """Pixels inside the image of the floor polygon ``corners_world`` (its edges curve in a fisheye), grown by
    ``grow_px`` (negative: shrunk)."""
    edges = np.concatenate(
        [
            np.linspace(a, b, 60, endpoint=False)
            for a, b in zip(corners_world, np.roll(corners_world, -1, axis=0), strict=True)
        ]
    )
    mask = np.zeros((rig.camera.height, rig.camera.width), np.uint8)
    cv2.fillPoly(mask, [np.rint(world_to_pixels(rig, pose, edges)).astype(np.int32)], 1)
    kernel = np.ones((2 * abs(grow_px) + 1,) * 2, np.uint8)
    return (cv2.dilate(mask, kernel) if grow_px > 0 else cv2.erode(mask, kernel)).astype(bool)


def sheet_truth(time_s: float) -> tuple[np.ndarray, float]:
    """SHEET's centre (2,) and heading at ``time_s``, from its constant velocity and turn rate."""
    return np.array([0.80, -0.02]) + np.array([0.04, 0.12]) * time_s, 0.3 + 0.4 * time_s


def sheet_corners(time_s: float) -> np.ndarray:
    centre, yaw = sheet_truth(time_s)
    half = np.array([[1, 1], [-1, 1], [-1, -1], [1, -1]]) * np.array([0.06, 0.0425])
    return centre + half @ np.array([[np.cos(yaw), np.sin(yaw)], [-np.sin(yaw), np.cos(yaw)]])


def test_without_disturbances_the_image_is_unchanged(floor):
    rig = RIGS["t265"]
    plain = FloorRenderer(rig, floor)
    none = Disturbances()
    idle = FloorRenderer(
        rig, floor, sheets=none.place_sheets(np.arange(3.0), np.zeros((3, 3))), glints=none.place_glints()
    )
    out_of_sight = FloorRenderer(rig, floor, sheets=(MovingSheet((0.1, 0.07), (40.0, 0.0), 0.0, (0.0, 0.0), 0.0),))
    for poses, times in (([0.1, 0.05, 0.2], 2.0), ([[0.1, 0.05, 0.2], [0.11, 0.05, 0.21]], [2.0, 2.1])):
        expected = plain.render(poses, frame_seed=3)
        assert np.array_equal(idle.render(poses, frame_seed=3, times_s=times), expected)
        assert np.array_equal(out_of_sight.render(poses, frame_seed=3, times_s=times), expected)


def test_a_printed_sheet_covers_its_area_exactly():
    printed = print_sheet((0.1234, 0.0871), 1e-3, seed=2)
    assert printed[..., 1].sum() * 1e-6 == pytest.approx(0.1234 * 0.0871, rel=1e-6)
    assert printed[..., 1].max() == 1.0 and (printed[..., 0] <= 255 * printed[..., 1] + 1e-3).all()
    assert np.array_equal(print_sheet((0.1234, 0.0871), 1e-3, seed=2), printed)


def test_a_sheet_lies_where_its_trajectory_puts_it(floor):
    """With the sheet, the image differs from the bare floor's inside the sheet's projected outline, nowhere else."""
    rig = RIGS["t265"]
    bare = FloorRenderer(rig, floor, QUIET)
    covered = FloorRenderer(rig, floor, QUIET, sheets=(SHEET,))
    for time_s, pose in zip(SHEET_TIMES, SHEET_POSES, strict=True):
        changed = covered.render(pose, times_s=time_s) != bare.render(pose, times_s=time_s)
        assert not changed[~outline_mask(rig, pose, sheet_corners(time_s), 3)].any()
        assert changed[outline_mask(rig, pose, sheet_corners(time_s), -2)].mean() > 0.95


def test_what_is_printed_on_a_sheet_moves_with_the_sheet(floor):
    """Each pixel on the sheet at the second time shows the print seen where the sheet's motion took that print
    from at the first time, not what lay there on the floor."""
    rig = RIGS["t265"]
    renderer = FloorRenderer(rig, floor, QUIET, sheets=(SHEET,))
    (t1, t2), (pose1, pose2) = SHEET_TIMES, SHEET_POSES
    first, second = (renderer.render(pose, times_s=t) for pose, t in zip((pose1, pose2), (t1, t2), strict=True))
    rows, cols = np.nonzero(outline_mask(rig, pose2, sheet_corners(t2), -4))
    x, y, yaw = pose2
    base = renderer.floor_points[rows, cols]
    seen = np.column_stack(
        [
            x + np.cos(yaw) * base[:, 0] - np.sin(yaw) * base[:, 1],
            y + np.sin(yaw) * base[:, 0] + np.cos(yaw) * base[:, 1],
        ]
    )
    (centre1, yaw1), (centre2, yaw2) = sheet_truth(t1), sheet_truth(t2)
    turn = yaw1 - yaw2
    carried = centre1 + (seen - centre2) @ np.array([[np.cos(turn), np.sin(turn)], [-np.sin(turn), np.cos(turn)]])

    def difference(world_at_t1):
        pixels = world_to_pixels(rig, pose1, world_at_t1).astype(np.float32)
        before = cv2.remap(first.astype(np.float32), pixels[:, :1], pixels[:, 1:], cv2.INTER_LINEAR)[:, 0]
        return np.median(np.abs(before - second[rows, cols]))

    assert difference(carried) < 3.0
    assert difference(seen) > 15.0  # had the print stayed on the floor


def patch_mask(rig) -> np.ndarray:
    """Pixels showing the ortho-GPI's floor patch."""
    x_min, x_max, y_min, y_max = GPI_PATCH_M
    return outline_mask(rig, np.zeros(3), np.array([[x_min, y_min], [x_max, y_min], [x_max, y_max], [x_min, y_max]]), 0)


def test_a_glint_stays_put_in_the_image_inside_the_floor_patch(floor):
    """The glint adds the same light at the same pixels whatever the pose; its centre is where the camera sees the
    floor point it is centred on, inside the ortho-GPI's floor patch."""
    rig = RIGS["t265"]
    glint = Glint((0.78, 0.03), radius_m=0.03, peak=60.0, flicker=0.0, seed=1)
    bare, lit = FloorRenderer(rig, floor, QUIET), FloorRenderer(rig, floor, QUIET, glints=(glint,))
    poses = ([0.0, 0.0, 0.0], [0.05, 0.01, 0.04])
    floors = [bare.render(pose).astype(float) for pose in poses]
    added = [lit.render(pose).astype(float) - floor_image for pose, floor_image in zip(poses, floors, strict=True)]
    assert np.median(np.abs(floors[0] - floors[1])[patch_mask(rig)]) > 10  # the floor moved
    unclipped = (floors[0] + added[0] < 255) & (floors[1] + added[1] < 255)
    assert np.abs(added[0] - added[1])[unclipped].max() <= 1.0
    centre = world_to_pixels(rig, np.zeros(3), np.array([[0.78, 0.03]]))[0]
    assert added[0][tuple(np.rint(centre[::-1]).astype(int))] >= 0.9 * 60.0
    lit_pixels = added[0] > 2.0
    assert lit_pixels.sum() > 500 and not (lit_pixels & ~patch_mask(rig)).any()


def test_features_on_a_glint_stand_still_while_the_floor_flows(floor):
    """KLT on two frames 1 cm apart: the glint's corners keep their place, the floor's move by pixels."""
    rig = RIGS["t265"]
    glint = Glint((0.78, 0.03), radius_m=0.03)
    lit = FloorRenderer(rig, floor, glints=(glint,))
    first, second = lit.render([0.0, 0.0, 0.0], frame_seed=1), lit.render([0.01, 0.0, 0.0], frame_seed=2)
    on_glint = FloorRenderer(rig, floor, QUIET, glints=(glint,)).render(np.zeros(3)).astype(float) - FloorRenderer(
        rig, floor, QUIET
    ).render(np.zeros(3))
    glint_mask = on_glint > 20.0
    floor_mask = patch_mask(rig) & ~cv2.dilate(glint_mask.astype(np.uint8), np.ones((15, 15), np.uint8)).astype(bool)

    def flow(mask):
        corners = cv2.goodFeaturesToTrack(first, 40, 0.01, 3, mask=mask.astype(np.uint8))
        moved, status, _ = cv2.calcOpticalFlowPyrLK(first, second, corners, None, winSize=(15, 15), maxLevel=3)
        return np.linalg.norm((moved - corners).reshape(-1, 2)[status.ravel() == 1], axis=1)

    assert np.median(flow(glint_mask)) < 0.5
    assert np.median(flow(floor_mask)) > 3.0


@pytest.mark.parametrize("rig_name, height_m", [("t265", 2.8), ("t265", 9.0), ("downward", 4.0)])
def test_a_glossy_floor_mirrors_the_ceiling_at_the_cameras_height_plus_the_ceilings(rig_name, height_m):
    # the mirror image of the ceiling lies height_m below the floor: seen from the camera at height h, a floor point
    # at a horizontal distance d from the camera's foot mirrors the ceiling point at d * (h + H) / h (similar
    # triangles), so the lamps' reflections move at h / (h + H) of the floor's speed
    rig = {"t265": t265_rig, "downward": downward_rig}[rig_name]()
    floor = dataclasses.replace(make_floor("industrial", (-3.0, 3.0, -3.0, 3.0), 4e-3, 1), sheen=True)
    renderer = FloorRenderer(rig, floor, ceiling=Ceiling(height_m=height_m))
    foot, h = rig.mount.position[:2], rig.mount.position[2]
    seen = renderer.floor_points[renderer.hits_floor]
    np.testing.assert_allclose(renderer._ceiling, foot + (seen - foot) * (h + height_m) / h, rtol=1e-5, atol=1e-5)


def test_the_ceiling_seen_and_the_ceiling_mirrored_share_one_lamp_layout():
    ceiling = Ceiling(pitch_m=(3.0, 2.0), lamp_m=(1.4, 0.4), yaw_rad=np.pi / 2, offset_m=(0.3, -0.2), reflection=50.0)
    x, y = np.meshgrid(np.linspace(-4, 4, 161, dtype=np.float32), np.linspace(-4, 4, 161, dtype=np.float32))
    lit = ceiling.shade(x, y) == LIT
    # turned a quarter turn: a lamp's length runs along y, its centres at the offset plus multiples of the pitch
    u, v = y - np.float32(-0.2), -(x - np.float32(0.3))
    expected = (np.abs((u % 3.0) - 1.5) < 0.7) & (np.abs((v % 2.0) - 1.0) < 0.2)
    assert (lit == expected).mean() > 0.995  # all but points on a lamp's edge, where float32 rounding decides
    mirrored = ceiling.mirrored(x, y)
    np.testing.assert_allclose(mirrored[lit], 50.0, rtol=1e-6)  # on a lamp: its whole reflection
    assert mirrored[~lit].max() <= 50.0 and np.median(mirrored[~lit]) < 5.0  # fading beyond its edge
    with pytest.raises(ValueError, match="fit"):
        Ceiling(pitch_m=(1.0, 1.0), lamp_m=(1.2, 0.3))
