"""Lab C, the second paper's experiments I-IX in its conditions: Table 2 as published and shipped, the road from the
paper's method as published to the shipped pipeline (the ablation), the targets, and the mu +- sigma band in a turn.

``python -m gpo.book.lab_c_second_paper [EXPERIMENTS]`` runs every step of
``gpo.experiments.table2.ablation_configs`` over the experiments (default: ``ABLATED``, I, II, III, VIII and IX), each
run kept as Table 2's are, and prints Table 2 (as published and shipped), the ablation and the targets. The
full-image SIFT of the published method takes a fifth of a second a frame on the wood floor, so the first call takes
about half an hour on one core; ``benchmarks/second_paper.py --write`` saves the same rows (``rows``) to
``benchmarks/results/second_paper.json``, which lab C prints with the same functions (``print_table2``,
``print_ablation``, ``print_targets``) and draws (``draw_table2``, ``draw_ablation``). Every number a run integrates
prints to ``SIGNIFICANT`` significant digits.

A row (``rows``) is a dict: ``pipeline`` (a step's name), ``experiment`` (I-IX), the columns of
``gpo.metrics.PaperTable2`` at the paper's ground-truth samples, the same prefixed ``continuous_`` against every
frame's truth, ``drift_percent_per_m`` (the suite's RPE per metre, None under a metre), ``frames`` and
``frames_per_second``.
"""

from __future__ import annotations

import argparse
import dataclasses
import math

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.collections import LineCollection

from gpo.experiments.table2 import EXPERIMENTS, HEADER, ablation_configs, experiment, format_row, reproduce_table2
from gpo.metrics import Alignment, PaperTable2, evaluate

ABLATED = ("I", "II", "III", "VIII", "IX")  # the experiments the ablation is printed for
TARGETS_PERCENT = {"I": 0.2, "II": 0.2, "III": 0.2, "IX": 0.5}  # the shipped pipeline's final error, % of distance
PAPER_GAP = 3.0  # as published, a final error more than this many times the paper's is traced through the ablation
SIGNIFICANT = 2  # the digits of a number a run integrates that another processor's run still gives (lab E)

PAPER_IMAGES = {"I": 8456, "II": 4538, "III": 3870, "IV": 51, "V": 101, "VI": 1380, "VII": 91, "VIII": 450, "IX": 26776}
"""The images of each experiment, the second paper's Table 1."""
PAPER_SECONDS = {
    "I": 17.83 / 0.16251,  # 17.83 m at 162.51 mm/s (its §4.2.1)
    "II": 19.27 / 0.29370,  # 19.27 m at 293.70 mm/s
    "III": 14.48 / 0.30166,  # 14.48 m at 301.66 mm/s (its §4.2.2)
    "VI": 3.18 / 0.12,  # 3.18 m at 0.12 m/s (its §4.2.3)
    "VIII": 180.0 / 19.96,  # 180 degrees at 19.96 degrees/s
    "IX": 80.21 / 0.6,  # 80.21 m (its Table 2) at about 0.6 m/s
}
"""How long each of the paper's continuous experiments lasted, from the distance and the speed it gives (seconds)."""


def rows(table: dict) -> list[dict]:
    """The rows (see the module) of ``reproduce_table2``'s ``{pipeline: [Table2Row]}``."""
    found = []
    for pipeline, measured in table.items():
        for row in measured:
            continuous = {f"continuous_{key}": value for key, value in vars(row.continuous).items()}
            found.append({
                "pipeline": pipeline, "experiment": row.experiment.number, **vars(row.paper), **continuous,
                "drift_percent_per_m": row.drift_percent_per_m, "frames": row.frames,
                "frames_per_second": round(row.frames_per_second, 1),
            })  # fmt: skip
    return [{key: None if isinstance(v, float) and math.isnan(v) else v for key, v in row.items()} for row in found]


def _paper_row(row: dict, prefix: str = "") -> PaperTable2:
    values = {f.name: row[prefix + f.name] for f in dataclasses.fields(PaperTable2)}
    return PaperTable2(**{key: math.nan if value is None else value for key, value in values.items()})


def _find(saved: list[dict], pipeline: str, number: str) -> dict | None:
    return next((row for row in saved if row["pipeline"] == pipeline and row["experiment"] == number), None)


def _steps(saved: list[dict], number: str) -> list[str]:
    """The pipelines ``saved`` ran on experiment ``number``, in the ablation's order."""
    return list(dict.fromkeys(row["pipeline"] for row in saved if row["experiment"] == number))


def _g(value: float, width: int = 0, significant: int = SIGNIFICANT) -> str:
    """``value`` to ``significant`` significant digits (1234.5 -> '1200', 0.0391 -> '0.039'), right-aligned."""
    return f"{float(f'{value:.{significant}g}'):>{width}g}"


def print_table2(saved: list[dict], pipelines=("as published", "shipped")) -> None:
    """Table 2 of each of ``pipelines`` over the experiments ``saved`` holds, in the paper's columns at its ground
    truth's samples, the suite's drift per metre beside, then the paper's own rows (as printed); III again against
    every frame. The runs' numbers to ``SIGNIFICANT`` digits, the distance (the truth's) to two decimals."""
    numbers = [e.number for e in EXPERIMENTS if _find(saved, pipelines[0], e.number)]
    for pipeline in pipelines:
        print(f"the pipeline {pipeline}")
        print(HEADER + f"{'drift[%/m]':>11}")
        for number in numbers:
            row = _find(saved, pipeline, number)
            drift = "-" if row["drift_percent_per_m"] is None else _g(row["drift_percent_per_m"])
            print(format_row(number, _paper_row(row), SIGNIFICANT) + f"{drift:>11}")
            if number == "III":
                print(format_row("  every frame", _paper_row(row, "continuous_"), SIGNIFICANT))
        print()
    print("the paper's rows")
    print(HEADER)
    for number in numbers:
        print(format_row(number, experiment(number).paper))


def print_ablation(saved: list[dict], numbers=ABLATED) -> None:
    """Each step from the paper's method to the shipped pipeline (one row each, the suite's changes added in turn)
    on each of the experiments ``numbers``: the final error (mm) and the heading RMSE (degrees, against every
    frame's truth) to ``SIGNIFICANT`` digits, then the paper's as printed (its heading RMSE where it printed one);
    experiments ``saved`` lacks are left out."""
    numbers = [number for number in numbers if _find(saved, "shipped", number)]
    steps = _steps(saved, numbers[0])
    print(f"{'':20}" + "".join(f"{number:>19}" for number in numbers))
    print(f"{'':20}" + f"{'final[mm]':>10}{'head.[°]':>9}" * len(numbers))
    for step in steps:
        cells = []
        for number in numbers:
            row = _find(saved, step, number)
            cells.append(_g(row["final_error_mm"], 10) + _g(row["continuous_heading_rmse_deg"], 9))
        print(f"{step:20}" + "".join(cells))
    paper = [experiment(number).paper for number in numbers]
    print(f"{'the paper':20}" + "".join(
        f"{p.final_error_mm:10.1f}" + (f"{'-':>9}" if math.isnan(p.heading_rmse_deg) else f"{p.heading_rmse_deg:9.2f}")
        for p in paper
    ))  # fmt: skip


def paper_percent(number: str) -> float:
    """The paper's final error of experiment ``number`` in % of its distance, from its own columns (100 e_N / distance,
    as the suite's rows are): its printed % is that only for IV."""
    paper = experiment(number).paper
    return paper.final_error_mm / paper.distance_m / 10.0


def draw_table2(saved: list[dict], pipelines=("as published", "shipped"), ax=None):
    """The final error (% of the distance, log scale) of each experiment ``saved`` holds, a bar for each of
    ``pipelines`` beside the paper's own (black: its millimetres over its metres, ``paper_percent``)."""
    numbers = [e.number for e in EXPERIMENTS if _find(saved, pipelines[0], e.number)]
    if ax is None:
        _, ax = plt.subplots(figsize=(11, 3.8))
    width = 0.8 / (len(pipelines) + 1)
    places = np.arange(len(numbers))
    for k, pipeline in enumerate(pipelines):
        values = [_find(saved, pipeline, number)["final_error_percent"] for number in numbers]
        ax.bar(places + (k - len(pipelines) / 2) * width, values, width, label=pipeline)
    paper = [paper_percent(number) for number in numbers]
    ax.bar(places + len(pipelines) / 2 * width, paper, width, color="k", label="the paper's Table 2 (e_N / distance)")
    ax.set_xticks(places, numbers)
    ax.set_yscale("log")
    ax.set_xlabel("experiment")
    ax.set_ylabel("final error [% of distance]")
    ax.legend(fontsize="small")
    return ax


def draw_ablation(saved: list[dict], numbers=ABLATED, ax=None):
    """The final error (% of the distance, log scale) of each step of the ablation, one line per experiment of
    ``numbers`` that ``saved`` holds, each with the paper's own final error (``paper_percent``) dotted in its
    colour."""
    numbers = [number for number in numbers if _find(saved, "shipped", number)]
    if ax is None:
        _, ax = plt.subplots(figsize=(11, 4.2))
    steps = _steps(saved, numbers[0])
    for number in numbers:
        values = [_find(saved, step, number)["final_error_percent"] for step in steps]
        (line,) = ax.plot(range(len(steps)), values, marker="o", label=number)
        ax.axhline(paper_percent(number), color=line.get_color(), ls=":", lw=1)
    ax.set_xticks(range(len(steps)), steps, rotation=20, ha="right")
    ax.set_yscale("log")
    ax.set_ylabel("final error [% of distance]")
    ax.set_title("from the paper's method to the shipped pipeline (dotted: the paper's own final errors)")
    ax.legend(title="experiment")
    return ax


HISTOGRAM_FATES = {  # which histogram dropped a match -> its colour
    "dropped by the orientation band": "tab:red",
    "dropped by the length band": "tab:orange",
    "kept by both bands": "tab:green",
}


def draw_histogram_decisions(image, matches, ax=None, scale: float = 5.0, centre_px=None) -> plt.Axes:
    """The histogram filter's decisions (the second paper's mu +- sigma bands) on the grey frame (H, W): each match
    vector of a ``gpo.motion.keypoints.FeatureMatches`` drawn from its start, ``scale`` times its length, coloured by
    ``HISTOGRAM_FATES``. ``centre_px`` (u, v), pixels: the centre of the frame pair's rotation, marked with a cross,
    or when outside the frame, an arrow from the frame's centre towards it. When the filter did not run, only the
    frame."""
    if ax is None:
        _, ax = plt.subplots(figsize=(7, 4.5))
    ax.imshow(image, cmap="gray", vmin=0, vmax=255)
    ax.set_xlim(-0.5, image.shape[1] - 0.5)  # the frame, whatever the vectors' reach
    ax.set_ylim(image.shape[0] - 0.5, -0.5)
    ax.set_axis_off()
    if matches.histogram is None:
        ax.set_title("the histogram filter did not run")
        return ax
    start, end = matches.matched
    orientation, length = matches.histogram
    by_length = length.kept if length is not None else np.zeros(len(start), bool)
    fates = {
        "dropped by the orientation band": ~orientation.kept,
        "dropped by the length band": orientation.kept & ~by_length,
        "kept by both bands": by_length,
    }
    for fate, chosen in fates.items():
        tips = start[chosen] + scale * (end[chosen] - start[chosen])
        lines = LineCollection(np.stack([start[chosen], tips], axis=1), colors=HISTOGRAM_FATES[fate], lw=1.2)
        lines.set_label(f"{chosen.sum()} {fate}")
        ax.add_collection(lines)
        ax.plot(*tips.T, ".", ms=3, color=HISTOGRAM_FATES[fate])
    if centre_px is not None:
        height, width = image.shape
        centre = np.asarray(centre_px, dtype=float)
        if 0 <= centre[0] < width and 0 <= centre[1] < height:
            ax.plot(*centre, "x", ms=12, mew=2.5, color="tab:blue", label="centre of rotation")
        else:
            middle = np.array([width / 2, height / 2])
            towards = (centre - middle) / np.linalg.norm(centre - middle) * 0.3 * min(width, height)
            ax.annotate(
                "", xy=middle + towards, xytext=middle, arrowprops={"arrowstyle": "->", "color": "tab:blue", "lw": 2}
            )
            away = np.hypot(*(centre - middle))
            ax.plot([], [], color="tab:blue", lw=2, label=f"towards the centre of rotation, {away:.0f} px away")
    ax.legend(loc="lower right", fontsize="small", framealpha=0.8)
    ax.set_title(f"the match vectors, {scale:g} times their length")
    return ax


def stage_errors(trajectory, truth) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The error of each pose of ``trajectory`` (a ``gpo.io.trajectory.Trajectory``, placed on ``truth`` at its first
    pose) along the truth's line from its start to its end, across it (left positive) and in heading, in mm, mm and
    degrees: where a straight run on a stage (IV, V, VI) goes wrong."""
    evaluation = evaluate(trajectory, truth, Alignment.ORIGIN)
    true_xy, estimated_xy = evaluation.truth.positions[:, :2], evaluation.estimate.positions[:, :2]
    direction = (true_xy[-1] - true_xy[0]) / np.hypot(*(true_xy[-1] - true_xy[0]))
    error = 1e3 * (estimated_xy - true_xy)
    return error @ direction, error @ np.array([-direction[1], direction[0]]), np.degrees(evaluation.heading_errors_rad)


def draw_stage_errors(trajectory, truth, axes=None) -> np.ndarray:
    """``stage_errors`` against the pose's number (a step of a stepped run): along and across the stage (mm) on the
    left, the heading (degrees) on the right."""
    if axes is None:
        _, axes = plt.subplots(1, 2, figsize=(12, 3.4))
    along, across, heading = stage_errors(trajectory, truth)
    steps = np.arange(len(along))
    axes[0].plot(steps, along, "o-", ms=3, label="along the stage")
    axes[0].plot(steps, across, "o-", ms=3, label="across it")
    axes[0].set_ylabel("error [mm]")
    axes[0].legend(fontsize="small")
    axes[1].plot(steps, heading, "o-", ms=3, color="tab:red")
    axes[1].set_ylabel("heading error [deg]")
    for ax in axes:
        ax.axhline(0, color="k", lw=0.6)
        ax.set_xlabel("step")
    return axes


def print_targets(saved: list[dict]) -> None:
    """The targets, each met or missed with its number: the shipped pipeline's final error on I-III and IX, its
    heading RMSE on I-II against the paper's, IV-VIII's final errors against the paper's; as published, I-III's
    final errors against the paper's and, where more than ``PAPER_GAP`` times it, the step of the ablation that
    divides the error by the most. The runs' numbers to ``SIGNIFICANT`` digits, the paper's as printed."""
    for number, target in TARGETS_PERCENT.items():
        row = _find(saved, "shipped", number)
        if row is not None:
            value = row["final_error_percent"]
            print(f"shipped {number:5} final error {_g(value)} % (target at most {target} %): {_met(value <= target)}")
    for number in ("I", "II"):
        row, paper = _find(saved, "shipped", number), experiment(number).paper
        if row is not None:
            value = row["heading_rmse_deg"]
            print(
                f"shipped {number:5} heading RMSE {_g(value)} deg (the paper: {paper.heading_rmse_deg} deg): "
                f"{_met(value < paper.heading_rmse_deg)}"
            )
    for number in ("IV", "V", "VI", "VII", "VIII"):
        row, paper = _find(saved, "shipped", number), experiment(number).paper
        if row is not None:
            value = row["final_error_mm"]
            print(
                f"shipped {number:5} final error {_g(value)} mm (the paper: {paper.final_error_mm} mm): "
                f"{_met(value <= paper.final_error_mm)}"
            )
    for number in ("I", "II", "III"):
        row, paper = _find(saved, "as published", number), experiment(number).paper
        if row is None:
            continue
        times = row["final_error_mm"] / paper.final_error_mm
        line = (
            f"as published {number:4} final error {_g(row['final_error_mm'])} mm, {_g(times)} times the paper's "
            f"{paper.final_error_mm} mm"
        )
        if times > PAPER_GAP:
            line += f"; the step that divides it most: {_largest_drop(saved, number)}"
        print(line)


def _met(met: bool) -> str:
    return "met" if met else "MISSED"


def _largest_drop(saved: list[dict], number: str) -> str:
    """The ablation's step that divides the experiment's final error by the most, with the error before and after."""
    steps = _steps(saved, number)
    chain = [_find(saved, step, number)["final_error_mm"] for step in steps]
    k = max(range(1, len(chain)), key=lambda i: chain[i - 1] / chain[i])
    return f"{steps[k]} ({_g(chain[k - 1])} -> {_g(chain[k])} mm, {_g(chain[k - 1] / chain[k])} times less)"


def print_report(saved: list[dict], numbers) -> None:
    """Table 2, the ablation over the experiments of ``numbers`` and the targets, as the chapter shows them."""
    print_table2(saved)
    print()
    print_ablation(saved, numbers)
    print()
    print_targets(saved)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("experiments", nargs="*", default=list(ABLATED), help="of I ... IX (default: I II III VIII IX)")
    args = parser.parse_args(argv)
    chosen = [experiment(number) for number in args.experiments]
    print_report(rows(reproduce_table2(ablation_configs(), chosen)), [e.number for e in chosen])


if __name__ == "__main__":  # `python -m gpo.book.lab_c_second_paper`: the runs made or read back, and printed
    main()
