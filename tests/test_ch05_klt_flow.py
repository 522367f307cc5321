"""Chapter 05's figures: what each draws is what it was given (the tracks kept and refused, the tracks each pyramid
depth keeps, the paper's Table 3 beside the suite's, the frames coasted and held)."""

from types import SimpleNamespace

import matplotlib.pyplot as plt
import numpy as np
import pytest
from matplotlib.quiver import Quiver

from gpo.book.ch05_klt_flow import (
    COASTING_COLOURS,
    draw_coasting,
    draw_forward_backward,
    draw_lk_steps,
    draw_pyramid_levels,
    draw_table3,
    draw_vector_errors,
)
from gpo.experiments.table3 import PAPER_TABLE3

pytestmark = pytest.mark.usefixtures("close_figures")  # conftest.py


IMAGE = np.full((60, 80), 128, np.uint8)


def _arrows(ax) -> int:
    return sum(artist.N for artist in ax.collections if isinstance(artist, Quiver))


def test_the_forward_backward_figure_keeps_the_tracks_under_the_threshold():
    start = np.array([[10.0, 10.0], [20.0, 20.0], [30.0, 30.0], [40.0, 40.0]])
    error = np.array([0.01, 0.2, 0.7, 30.0])  # two under the 0.5 px threshold, two over
    fig = draw_forward_backward(IMAGE, start, start + 3.0, error, np.array([0.1, 0.1, 0.1, 9.0]), 0.5)
    left, right = fig.axes
    assert left.get_title() == "2 kept (green), 2 refused (red)"
    assert _arrows(left) == 4
    assert [line.get_xdata()[0] for line in right.lines] == [0.5]
    heights = np.array([patch.get_height() for patch in right.patches]).reshape(2, -1)  # right ones, then the rest
    assert heights.sum(axis=1).tolist() == [3, 1]


def test_each_pyramid_depth_counts_its_kept_and_right_tracks():
    start = np.array([[10.0, 10.0], [20.0, 20.0], [30.0, 30.0]])
    down, astray = np.array([0.0, 5.0]), np.array([0.5, 0.5])
    right = SimpleNamespace(start=start, end=start + down)
    wrong = SimpleNamespace(start=start[:2], end=start[:2] + astray)
    fig = draw_pyramid_levels(IMAGE, [("deep", right, start + 1.04 * down), ("shallow", wrong, start[:2] + down)])
    assert [ax.get_title() for ax in fig.axes] == ["deep\n3 kept, 3 right", "shallow\n2 kept, 0 right"]


def test_lucas_kanade_steps_draw_the_residual_at_each_step_and_the_error_falling():
    rng = np.random.default_rng(0)
    residuals = [rng.normal(0, scale, (21, 21)) for scale in (1.0, 0.5, 0.2, 0.1, 0.1)]
    history = [np.array([0.0, v]) for v in (1.5, 2.9, 3.2, 3.2, 3.2)]
    fig = draw_lk_steps(residuals[0], residuals, history, np.array([0.0, 3.2]))
    titles = [ax.get_title() for ax in fig.axes[1:5]]
    assert titles[0].startswith("I_t at the guess") and titles[-1].startswith("I_t after step 4")
    errors = fig.axes[5].lines[0].get_ydata()
    np.testing.assert_allclose(errors, [1.7, 0.3, 0.0, 0.0, 0.0], atol=1e-12)


def test_the_vector_errors_shade_each_run_of_frames_with_outliers():
    frames = np.arange(10)
    outliers = np.array([0, 1, 1, 0, 0, 1, 0, 0, 1, 1], bool)
    ax = draw_vector_errors(np.full((10, 2), 0.1), outliers, frames)
    assert len(ax.patches) == 3  # one shaded span a run


def test_table3_draws_the_papers_averages_beside_the_suites():
    ours = {key: tuple(v / 10 for v in values) for key, values in PAPER_TABLE3.values.items()}
    fig = draw_table3(PAPER_TABLE3.values, ours, ["Test1", "Test2", "Test3", "Average"])
    paper_bars, our_bars = ([patch.get_height() for patch in ax.patches] for ax in fig.axes)
    np.testing.assert_allclose(paper_bars[:4], [1e3 * v for v in PAPER_TABLE3.values["mean", "avg"]])
    np.testing.assert_allclose(our_bars[4:], [1e2 * v for v in PAPER_TABLE3.values["median", "avg"]])


def test_the_coasting_figure_shades_each_run_of_coasted_and_held_frames():
    times = np.arange(10) / 30.0
    statuses = ["measured"] * 3 + ["coasted"] * 3 + ["held"] * 2 + ["measured", "coasted"]
    ax = draw_coasting(times, times * 0.5, times * 0.4, statuses)
    spans = ax.patches
    colours = [span.get_facecolor()[:3] for span in spans]
    coasted = plt.matplotlib.colors.to_rgb(COASTING_COLOURS["coasted"])
    held = plt.matplotlib.colors.to_rgb(COASTING_COLOURS["held"])
    assert colours.count(coasted) == 2 and colours.count(held) == 1  # two runs coasted, one held
    assert [line.get_label() for line in ax.get_lines()] == ["truth", "odometry"]
