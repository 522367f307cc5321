"""Kalibr's car: four omni cameras read from pipeline.info, their mounts (JPL quaternions), and the ground z = 0."""

import cv2
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from gpo.cameras import Omni
from gpo.cameras.files import load_kalibr, save_kalibr
from gpo.io.kalibr_car import CAMERA_NAMES, CarCamera, kalibr_car_cameras, parse_info, read_pipeline_info

EXAMPLE = "kalibr/aslam_cv/aslam_cv_python/example"


@pytest.fixture
def pipeline_info(fetch_or_skip):
    return fetch_or_skip(f"{EXAMPLE}/pipeline.info")


@pytest.fixture
def cameras(pipeline_info) -> dict[str, CarCamera]:
    return read_pipeline_info(pipeline_info)


def car_image(fetch_or_skip, name: str) -> np.ndarray:
    return cv2.imread(str(fetch_or_skip(f"{EXAMPLE}/im_{name}.jpg")), cv2.IMREAD_GRAYSCALE)


def vehicle_to_camera(car: CarCamera, points: np.ndarray) -> np.ndarray:
    """Vehicle-frame points (N, 3) in the camera's optical frame."""
    return car.mount.rotation.inv().apply(points - car.mount.position)


def ground_points(car: CarCamera, pixels: np.ndarray, rotation: Rotation | None = None) -> np.ndarray:
    """Where the rays of ``pixels`` (N, 2) meet the ground z = 0 of the vehicle frame, (N, 3) metres; the camera's
    rotation vehicle <- optical is ``car.mount.rotation`` unless another ``rotation`` is given."""
    rays, valid = car.camera.unproject(pixels)
    assert valid.all()
    directions = (rotation or car.mount.rotation).apply(rays)
    reach = -car.mount.position[2] / directions[:, 2]
    return car.mount.position + reach[:, None] * directions


def line_fit(points: np.ndarray):
    """Least-squares line through points (N, 2): RMS and largest perpendicular residual, unit direction, centroid."""
    centroid = points.mean(axis=0)
    _, _, axes = np.linalg.svd(points - centroid)
    residuals = (points - centroid) @ axes[1]
    return np.sqrt(np.mean(residuals**2)), np.max(np.abs(residuals)), axes[0], centroid


def lane_edge(image: np.ndarray, rows: tuple[int, int], columns: tuple[int, int], min_step: float = 10.0):
    """Sub-pixel (u, v) (N, 2) of the strongest dark-to-bright step down each column of the window: the far edge
    of a painted line seen below darker ground. Columns whose step is under ``min_step`` grey levels are left out."""
    smooth = cv2.GaussianBlur(image.astype(np.float64), (0, 0), 1.5)
    steps = np.diff(smooth, axis=0)[rows[0] : rows[1], columns[0] : columns[1]]
    peak = np.clip(np.argmax(steps, axis=0), 1, steps.shape[0] - 2)
    column = np.arange(steps.shape[1])
    above, at, below = steps[peak - 1, column], steps[peak, column], steps[peak + 1, column]
    offset = 0.5 * (above - below) / (above - 2.0 * at + below)  # parabola through the three steps
    pixels = np.column_stack([columns[0] + column, rows[0] + peak + offset + 0.5])  # step k lies between rows k, k+1
    return pixels[at >= min_step]


def test_four_cameras_with_the_published_intrinsics(cameras):
    assert list(cameras) == list(CAMERA_NAMES) == ["front", "left", "rear", "right"]
    for car in cameras.values():
        assert 1.99 < car.camera.xi < 2.14 and (car.camera.width, car.camera.height) == (1280, 800)
    assert cameras["front"].camera == Omni(
        fx=1291.5401445,
        fy=1293.30949252,
        cx=668.470297131,
        cy=407.046502189,
        xi=2.08685514589,
        dist=(-0.987434485774, 0.918697852674, -0.00433403483603, 8.78094632122e-05),
        width=1280,
        height=800,
    )
    heights = [cameras[name].mount.height for name in CAMERA_NAMES]
    np.testing.assert_allclose(heights, [0.588, 0.930, 0.855, 0.958], atol=1e-3)


def test_the_registered_file_gives_the_same_cameras(cameras):
    registered = kalibr_car_cameras()
    assert [car.camera for car in registered.values()] == [car.camera for car in cameras.values()]
    for name, car in registered.items():
        np.testing.assert_array_equal(car.mount.position, cameras[name].mount.position)


def test_front_camera_looks_forward_from_0_588_m_up(cameras):
    front = cameras["front"].mount
    forward, right, down = front.rotation.apply(np.eye(3)[[2, 0, 1]])
    assert np.degrees(np.arccos(forward[0])) < 10.0  # along +x, tilted 9 degrees up
    assert right @ [0.0, -1.0, 0.0] > 0.999 and down @ [0.0, 0.0, -1.0] > 0.98
    assert front.position == pytest.approx([3.5857441246, 0.1335050543, 0.5876957529])


def test_side_cameras_look_sideways_and_36_degrees_down_and_the_rear_one_back(cameras):
    axes = {name: car.mount.rotation.apply([0.0, 0.0, 1.0]) for name, car in cameras.items()}
    assert axes["left"][1] > 0.8 and axes["right"][1] < -0.79
    for name in ("left", "right"):
        assert np.degrees(np.arcsin(-axes[name][2])) == pytest.approx(36.0, abs=1.5)
    assert axes["rear"][0] < -0.99


def test_the_jpl_reading_stands_every_image_upright_and_hamilton_would_not(cameras):
    # the image's down axis (optical +y) in the vehicle frame: down in all four images only when R_vc = R_hamilton^T
    for car in cameras.values():
        assert car.mount.rotation.apply([0.0, 1.0, 0.0])[2] < -0.79
    literal = {name: car.mount.rotation.inv() for name, car in cameras.items()}  # R_hamilton(q) itself
    assert abs(literal["front"].apply([0.0, 1.0, 0.0])[2]) < 0.01  # the front image's down would be level
    assert literal["left"].apply([0.0, 1.0, 0.0])[2] > 0.8  # and the left image upside down
    assert literal["front"].apply([0.0, 0.0, 1.0])[1] < -0.98  # the front camera would look to the right


def test_front_image_pixels_unproject_and_project_back(cameras, fetch_or_skip):
    image = car_image(fetch_or_skip, "front")
    camera = cameras["front"].camera
    assert image.shape == (camera.height, camera.width)
    pixels = camera.pixel_grid()
    rays, valid = camera.unproject(pixels)
    back, valid_back = camera.project(rays)
    assert (valid_back == valid).all() and np.max(np.abs(back[valid] - pixels[valid])) < 1e-6
    # one disc around the principal point, out to the fold 118.6 degrees off the axis; outside, no ray
    assert 0.78 < valid.mean() < 0.79
    assert cv2.connectedComponents(valid.astype(np.uint8))[0] == 2
    assert np.degrees(np.arccos(np.nanmin(rays[..., 2]))) == pytest.approx(
        np.degrees(np.arccos(-1 / camera.xi)), abs=0.2
    )
    assert np.median(image[valid]) > 50  # and what the disc holds is the lit scene


@pytest.mark.parametrize("name", ["left", "right"])
def test_principal_ray_of_a_side_camera_meets_the_ground_beside_the_car(cameras, name):
    car = cameras[name]
    hit = ground_points(car, np.array([car.camera.principal_point]))[0]
    reach = np.linalg.norm(hit[:2] - car.mount.position[:2])
    assert reach == pytest.approx(car.mount.height / np.tan(np.radians(36.0)), rel=0.1)  # about 1.3 m
    assert abs(hit[1]) > abs(car.mount.position[1]) + 1.0


# per camera, a straight line on the ground it sees: start and end (x, y) in the vehicle frame, metres
GROUND_LINES = {
    "front": ((4.5, -3.0), (4.5, 3.0)),
    "left": ((-1.0, 2.9), (5.0, 2.9)),
    "rear": ((-1.5, -3.0), (-1.5, 3.0)),
    "right": ((-0.3, -1.5), (4.5, -1.5)),
}


@pytest.mark.parametrize("name", GROUND_LINES)
def test_a_straight_ground_line_projects_to_a_curve_that_unprojects_back_onto_it(cameras, name):
    car = cameras[name]
    start, end = np.array(GROUND_LINES[name])
    along = np.linspace(0.0, 1.0, 200)[:, None]
    line = np.column_stack([(1 - along) * start + along * end, np.zeros(200)])
    pixels, valid = car.camera.project(vehicle_to_camera(car, line))
    assert valid.all() and car.camera.in_image(pixels).all()
    assert line_fit(pixels)[1] > 10.0  # pixels off the straight image line through them
    np.testing.assert_allclose(ground_points(car, pixels), line, atol=1e-9)


def test_the_lane_lines_beside_the_car_are_straight_and_parallel_on_the_ground(cameras, fetch_or_skip):
    lanes = {"left": ((290, 400), (240, 1120)), "right": ((520, 720), (300, 1050))}
    fits = {}
    for name, (rows, columns) in lanes.items():
        edge = lane_edge(car_image(fetch_or_skip, name), rows, columns)
        assert len(edge) > 0.9 * (columns[1] - columns[0])
        fits[name] = line_fit(ground_points(cameras[name], edge)[:, :2])
        assert line_fit(edge)[1] > 10.0  # curved in the image
    (left_rms, _, left_direction, left_centre), (right_rms, _, right_direction, right_centre) = fits.values()
    assert left_rms < 0.03 and right_rms < 0.05  # straight on the ground, to a few centimetres over 3-8 m
    angles = np.degrees(np.arctan([left_direction[1] / left_direction[0], right_direction[1] / right_direction[0]]))
    assert np.all(np.abs(angles) < 2.0) and abs(angles[0] - angles[1]) < 2.5  # along the car, parallel
    assert 2.5 < left_centre[1] < 3.5 and -1.3 < right_centre[1] < -0.9  # beside the car, 3.9 m apart


def test_car_cameras_round_trip_through_a_kalibr_camchain(cameras, tmp_path):
    named = {name: car.camera for name, car in cameras.items()}
    assert load_kalibr(save_kalibr(tmp_path / "camchain.yaml", named)) == named


def test_parse_info_reads_keys_values_and_nested_sections():
    text = "a 1 ; comment\nb\n{\n  c  x\n  d { e 2 }\n}\nf\n"
    assert parse_info(text, "t.info") == {"a": "1", "b": {"c": "x", "d": {"e": "2"}}, "f": ""}


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("a {\n b 1\n", r"t\.info: a '\{' is never closed"),
        ("a 1\n}\n", r"t\.info, line 2: unexpected '\}'"),
        ("a 1\na 2\n", r"t\.info, line 2: the key 'a' is repeated"),
        ('a "quoted"\n', r"t\.info, line 1: unexpected '\"' \(quoted strings are not supported\)"),
        ("a 1 2\n", r"t\.info, line 1: more than a key and a value"),
    ],
)
def test_parse_info_refuses_what_it_cannot_read(text, message):
    with pytest.raises(ValueError, match=message):
        parse_info(text, "t.info")


def test_a_missing_value_is_named_with_its_section(pipeline_info, tmp_path):
    text = pipeline_info.read_text()
    broken = tmp_path / "pipeline.info"
    broken.write_text(text.replace("xi  2.04856460301", ""))
    with pytest.raises(ValueError, match=r"grobi_cvg_may2013_second, intrinsics1, projection: missing the value 'xi'"):
        read_pipeline_info(broken)
    with pytest.raises(ValueError, match=r"pipeline\.info: missing the section 'no_such_car'"):
        read_pipeline_info(pipeline_info, system="no_such_car")
