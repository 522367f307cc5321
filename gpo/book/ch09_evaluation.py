"""Chapter 09, evaluation: evaluated paths over the truth, their errors along the distance, and a panel over
every row of Table 4 (``gpo.book.ch09_table4``) under the alignment chosen."""

from __future__ import annotations

import ipywidgets as widgets
import matplotlib.pyplot as plt
import numpy as np

from gpo.metrics import Alignment, evaluate


def draw_evaluated_paths(evaluations: dict, ax=None, styles: dict | None = None) -> plt.Axes:
    """Top view of evaluated estimates (label -> ``gpo.metrics.Evaluation``), each where its evaluation's alignment
    put it, over the truth (a wide grey line: the associated truth with the most poses); the start, the truth's end
    (a cross) and each estimate's end (a dot) marked."""
    if ax is None:
        _, ax = plt.subplots(figsize=(7, 5))
    styles = styles or {}
    truth = max((evaluation.truth for evaluation in evaluations.values()), key=len)
    ax.plot(*truth.positions[:, :2].T, color="k", lw=5, alpha=0.2, label="truth")
    for label, evaluation in evaluations.items():
        placed = evaluation.estimate.positions[:, :2]
        (line,) = ax.plot(*placed.T, label=label, **{"lw": 1.2, **styles.get(label, {})})
        ax.plot(*placed[-1], "o", color=line.get_color(), ms=4)
    ax.plot(*truth.positions[0, :2], "go", label="start")
    ax.plot(*truth.positions[-1, :2], "kx", ms=9, mew=2, label="end (truth)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize="small")
    return ax


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
    """Every row of a Table 4 (``gpo.book.ch09_table4.Table4``) on one path, under the alignment chosen.

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
