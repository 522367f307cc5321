"""The evaluation panel: what it prints and draws is ``gpo.metrics.evaluate`` of each row's own estimate on the path
and under the alignment chosen, though it starts from the table's estimates already placed at the first pose."""

import re

import matplotlib.pyplot as plt
import numpy as np
import pytest

from gpo.book.ch09_evaluation import evaluation_panel
from gpo.experiments.table4 import Row, Table4
from gpo.io.trajectory import Trajectory
from gpo.metrics import evaluate

ROWS = (Row("camera"), Row("floor", "gpo", "ortho-gpi"), Row("fused", "gpo", "ortho-gpi"), Row("floor", "gpo", "gpi"))
PATHS = ("arc", "line")


pytestmark = pytest.mark.usefixtures("close_figures")  # conftest.py


def _truth(path: str) -> Trajectory:
    t = np.linspace(0.0, 20.0, 401)
    turn = 0.15 if path == "arc" else 0.0
    yaw = 0.4 + turn * t
    x = 2.0 + np.cumsum(0.5 * np.cos(yaw)) * 0.05
    y = -1.0 + np.cumsum(0.5 * np.sin(yaw)) * 0.05
    return Trajectory.from_planar(np.round(t * 1e9).astype(np.int64), x, y, yaw)


def _estimate(truth: Trajectory, index: int) -> Trajectory:
    """The truth seen from its first pose (an odometry frame), with a scale error, a heading drift and noise that
    differ from row to row."""
    rng = np.random.default_rng(index)
    start = truth.positions[0, :2]
    turn = -truth.yaw[0]
    local = (truth.positions[:, :2] - start) @ np.array([[np.cos(turn), np.sin(turn)], [-np.sin(turn), np.cos(turn)]])
    local *= 1.0 + 0.01 * (index + 1)
    drift = 0.002 * (index + 1) * np.arange(len(truth))
    bend = 0.02 * index
    bent = local @ np.array([[np.cos(bend), np.sin(bend)], [-np.sin(bend), np.cos(bend)]])
    bent += rng.normal(0.0, 0.003, bent.shape)
    return Trajectory.from_planar(truth.stamps_ns, *bent.T, truth.yaw - truth.yaw[0] + drift * 1e-2, frame_id="odom")


@pytest.fixture
def table():
    truths = {path: _truth(path) for path in PATHS}
    raw = {row: {path: _estimate(truths[path], index) for path in PATHS} for index, row in enumerate(ROWS)}
    evaluations = {row: {path: evaluate(raw[row][path], truths[path]) for path in PATHS} for row in ROWS}
    return Table4(ROWS, PATHS, evaluations, dict.fromkeys(ROWS, 30.0)), raw, truths


def _controls(panel) -> dict:
    return {control.description: control for control in panel.children[0].children}


def _printed(text: str) -> dict[str, tuple[float, ...]]:
    numbers = r"APE RMSE\s+([0-9.]+) mm, max\s+([0-9.]+) mm; final\s+([0-9.]+) mm \(([0-9.]+) %\);"
    numbers += r" heading RMSE ([0-9.]+)"
    pattern = r"([^\r\n]+?)\s+" + numbers
    return {m.group(1).strip(): tuple(map(float, m.groups()[1:])) for m in re.finditer(pattern, text)}


def _expected(evaluation) -> tuple[float, ...]:
    final = evaluation.final
    values = (1e3 * evaluation.ape_m.rmse, 1e3 * evaluation.ape_m.max, 1e3 * final.position_m, final.percent)
    return (*values, evaluation.heading_rmse_deg)


@pytest.mark.parametrize("alignment", ["origin", "se2", "se3", "posyaw"])
def test_each_row_reads_as_its_own_estimate_evaluated_under_the_alignment(table, capsys, alignment):
    data, raw, truths = table
    panel = evaluation_panel(data)  # drawn at once with the first pose placed on the truth
    if alignment != "origin":
        capsys.readouterr()
        _controls(panel)["alignment"].value = alignment
    printed = _printed(capsys.readouterr().out)
    assert list(printed) == [row.label for row in ROWS[:3]]
    for row in ROWS[:3]:
        direct = evaluate(raw[row]["arc"], truths["arc"], alignment)
        np.testing.assert_allclose(printed[row.label], _expected(direct), atol=0.06)


def test_the_alignment_changes_the_numbers_and_the_path_changes_the_drawing(table, capsys):
    data, raw, truths = table
    panel = evaluation_panel(data, shown=(ROWS[3],))
    controls = _controls(panel)
    placed = capsys.readouterr().out
    controls["alignment"].value = "se2"
    assert _printed(capsys.readouterr().out) != _printed(placed)
    controls["alignment"].value = "origin"
    controls["path"].value = "line"
    drawn = next(line for line in plt.gcf().axes[0].lines if line.get_label() == ROWS[3].label).get_xydata()
    expected = evaluate(raw[ROWS[3]]["line"], truths["line"]).estimate.positions[:, :2]
    np.testing.assert_allclose(drawn, expected, atol=1e-9)


def test_no_row_chosen_says_so_and_draws_nothing(table, capsys):
    panel = evaluation_panel(table[0])
    capsys.readouterr()
    _controls(panel)["rows"].value = ()
    assert capsys.readouterr().out.splitlines()[-1] == "choose at least one row"
    assert plt.get_fignums() == []
