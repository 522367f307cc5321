"""Chapter 09, evaluation: evo's own command line beside ``gpo.metrics``, evaluated paths over the truth and their
errors along the distance, Table 4's rows (``gpo.experiments.table4``) compared and drawn (the paper's rows against
the suite's, each row's turn bias against its final heading, the drift against the final error), the EKF's
inputs and its estimate of the camera's yaw bias, and a panel over every row under the alignment chosen. (The
population benchmark's results are lab B's: ``gpo.book.lab_b_population``.)"""

from __future__ import annotations

import subprocess
import sys
import tempfile
from itertools import pairwise
from pathlib import Path

import ipywidgets as widgets
import matplotlib.pyplot as plt
import numpy as np
from evo.tools import file_interface

from gpo.book.figures import draw_placed_paths
from gpo.experiments.runs import floor_run, route_config
from gpo.experiments.table4 import PATHS
from gpo.fusion import FusionSettings
from gpo.io.bag import Recording
from gpo.metrics import MAX_STAMP_DIFFERENCE_S, Alignment, evaluate
from gpo.pipeline.run import tracking_path
from gpo.sim.record import GROUND_TRUTH_TOPIC, recording


def draw_evaluated_paths(evaluations: dict, ax=None, styles: dict | None = None) -> plt.Axes:
    """Top view of evaluated estimates (label -> ``gpo.metrics.Evaluation``), each where its evaluation's alignment
    put it, over the truth (a wide grey line: the associated truth with the most poses); the start, the truth's end
    (a cross) and each estimate's end (a dot) marked."""
    truth = max((evaluation.truth for evaluation in evaluations.values()), key=len)
    placed = {label: evaluation.estimate.positions[:, :2] for label, evaluation in evaluations.items()}
    return draw_placed_paths(placed, truth, ax, styles, truth_end=True)


def draw_evaluation_errors(evaluations: dict, ax=None, styles: dict | None = None, kind: str = "position") -> plt.Axes:
    """Each evaluation's error (label -> ``gpo.metrics.Evaluation``) against the distance the truth travelled from its
    first associated pose, metres: ``kind`` "position" (evo's APE of each pose, millimetres) or "heading" (the
    estimate's yaw minus the truth's, degrees)."""
    errors = {
        "position": (lambda evaluation: 1e3 * evaluation.position_errors_m, "position error [mm]"),
        "heading": (lambda evaluation: np.degrees(evaluation.heading_errors_rad), "heading error [deg]"),
    }
    if kind not in errors:
        raise ValueError(f"unknown kind {kind!r}: expected {' or '.join(errors)}")
    values, ylabel = errors[kind]
    if ax is None:
        _, ax = plt.subplots(figsize=(7, 4))
    styles = styles or {}
    for label, evaluation in evaluations.items():
        ax.plot(evaluation.distances_m, values(evaluation), label=label, **{"lw": 1.2, **styles.get(label, {})})
    if kind == "heading":
        ax.axhline(0.0, color="k", lw=0.8)
    ax.set_xlabel("distance travelled by the truth [m]")
    ax.set_ylabel(ylabel)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize="small")
    return ax


def evaluation_panel(table, shown: tuple | None = None) -> widgets.VBox:
    """Every row of a Table 4 (``gpo.experiments.table4.Table4``) on one path, under the alignment chosen.

    ``table.evaluations[row][path]`` holds each row's estimate placed on the truth at its first pose (``origin``,
    shown as it is); for ``se2``, ``se3`` or ``posyaw`` the panel aligns it again (``gpo.metrics.evaluate``, once
    per row, path and alignment; an alignment that moves the whole path is the same from either start) and draws
    the paths over the truth and their position errors along the distance travelled. ``shown``: the rows selected
    at first (default: the table's first three). One line a row reads out its APE RMSE and maximum, final position
    error in mm and % of the distance, and heading RMSE.
    """
    labels = {row.label: row for row in table.rows}
    style = {"description_width": "initial"}
    controls = {
        "path": widgets.Dropdown(options=table.paths, value=table.paths[0], description="path", style=style),
        "alignment": widgets.Dropdown(
            options=[mode.value for mode in Alignment if mode is not Alignment.NONE],
            value=Alignment.ORIGIN.value,
            description="alignment",
            style=style,
        ),
        "chosen": widgets.SelectMultiple(
            options=list(labels),
            value=[row.label for row in (shown or table.rows[:3])],
            rows=min(len(labels), 8),
            description="rows",
            layout={"width": "34em"},
            style=style,
        ),
    }

    aligned = {}  # (label, path, alignment) -> Evaluation, each computed once

    def evaluated(label: str, path: str, alignment: str):
        placed = table.evaluations[labels[label]][path]
        if alignment == Alignment.ORIGIN:
            return placed
        if (label, path, alignment) not in aligned:
            aligned[label, path, alignment] = evaluate(placed.estimate, placed.truth, alignment)
        return aligned[label, path, alignment]

    def redraw(path: str, alignment: str, chosen: tuple[str, ...]) -> None:
        plt.close("all")
        if not chosen:
            print("choose at least one row")
            return
        evaluations = {label: evaluated(label, path, alignment) for label in chosen}
        _, (left, right) = plt.subplots(1, 2, figsize=(13, 4.8), gridspec_kw={"width_ratios": [1, 1.2]})
        draw_evaluated_paths(evaluations, ax=left)
        left.set_title(f"{path}, aligned by {alignment}")
        draw_evaluation_errors(evaluations, ax=right)
        right.set_title("how far from the truth, along the way")
        for label, evaluation in evaluations.items():
            final = evaluation.final
            print(
                f"{label:<38} APE RMSE {1e3 * evaluation.ape_m.rmse:6.1f} mm, max {1e3 * evaluation.ape_m.max:6.1f} mm;"
                f" final {1e3 * final.position_m:6.1f} mm ({final.percent:.2f} %); heading RMSE"
                f" {evaluation.heading_rmse_deg:.2f} deg"
            )
        plt.show()

    return widgets.VBox([widgets.HBox(list(controls.values())), widgets.interactive_output(redraw, controls)])


def evo_statistics(tool: str, truth_file: Path, estimate_file: Path, flags: list[str]) -> dict[str, float]:
    """The statistics (metres: rmse, mean, median, max, ...) that evo's own command line ``tool`` (``evo_ape`` or
    ``evo_rpe``) saves for two TUM files, with its ``flags`` (e.g. ``--align_origin``) and the association of
    ``gpo.metrics``."""
    with tempfile.TemporaryDirectory() as folder:
        saved = Path(folder) / "results.zip"
        command = [str(Path(sys.executable).parent / tool), "tum", str(truth_file), str(estimate_file), *flags]
        command += ["--t_max_diff", str(MAX_STAMP_DIFFERENCE_S), "--save_results", str(saved), "--no_warnings"]
        subprocess.run(command, check=True, capture_output=True, text=True)
        return file_interface.load_res_file(saved).stats


def fusion_inputs(paths=PATHS, settings: FusionSettings | None = None) -> dict[str, tuple]:
    """path -> (GPO's floor run on the ortho-GPI, kept on disk (``gpo.experiments.runs.floor_run``); the tracking
    camera's
    path of base_link (``gpo.pipeline.run.tracking_path`` with ``settings``, default the package's); the truth)."""
    settings = settings or FusionSettings()
    inputs = {}
    for path in paths:
        bag = recording(path, progress=False)
        with Recording(bag) as recorded:
            floor = floor_run(bag, route_config("gpo", "ortho-gpi"))
            inputs[path] = floor, tracking_path(recorded, settings), recorded.trajectory(GROUND_TRUTH_TOPIC)
    return inputs


def ordered(table, *chain) -> str:
    """Whether the rows of ``chain`` (of a ``Table4``) come in increasing order of translation error, on the mean over
    the paths and on every path: one line."""
    errors = dict(zip(table.rows, table.translation_errors_m(), strict=True))
    on_mean = all(errors[a].mean() < errors[b].mean() for a, b in pairwise(chain))
    on_paths = all(np.all(errors[a] < errors[b]) for a, b in pairwise(chain))
    return f"mean: {on_mean!s:<5}  every path: {on_paths}"


ROW_COLOURS = {  # (source, method) of a row of Table 4 -> its colour; an EKF row takes its floor odometry's
    ("camera", None): "tab:orange",
    ("floor", "gpo"): "tab:red",
    ("floor", "gpo-exact"): "tab:blue",
    ("floor", "gpo-rigid"): "tab:green",
    ("floor", "features"): "tab:brown",
}
ROUTE_LINES = {None: "-", "ortho-gpi": "-", "gpi": "--", "analytic": ":"}  # a row's route -> its line style
EKF_BAND = {"lw": 6.0, "alpha": 0.3, "zorder": 1}  # an EKF row: a wide pale band under its floor odometry's line


def row_styles(rows) -> dict[str, dict]:
    """Each row's label -> its line's style: colour by method, dashes by route; an EKF row in its floor odometry's
    colour as a wide pale band (``EKF_BAND``) drawn under the floor odometry's line, so that both stay visible where
    they coincide."""
    styles = {}
    for row in rows:
        source = "floor" if row.source == "fused" else row.source
        style = {"color": ROW_COLOURS[source, row.method], "ls": ROUTE_LINES[row.route], "lw": 1.2}
        styles[row.label] = style | EKF_BAND if row.source == "fused" else style
    return styles


def draw_table4_paths(table, styles: dict, end_m: float = 0.45) -> plt.Figure:
    """Every row of a ``Table4`` on each of its paths (one row of panels a path): the paths over the truth, the last
    ``end_m`` metres around the truth's end, and the position error along the way; one legend below."""
    fig, axes = plt.subplots(
        len(table.paths),
        3,
        figsize=(17, 5 * len(table.paths)),
        gridspec_kw={"width_ratios": [1.1, 1, 1.4]},
        squeeze=False,
    )
    camera = next(row for row in table.rows if row.source == "camera")
    for (whole, end, along), path in zip(axes, table.paths, strict=True):
        shown = {row.label: table.evaluations[row][path] for row in table.rows}
        draw_evaluated_paths(shown, ax=whole, styles=styles)
        whole.set_title(f"{path}: {table.evaluations[camera][path].final.distance_m:.1f} m")
        draw_evaluated_paths(shown, ax=end, styles=styles)
        finish = table.evaluations[camera][path].truth.positions[-1, :2]
        end.set_aspect("equal", adjustable="box")
        end.set_xlim(finish[0] - end_m, finish[0] + end_m)
        end.set_ylim(finish[1] - end_m, finish[1] + end_m)
        end.set_title(f"{path}: the last {end_m:g} m around the truth's end")
        draw_evaluation_errors(shown, ax=along, styles=styles)
        along.set_title(f"{path}: position error along the way")
        for ax in (whole, end, along):
            ax.get_legend().remove()
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=5, fontsize="small")
    fig.tight_layout(rect=(0, 0.05, 1, 1))
    return fig


def draw_table4_bars(paper, table, ax=None) -> plt.Axes:
    """The paper's rows of Table 4 (``PAPER_TABLE4``) against the same rows here (a ``Table4``): each row's mean
    translation error in % of the path, the paper's bar beside the suite's, each of its tests or paths a dot."""
    if ax is None:
        _, ax = plt.subplots(figsize=(10, 4))
    ours = dict(zip(table.rows, table.percent(), strict=True))
    x = np.arange(len(paper.rows))
    for offset, name, colour, values in (
        (-0.2, "the paper (Test4-6)", "0.55", paper.percent()),
        (0.2, "here (" + ", ".join(table.paths) + ")", "tab:blue", np.array([ours[row] for row in paper.rows])),
    ):
        ax.bar(x + offset, values.mean(axis=1), 0.38, color=colour, alpha=0.8, label=name)
        for i, row_values in enumerate(values):
            ax.scatter(np.full(len(row_values), x[i] + offset), row_values, color="k", s=12, zorder=3)
    ax.set_xticks(x, [row.label.replace(", ", "\n") for row in paper.rows], fontsize="small")
    ax.set_ylabel("translation error [% of the path]")
    ax.legend(fontsize="small")
    ax.grid(True, axis="y", alpha=0.3)
    return ax


def _annotate_apart(ax, points: dict) -> None:
    """Label each point (label -> (x, y) in data) beside it, moving a label down a line where it would overlap one
    placed before (in display space, after the axes' limits are set)."""
    ax.autoscale_view()
    placed = []
    for label, xy in sorted(points.items(), key=lambda item: -item[1][1]):
        x, y = ax.transData.transform(xy)
        dy = 3
        while any(abs(x - px) < 150 and abs(y + dy - py) < 9 for px, py in placed):
            dy -= 9
        placed.append((x, y + dy))
        ax.annotate(label, xy, xytext=(5, dy), textcoords="offset points", fontsize="x-small")


def _scatter_row(ax: plt.Axes, x: float, y: float, style: dict) -> None:
    """One row's point in its style's colour: a filled dot, or a hollow square for the EKF's rows (drawn wider)."""
    fused = style.get("lw", 1) > 2
    colour = style.get("color", "k")
    ax.scatter(x, y, s=90 if fused else 30, marker="s" if fused else "o", zorder=3,
               facecolors="none" if fused else colour, edgecolors=colour)


def draw_turn_bias(found: dict, styles: dict, ax=None) -> plt.Axes:
    """Each row's turn bias against its final heading error (``found``: label -> (turn bias %, final heading degrees),
    means over the paths), a point a row in its style's colour (the EKF's rows hollow squares), labelled."""
    if ax is None:
        _, ax = plt.subplots(figsize=(9, 5))
    for label, (turn, heading) in found.items():
        _scatter_row(ax, turn, heading, styles.get(label, {}))
    _annotate_apart(ax, found)
    ax.axhline(0.0, color="k", lw=0.8)
    ax.axvline(0.0, color="k", lw=0.8)
    ax.set_xlabel("turn bias κ: heading steps read against the truth's, minus 1 [%]")
    ax.set_ylabel("final heading error [deg]")
    ax.grid(True, alpha=0.3)
    return ax


PATH_COLOURS = ("tab:blue", "tab:green", "tab:purple")  # the paths' lines in the yaw-bias figure


def draw_yaw_bias(
    fused: dict, true_bias: float, predicted: dict, finals: dict, bar_styles: dict | None = None, axes=None
) -> np.ndarray:
    """Left: the EKF's estimate of the camera's yaw-rate bias over time on each path (``fused``: path -> its
    ``FusedPath``), the simulator's bias (``true_bias``, rad/s) and each path's prediction b - kappa mean turn rate
    (``predicted``: path -> rad/s) as lines. Right: the final heading error on each path (``finals``: label -> one
    value a path, degrees) as grouped bars, each label's bars in its ``bar_styles`` (label -> keyword arguments of
    ``Axes.bar``, such as colour, alpha and hatch)."""
    if axes is None:
        _, axes = plt.subplots(1, 2, figsize=(14, 4), gridspec_kw={"width_ratios": [1.3, 1]})
    left, right = axes
    for colour, (path, result) in zip(PATH_COLOURS, fused.items(), strict=False):
        seconds = result.trajectory.times - result.trajectory.times[0]
        left.plot(seconds, 1e3 * result.biases[:, 1], color=colour, label=f"{path}: estimate")
        left.axhline(1e3 * predicted[path], color=colour, ls="--", lw=1)
    left.axhline(1e3 * true_bias, color="k", ls=":", label="the simulator's bias")
    left.plot([], [], color="0.4", ls="--", lw=1, label="predicted: b - κ · mean turn rate")
    left.set_xlabel("time [s]")
    left.set_ylabel("camera's yaw-rate bias [mrad/s]")
    left.legend(fontsize="small")
    paths = list(fused)
    width = 0.8 / len(finals)
    bar_styles = bar_styles or {}
    for k, (label, values) in enumerate(finals.items()):
        x = np.arange(len(paths)) + (k - (len(finals) - 1) / 2) * width
        right.bar(x, values, width, label=label, **bar_styles.get(label, {}))
    right.axhline(0.0, color="k", lw=0.8)
    right.set_xticks(range(len(paths)), paths)
    right.set_ylabel("final heading error [deg]")
    right.legend(fontsize="small")
    return np.asarray(axes)


def draw_drift_against_final(table, styles: dict, ax=None) -> plt.Axes:
    """Each row of a ``Table4``: its final position error (% of the distance) against its drift (the mean RPE of its
    1 m segments, % of a segment's length), both as means over the paths (log scales), a point a row in its style's
    colour (the EKF's rows hollow squares), labelled."""
    if ax is None:
        _, ax = plt.subplots(figsize=(9, 5))
    points = {}
    for row in table.rows:
        evaluations = table.evaluations[row].values()
        final = np.mean([evaluation.final.percent for evaluation in evaluations])
        drift = np.mean([evaluation.drift_percent_per_m for evaluation in evaluations])
        _scatter_row(ax, final, drift, styles.get(row.label, {}))
        points[row.label] = final, drift
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.autoscale_view()
    ax.set_xlim(right=ax.get_xlim()[1] * 4)  # room for the labels
    _annotate_apart(ax, points)
    ax.set_xlabel("final position error [% of the distance]")
    ax.set_ylabel("drift: mean RPE over 1 m segments [% of 1 m]")
    ax.grid(True, which="both", alpha=0.3)
    return ax
