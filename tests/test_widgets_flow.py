"""The KLT flow and bicycle-model panels: each control changes what is drawn, and what is drawn is right."""

import cv2
import matplotlib.pyplot as plt
import numpy as np
import pytest
from matplotlib.quiver import Quiver

from gpo.book.ch05_klt_flow import klt_flow_panel
from gpo.book.ch06_kinematics import bicycle_panel, constant_steering_paths
from gpo.odometry.kinematics import exact_velocities

pytestmark = pytest.mark.usefixtures("close_figures")  # conftest.py


def _texture(size=160, seed=0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    blurred = cv2.GaussianBlur(rng.normal(0.0, 1.0, (size + 40, size + 40)).astype(np.float32), (0, 0), 2.0)
    return cv2.normalize(blurred, None, 30, 220, cv2.NORM_MINMAX).astype(np.uint8)


def _shifted_run(shifts) -> list[np.ndarray]:
    """Floor images of one texture, the k-th shifted by the sum of the first k ``shifts`` (du, dv) pixels."""
    texture, images, offset = _texture(), [], np.zeros(2)
    for shift in [(0.0, 0.0), *shifts]:
        offset = offset + shift
        matrix = np.float32([[1, 0, offset[0] - 20], [0, 1, offset[1] - 20]])
        images.append(cv2.warpAffine(texture, matrix, (160, 160), flags=cv2.INTER_CUBIC))
    return images


def _controls(panel) -> dict:
    return {control.description: control for control in panel.children[0].children}


def _vectors_drawn(ax) -> int:
    return sum(artist.N for artist in ax.collections if isinstance(artist, Quiver))


def _marker(ax, name) -> np.ndarray:
    line = next(line for line in ax.lines if line.get_label().startswith(name))
    return np.array([line.get_xdata()[0], line.get_ydata()[0]])


def test_klt_panel_draws_the_kept_tracks_and_the_true_median():
    panel = klt_flow_panel(_shifted_run([(1.0, 3.0), (1.5, 4.0)]))
    _, tracks, scatter = plt.gcf().axes[:3]
    before = _vectors_drawn(tracks)
    assert before > 40
    np.testing.assert_allclose(_marker(scatter, "median"), [1.5, 4.0], atol=0.05)

    _controls(panel)["max corners"].value = 20
    _, tracks, _ = plt.gcf().axes[:3]
    assert 12 <= _vectors_drawn(tracks) <= 20 < before


def test_klt_panel_frame_slider_shows_that_frames_motion(capsys):
    panel = klt_flow_panel(_shifted_run([(1.0, 3.0), (-2.0, 6.0), (0.5, -1.0)]))
    capsys.readouterr()
    _controls(panel)["frame"].value = 2
    np.testing.assert_allclose(_marker(plt.gcf().axes[2], "median"), [-2.0, 6.0], atol=0.05)
    assert "median (-2.00, +6.00) px" in capsys.readouterr().out


def test_klt_panel_reads_out_a_flag(capsys):
    flat = np.full((160, 160), 120, np.uint8)
    panel = klt_flow_panel([flat, flat])
    assert "flagged: no texture" in capsys.readouterr().out
    assert _controls(panel)["frame"].disabled
    with pytest.raises(ValueError, match="two or more"):
        klt_flow_panel([flat])


def test_bicycle_panel_lever_changes_the_ratio_and_the_papers_path(capsys):
    panel = bicycle_panel(wheelbase_m=0.8, rear_to_reference_m=0.8)
    controls = _controls(panel)
    controls["delta [deg]"].value = 24.0
    first = capsys.readouterr().out
    assert "eq. 30 turns 1.000x" in first
    exact, paper = (line.get_xydata().copy() for line in plt.gcf().axes[1].lines[0:4:2])

    controls["l_r [m]"].value = 0.0
    assert "eq. 30 turns 1.095x" in capsys.readouterr().out  # 9.5 % too fast at 24 degrees with l_r = 0
    exact_now, paper_now = (line.get_xydata() for line in plt.gcf().axes[1].lines[0:4:2])
    np.testing.assert_allclose(exact_now, exact)  # the truth does not depend on the model
    assert np.abs(paper_now - paper).max() > 0.05

    controls["L [m]"].value = 0.5
    controls["l_r [m]"].value = 0.8
    assert controls["l_r [m]"].max == 0.5 and controls["l_r [m]"].value == 0.5  # l_r stays between the axles


def test_constant_steering_paths_exact_circle_and_the_chord_bias():
    length, speed, steering, rate = 0.8, 0.5, np.radians(30.0), 30.0
    exact, paper = constant_steering_paths(length, length, speed, steering, duration_s=4.0, rate_hz=rate)
    v, omega = exact_velocities(speed, steering, length)
    centre = np.array([0.0, v / omega])  # the rear axle turns about a point on its own line
    np.testing.assert_allclose(np.hypot(*(exact[:, :2] - centre).T), v / omega, rtol=1e-12)
    np.testing.assert_allclose(exact[-1, 2], omega * 4.0, rtol=1e-12)
    chord = -v / rate / (2 * length)  # eq. 26's first-order heading-rate bias with l_r = L
    assert paper[-1, 2] / exact[-1, 2] - 1 == pytest.approx(chord, rel=0.05)
