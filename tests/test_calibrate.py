"""Calibration against the simulator's truth: detection, the EUCM and pinhole fits, their error bars,
outlier views and bad input.

The target test adds Gaussian noise of 0.3 px (per coordinate) to the detected corners. With the
24 views of ``board_views(seed=0)`` the fit's standard deviation of fx is then 0.6 px (0.21 %), so
the 0.3 % target on fx is a 1.4-sigma bound: it holds for about 70 % of noise draws (noise seed 0
is one of them); the 3-sigma consistency test and the Monte Carlo check of the error bars hold for
every draw.
"""

import cv2
import numpy as np
import pytest
import yaml
from scipy.spatial.transform import Rotation

from gpo.cameras import Pinhole
from gpo.cameras.calibrate import (
    CalibrationError,
    calibrate_corners,
    calibrate_images,
    calibrate_views,
    initial_eucm,
)
from gpo.cameras.chessboard import find_corners, parse_board
from gpo.cameras.files import load_kalibr, save_kalibr
from gpo.cameras.targets import Chessboard
from gpo.cli.calibrate import main_calibrate
from gpo.sim.boardviews import CALIBRATION_BOARD, board_poses, board_views
from gpo.sim.render import render_board_view
from gpo.sim.rigs import downward_rig, t265_rig

FISHEYE = t265_rig().camera
IMAGE_SIZE = (FISHEYE.width, FISHEYE.height)
NOISE_PX = 0.3


def noisy(corners: dict, seed: int) -> list[np.ndarray]:
    rng = np.random.default_rng(seed)
    return [corners[index] + rng.normal(0.0, NOISE_PX, corners[index].shape) for index in sorted(corners)]


def true_corners(camera, poses, board=CALIBRATION_BOARD) -> list[np.ndarray]:
    return [camera.project(rotation.apply(board.inner_corners()) + position)[0] for rotation, position in poses]


@pytest.fixture(scope="module")
def fisheye_views():
    """24 rendered views of the default board by the T265-like fisheye (about 4 s)."""
    return board_views(FISHEYE, 24, seed=0)


@pytest.fixture(scope="module")
def detected(fisheye_views):
    """The whole path: images -> corner detection -> EUCM calibration."""
    return calibrate_views([view.image for view in fisheye_views], CALIBRATION_BOARD)


@pytest.fixture(scope="module")
def noisy_fit(detected):
    return calibrate_corners(noisy(detected.corners, seed=0), CALIBRATION_BOARD, IMAGE_SIZE)


def assert_meets_eucm_targets(result):
    fx, fy, cx, cy, alpha, beta = result.camera.params
    assert abs(fx / FISHEYE.fx - 1.0) < 0.003 and abs(fy / FISHEYE.fy - 1.0) < 0.003
    assert abs(cx - FISHEYE.cx) < 1.0 and abs(cy - FISHEYE.cy) < 1.0
    assert abs(alpha - FISHEYE.alpha) < 0.01 and abs(beta - FISHEYE.beta) < 0.02
    assert result.rms_px <= 0.35
    assert result.ok, result.summary()


# --- detection ---------------------------------------------------------------------------------


def matches_up_to_half_turn(found, truth, pattern_size, tolerance_px):
    """Corners equal to the truth, or to the truth turned by a half turn of the board (never mirrored)."""
    per_row, per_column = pattern_size
    grid = found.reshape(per_column, per_row, 2)
    return any(np.abs(candidate.reshape(-1, 2) - truth).max() < tolerance_px for candidate in (grid, grid[::-1, ::-1]))


def test_detection_finds_every_board_to_a_tenth_of_a_pixel(fisheye_views, detected):
    assert detected.used == list(range(24)) and not detected.dropped
    errors = []
    for index, view in enumerate(fisheye_views):
        assert matches_up_to_half_turn(detected.corners[index], view.corners, CALIBRATION_BOARD.pattern_size, 0.3)
        grid = detected.corners[index].reshape(5, 7, 2)
        best = min((grid, grid[::-1, ::-1]), key=lambda g: np.abs(g.reshape(-1, 2) - view.corners).max())
        errors.append(best.reshape(-1, 2) - view.corners)
    assert np.sqrt(np.mean(np.square(errors))) < 0.1


def test_detection_order_follows_the_board_where_its_colours_tell():
    # 9 x 6 squares: a half turn swaps the colours, so the order must equal the truth exactly
    board = Chessboard((9, 6), 0.03, 0.02)
    for rotation, position in board_poses(FISHEYE, 2, board, seed=4):
        image = render_board_view(FISHEYE, board, (rotation, position), seed=1)
        truth = true_corners(FISHEYE, [(rotation, position)], board)[0]
        found = find_corners(image, board.pattern_size, initial_eucm(*IMAGE_SIZE))
        assert np.abs(found - truth).max() < 0.3


def test_an_image_searched_again_is_answered_without_the_detector(fisheye_views, monkeypatch):
    """The same image and question: the corners the detector found before, a copy each time; another question or
    another image: the detector again."""
    calls = []
    detector = cv2.findChessboardCornersSB
    monkeypatch.setattr(cv2, "findChessboardCornersSB", lambda *args, **kwargs: calls.append(1) or detector(*args,
                                                                                                           **kwargs))
    image = fisheye_views[5].image.copy()
    image[0, 0] ^= 1  # an image no other test searched
    first = find_corners(image, CALIBRATION_BOARD.pattern_size)
    first[:] = 0.0  # the caller's copy
    again = find_corners(image.copy(), CALIBRATION_BOARD.pattern_size)
    assert len(calls) == 1
    assert matches_up_to_half_turn(again, fisheye_views[5].corners, CALIBRATION_BOARD.pattern_size, 0.3)
    find_corners(image, (5, 4))  # another board
    image[0, 1] ^= 1
    find_corners(image, CALIBRATION_BOARD.pattern_size)  # another image
    assert len(calls) == 3


def test_a_board_the_plain_detectors_miss_is_found_in_a_perspective_view():
    # a large board at 53 degrees off axis, cut by the image's top edge
    board = Chessboard((8, 6), 0.05, 0.03)
    poses = board_poses(FISHEYE, 31, board, distance=(0.25, 0.45), max_tilt=np.radians(60), margin_px=3, seed=7)
    image = render_board_view(FISHEYE, board, poses[30], seed=30)
    assert find_corners(image, board.pattern_size) is None
    found = find_corners(image, board.pattern_size, initial_eucm(*IMAGE_SIZE))
    truth = true_corners(FISHEYE, poses[30:], board)[0]
    assert matches_up_to_half_turn(found, truth, board.pattern_size, 1.0)


# --- EUCM ----------------------------------------------------------------------------------------


def test_full_path_meets_the_targets(detected):
    assert_meets_eucm_targets(detected)
    assert detected.rms_px < 0.1  # detection alone is good to a few hundredths of a pixel


def test_eucm_meets_the_targets_with_noisy_corners(noisy_fit):
    assert_meets_eucm_targets(noisy_fit)
    assert noisy_fit.converged
    assert set(noisy_fit.residuals) == set(range(24)) and noisy_fit.residuals[0].shape == (35, 2)
    rotation, position = noisy_fit.board_poses[0]
    assert isinstance(rotation, Rotation) and position.shape == (3,)


def test_standard_deviations_hold_the_truth_within_three_sigma(noisy_fit):
    errors = noisy_fit.camera.params - FISHEYE.params
    sigmas = np.array([noisy_fit.std[name] for name in ("fx", "fy", "cx", "cy", "alpha", "beta")])
    assert np.all(sigmas > 0)
    assert np.all(np.abs(errors) < 3.0 * sigmas)


def test_standard_deviations_match_the_scatter_over_noise_draws(detected):
    normalised = []
    for seed in range(1, 5):
        result = calibrate_corners(noisy(detected.corners, seed), CALIBRATION_BOARD, IMAGE_SIZE)
        sigmas = np.array(list(result.std.values()))
        normalised.append((result.camera.params - FISHEYE.params) / sigmas)
    assert 0.6 < np.sqrt(np.mean(np.square(normalised))) < 1.6


@pytest.mark.parametrize("corruption", ["shuffled", "displaced 5 px"])
def test_a_corrupted_view_is_dropped_and_the_targets_still_hold(detected, corruption):
    corners = noisy(detected.corners, seed=0)
    rng = np.random.default_rng(1)
    if corruption == "shuffled":
        corners[7] = rng.permutation(corners[7])
    else:
        angles = rng.uniform(-np.pi, np.pi, len(corners[7]))
        corners[7] = corners[7] + 5.0 * np.column_stack([np.cos(angles), np.sin(angles)])
    result = calibrate_corners(corners, CALIBRATION_BOARD, IMAGE_SIZE)
    reason = "do not form the board's grid" if corruption == "shuffled" else "outlier: RMS reprojection error"
    assert list(result.dropped) == [7] and reason in result.dropped[7]
    assert 7 not in result.used and len(result.used) == 23
    assert_meets_eucm_targets(result)
    assert f"view 7: {result.dropped[7]}" in result.summary()


def test_a_fit_that_does_not_converge_is_flagged(detected):
    result = calibrate_corners(noisy(detected.corners, 0), CALIBRATION_BOARD, IMAGE_SIZE, max_iterations=3)
    assert not result.converged and not result.ok
    assert any("did not converge" in warning for warning in result.warnings)
    assert "NOT A GOOD CALIBRATION" in result.summary()


def test_alpha_at_its_bound_is_flagged():
    # an EUCM fitted to a distortion-free pinhole drives alpha to its bound 0
    pinhole = Pinhole(400.0, 400.0, 320.0, 240.0, (0.0, 0.0, 0.0, 0.0), 640, 480)
    corners = true_corners(pinhole, board_poses(pinhole, 12, CALIBRATION_BOARD, seed=2))
    result = calibrate_corners(corners, CALIBRATION_BOARD, (640, 480))
    assert result.camera.alpha < 1e-3 and not result.ok
    assert any("alpha" in warning and "bound" in warning for warning in result.warnings)


# --- pinhole -------------------------------------------------------------------------------------


def test_pinhole_on_the_downward_rig_is_close_to_the_truth():
    """40 views at the poses of ``board_views`` (their true corners plus 0.3 px noise: rendering this
    camera's views takes over a second each). The tolerances are about 3.3 sigma of this set, from its
    reported standard deviations (which match the scatter over 20 noise draws): 1.1 px for f (0.18 %),
    cx and cy, 0.006 for k1, 0.035 for k2, 0.063 for k3 and 3.5e-4 for p1 and p2."""
    camera = downward_rig().camera
    corners = true_corners(camera, board_poses(camera, 40, CALIBRATION_BOARD, seed=0))
    result = calibrate_corners(noisy(dict(enumerate(corners)), seed=0), CALIBRATION_BOARD, (752, 480), "pinhole")
    assert result.ok, result.summary()
    assert result.rms_px <= 0.35
    fitted = result.params
    assert abs(fitted["fx"] / camera.fx - 1) < 0.006 and abs(fitted["fy"] / camera.fy - 1) < 0.006
    assert abs(fitted["cx"] - camera.cx) < 3.5 and abs(fitted["cy"] - camera.cy) < 3.5
    assert abs(fitted["k1"] - camera.dist[0]) < 0.02 and abs(fitted["k2"] - camera.dist[1]) < 0.12
    assert abs(fitted["p1"] - camera.dist[2]) < 0.0012 and abs(fitted["p2"] - camera.dist[3]) < 0.0012
    assert abs(fitted["k3"] - camera.dist[4]) < 0.2
    truth = np.array([camera.fx, camera.fy, camera.cx, camera.cy, *camera.dist])
    sigmas = np.array(list(result.std.values()))
    assert np.all(np.abs(np.array(list(fitted.values())) - truth) < 3.0 * sigmas)


def test_pinhole_with_k3_fixed_is_written_as_a_kalibr_camchain(tmp_path):
    camera = downward_rig().camera
    corners = true_corners(camera, board_poses(camera, 12, CALIBRATION_BOARD, seed=1))
    result = calibrate_corners(corners, CALIBRATION_BOARD, (752, 480), "pinhole", fix_k3=True)
    assert result.params["k3"] == 0.0 and result.ok
    written = load_kalibr(save_kalibr(tmp_path / "pinhole.yaml", {"cam0": result.camera}))["cam0"]
    np.testing.assert_allclose(written.camera_matrix, result.camera.camera_matrix)
    np.testing.assert_allclose((*written.dist, 0.0)[:5], result.camera.dist)  # Kalibr's radtan has no k3


def test_a_pinhole_cannot_hold_the_fisheye(detected):
    result = calibrate_corners(
        [detected.corners[index]
        for
        index
        in
        detected.used],
        CALIBRATION_BOARD,
        IMAGE_SIZE,
        "pinhole"
    )
    assert not result.ok
    assert result.rms_px > 10.0 * detected.rms_px
    assert any("model" in warning for warning in result.warnings)


# --- bad input -----------------------------------------------------------------------------------


def test_an_image_without_the_board_is_reported_not_fatal(fisheye_views):
    blank = np.full_like(fisheye_views[0].image, 120)
    images = [view.image for view in fisheye_views[:5]] + [blank]
    result = calibrate_views(images, CALIBRATION_BOARD)
    assert result.used == list(range(5))
    assert result.dropped == {5: "no chessboard of 7x5 inner corners found"}
    assert "view 5: no chessboard" in result.summary()


def test_a_wrong_pattern_size_says_what_was_asked_and_what_is_there(fisheye_views):
    with pytest.raises(CalibrationError, match=r"no chessboard of 8x6 inner corners .* 7x5 inner corners"):
        calibrate_views([fisheye_views[0].image], Chessboard((9, 7), 0.03))


def test_fewer_than_three_views_is_an_error(detected):
    with pytest.raises(CalibrationError, match="at least 3"):
        calibrate_corners([detected.corners[0], detected.corners[1], None], CALIBRATION_BOARD, IMAGE_SIZE)


def fronto_parallel_corners(camera, count, rng):
    """Corners of boards all facing the camera square on (normal along the optical axis), spread over the image."""
    board = CALIBRATION_BOARD
    centre = np.array([board.squares[0] * board.square / 2, board.squares[1] * board.square / 2, 0.0])
    views = []
    while len(views) < count:
        pixel = rng.uniform([0.2 * camera.width, 0.2 * camera.height], [0.8 * camera.width, 0.8 * camera.height])
        ray, _ = camera.unproject(pixel)
        rotation = Rotation.from_euler("xz", [np.pi, rng.uniform(-np.pi, np.pi)])
        position = ray / ray[2] * rng.uniform(0.25, 0.4) - rotation.apply(centre)
        corners, valid = camera.project(rotation.apply(board.inner_corners()) + position)
        if valid.all() and camera.in_image(corners).all():
            views.append(corners + rng.normal(0.0, NOISE_PX, corners.shape))
    return views


@pytest.mark.parametrize("rig, model", [(t265_rig, "eucm"), (downward_rig, "pinhole")])
def test_fronto_parallel_views_ask_to_tilt_the_board(rig, model):
    camera = rig().camera
    corners = fronto_parallel_corners(camera, 12, np.random.default_rng(0))
    with pytest.raises(CalibrationError, match="tilt the board"):
        calibrate_corners(corners, CALIBRATION_BOARD, (camera.width, camera.height), model)


def test_corners_of_the_wrong_shape_are_refused(detected):
    with pytest.raises(CalibrationError, match=r"view 1: corners of shape \(34, 2\), expected \(35, 2\)"):
        calibrate_corners([detected.corners[0], detected.corners[1][:-1]], CALIBRATION_BOARD, IMAGE_SIZE)


def test_unknown_model_is_refused(detected):
    with pytest.raises(ValueError, match="unknown camera model 'kannala'"):
        calibrate_corners(list(detected.corners.values()), CALIBRATION_BOARD, IMAGE_SIZE, "kannala")


@pytest.mark.parametrize("text, expected", [("7x5", (7, 5)), ("9 X 6", (9, 6))])
def test_parse_board(text, expected):
    assert parse_board(text) == expected


@pytest.mark.parametrize("text", ["7", "7x5x3", "2x5", "sevenxfive", "7.5x5"])
def test_parse_board_refuses_bad_text(text):
    with pytest.raises(ValueError, match="inner corners"):
        parse_board(text)


def test_image_files_that_are_missing_or_not_images(tmp_path):
    with pytest.raises(FileNotFoundError, match=r"missing\.png: no such image file"):
        calibrate_images([tmp_path / "missing.png"], (7, 5), 0.03)
    (tmp_path / "notes.png").write_text("not an image")
    with pytest.raises(ValueError, match=r"notes\.png: not an image that OpenCV can read"):
        calibrate_images([tmp_path / "notes.png"], (7, 5), 0.03)


# --- command line --------------------------------------------------------------------------------


def test_main_calibrate_writes_a_kalibr_camchain(fisheye_views, tmp_path, capsys):
    paths = []
    for index, view in enumerate(fisheye_views[:6]):
        paths.append(tmp_path / f"board_{index:02d}.png")
        cv2.imwrite(str(paths[-1]), view.image)
    result = main_calibrate(paths, "7x5", 0.03, "eucm", tmp_path / "calib.yaml")
    camera = load_kalibr(tmp_path / "calib.yaml")["cam0"]
    np.testing.assert_allclose(camera.params, result.camera.params)
    assert yaml.safe_load((tmp_path / "calib.yaml").read_text())["cam0"]["camera_model"] == "eucm"
    printed = capsys.readouterr().out
    assert "eucm calibration from 6 of 6 views" in printed and "calib.yaml" in printed
    assert result.ok
