"""Chapter 09, the population benchmark's results (``benchmarks/population.py``): its fisheye draws beside the same
worlds with their floors matte, and each method's distribution over two populations (the short paths first run, and
the papers' lengths) per floor kind and finish."""

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
    runs = [*result["runs"], *({"draw": draw, "method": PEER, **errors}
                               for draw, errors in result.get("peer", {}).get("runs", {}).items())]
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
        lines.append(f"{method:10s} {len(failing):3d} of {stats['runs']} runs over {limit} or not finished, "
                     f"{sum(not run['explained'] for run in failing)} of them without a named cause")
        for run in failing:
            steps = run.get("heading_steps")
            if not run["explained"] and steps is not None:
                kind = "a steady drift" if steps["steady"] else "a random walk"
                lines.append(f"{'':10s} {run['draw']} {run['final_error_percent']:.3f} %, against the truth: its "
                             f"heading's error {kind}, {steps['mean_deg']:+.3f} +- {steps['sd_deg']:.3f} deg a metre "
                             f"over {steps['steps']} metres (t {steps['t']:+.1f})")
    return "\n".join(lines)


def sources_text(result: dict) -> str:
    """The fused route beside its two sources, the floor odometry it fuses and the tracking camera alone, over a
    ``benchmarks/population.py --fused`` result: on how many draws it ends further off than the better of them, and
    the draws where it does by more than a hundredth of a per cent."""
    sources = result["sources"]
    floor = sources["floor_method"]
    runs = sources["runs"]
    lines = [f"fused worse than the better of {floor} and the camera alone on {sources['worse']} of "
             f"{sources['draws']} draws"]
    over = {label: np.inf if row["over_better"] is None else row["over_better"] for label, row in runs.items()}
    for label in sorted(over, key=lambda label: -over[label]):
        row = runs[label]
        if row["fused"] is None:
            lines.append(f"  {label}: fused did not finish")
        elif over[label] > 0.01:
            lines.append(f"  {label}: fused {row['fused']:.3f} %, {floor} {row[floor]:.3f} %, camera "
                         f"{row['camera']:.3f} % (x{row['ratio']:.2f} the better)")
    return "\n".join(lines)


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
    lines = [f"{'method':16s} {'population':16s} {'runs':>4s} {'median':>7s} {'p90':>7s} {'worst':>7s} | p90 on "
             + " ".join(f"{c:>10s}" for c in columns[1:])]
    grouped = {name: population_groups(result) for name, result in populations.items()}
    methods = list(dict.fromkeys(m for groups in grouped.values() for m in groups))
    for method in methods:
        target = f" ({TARGETS[method]})" if method in TARGETS else ""
        for name, groups in grouped.items():
            if method not in groups:
                continue
            errors = np.array(groups[method]["all"])
            cells = [_p90(groups[method].get(column)) for column in columns[1:]]
            lines.append(f"{method + target:16s} {name:16s} {len(errors):4d} {np.median(errors):7.3f} "
                         f"{_p90(errors)} {errors.max():7.2f} | p90 on " + " ".join(f"{c:>10s}" for c in cells))
    lines.append("final position error, % of the distance; p90 of each group (-: no draw); (target p90)")
    return "\n".join(lines)


def _p90(errors) -> str:
    return "      -" if errors is None or not len(errors) else f"{np.percentile(errors, 90):7.3f}"


def draw_population_distributions(populations: dict[str, dict], methods: tuple[str, ...]) -> plt.Figure:
    """One panel a method: each draw's final error (log scale) by floor kind and finish (circles matte, diamonds
    glossy), one column of points per population side by side, its median a bar, with the method's p90 target."""
    fig, axes = plt.subplots(1, len(methods), figsize=(5.5 * len(methods), 4), sharey=True, squeeze=False)
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    rng = np.random.default_rng(0)  # the points' sideways jitter
    groups = [(kind, shine) for kind in FLOOR_KINDS for shine in FINISHES]
    for ax, method in zip(axes[0], methods, strict=True):
        for p, (name, result) in enumerate(populations.items()):
            rows = [row for row in run_errors(result) if row[0] == method]
            for g, (kind, shine) in enumerate(groups):
                errors = [error for _, kinds, finish_, error in rows if kind in kinds and finish_ == shine]
                if not errors:
                    continue
                x = g + (p - (len(populations) - 1) / 2) * 0.3
                marker = "o" if shine == "matte" else "D"
                ax.scatter(x + rng.uniform(-0.06, 0.06, len(errors)), errors, s=14, color=colours[p], marker=marker,
                           label=name)
                ax.hlines(np.median(errors), x - 0.12, x + 0.12, color=colours[p], lw=2)
        if method in TARGETS:
            ax.axhline(TARGETS[method], color="k", ls="--", lw=1, label="p90 target")
        ax.set_yscale("log")
        ax.set_xticks(range(len(groups)), [f"{kind}\n{shine}" for kind, shine in groups], fontsize="small")
        ax.set_title(method)
    axes[0, 0].set_ylabel("final position error [% of distance]")
    handles, labels = axes[0, 0].get_legend_handles_labels()
    unique = dict(zip(labels, handles, strict=True))
    axes[0, 0].legend(unique.values(), unique.keys(), fontsize="small")
    fig.tight_layout()
    return fig
