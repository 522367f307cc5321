"""A new floor estimator and a new camera model are each one class and one registry line: a toy of each, added that
way in this file, runs through everything that reads the registries, and agrees with an independent truth.

- The toy estimator reads the floor's mean motion as a pure translation. On the sample's first two seconds (straight
  ahead) it follows the simulator's truth as the shipped methods do; the config file, its checker and the command
  line's ``--method`` take it by its name.
- The toy camera is the equidistant fisheye (r = f theta), which is exactly a Kannala-Brandt camera with k1..k4 = 0:
  it projects as that KB4 does, goes through a Kalibr file and back, is fitted by the KB4 to nothing, and the floor
  image built through it is the KB4's.
"""

from dataclasses import dataclass

import numpy as np
import pytest

from gpo.cameras import KB4, MODELS, CameraModel
from gpo.cameras.base import check_intrinsics, flat_from_params, round_trip_valid, shaped
from gpo.cameras.files import load_kalibr, save_kalibr
from gpo.cameras.fit import fit_model
from gpo.cli import main
from gpo.floor_image.analytic import analytic_table
from gpo.floor_image.image import FloorImage
from gpo.io.bag import Recording
from gpo.io.trajectory import Trajectory
from gpo.odometry.estimators import ESTIMATORS
from gpo.odometry.estimators.base import FloorEstimator, vector_motion
from gpo.pipeline.config import load_config, methods, save_config
from gpo.pipeline.run import odometry
from gpo.sim.record import GROUND_TRUTH_TOPIC, recording


class MeanTranslation(FloorEstimator):
    """The floor's mean motion vector, reversed, as the robot's increment: no turn."""

    NAME = "toy-translation"

    def increment(self, measurement, dt: float):
        _, moved = vector_motion(measurement, self.geometry, "mean")
        return np.array([-moved[0], -moved[1], 0.0]), None


@dataclass(frozen=True)
class Equidistant(CameraModel):
    """u = fx theta x / r + cx, v = fy theta y / r + cy, theta = atan2(r, z): the ideal fisheye, up to 90 degrees."""

    fx: float
    fy: float
    cx: float
    cy: float
    width: int
    height: int

    NAME = "equidistant"
    PARAMETER_NAMES = ("fx", "fy", "cx", "cy")
    KALIBR_MODEL, KALIBR_DISTORTIONS, KALIBR_INTRINSICS = "equidistant", ("none",), 4

    @classmethod
    def from_kalibr(cls, intrinsics, distortion, coeffs, width, height, where):
        return cls(*intrinsics, width, height)

    def kalibr(self, name):
        return [self.fx, self.fy, self.cx, self.cy], "none", []

    def __post_init__(self):
        check_intrinsics(self)

    @classmethod
    def from_params(cls, params, width, height):
        return flat_from_params(cls, cls.PARAMETER_NAMES, params, width, height)

    @property
    def params(self):
        return np.array([self.fx, self.fy, self.cx, self.cy])

    def project(self, points):
        points = shaped(points, 3, "points")
        x, y, z = np.moveaxis(points, -1, 0)
        r = np.hypot(x, y)
        with np.errstate(invalid="ignore", divide="ignore"):
            scale = np.where(r > 0, np.arctan2(r, z) / np.where(r > 0, r, 1.0), 1.0 / z)
        valid = np.isfinite(points).all(axis=-1) & (z > 0)
        uv = np.stack([self.fx * scale * x + self.cx, self.fy * scale * y + self.cy], axis=-1)
        uv[~valid] = np.nan
        return uv, valid

    def unproject(self, uv):
        uv = shaped(uv, 2, "pixels")
        mx, my = (uv[..., 0] - self.cx) / self.fx, (uv[..., 1] - self.cy) / self.fy
        theta = np.hypot(mx, my)
        with np.errstate(invalid="ignore", divide="ignore"):
            sin_over = np.where(theta > 0, np.sin(theta) / np.where(theta > 0, theta, 1.0), 1.0)
        rays = np.stack([sin_over * mx, sin_over * my, np.cos(theta)], axis=-1)
        valid = round_trip_valid(self, rays, uv)
        rays[~valid] = np.nan
        return rays, valid


@pytest.fixture
def registered(monkeypatch):
    """The toys registered as a new module would register them: one line each."""
    monkeypatch.setitem(ESTIMATORS, MeanTranslation.NAME, MeanTranslation)
    monkeypatch.setitem(MODELS, Equidistant.NAME, Equidistant)


CAMERA = Equidistant(280.0, 281.0, 423.5, 399.5, 848, 800)
SAME_KB4 = KB4(280.0, 281.0, 423.5, 399.5, 0.0, 0.0, 0.0, 0.0, 848, 800)
FRAMES = 60  # the sample's first two seconds: straight ahead, speeding up to 0.5 m/s


def test_a_new_estimator_runs_end_to_end(registered, tmp_path, capsys):
    assert MeanTranslation.NAME in methods()
    config = load_config().replace(method=MeanTranslation.NAME)
    written = save_config(tmp_path / "toy.yaml", config)
    assert load_config(written).method == MeanTranslation.NAME and load_config(written).estimator is MeanTranslation

    sample = recording("sample")
    with Recording(sample) as bag:
        stream = zip(range(FRAMES), bag.frames(gray=True, progress=False), strict=False)
        frames = [(frame.stamp_ns, frame.image) for _, frame in stream]
        truth = bag.trajectory(GROUND_TRUTH_TOPIC)
    result = odometry(frames, config)
    assert [record.status for record in result.records[1:]] == ["measured"] * (FRAMES - 1)
    index = np.searchsorted(truth.stamps_ns, result.trajectory.stamps_ns)
    travelled = truth.positions[index[-1], :2] - truth.positions[index[0], :2]
    estimated = result.trajectory.positions[-1, :2] - result.trajectory.positions[0, :2]
    assert np.linalg.norm(travelled) > 0.3  # 0.67 m straight ahead, where a translation alone is the motion
    assert np.linalg.norm(estimated - travelled) < 4e-4 * np.linalg.norm(travelled)  # measured 1.6e-4 of it

    out = tmp_path / "toy.tum"
    arguments = ["run", str(sample), "--config", str(written), "--method", MeanTranslation.NAME, "--out", str(out)]
    assert main(arguments) == 0
    assert f"method {MeanTranslation.NAME}" in capsys.readouterr().out
    assert len(Trajectory.read_tum(out).stamps_ns) > FRAMES


def test_an_unregistered_estimator_is_refused_by_name():
    with pytest.raises(ValueError, match=f"unknown method '{MeanTranslation.NAME}'; the methods are gpo, "):
        load_config().replace(method=MeanTranslation.NAME)


def test_a_new_camera_model_is_a_kb4_without_distortion(registered):
    rays = np.random.default_rng(7).normal(size=(500, 3))
    rays[:, 2] = np.abs(rays[:, 2]) + 0.05  # in front of the lens, up to 88 degrees off the axis
    uv, valid = CAMERA.project(rays)
    expected, expected_valid = SAME_KB4.project(rays)
    assert valid.sum() > 450 and (valid == expected_valid).all()
    np.testing.assert_allclose(uv[valid], expected[valid], atol=1e-9)
    back, back_valid = CAMERA.unproject(uv[valid])
    assert back_valid.all()
    np.testing.assert_allclose(back, rays[valid] / np.linalg.norm(rays[valid], axis=1, keepdims=True), atol=1e-9)


def test_a_new_camera_model_goes_through_the_registry_readers(registered, tmp_path):
    path = save_kalibr(tmp_path / "camchain.yaml", {"cam0": CAMERA})
    assert "camera_model: equidistant" in path.read_text()
    assert load_kalibr(path) == {"cam0": CAMERA}
    fit = fit_model(CAMERA, "kb4")
    assert isinstance(fit.camera, KB4) and fit.worst_px < 1e-3
    np.testing.assert_allclose(fit.camera.dist, 0.0, atol=1e-6)
    floor = FloorImage.top_view(metres_per_pixel=4e-3)
    mount = (0.2, np.radians(-30.0), 0.0)
    toy_table = analytic_table(CAMERA, mount, floor, max_outside=1.0, cache=False)
    kb4_table = analytic_table(SAME_KB4, mount, floor, max_outside=1.0, cache=False)
    np.testing.assert_allclose(toy_table.map_x, kb4_table.map_x, atol=1e-3, equal_nan=True)
    np.testing.assert_allclose(toy_table.map_y, kb4_table.map_y, atol=1e-3, equal_nan=True)
