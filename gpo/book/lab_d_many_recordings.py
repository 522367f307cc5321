"""Lab D, many recordings on Dask: what a sweep keeps of each run, and the saved measurement of how fast a sweep runs
on a local cluster against the same runs one after another (``benchmarks/sweep_speed.py``, its JSON in
``benchmarks/results/sweep_speed.json``)."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

SPEEDUP_TARGET = 1.8  # benchmarks/sweep_speed.py: the sweep at least this much faster on 2 cores than the loop
OVERHEAD_TARGET_PERCENT = 5.0  # ... and its overhead per run under this share of a one-minute run


def kept_files(out) -> list[str]:
    """The files a sweep keeps in its folder ``out``, as paths relative to it, each run's key written ``KEY``: the
    table, and per run what ``gpo.batch.sweep`` writes (its trajectory, summary, config, row and seal)."""
    out = Path(out)
    keys = sorted(path.name for path in (out / "runs").iterdir() if path.is_dir())
    names = set()
    for path in out.rglob("*"):
        if path.is_file():
            name = str(path.relative_to(out))
            for key in keys:
                name = name.replace(key, "KEY")
            names.add(name)
    return sorted(names)


def speed_text(result: dict) -> str:
    """The saved sweep-speed measurement in a few lines: the runs, the wall times (medians of the repeats), the
    speed-up as the ratio of the medians against its target and as each repeat's (with their median), the estimated
    bound on it and how it is made, the overhead per run against its target and against one of the runs measured,
    and whether both ways gave the same numbers."""
    overhead = result["overhead_percent_of_a_minute"]
    repeats = result["speedups_each_repeat"]
    lines = [
        f"{result['runs']} runs of the {result['preset']} recording, {result['repeats']} repeats (medians), "
        f"{result['workers']} workers on {result['cores']} cores",
        f"one after another, OpenCV's threads {result['sequential_s']:6.2f} s",
        f"one after another, one thread       {result['sequential_one_thread_s']:6.2f} s",
        f"as a sweep on the cluster           {result['sweep_s']:6.2f} s   (starting the cluster: "
        f"{result['cluster_start_s']:.2f} s more)",
        f"speed-up {result['speedup']:.2f} = {result['sequential_s']:.2f} s / {result['sweep_s']:.2f} s, the ratio "
        f"of the medians (target {SPEEDUP_TARGET}: {'met' if result['speedup'] >= SPEEDUP_TARGET else 'missed'}); "
        f"over one thread {result['speedup_over_one_thread']:.2f}",
        "speed-up of each repeat: " + " ".join(f"{value:.2f}" for value in repeats) + f" (their median "
        f"{np.median(repeats):.2f})",
        f"estimated bound {result['speedup_bound']:.2f} = {result['workers']} workers x "
        f"{result['sequential_s']:.2f} s / {result['sequential_one_thread_s']:.2f} s (the loop with threads over the "
        "loop on one thread)",
        f"overhead per run {result['overhead_per_run_s']:.3f} s, {overhead:.2f} % of a one-minute run (target under "
        f"{OVERHEAD_TARGET_PERCENT:g} %: {'met' if overhead < OVERHEAD_TARGET_PERCENT else 'missed'}), "
        f"{100 * result['overhead_per_run_s'] / result['mean_run_s_on_workers']:.0f} % of one of these runs "
        f"({result['mean_run_s_on_workers']:.3f} s on a worker)",
        f"every number of every run the same both ways: {result['identical_results']}",
    ]
    return "\n".join(lines)


def draw_sweep_speed(result: dict) -> plt.Figure:
    """The saved measurement: the wall times of the runs one after another (with OpenCV's threads and on one) and as
    a sweep (the cluster's start stacked on it), left; each repeat's speed-up with the ratio of the medians, the
    estimated bound and the target, right."""
    fig, (times, speedups) = plt.subplots(1, 2, figsize=(12, 3.6), gridspec_kw={"width_ratios": [1.2, 1]})
    labels = ["loop, OpenCV's threads", "loop, one thread", "sweep"]
    values = [result["sequential_s"], result["sequential_one_thread_s"], result["sweep_s"]]
    times.barh(labels, values, color=["tab:gray", "tab:gray", "tab:blue"])
    times.barh(
        ["sweep"],
        [result["cluster_start_s"]],
        left=[result["sweep_s"]],
        color="tab:blue",
        alpha=0.35,
        label="starting the cluster",
    )
    times.invert_yaxis()
    times.set_xlabel(f"wall time of {result['runs']} runs, median of the repeats [s]")
    times.legend(fontsize="small", loc="lower right")
    repeats = np.arange(1, len(result["speedups_each_repeat"]) + 1)
    speedups.plot(repeats, result["speedups_each_repeat"], "o-", color="tab:blue", label="speed-up, each repeat")
    speedups.axhline(result["speedup"], color="tab:blue", lw=1, alpha=0.6, label="ratio of the median times")
    speedups.axhline(result["speedup_bound"], color="k", ls=":", label="estimated bound (from the medians)")
    speedups.axhline(SPEEDUP_TARGET, color="tab:red", ls="--", label="target")
    speedups.axhline(1.0, color="0.6", lw=1)
    speedups.set_xticks(repeats)
    speedups.set_xlabel("repeat")
    speedups.set_ylabel("loop (OpenCV's threads) / sweep")
    speedups.set_ylim(0.8, 2.0)
    speedups.legend(fontsize="small", loc="lower right")
    fig.tight_layout()
    return fig
