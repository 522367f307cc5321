# long: one job, lab B's readings of the saved population results, section by section in the order the lab prints
# them (each a text and a figure)
"""Lab B, the population of drawn worlds: the results ``benchmarks/population.py`` saved (``benchmarks/results/``),
read and drawn, never run here (the papers' lengths take half an hour on two workers). The first population's fisheye
draws beside the same worlds with their floors matte; what was drawn; each method's distribution, with the
correlation peer's, over the populations per floor kind and finish; the targets met and missed; the runs the report
lists with the causes they name, and how their heading errors grew against the truth; the fused route beside its two
sources, per draw."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np

from gpo.sim.floors import FLOOR_KINDS

POPULATION_METHODS = ("gpo-exact", "gpo-rigid")  # the fisheye methods with a target in benchmarks/population.py


def population_errors(drawn: dict, matte: dict, methods=POPULATION_METHODS) -> dict[str, dict[str, tuple]]:
    """Per fisheye draw of two ``benchmarks/population.py`` results (the drawn floors, and ``--matte``: the same
    worlds with every floor matte): {draw: {method: (final error % on the drawn floor, on the matte one)}}, with
    ``"floor"``: the draw's floor kinds."""

    def by_run(result):
        return {(run["draw"], run["method"]): run["final_error_percent"] for run in result["runs"]}

    errors, matte_errors = by_run(drawn), by_run(matte)
    draws = sorted({name for name, method in errors if method == methods[0]})
    return {
        name: {"floor": drawn["draw_parameters"][name]["floor"]}
        | {method: (errors[name, method], matte_errors[name, method]) for method in methods}
        for name in draws
    }


def population_text(drawn: dict, matte: dict, methods=POPULATION_METHODS) -> str:
    """The fisheye draws' final errors on the drawn floors and matte, one line a draw, then each method's p90 and
    target as ``benchmarks/population.py`` reports them."""
    rows = population_errors(drawn, matte, methods)
    header = f"{'draw':17s} {'floor':18s}" + "".join(f"{method:>11s} {'matte':>7s}" for method in methods)
    lines = [header]
    for name, row in rows.items():
        lines.append(f"{name:17s} {row['floor']:18s}" + "".join(f"{row[m][0]:11.3f} {row[m][1]:7.3f}" for m in methods))
    p90 = "".join(f"{drawn['methods'][m]['p90']:11.3f} {matte['methods'][m]['p90']:7.3f}" for m in methods)
    lines.append(f"{'p90':36s}" + p90)
    targets = ", ".join(f"{m} {drawn['methods'][m]['p90_target']} %" for m in methods)
    lines.append(f"final position error, % of the distance; p90 targets: {targets}")
    return "\n".join(lines)


def draw_population(drawn: dict, matte: dict, methods=POPULATION_METHODS) -> plt.Figure:
    """One panel a method: each fisheye draw's final error on its drawn floor (filled, red where the floor holds glossy
    screed) and on the same floor matte (hollow), on a log scale, with the method's p90 target."""
    rows = population_errors(drawn, matte, methods)
    fig, axes = plt.subplots(1, len(methods), figsize=(6.5 * len(methods), 4), sharey=True, squeeze=False)
    positions = np.arange(len(rows))
    glossy = np.array(["industrial" in row["floor"] for row in rows.values()])
    for ax, method in zip(axes[0], methods, strict=True):
        on_drawn = np.array([row[method][0] for row in rows.values()])
        on_matte = np.array([row[method][1] for row in rows.values()])
        ax.vlines(positions, np.minimum(on_drawn, on_matte), np.maximum(on_drawn, on_matte), color="0.8", lw=1)
        ax.scatter(positions[glossy], on_drawn[glossy], color="tab:red", zorder=3, label="drawn floor, glossy screed")
        ax.scatter(positions[~glossy], on_drawn[~glossy], color="tab:blue", zorder=3, label="drawn floor, no screed")
        ax.scatter(positions, on_matte, facecolors="none", edgecolors="k", zorder=3, label="the same floor, matte")
        ax.axhline(drawn["methods"][method]["p90_target"], color="k", ls="--", lw=1, label="p90 target")
        ax.set_yscale("log")
        ax.set_xticks(positions, [name.removesuffix("-fisheye") for name in rows], rotation=60, fontsize="small")
        ax.set_title(method)
    axes[0, 0].set_ylabel("final position error [% of distance]")
    axes[0, 0].legend(fontsize="small")
    fig.tight_layout()
    return fig


FINISHES = ("matte", "glossy")
TARGETS = {"gpo-exact": 0.3, "gpo-rigid": 0.5, "features": 0.3, "fused": 0.3}  # the p90 targets, %


def finish(parameters: dict) -> str:
    """Whether a draw's floor was ``glossy`` (it mirrored the ceiling's lamps) or ``matte``, from its parameters as
    ``benchmarks/population.py`` writes them (the first population's name no sheen: its screed alone was glossy)."""
    sheen = parameters.get("sheen", "on" if "industrial" in parameters["floor"] else "off")
    return "glossy" if sheen == "on" else "matte"


PEER = "peer"  # the correlation odometer of benchmarks/correlation_peer.py, run with --peer


def run_errors(result: dict) -> list[tuple[str, tuple[str, ...], str, float]]:
    """A ``benchmarks/population.py`` result's runs as (method, the floor's kinds, its finish, final error %), the
    correlation peer's (``--peer``) as method ``PEER``; a run that failed counts as infinitely far."""
    runs = [
        *result["runs"],
        *({"draw": draw, "method": PEER, **errors} for draw, errors in result.get("peer", {}).get("runs", {}).items()),
    ]
    rows = []
    for run in runs:
        parameters = result["draw_parameters"][run["draw"]]
        kinds = tuple(kind for kind in FLOOR_KINDS if kind in parameters["floor"])
        error = np.inf if run["final_error_percent"] is None else run["final_error_percent"]
        rows.append((run["method"], kinds, finish(parameters), error))
    return rows


def failing_text(result: dict) -> str:
    """Per method, how many runs of a ``benchmarks/population.py`` result ended over the error it lists them from
    (the method's p90 target; ``gpo`` 1 %, ``fused`` 0.3 %) or did not finish, and how many of those carry no caution,
    flag or error that names a cause; of each of those, how its heading error grew against the truth (the report's
    ``heading_steps``: a steady drift or a random walk), where the report measured it."""
    lines = []
    for method, stats in result["methods"].items():
        failing = [run for run in result["failing"] if run["method"] == method]
        over = {run["over"] for run in failing} or {stats["p90_target"]}
        limit = "/".join(f"{value} %" for value in sorted(over) if value is not None) or "its limit"
        lines.append(
            f"{method:10s} {len(failing):3d} of {stats['runs']} runs over {limit} or not finished, "
            f"{sum(not run['explained'] for run in failing)} of them without a named cause"
        )
        for run in failing:
            steps = run.get("heading_steps")
            if not run["explained"] and steps is not None:
                kind = "a steady drift" if steps["steady"] else "a random walk"
                lines.append(
                    f"{'':10s} {run['draw']} {run['final_error_percent']:.3f} %, against the truth: its "
                    f"heading's error {kind}, {steps['mean_deg']:+.3f} +- {steps['sd_deg']:.3f} deg a metre "
                    f"over {steps['steps']} metres (t {steps['t']:+.1f})"
                )
    return "\n".join(lines)


LISTED_OVER_POINTS = 0.01  # sources_text lists a draw where the fused route ends more than this further off (points)


def sources_text(result: dict) -> str:
    """The fused route beside its two sources, the floor odometry it fuses and the tracking camera alone, over a
    ``benchmarks/population.py --fused`` result: on how many draws it ends further off than the better of them, and
    the draws where it does by more than ``LISTED_OVER_POINTS`` (points of % of the distance), said in the first line
    with their count."""
    sources = result["sources"]
    floor = sources["floor_method"]
    runs = sources["runs"]
    over = {label: np.inf if row["over_better"] is None else row["over_better"] for label, row in runs.items()}
    lines = []
    for label in sorted(over, key=lambda label: -over[label]):
        row = runs[label]
        if row["fused"] is None:
            lines.append(f"  {label}: fused did not finish")
        elif over[label] > LISTED_OVER_POINTS:
            lines.append(
                f"  {label}: fused {row['fused']:.3f} %, {floor} {row[floor]:.3f} %, camera "
                f"{row['camera']:.3f} % (x{row['ratio']:.2f} the better)"
            )
    head = (
        f"fused worse than the better of {floor} and the camera alone on {sources['worse']} of {sources['draws']} "
        f"draws; by more than {LISTED_OVER_POINTS} points on {len(lines)}:"
    )
    return "\n".join([head, *lines])


def population_groups(result: dict) -> dict[str, dict[str, list[float]]]:
    """A result's final errors (%) by method, then by group: ``all``, each floor kind (a draw whose floor mixes two
    counts under both) and each finish."""
    groups: dict[str, dict[str, list[float]]] = {}
    for method, kinds, shine, error in run_errors(result):
        for group in ("all", *kinds, shine):
            groups.setdefault(method, {}).setdefault(group, []).append(error)
    return groups


def distributions_text(populations: dict[str, dict]) -> str:
    """Each method's final errors over each population (name -> result): runs, median, p90 and worst over all its
    draws, then the p90 per floor kind and per finish; a method's target beside its name."""
    columns = ["all", *FLOOR_KINDS, *FINISHES]
    lines = [
        f"{'method':16s} {'population':16s} {'runs':>4s} {'median':>7s} {'p90':>7s} {'worst':>7s} | p90 on "
        + " ".join(f"{c:>10s}" for c in columns[1:])
    ]
    grouped = {name: population_groups(result) for name, result in populations.items()}
    methods = list(dict.fromkeys(m for groups in grouped.values() for m in groups))
    for method in methods:
        target = f" ({TARGETS[method]})" if method in TARGETS else ""
        for name, groups in grouped.items():
            if method not in groups:
                continue
            errors = np.array(groups[method]["all"])
            cells = [_p90(groups[method].get(column)) for column in columns[1:]]
            lines.append(
                f"{method + target:16s} {name:16s} {len(errors):4d} {np.median(errors):7.3f} "
                f"{_p90(errors)} {errors.max():7.2f} | p90 on " + " ".join(f"{c:>10s}" for c in cells)
            )
    lines.append("final position error, % of the distance; p90 of each group (-: no draw); (target p90)")
    return "\n".join(lines)


def _p90(errors) -> str:
    return "      -" if errors is None or not len(errors) else f"{np.percentile(errors, 90):7.3f}"


def draw_population_distributions(
    populations: dict[str, dict], methods: tuple[str, ...], columns: int = 3
) -> plt.Figure:
    """One panel a method, ``columns`` panels a row: each draw's final error (log scale) by floor kind and finish
    (circles matte, diamonds glossy), one column of points per population side by side, its median a bar, with the
    method's p90 target. Panels left over in the last row are hidden."""
    rows_of_panels = -(-len(methods) // columns)
    fig, axes = plt.subplots(
        rows_of_panels, columns, figsize=(5.2 * columns, 4 * rows_of_panels), sharey=True, squeeze=False
    )
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    rng = np.random.default_rng(0)  # the points' sideways jitter
    groups = [(kind, shine) for kind in FLOOR_KINDS for shine in FINISHES]
    for ax, method in zip(axes.flat, methods, strict=False):
        for p, (name, result) in enumerate(populations.items()):
            rows = [row for row in run_errors(result) if row[0] == method]
            for g, (kind, shine) in enumerate(groups):
                errors = [error for _, kinds, finish_, error in rows if kind in kinds and finish_ == shine]
                if not errors:
                    continue
                x = g + (p - (len(populations) - 1) / 2) * 0.3
                marker = "o" if shine == "matte" else "D"
                ax.scatter(
                    x + rng.uniform(-0.06, 0.06, len(errors)), errors, s=14, color=colours[p], marker=marker, label=name
                )
                ax.hlines(np.median(errors), x - 0.12, x + 0.12, color=colours[p], lw=2)
        if method in TARGETS:
            ax.axhline(TARGETS[method], color="k", ls="--", lw=1, label="p90 target")
        ax.set_yscale("log")
        ax.set_xticks(range(len(groups)), [f"{kind}\n{shine}" for kind, shine in groups], fontsize="small")
        ax.set_title(method)
        ax.grid(True, axis="y", alpha=0.3)
    for ax in axes.flat[len(methods) :]:
        ax.set_visible(False)
    for ax in axes[:, 0]:
        ax.set_ylabel("final position error [% of distance]")
    handles, labels = axes[0, 0].get_legend_handles_labels()
    unique = dict(zip(labels, handles, strict=True))
    axes[0, 0].legend(unique.values(), unique.keys(), fontsize="small")
    fig.tight_layout()
    return fig


RIGS = ("fisheye", "downward")  # a draw's label ends with its rig: draw000-fisheye, draw001-downward


def rig_of(label: str) -> str:
    """The rig of a draw from its label (``draw000-fisheye`` -> ``fisheye``)."""
    return label.rsplit("-", 1)[1]


def drawn_text(result: dict) -> str:
    """What a population drew, one line a rig: its draws, the glossy ones (and how many of those hold industrial
    screed), path lengths and camera heights."""
    lines = []
    for rig in RIGS:
        drawn = {label: p for label, p in result["draw_parameters"].items() if rig_of(label) == rig}
        if not drawn:
            continue
        lengths = [p["path_m"] for p in drawn.values()]
        heights = [100 * p["height_m"] for p in drawn.values()]
        glossy = [p for p in drawn.values() if finish(p) == "glossy"]
        screed = sum("industrial" in p["floor"] for p in glossy)
        lines.append(
            f"{rig:9s} {len(drawn):3d} draws, {len(glossy):2d} glossy ({screed} on industrial screed); paths "
            f"{min(lengths):4.1f}-{max(lengths):4.1f} m, camera {min(heights):4.1f}-{max(heights):4.1f} cm above the "
            "floor"
        )
    return "\n".join(lines)


def draw_drawn(result: dict) -> plt.Figure:
    """What a population drew, per rig: the draws by floor kind and finish (a draw whose floor mixes two kinds counts
    under both), the path lengths and the camera's height above the floor."""
    fig, (kinds, lengths, heights) = plt.subplots(1, 3, figsize=(15, 3.8))
    colours = {"fisheye": "tab:blue", "downward": "tab:orange"}
    width = 0.2
    for r, rig in enumerate(RIGS):
        drawn = [p for label, p in result["draw_parameters"].items() if rig_of(label) == rig]
        for f, shine in enumerate(FINISHES):
            counts = [sum(kind in p["floor"] and finish(p) == shine for p in drawn) for kind in FLOOR_KINDS]
            x = np.arange(len(FLOOR_KINDS)) + (2 * r + f - 1.5) * width
            kinds.bar(
                x, counts, width, color=colours[rig], alpha=1.0 if shine == "glossy" else 0.45, label=f"{rig}, {shine}"
            )
        lengths.hist([p["path_m"] for p in drawn], bins=np.arange(0, 22, 2), alpha=0.6, color=colours[rig], label=rig)
        heights.hist(
            [100 * p["height_m"] for p in drawn], bins=np.arange(0, 62, 4), alpha=0.6, color=colours[rig], label=rig
        )
    kinds.set_xticks(range(len(FLOOR_KINDS)), FLOOR_KINDS)
    kinds.set_ylabel("draws")
    kinds.set_title("floors drawn")
    kinds.legend(fontsize="small")
    lengths.set_xlabel("path length [m]")
    lengths.set_title("paths")
    heights.set_xlabel("camera above the floor [cm]")
    heights.set_title("heights")
    for ax in (lengths, heights):
        ax.set_ylabel("draws")
        ax.legend(fontsize="small")
    fig.tight_layout()
    return fig


def p90s(result: dict) -> dict[str, dict[str, float]]:
    """Each method's p90 of the final error (%) over all its draws, the matte ones and the glossy ones, as the report
    gives them, with its target (None for a method without one)."""
    return {
        method: {
            "all": stats["p90"],
            **{shine: stats["by_finish"][shine]["p90"] for shine in FINISHES},
            "target": stats["p90_target"],
        }
        for method, stats in result["methods"].items()
    }


def draw_p90s(result: dict, methods=("gpo-exact", "gpo-rigid", "fused", "features")) -> plt.Axes:
    """Each method's p90 over all its draws, the matte and the glossy ones (bars, log scale), its target a line."""
    found = p90s(result)
    _, ax = plt.subplots(figsize=(8, 3.8))
    width = 0.25
    for g, (group, alpha) in enumerate((("all", 1.0), ("matte", 0.45), ("glossy", 0.75))):
        x = np.arange(len(methods)) + (g - 1) * width
        ax.bar(
            x,
            [found[m][group] for m in methods],
            width,
            alpha=alpha,
            label=group,
            color={"all": "tab:gray", "matte": "tab:blue", "glossy": "tab:red"}[group],
        )
    for i, method in enumerate(methods):
        ax.hlines(
            found[method]["target"],
            i - 1.6 * width,
            i + 1.6 * width,
            color="k",
            lw=2,
            label="target" if i == 0 else None,
        )
    ax.set_yscale("log")
    ax.set_xticks(range(len(methods)), methods)
    ax.set_ylabel("p90 of the final error [% of distance]")
    ax.legend(fontsize="small")
    return ax


WORST_OVER_P90 = 3.0  # the population's target: a method's worst run within three times its p90


def targets_text(result: dict) -> str:
    """The population's targets, one line each with what was measured and whether it was met: each method's p90 and
    worst over p90, the fisheye methods ahead of the correlation peer on every group (``--peer``), the runs listed
    without a named cause, the fused route against its better source (``--fused``)."""
    lines = [f"{'target':44s} {'method':10s} {'measured':>10s}  "]
    for method, stats in result["methods"].items():
        if stats["p90_target"] is not None:
            p90 = stats["p90"]
            lines.append(
                f"{'p90 <= ' + str(stats['p90_target']) + ' %':44s} {method:10s} {p90:8.3f} %  "
                + ("met" if p90 <= stats["p90_target"] else "missed")
            )
    for method, stats in result["methods"].items():
        if stats["p90_target"] is not None:
            ratio = stats["worst"] / stats["p90"]
            lines.append(
                f"{'worst <= 3 x p90':44s} {method:10s} {ratio:8.2f} x  "
                + ("met" if ratio <= WORST_OVER_P90 else "missed")
            )
    for method, ahead in result.get("peer", {}).get("ahead_everywhere", {}).items():
        behind = [g for g, row in result["peer"]["groups"].items() if not (row[method] or np.inf) < row["peer"]]
        lines.append(
            f"{'ahead of the peer on every floor and finish':44s} {method:10s} {len(behind):4d} behind  "
            + ("met" if ahead else "missed: " + ", ".join(behind))
        )
    unexplained = [run for run in result["failing"] if not run["explained"]]
    over_one = [run for run in unexplained if run["final_error_percent"] is None or run["final_error_percent"] > 1.0]
    lines.append(
        f"{'no listed run over 1 % without a named cause':44s} {'all':10s} {len(over_one):4d} runs  "
        + ("met" if not over_one else "missed")
    )
    lines.append(
        f"{'every listed run names a cause':44s} {'all':10s} {len(unexplained):4d} runs  "
        + ("met" if not unexplained else "missed: " + ", ".join(r["draw"] for r in unexplained))
    )
    if "sources" in result:
        sources = result["sources"]
        lines.append(
            f"{'fused never worse than its better source':44s} {'fused':10s} {sources['worse']:4d} draws  "
            + ("met" if not sources["worse"] else f"missed on {sources['worse']} of {sources['draws']}")
        )
    return "\n".join(lines)


PEER_METHODS = ("gpo-exact", "gpo-rigid")  # the fisheye methods the report sets beside the correlation peer


def draw_peer_groups(result: dict) -> plt.Axes:
    """The correlation peer's median final error beside each fisheye method's on the same draws, per floor kind and
    finish (the report's ``peer.groups``), on a log scale."""
    groups = result["peer"]["groups"]
    names = list(groups)
    _, ax = plt.subplots(figsize=(10, 3.8))
    shown = (PEER, *PEER_METHODS)
    width = 0.8 / len(shown)
    for k, method in enumerate(shown):
        x = np.arange(len(names)) + (k - (len(shown) - 1) / 2) * width
        ax.bar(
            x,
            [groups[g][method] for g in names],
            width,
            label=method,
            color={"peer": "tab:gray", "gpo-exact": "tab:blue", "gpo-rigid": "tab:green"}[method],
        )
    ax.set_yscale("log")
    ax.set_xticks(range(len(names)), [f"{g}\n({groups[g]['draws']} draws)" for g in names], fontsize="small")
    ax.set_ylabel("median final error [% of distance]")
    ax.legend(fontsize="small")
    return ax


STEADY_T = 3.0  # benchmarks/population.py: a heading step's mean this many standard errors from zero is a drift
CAUSES = (
    "a leg outside the paper's model",
    "frames flagged and coasted",
    "steps on the whole view",
    "a slower layer of motion",
    "none named",
)


def cause_of(run: dict) -> str:
    """The first cause (of ``CAUSES``) a listed run of a ``benchmarks/population.py`` report names: a leg the
    paper's bicycle reads wrong (``gpo``), frames not measured, the caution of steps measured on the whole view, the
    caution of a slower layer of motion, or none."""
    cautions = " ".join(run["cautions"])
    if run.get("outside_paper_model"):
        return CAUSES[0]
    if run["frames_not_measured"] or run["flags"] or run["status"] != "ok":
        return CAUSES[1]
    if "whole view" in cautions:
        return CAUSES[2]
    if "slower layer" in cautions:
        return CAUSES[3]
    return CAUSES[4]


def causes_text(result: dict) -> str:
    """Per method, its listed runs by the first cause each names, and each run's draw, final error and finish."""
    lines = []
    for method in result["methods"]:
        listed = [run for run in result["failing"] if run["method"] == method]
        counts = {cause: sum(cause_of(run) == cause for run in listed) for cause in CAUSES}
        lines.append(
            f"{method:10s} {len(listed):3d} listed: " + ", ".join(f"{n} {cause}" for cause, n in counts.items() if n)
        )
    return "\n".join(lines)


def draw_listed(result: dict) -> plt.Figure:
    """The runs a report lists: per method, how many by the first cause each names (left); each run's heading-step
    ``t`` against the truth (its final heading error over one standard deviation of a random walk of its steps)
    against its final error (right), with |t| = 3 the line between a random walk and a steady drift."""
    fig, (left, right) = plt.subplots(1, 2, figsize=(14, 4.2), gridspec_kw={"width_ratios": [1, 1.3]})
    methods = list(result["methods"])
    bottom = np.zeros(len(methods))
    for cause, colour in zip(CAUSES, ("tab:purple", "tab:orange", "tab:red", "tab:pink", "k"), strict=True):
        counts = np.array(
            [sum(run["method"] == m and cause_of(run) == cause for run in result["failing"]) for m in methods]
        )
        left.bar(methods, counts, bottom=bottom, color=colour, label=cause)
        bottom += counts
    left.set_ylabel(f"runs listed (of {result['methods'][methods[0]]['runs']} each)")
    left.legend(fontsize="small")
    left.set_title("the cause each listed run names")
    markers = dict(zip(methods, "oDs^v", strict=False))
    for method in methods:
        listed = [run for run in result["failing"] if run["method"] == method and run.get("heading_steps")]
        right.scatter(
            [run["heading_steps"]["t"] for run in listed],
            [run["final_error_percent"] for run in listed],
            marker=markers[method],
            label=method,
            alpha=0.8,
        )
    for run in result["failing"]:
        if not run["explained"] and run.get("heading_steps"):
            right.annotate(
                f"{run['draw']}: no cause named",
                (run["heading_steps"]["t"], run["final_error_percent"]),
                xytext=(-10, 4),
                textcoords="offset points",
                ha="right",
                fontsize="small",
            )
    for t in (-STEADY_T, STEADY_T):
        right.axvline(t, color="k", ls="--", lw=1)
    right.set_yscale("log")
    right.set_xlabel("t of the heading error's metre steps (|t| >= 3: a steady drift)")
    right.set_ylabel("final error [% of distance]")
    right.legend(fontsize="small")
    right.set_title("random walk or steady drift, against the truth")
    fig.tight_layout()
    return fig


def draw_sources(result: dict) -> plt.Axes:
    """The fused route beside its two sources on each draw of a ``--fused`` report: the fused path's final error, the
    floor odometry's it fuses and the tracking camera's alone (log scale), the draws in order of the fused path's
    error over the better source's, glossy floors shaded."""
    sources = result["sources"]
    floor = sources["floor_method"]
    runs = sources["runs"]
    order = sorted(runs, key=lambda label: runs[label]["ratio"] if runs[label]["ratio"] is not None else np.inf)
    _, ax = plt.subplots(figsize=(14, 4.2))
    x = np.arange(len(order))
    for i, label in enumerate(order):
        if finish(result["draw_parameters"][label]) == "glossy":
            ax.axvspan(i - 0.5, i + 0.5, color="tab:red", alpha=0.08, lw=0)
    ax.scatter(x, [runs[label][floor] for label in order], marker="s", color="tab:blue", label=f"{floor} alone")
    ax.scatter(x, [runs[label]["camera"] for label in order], marker="^", color="tab:orange", label="camera alone")
    ax.scatter(
        x,
        [runs[label]["fused"] for label in order],
        marker="o",
        s=60,
        facecolors="none",
        edgecolors="k",
        linewidths=1.5,
        label="fused",
    )
    worse = sum(runs[label]["ratio"] is not None and runs[label]["ratio"] > 1 for label in order)
    ax.axvline(len(order) - worse - 0.5, color="k", ls=":", lw=1)
    ax.set_yscale("log")
    ax.set_xticks(x, [label.removeprefix("draw").removesuffix("-fisheye") for label in order], fontsize="small")
    ax.set_xlabel("draw, in order of fused / better source (right of the dotted line: fused worse; shaded: glossy)")
    ax.set_ylabel("final error [% of distance]")
    ax.legend(fontsize="small", loc="upper left")
    return ax


def sources_by_finish(result: dict) -> str:
    """Of a ``--fused`` report, per finish: on how many draws the fused route ends further off than the better of its
    sources, by how much at most (points of % of the distance) and which source was the better there."""
    sources = result["sources"]
    floor = sources["floor_method"]
    lines = []
    for shine in FINISHES:
        runs = {
            label: row for label, row in sources["runs"].items() if finish(result["draw_parameters"][label]) == shine
        }
        worse = {label: row for label, row in runs.items() if row["ratio"] is not None and row["ratio"] > 1}
        better = [floor if row[floor] <= row["camera"] else "camera" for row in worse.values()]
        most = max((row["over_better"] for row in worse.values()), default=0.0)
        lines.append(
            f"{shine:7s} fused worse on {len(worse):2d} of {len(runs):2d} draws, by at most {most:.3f} points; "
            f"the better source there: {floor} {better.count(floor)}, camera {better.count('camera')}"
        )
    return "\n".join(lines)


FEATURE_WAYS = ("per-frame detector", "keyframes + LK")  # benchmarks/features_population.py's two variants
FURTHER_OFF_POINTS = 0.05  # features_ways_text names each draw where the follower ends this much further off (points)


def features_ways_table(runs: list[dict]) -> dict[str, dict[str, tuple[float, float]]]:
    """Per downward draw of the ``runs`` of ``benchmarks/features_population.py`` results: {draw: {way: (final error
    %, heading RMSE deg)}} for each of ``FEATURE_WAYS``."""
    table: dict[str, dict[str, tuple[float, float]]] = {}
    for run in runs:
        table.setdefault(run["draw"], {})[run["variant"]] = (run["final_error_percent"], run["heading_rmse_deg"])
    return table


def features_ways_text(results: dict[str, list[dict]]) -> str:
    """Both ways of the feature odometer on each set of draws of ``results`` (label -> the runs of one or more
    ``benchmarks/features_population.py`` results): the runs, the final error (%) and the heading RMSE (degrees) as
    median, p90 (linear interpolation, as the benchmark's) and worst, and on how many draws the follower ends further
    off or its heading RMSE is larger, each draw where it ends more than ``FURTHER_OFF_POINTS`` further off named."""
    lines = [f"{'draws':20}{'way':20}{'runs':>5}{'final error [%]: median':>25}{'p90':>7}{'worst':>7}"
             f"{'heading RMSE [deg]: median':>28}{'p90':>7}{'worst':>7}"]
    tables = {label: features_ways_table(runs) for label, runs in results.items()}
    for label, table in tables.items():
        for way in FEATURE_WAYS:
            final, heading = (np.array([ways[way][k] for ways in table.values()]) for k in (0, 1))
            cells = [np.median(final), np.percentile(final, 90), final.max()]
            cells += [np.median(heading), np.percentile(heading, 90), heading.max()]
            lines.append(f"{label:20}{way:20}{len(table):5d}{cells[0]:25.3f}{cells[1]:7.3f}{cells[2]:7.2f}"
                         f"{cells[3]:28.3f}{cells[4]:7.3f}{cells[5]:7.2f}")
    for label, table in tables.items():
        worse = [sum(ways[FEATURE_WAYS[1]][k] > ways[FEATURE_WAYS[0]][k] for ways in table.values()) for k in (0, 1)]
        lines.append(f"{label}: the follower ends further off on {worse[0]} of {len(table)} draws, its heading RMSE is "
                     f"larger on {worse[1]}")
        for draw, ways in table.items():
            (followed, followed_heading), (detected, detected_heading) = ways[FEATURE_WAYS[1]], ways[FEATURE_WAYS[0]]
            if followed - detected > FURTHER_OFF_POINTS:
                lines.append(f"  {draw}: {followed:.3f} % against {detected:.3f} %, heading RMSE "
                             f"{followed_heading:.2f} against {detected_heading:.2f} deg")
    return "\n".join(lines)


def draw_features_ways(results: dict[str, list[dict]]) -> np.ndarray:
    """Per draw, the follower's final error and heading RMSE against the per-frame detector's (log-log, the diagonal
    where they are equal), one marker per set of draws of ``results`` (label -> the runs of features_population
    results)."""
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.6))
    units = ("final error [%]", "heading RMSE [deg]")
    for column, (ax, unit) in enumerate(zip(axes, units, strict=True)):
        values = []
        for (label, runs), marker in zip(results.items(), "os", strict=False):
            table = features_ways_table(runs)
            x = [ways[FEATURE_WAYS[0]][column] for ways in table.values()]
            y = [ways[FEATURE_WAYS[1]][column] for ways in table.values()]
            ax.scatter(x, y, marker=marker, label=label, alpha=0.8)
            values += x + y
        low, high = min(values) / 1.5, max(values) * 1.5
        ax.plot([low, high], [low, high], color="k", lw=0.7, label="equal")
        ax.set(xscale="log", yscale="log", xlim=(low, high), ylim=(low, high), aspect="equal",
               xlabel=f"detected in every frame: {unit}", ylabel=f"followed from keyframes: {unit}")
        ax.grid(True, which="both", alpha=0.3)
    axes[0].legend(fontsize="small")
    fig.tight_layout()
    return axes
