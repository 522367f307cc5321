"""Floor images against independent truth.

- The composed table against the stages chained as point maps through the cubemap's own look-up tables
  (bilinear in float64) and the two homographies, written out here.
- The ortho-GPI against the simulator: a board rendered at a place the route was not calibrated on has its
  corners where ``FloorImage.base_to_pixel`` puts its true corners; the analytic table against the true
  mount's projection through the simulator's own camera pose.
- Table 1 (measured on boards at other places), the two routes against each other, the disk cache and the
  errors of bad input.
"""

import dataclasses

import cv2
import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from scipy.ndimage import map_coordinates

import gpo.floor_image.analytic
from gpo.cameras.mount import detect_corners
from gpo.cameras.rig import CameraMount
from gpo.experiments.table1 import reproduce_table1
from gpo.floor_image.analytic import (
    PixelsOnFloor,
    analytic_points,
    analytic_table,
    pixels_to_floor,
    route_difference,
)
from gpo.floor_image.gpi import front_face_corners, ground_plane_image
from gpo.floor_image.image import FloorImage, GroundImageError
from gpo.floor_image.ortho import chessboard_route, ortho_rectify
from gpo.sim.floors import make_floor
from gpo.sim.record import FLOOR_BOARDS, TEXEL_M, floor_board_image
from gpo.sim.render import FloorRenderer, camera_pose_in_world
from gpo.sim.rigs import downward_rig, t265_rig

RIG = t265_rig()
BOARD = FLOOR_BOARDS["t265"]
FINE_FLOOR = FloorImage.top_view(metres_per_pixel=0.5e-3)  # the chapters' floor patch at 0.5 mm per pixel
CHAIN_TOLERANCE_PX = 0.05
# a floor image reaching back over the seam, so that part of it is seen through the GPI's bottom-face rows
OVER_THE_SEAM = FloorImage.top_view(x_range=(0.64, 0.84), y_range=(-0.10, 0.10), metres_per_pixel=1e-3)


@pytest.fixture(scope="module", autouse=True)
def table_cache(tmp_path_factory):
    """Every table of this module in a fresh cache folder."""
    with pytest.MonkeyPatch.context() as patch:
        folder = tmp_path_factory.mktemp("cache")
        patch.setenv("GPO_CACHE_DIR", str(folder))
        yield folder / "tables"


@pytest.fixture(scope="module")
def calibration_frame() -> np.ndarray:
    return floor_board_image("t265", seed=0)


@pytest.fixture(scope="module")
def ortho(calibration_frame):
    return chessboard_route(calibration_frame, RIG.camera, BOARD, FINE_FLOOR)


@pytest.fixture(scope="module")
def renderer() -> FloorRenderer:
    return FloorRenderer(RIG, make_floor("raised", (-1.0, 2.0, -1.5, 1.5), TEXEL_M["t265"], 3))


def apply_homography(homography: np.ndarray, uv: np.ndarray) -> np.ndarray:
    mapped = np.concatenate([uv, np.ones((*uv.shape[:-1], 1))], axis=-1) @ homography.T
    return mapped[..., :2] / mapped[..., 2:]


def lookup(maps, uv: np.ndarray) -> np.ndarray:
    """A face's look-up tables (float32, pixel centres) read bilinearly in float64 at face pixels ``uv`` (..., 2);
    NaN where a neighbour is missing."""
    coordinates = [uv[..., 1].ravel(), uv[..., 0].ravel()]
    values = [map_coordinates(table.astype(np.float64), coordinates, order=1, cval=np.nan) for table in maps[:2]]
    return np.stack(values, axis=-1).reshape(uv.shape)


def chained(gpi, gpi_uv: np.ndarray) -> np.ndarray:
    """Fisheye pixels of GPI points: the stages' maps one after the other (NaN where a stage has none)."""
    front_rows, (width, height) = gpi.front_rows, gpi.size
    upper = (gpi_uv[..., 1] < front_rows - 0.5) & (gpi_uv[..., 1] >= -0.5)
    lower = (gpi_uv[..., 1] >= front_rows - 0.5) & (gpi_uv[..., 1] <= height - 0.5)
    inside = (gpi_uv[..., 0] >= -0.5) & (gpi_uv[..., 0] <= width - 0.5)
    front = lookup(gpi.cubemap.maps("front"), apply_homography(np.linalg.inv(gpi.homography), gpi_uv))
    bottom = lookup(gpi.cubemap.maps("bottom"), gpi_uv - [0.0, front_rows])
    result = np.where(upper[..., None], front, np.where(lower[..., None], bottom, np.nan))
    return np.where(inside[..., None], result, np.nan)


def assert_agrees_with_chain(table, chain: np.ndarray) -> None:
    both = table.valid & np.isfinite(chain).all(axis=-1)
    assert both.sum() >= 0.99 * table.valid.sum()  # the chain lacks only a rim where a bilinear neighbour is missing
    assert not (np.isfinite(chain).all(axis=-1) & ~table.valid).any()
    composed = np.stack([table.map_x, table.map_y], axis=-1)
    assert np.max(np.linalg.norm(composed[both] - chain[both], axis=-1)) <= CHAIN_TOLERANCE_PX


def test_gpi_table_agrees_with_the_faces_and_eq_22_chained(ortho):
    gpi = ortho.gpi
    assert_agrees_with_chain(gpi.table, chained(gpi, gpi.floor.pixel_centres()))


@pytest.mark.parametrize("floor", [FINE_FLOOR, OVER_THE_SEAM], ids=["ahead", "over-the-seam"])
def test_composed_table_agrees_with_the_three_stages_chained(ortho, calibration_frame, floor):
    rectified = ortho_rectify(ortho.gpi, ortho.gpi.table.apply(calibration_frame), BOARD, floor, max_outside=0.01)
    gpi_uv = apply_homography(np.linalg.inv(rectified.homography), floor.pixel_centres())
    assert_agrees_with_chain(rectified.table, chained(ortho.gpi, gpi_uv))
    assert rectified.through_bottom_face().any() == (floor is OVER_THE_SEAM)


def test_gpi_homography_maps_the_four_corners_onto_the_boards_rectangle(ortho):
    gpi = ortho.gpi
    corners = BOARD.corners_world()[[0, 6, 34, 28], :2]  # inner corners (1, 1), (7, 1), (7, 5), (1, 5)
    in_gpi = apply_homography(gpi.homography, gpi.face_corners)
    np.testing.assert_allclose(in_gpi, gpi.floor.base_to_pixel(corners), rtol=0.0, atol=1e-4)
    sides = np.linalg.norm(np.roll(in_gpi, -1, axis=0) - in_gpi, axis=1) * gpi.floor.metres_per_pixel
    np.testing.assert_allclose(sides, [0.12, 0.08, 0.12, 0.08], rtol=1e-6)  # 6 x 4 squares of 20 mm
    assert not gpi.floor.metric and ortho.floor.metric


def test_plain_gpi_is_only_approximately_metric(ortho):
    """Exact up to the four corners on the front face's part, centimetre-good on the bottom face's rows."""
    gpi = ortho.gpi
    truth = analytic_table(RIG.camera, RIG.mount, gpi.floor, max_outside=0.01)
    error_mm = route_difference(gpi.table, truth).floor_mm
    upper, lower = error_mm[: gpi.front_rows], error_mm[gpi.front_rows :]
    assert np.nanmean(upper) < 0.5 and np.nanmax(upper) < 1.5
    assert 1.0 < np.nanmean(lower) < 5.0 and np.nanmax(lower) < 15.0


def test_the_resampled_gpi_is_as_metric_as_the_gpi(ortho):
    """Resampled onto the ortho-GPI's grid by its own placement, the plain GPI puts the floor where the analytic
    route does to within the four corners' accuracy (this grid lies on the GPI's front-face part)."""
    table = ortho.gpi.resampled(ortho.floor)
    assert not table.floor.metric and table.floor.width == ortho.floor.width
    difference = route_difference(table, analytic_table(RIG.camera, RIG.mount, table.floor))
    assert difference.common_fraction == 1.0 and difference.mean_mm < 0.5 and difference.max_mm < 1.5


def test_hand_picked_corners_give_nearly_the_same_gpi(ortho, calibration_frame):
    """Corners a fifth of a pixel off put the front face's floor within a millimetre of where the found ones do on
    the board, but the four-corner homography carries the error out to several millimetres at the GPI's far end:
    one reason to ortho-rectify."""
    auto = ortho.gpi
    found = front_face_corners(calibration_frame, auto.cubemap, BOARD)
    nudged = found + np.random.default_rng(0).uniform(-0.2, 0.2, found.shape)
    by_hand = ground_plane_image(calibration_frame, RIG.camera, BOARD, corners=nudged, cache=False)
    np.testing.assert_array_equal(by_hand.face_corners, nudged)

    def floor_mm(gpi, face_uv):
        return gpi.floor.pixel_to_base(apply_homography(gpi.homography, face_uv)) * 1e3

    board = found
    upper = apply_homography(np.linalg.inv(auto.homography), auto.floor.pixel_centres()[: auto.front_rows : 40, ::40])
    assert np.max(np.linalg.norm(floor_mm(by_hand, board) - floor_mm(auto, board), axis=-1)) < 1.0
    assert np.max(np.linalg.norm(floor_mm(by_hand, upper) - floor_mm(auto, upper), axis=-1)) < 6.0


def found_corners(image: np.ndarray, floor: FloorImage, board) -> tuple[np.ndarray, np.ndarray]:
    """OpenCV's corners in a floor image, each matched to the board's nearest true corner: (found, truth) pixels."""
    truth = floor.base_to_pixel(board.corners_world()[:, :2])
    stand_in = dataclasses.replace(RIG.camera, width=floor.width, height=floor.height)
    corners = detect_corners(image, stand_in, board.board, rectify=False)
    nearest = np.linalg.norm(truth[:, None] - corners[None], axis=-1).argmin(axis=1)
    assert len(set(nearest.tolist())) == len(truth)
    return corners[nearest], truth


MOVED_BOARD = dataclasses.replace(BOARD, x=0.72, y=-0.055, yaw=np.radians(3.0))


def test_ortho_gpi_shows_floor_points_where_its_description_puts_them(ortho, renderer):
    image = ortho.table.apply(renderer.render(np.zeros(3), frame_seed=11, boards=(MOVED_BOARD,)))
    corners, truth = found_corners(image, ortho.floor, MOVED_BOARD)
    assert np.max(np.linalg.norm(corners - truth, axis=1)) < 0.5


def test_analytic_table_is_the_true_mounts_projection(renderer):
    floor = FINE_FLOOR
    rotation, centre = camera_pose_in_world(RIG, np.zeros(3))  # the robot at the world origin: world = base_link
    xy = floor.pixel_to_base(floor.pixel_centres())
    points = np.concatenate([xy, np.zeros((*xy.shape[:-1], 1))], axis=-1)
    truth, seen = RIG.camera.project(rotation.inv().apply(points.reshape(-1, 3) - centre).reshape(points.shape))
    exact, valid = analytic_points(RIG.camera, RIG.mount, floor)
    assert valid.all() and seen.all()
    assert np.max(np.abs(exact - truth)) < 1e-6
    table = analytic_table(RIG.camera, RIG.mount, floor)
    assert np.max(np.abs(table.map_x - truth[..., 0])) <= 2.0**-14  # float32 rounding of numbers below 1024
    assert np.max(np.abs(table.map_y - truth[..., 1])) <= 2.0**-14
    image = table.apply(renderer.render(np.zeros(3), frame_seed=12, boards=(MOVED_BOARD,)))
    corners, truth_px = found_corners(image, floor, MOVED_BOARD)
    assert np.max(np.linalg.norm(corners - truth_px, axis=1)) < 0.5


def test_height_pitch_roll_is_a_forward_mount_above_base_links_origin():
    floor = FloorImage.top_view(x_range=(0.10, 0.30), y_range=(-0.1, 0.1), metres_per_pixel=1e-3)
    height, pitch, roll = 0.12, np.radians(6.0), np.radians(1.5)
    table = analytic_table(RIG.camera, (height, pitch, roll), floor, cache=False)
    mount = CameraMount.forward(0.0, 0.0, height, pitch, roll)
    np.testing.assert_array_equal(table.map_x, analytic_table(RIG.camera, mount, floor, cache=False).map_x)


@pytest.fixture(scope="module")
def table1():
    return {row.image: row for row in reproduce_table1()}


def test_table1_ortho_gpi_meets_the_papers_figures(table1):
    row = table1["ortho-GPI"]
    assert abs(row.short_error_mm) <= 0.06 and abs(row.long_error_mm) <= 0.06
    assert abs(row.area_error_mm2) <= 1.3
    assert abs(row.short_mm - 40.0) == pytest.approx(abs(row.short_error_mm))


def test_table1_plain_gpi_is_visibly_worse(table1):
    gpi, ortho = table1["GPI"], table1["ortho-GPI"]
    assert abs(gpi.long_error_mm) > 3 * abs(ortho.long_error_mm)
    assert abs(gpi.area_error_mm2) > 3 * abs(ortho.area_error_mm2)
    assert gpi.single_side_rms_mm > 2 * ortho.single_side_rms_mm


def test_table1_analytic_row_is_the_measurements_own_floor(table1):
    """With the true geometry a block still scatters by a few hundredths of a millimetre: the corners' limit."""
    analytic = table1["analytic"]
    assert analytic.single_side_rms_mm < 0.05 and abs(analytic.area_error_mm2) < 2.5


def test_chessboard_and_analytic_routes_agree(ortho):
    """The ortho-GPI's homography rests on 15 corners found to ~0.05 mm in the GPI, over a 40 x 80 mm block; carried
    out to the 200 x 200 mm image's corners the error grows about three-fold: ~0.1 mm on average, < 0.6 mm."""
    difference = route_difference(ortho.table, analytic_table(RIG.camera, RIG.mount, ortho.floor))
    assert difference.common_fraction == 1.0
    assert difference.mean_mm < 0.15 and difference.max_mm < 0.6
    assert difference.mean_px < 0.2 and difference.max_px < 1.0


def test_route_difference_reads_a_known_shift_in_millimetres():
    moved = CameraMount(RIG.mount.position + np.array([0.001, 0.0, 0.0]), RIG.mount.rotation)  # the camera 1 mm forward
    difference = route_difference(
        analytic_table(RIG.camera, moved, FINE_FLOOR, cache=False),
        analytic_table(RIG.camera, RIG.mount, FINE_FLOOR, cache=False),
    )
    assert difference.mean_mm == pytest.approx(1.0, rel=0.02) and difference.max_mm == pytest.approx(1.0, rel=0.05)


def test_fixed_point_table_reads_the_same_image(ortho, calibration_frame):
    map1, map2 = ortho.table.fixed_point
    assert map1.dtype == np.int16 and map1.shape == (*ortho.table.map_x.shape, 2) and map2.dtype == np.uint16
    floating = ortho.table.apply(calibration_frame).astype(int)
    fixed = ortho.table.apply(calibration_frame, fixed=True).astype(int)
    assert np.mean(np.abs(floating - fixed)) < 0.5 and np.max(np.abs(floating - fixed)) <= 8


def test_pixels_not_seen_are_masked(calibration_frame):
    floor = FloorImage.top_view(x_range=(0.62, 1.0), y_range=(-0.8, 0.8), metres_per_pixel=4e-3)
    table = analytic_table(RIG.camera, RIG.mount, floor, max_outside=1.0, cache=False)
    assert 0.0 < table.outside_fraction < 1.0
    assert np.isnan(table.map_x[~table.valid]).all() and np.isfinite(table.map_x[table.valid]).all()
    image = table.apply(np.full_like(calibration_frame, 200), border_value=7)
    assert (image[~table.valid] == 7).all() and (image[table.valid] == 200).all()


def test_second_build_is_read_from_the_cache_and_a_new_calibration_makes_a_new_key(monkeypatch, table_cache):
    floor = FloorImage.top_view(x_range=(0.7, 0.8), y_range=(-0.05, 0.05), metres_per_pixel=1e-3)
    first = analytic_table(RIG.camera, RIG.mount, floor)
    assert (table_cache / f"table-{first.key}.npz").exists()

    def fail(*args):
        raise AssertionError("the table was built again instead of read from the cache")

    monkeypatch.setattr(gpo.floor_image.analytic, "analytic_points", fail)
    second = analytic_table(RIG.camera, RIG.mount, floor)
    assert second.key == first.key
    for name in ("map_x", "map_y", "valid"):
        np.testing.assert_array_equal(getattr(second, name), getattr(first, name))
    monkeypatch.undo()
    recalibrated = dataclasses.replace(RIG.camera, fx=RIG.camera.fx + 0.1)
    assert analytic_table(recalibrated, RIG.mount, floor).key != first.key
    assert analytic_table(RIG.camera, RIG.mount, dataclasses.replace(floor, width=99)).key != first.key


def test_uncached_tables_leave_no_file(table_cache):
    floor = FloorImage.top_view(x_range=(0.7, 0.75), y_range=(-0.05, 0.05), metres_per_pixel=1e-3)
    table = analytic_table(RIG.camera, RIG.mount, floor, cache=False)
    assert not (table_cache / f"table-{table.key}.npz").exists()


@given(st.floats(0.2, 1.0), st.floats(0.01, 0.5), st.floats(-0.5, 0.2), st.floats(0.01, 0.5), st.floats(0.2e-3, 5e-3))
def test_top_view_axes_and_round_trip(near, length, right, width, step):
    floor = FloorImage.top_view((near, near + length), (right, right + width), step)
    assert floor.metres_per_pixel == pytest.approx(step)
    x_min, x_max, y_min, y_max = floor.extent
    assert x_max == pytest.approx(near + length) and y_max == pytest.approx(right + width)  # the far-left corner kept
    assert x_max - x_min == pytest.approx(floor.height * step) and y_max - y_min == pytest.approx(floor.width * step)
    origin = floor.pixel_to_base([0.0, 0.0])
    np.testing.assert_allclose(floor.pixel_to_base([0.0, 1.0]) - origin, [-step, 0.0], atol=1e-15)  # down = back
    np.testing.assert_allclose(floor.pixel_to_base([1.0, 0.0]) - origin, [0.0, -step], atol=1e-15)  # right = -y
    uv = np.array([[0.0, 0.0], [floor.width - 1.0, floor.height - 1.0], [floor.width / 2.0, floor.height / 3.0]])
    np.testing.assert_allclose(floor.base_to_pixel(floor.pixel_to_base(uv)), uv, atol=1e-9)


# ---------------------------------------------------------------------------------------------- bad input


def test_image_of_another_size_than_the_calibration(calibration_frame, ortho):
    small = cv2.resize(calibration_frame, (640, 480))
    with pytest.raises(GroundImageError, match=r"640 x 480 pixels but the calibration is for 848 x 800"):
        ground_plane_image(small, RIG.camera, BOARD)
    with pytest.raises(GroundImageError, match=r"calibration is for 848 x 800"):
        ortho.table.apply(small)


def test_chessboard_not_found(calibration_frame):
    blank = np.full_like(calibration_frame, 128)
    with pytest.raises(GroundImageError, match=r"not found .*front face.*corners="):
        ground_plane_image(blank, RIG.camera, BOARD)


@pytest.mark.parametrize(
    ("corners", "message"),
    [
        ([[100, 300], [200, 300], [300, 300], [400, 300]], "convex"),  # on a line
        ([[300, 400], [302, 401], [250, 380], [200, 400]], "px apart"),  # two nearly the same
        ([[356, 455], [248, 375], [327, 373], [223, 458]], "convex"),  # not in turn round the board
        ([[356, 455], [327, 373], [248, 375], [223, 458], [0, 0]], "four"),
        ([[356, 455], [327, 373], [248, 375], [223, 900]], "inside"),
    ],
)
def test_degenerate_corners(calibration_frame, corners, message):
    with pytest.raises(GroundImageError, match=message):
        ground_plane_image(calibration_frame, RIG.camera, BOARD, corners=corners)


def test_extent_leaving_the_lens_says_how_much_and_what_fits():
    wide = FloorImage.top_view(x_range=(0.62, 1.0), y_range=(-0.8, 0.8), metres_per_pixel=4e-3)
    with pytest.raises(GroundImageError, match=r"\d+\.\d% of the floor image .* outside the fisheye") as error:
        analytic_table(RIG.camera, RIG.mount, wide, cache=False)
    x_range, y_range = _suggested(str(error.value))
    smaller = FloorImage.top_view(x_range, y_range, 4e-3)
    assert analytic_table(RIG.camera, RIG.mount, smaller, cache=False).outside_fraction == 0.0
    behind = FloorImage.top_view(x_range=(-1.0, -0.5), y_range=(-0.1, 0.1), metres_per_pixel=4e-3)
    with pytest.raises(GroundImageError, match="none of it is seen"):
        analytic_table(RIG.camera, RIG.mount, behind, cache=False)


def test_extent_leaving_the_gpi(ortho, calibration_frame):
    wide = FloorImage.top_view(x_range=(0.70, 0.90), y_range=(-0.2, 0.2), metres_per_pixel=1e-3)
    with pytest.raises(GroundImageError, match=r"outside the GPI.*choose a smaller extent") as error:
        ortho_rectify(ortho.gpi, ortho.gpi.table.apply(calibration_frame), BOARD, wide)
    smaller = FloorImage.top_view(*_suggested(str(error.value)), 1e-3)
    assert ortho_rectify(ortho.gpi, ortho.gpi.table.apply(calibration_frame), BOARD, smaller).table.valid.all()


def _suggested(message: str):
    """The x_range and y_range an error message suggests."""
    x_part = message.split("x_range=(")[1].split(")")[0]
    y_part = message.split("y_range=(")[1].split(")")[0]
    return tuple(map(float, x_part.split(", "))), tuple(map(float, y_part.split(", ")))


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda: FloorImage.top_view((0.9, 0.7)), "far > near"),
        (lambda: FloorImage.top_view(metres_per_pixel=0.0), "positive"),
        (lambda: analytic_table(RIG.camera, (0.12, 0.1), FINE_FLOOR), "height m, pitch rad, roll rad"),
        (lambda: gpo.floor_image.ortho.block_corner_indices(BOARD.board, (4, 2)), "1 <= i <= 3"),
    ],
)
def test_bad_parameters(call, message):
    with pytest.raises(GroundImageError, match=message):
        call()


def test_gpi_reaching_too_far_ahead(calibration_frame):
    with pytest.raises(GroundImageError, match=r"ahead_m <= 0\.\d\d") as error:
        ground_plane_image(calibration_frame, RIG.camera, BOARD, ahead_m=50.0, cache=False)
    allowed = float(str(error.value).split("ahead_m <= ")[1].split()[0])
    assert ground_plane_image(calibration_frame, RIG.camera, BOARD, ahead_m=allowed, cache=False).front_rows > 0


@pytest.mark.parametrize("make_rig", [downward_rig, t265_rig])
def test_floor_points_invert_the_analytic_projection(make_rig):
    """Pixels of known floor points (``analytic_points``) come back to those points: undistortion, tilt and height."""
    rig = make_rig()
    x_range = (-0.10, 0.10) if rig.name == "downward" else (0.70, 0.90)
    floor = FloorImage.top_view(x_range, (-0.10, 0.10), 2e-3)
    pixels, seen = analytic_points(rig.camera, rig.mount, floor)
    points, valid = pixels_to_floor(rig.camera, rig.mount, pixels[seen])
    assert valid.all()
    truth = floor.pixel_to_base(floor.pixel_centres())[seen]
    np.testing.assert_allclose(points, truth, rtol=0, atol=1e-9)


@pytest.mark.parametrize("k1k2", [None, (-0.36, 0.10)])  # the shipped lens, the population's strongest barrel
def test_the_table_of_pixels_on_the_floor_reads_as_each_pixel_followed_down(k1k2):
    """On a downward camera (the keypoints route's), ``PixelsOnFloor`` interpolates between pixel centres within a
    few thousandths of a pixel's footprint of ``pixels_to_floor``; a pixel beyond the last centres is followed down
    itself."""
    rig = downward_rig()
    if k1k2 is not None:
        rig = dataclasses.replace(rig, camera=dataclasses.replace(rig.camera, dist=(*k1k2, *rig.camera.dist[2:])))
    table = PixelsOnFloor.of(rig.camera, rig.mount)
    rng = np.random.default_rng(4)
    pixels = rng.uniform([0, 0], [rig.camera.width - 1, rig.camera.height - 1], (400, 2))
    pixels = np.vstack([pixels, [[rig.camera.width - 0.6, 10.3], [-0.4, 20.0]]])  # past the last centres
    points, valid = table(pixels)
    exact, exact_valid = pixels_to_floor(rig.camera, rig.mount, pixels)
    np.testing.assert_array_equal(valid, exact_valid)
    footprint = rig.mount.height / rig.camera.fx  # metres a pixel covers straight below the camera
    assert np.hypot(*(points - exact)[valid].T).max() < 5e-3 * footprint
    np.testing.assert_array_equal(points[-2:][valid[-2:]], exact[-2:][valid[-2:]])


def test_floor_points_above_the_horizon_are_invalid():
    rig = t265_rig()  # pitched 6 degrees down: the top of the fisheye sees the ceiling
    points, valid = pixels_to_floor(rig.camera, rig.mount, [[424.0, 5.0], [424.0, 790.0]])
    assert valid.tolist() == [False, True]
    assert np.isnan(points[0]).all()


def test_a_widened_floor_image_keeps_its_centre_and_orientation():
    floor = FloorImage.top_view((0.55, 0.79), (-0.1, 0.1), 0.0008)
    wide = floor.widened(2.0)
    centre = [(floor.width - 1) / 2, (floor.height - 1) / 2]
    np.testing.assert_allclose(wide.pixel_to_base(centre), floor.pixel_to_base(centre), atol=1e-12)
    assert (wide.width, wide.height) == (floor.width, floor.height)
    assert wide.metres_per_pixel == pytest.approx(2 * floor.metres_per_pixel, rel=1e-12)
    x_min, x_max, y_min, y_max = floor.extent
    np.testing.assert_allclose(wide.extent, [x_min - 0.12, x_max + 0.12, y_min - 0.1, y_max + 0.1], atol=1e-9)
    np.testing.assert_allclose(wide.affine[:, :2], 2 * floor.affine[:, :2], atol=1e-15)  # same axes
    with pytest.raises(GroundImageError, match="positive"):
        floor.widened(0.0)
