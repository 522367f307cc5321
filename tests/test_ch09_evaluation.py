"""Chapter 09's figures: Table 4's rows against the paper's, each row's turn bias against its final heading, the EKF's
yaw-bias estimate and final headings, the drift against the final error, the EKF rows as pale bands."""

from types import SimpleNamespace

import numpy as np
import pytest
from matplotlib.colors import to_hex

from gpo.book.ch09_evaluation import (
    draw_drift_against_final,
    draw_table4_bars,
    draw_turn_bias,
    draw_yaw_bias,
    row_styles,
)
from gpo.experiments.table4 import PAPER_TABLE4, Row

pytestmark = pytest.mark.usefixtures("close_figures")  # conftest.py


class FakeTable:
    """A ``Table4``'s rows, paths, percentages and evaluations (each with a final error and a drift per metre)."""

    def __init__(self, rows, finals):
        self.rows, self.paths = tuple(rows), ("long1", "long2", "long3")
        self._finals = np.asarray(finals, dtype=float)
        self.evaluations = {
            row: {
                path: SimpleNamespace(final=SimpleNamespace(percent=value), drift_percent_per_m=value / 2)
                for path, value in zip(self.paths, values, strict=True)
            }
            for row, values in zip(self.rows, self._finals, strict=True)
        }

    def percent(self):
        return self._finals


def test_the_papers_rows_stand_beside_the_same_rows_here():
    table = FakeTable(PAPER_TABLE4.rows, np.arange(15).reshape(5, 3) / 10)
    ax = draw_table4_bars(PAPER_TABLE4, table)
    bars = [patch.get_height() for patch in ax.patches]
    assert len(bars) == 10  # the paper's five rows, then the same five here
    np.testing.assert_allclose(bars[:5], PAPER_TABLE4.percent().mean(axis=1))
    np.testing.assert_allclose(bars[5:], [0.1, 0.4, 0.7, 1.0, 1.3])
    assert len(ax.collections) == 10  # each row's tests, and its paths, as dots


def test_each_row_is_a_labelled_point_and_the_ekf_rows_are_hollow():
    rows = (Row("floor", "gpo", "ortho-gpi"), Row("fused", "gpo", "ortho-gpi"), Row("camera"))
    found = {rows[0].label: (-0.69, -1.37), rows[1].label: (-0.69, -1.34), rows[2].label: (0.26, 8.0)}
    ax = draw_turn_bias(found, row_styles(rows))
    assert [text.get_text() for text in ax.texts] == [rows[2].label, rows[1].label, rows[0].label]  # from the top
    offsets = [text.get_position()[1] for text in ax.texts]  # the two close points' labels one below the other
    assert offsets[2] < offsets[1] == offsets[0]
    assert ax.collections[1].get_facecolor().size == 0 or ax.collections[1].get_facecolor()[0][3] == 0


def test_the_drift_is_drawn_against_the_final_error_on_log_scales():
    rows = (Row("camera"), Row("floor", "gpo-exact", "analytic"))
    ax = draw_drift_against_final(FakeTable(rows, [[0.4, 0.8, 1.2], [0.02, 0.02, 0.02]]), row_styles(rows))
    assert ax.get_xscale() == ax.get_yscale() == "log"
    np.testing.assert_allclose(ax.collections[0].get_offsets()[0], [0.8, 0.4])
    assert {text.get_text() for text in ax.texts} == {row.label for row in rows}


def test_the_yaw_bias_estimate_is_drawn_with_the_truth_and_each_prediction():
    times = np.linspace(100.0, 110.0, 11)
    fused = {
        path: SimpleNamespace(trajectory=SimpleNamespace(times=times), biases=np.full((11, 2), 0.002))
        for path in ("long1", "long2")
    }
    finals = {"GPO alone": [-2.2, -0.6], "camera alone": [2.5, 2.7]}
    bar_styles = {"GPO alone": {"color": "tab:red"}, "camera alone": {"color": "tab:orange", "hatch": "//"}}
    left, right = draw_yaw_bias(fused, 0.001, {"long1": 0.00197, "long2": 0.00153}, finals, bar_styles)
    np.testing.assert_allclose(left.lines[0].get_ydata(), 2.0)  # mrad/s
    assert left.lines[0].get_xdata()[0] == 0.0  # seconds from the start
    assert len(right.patches) == 4
    assert to_hex(right.patches[0].get_facecolor()) == to_hex("tab:red")  # each label's bars in its style
    assert right.patches[2].get_hatch() == "//" and to_hex(right.patches[2].get_facecolor()) == to_hex("tab:orange")


def test_an_ekf_row_is_a_pale_band_in_its_floor_odometrys_colour_under_its_line():
    floor, fused, analytic = (
        Row("floor", "gpo", "gpi"),
        Row("fused", "gpo", "gpi"),
        Row("floor", "gpo-exact", "analytic"),
    )
    styles = row_styles((floor, fused, analytic, Row("camera")))
    assert styles[fused.label]["color"] == styles[floor.label]["color"] == "tab:red"
    assert styles[fused.label]["ls"] == styles[floor.label]["ls"] == "--"  # the route's dashes kept
    assert styles[fused.label]["lw"] > 2 * styles[floor.label]["lw"] and styles[fused.label]["alpha"] < 0.5
    assert styles[fused.label]["zorder"] < 2  # under the floor odometry's line (matplotlib draws lines at 2)
    assert styles[analytic.label]["ls"] == ":" and styles[Row("camera").label]["color"] == "tab:orange"
