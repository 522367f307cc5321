"""The EKF panel: each slider reaches the filter, and what is drawn and printed is the fused path's."""

import re

import matplotlib.pyplot as plt
import numpy as np
import pytest

from gpo.book.ch07_ekf_fusion import FUSION_SLIDERS, fusion_panel
from gpo.fusion import FusionSettings, fuse
from gpo.io.trajectory import Trajectory
from gpo.metrics import final_error
from gpo.odometry.kinematics import arc_increment, integrate
from gpo.pipeline.run import FloorRun

V, OMEGA, SECONDS = 0.3, 0.4, 2.0


pytestmark = pytest.mark.usefixtures("close_figures")  # conftest.py


def _arc(rate_hz: float, sigma=(0.0, 0.0), scale: float = 1.0, seed: int = 0) -> Trajectory:
    """A constant arc sampled at ``rate_hz``, each step's (v, omega) with white noise ``sigma`` and its length scaled
    by ``scale`` (a source's scale error)."""
    rng = np.random.default_rng(seed)
    steps = round(SECONDS * rate_hz)
    velocities = np.array([V, OMEGA]) + rng.standard_normal((steps, 2)) * sigma
    increments = arc_increment(velocities[:, 0], velocities[:, 1], 1 / rate_hz)
    increments[:, :2] *= scale
    stamps = np.round(np.arange(steps + 1) / rate_hz * 1e9).astype(np.int64)
    return Trajectory.from_planar(stamps, *integrate(increments).T, frame_id="odom")


@pytest.fixture
def sources():
    floor = _arc(30.0, sigma=(0.004, 0.02), seed=1)
    inliers = np.full(len(floor), 100)
    inliers[0] = 0
    tracking = _arc(200.0, sigma=(0.02, 0.02), scale=1.05, seed=2)
    return FloorRun(floor, inliers, 30.0), tracking, _arc(120.0)


def _controls(panel) -> dict:
    return {control.description: control for control in panel.children[0].children}


def _final_mm(text: str) -> float:
    return float(re.search(r"final error ([0-9.]+) mm", text).group(1))


def _fused_line(ax) -> np.ndarray:
    return next(line for line in ax.lines if line.get_label() == "fused").get_xydata().copy()


def test_panel_draws_and_reads_out_the_fused_path(sources, capsys):
    floor, tracking, truth = sources
    panel = fusion_panel(floor, tracking, truth)
    assert {control.description for control in _controls(panel).values()} == {
        *(label for label, _, _ in FUSION_SLIDERS.values()), "outage from [s]", "outage length [s]"
    }
    assert all(not control.continuous_update for control in _controls(panel).values())
    printed = capsys.readouterr().out
    expected = final_error(fuse(floor.trajectory, floor.inliers, tracking, FusionSettings()).trajectory, truth)
    assert _final_mm(printed) == pytest.approx(1e3 * expected.position_m, abs=0.051)
    assert "refused 0 measurement(s)" in printed
    top, errors = plt.gcf().axes[:2]
    assert {line.get_label() for line in top.lines} >= {"truth", "floor", "tracking camera", "fused"}
    fused = _fused_line(top)
    np.testing.assert_allclose(fused[0], truth.positions[0, :2], atol=1e-12)  # placed on the truth at the start
    assert len(errors.lines) == 3


def test_trusting_the_camera_moves_the_fused_path_towards_it(sources, capsys):
    floor, tracking, truth = sources
    panel = fusion_panel(floor, tracking, truth)
    before = _final_mm(capsys.readouterr().out)
    fused_before = _fused_line(plt.gcf().axes[0])

    controls = _controls(panel)
    controls["floor sigma v [m/s]"].value = 1.0  # the floor's speeds hardly count: the camera's 5 % scale shows
    controls["floor sigma omega [rad/s]"].value = 1.0
    after = _final_mm(capsys.readouterr().out.splitlines()[-1])
    camera = 1e3 * final_error(tracking, truth).position_m
    assert before < 0.5 * camera < after
    assert np.abs(_fused_line(plt.gcf().axes[0]) - fused_before).max() > 0.01


def test_each_slider_reaches_the_filter(sources, capsys):
    floor, tracking, truth = sources
    panel = fusion_panel(floor, tracking, truth, FusionSettings(accel_mps2=0.2))
    controls = _controls(panel)
    assert controls["accel [m/s^2/sqrt(Hz)]"].value == pytest.approx(0.2)
    capsys.readouterr()
    for label, control in controls.items():
        if label.startswith("outage"):
            continue
        before = _fused_line(plt.gcf().axes[0])
        control.value = control.value * 30
        assert "fused: final error" in capsys.readouterr().out, label
        assert np.abs(_fused_line(plt.gcf().axes[0]) - before).max() > 1e-9, label  # the fused path moved


def test_the_outage_and_drift_sliders_reach_the_filter(sources, capsys):
    """An outage leaves the floor's steps inside it out, exactly as ``fuse`` with their inliers at zero; the drift
    sliders ask ``drifted`` for a camera path with that scale error and yaw bias, and the filter estimates them."""
    floor, tracking, truth = sources
    asked = []

    def drifted(scale_error, yaw_bias_radps):
        asked.append((scale_error, yaw_bias_radps))
        return _arc(200.0, sigma=(0.02, 0.02), scale=1 + scale_error, seed=2)

    panel = fusion_panel(floor, tracking, truth, drifted=drifted)
    controls = _controls(panel)
    assert asked[-1] == pytest.approx((0.02, 1e-3))
    controls["camera scale error [%]"].value = -3.0
    assert asked[-1] == pytest.approx((-0.03, 1e-3))
    capsys.readouterr()
    controls["outage from [s]"].value = 0.5
    controls["outage length [s]"].value = 1.0
    printed = capsys.readouterr().out.splitlines()[-1]
    seconds = floor.trajectory.times - floor.trajectory.times[0]
    inliers = np.where((seconds >= 0.5) & (seconds < 1.5), 0, floor.inliers)
    camera = drifted(-0.03, 1e-3)
    expected = fuse(floor.trajectory, inliers, camera, FusionSettings())
    assert _final_mm(printed) == pytest.approx(1e3 * final_error(expected.trajectory, truth).position_m, abs=0.051)
    assert f"camera scale {100 * expected.biases[-1, 0]:+.2f} %" in printed
