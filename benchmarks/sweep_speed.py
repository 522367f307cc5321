"""A sweep on a local Dask cluster against the same runs one after another: speed-up, per-run overhead, same results.

    python benchmarks/sweep_speed.py [--preset test] [--workers N] [--repeats 5]
        [--write benchmarks/results/sweep_speed.json]

24 runs of one recording (``--preset``, rendered on first use and cached): the KLT window (15, 21, 31 px) x the
method (gpo, gpo-exact, gpo-rigid, fused) x the motion vector (median, mean). First one after another in this
process, each exactly as a worker makes it (``gpo.batch.runs.execute``), with OpenCV's own threads (as a loop in a
notebook runs them) and again on one thread (as each worker runs); then as one ``gpo.batch.sweep.sweep`` on a local
cluster of ``--workers`` processes (default one per core), into a new folder. The three are measured ``--repeats``
times, interleaved, on one cluster; the times printed are their medians. Printed: the wall times and the speed-up
(target at least 1.8 on 2 cores over the loop with OpenCV's threads, the cluster's start not counted; its start is
printed beside, and the speed-up over the loop on one thread), the bound on the speed-up (``speedup_bound``: the
workers' count times the threaded loop's share of the one-thread loop's time, what single-threaded workers could
reach with no cost at all, since the loop with OpenCV's threads already keeps every core busy part of the time), the
overhead per run (target under 5 % of a one-minute run) and whether every number of every run is the same both ways.
The overhead per run is the sweep's wall time times its workers, less the time the runs themselves took on the
workers (``run_seconds``), over the runs: scheduling, sending configs and results, hashing the recording, writing
each run's files and the table. On a machine shared with other work the load average before and after and whether
the kernel shares the CPU by session (autogroup) are printed so that the conditions are on record: under autogroup,
with other sessions busy, this benchmark and its workers share one session's part of the CPU and the speed-up cannot
show; measure it on an otherwise idle machine.
"""

import argparse
import itertools
import os
import tempfile
import time
from pathlib import Path

import cv2
import numpy as np

from gpo.batch.cluster import cluster_client
from gpo.batch.runs import Run, code_version, configured, execute, recording_digest, run_key
from gpo.batch.sweep import sweep
from gpo.io.outputs import write_json
from gpo.pipeline.config import config_to_dict
from gpo.sim.record import recording

GRID = {
    "klt.window_px": [15, 21, 31],
    "odometry.method": ["gpo", "gpo-exact", "gpo-rigid", "fused"],
    "odometry.vector": ["median", "mean"],
}
TIMINGS = ("seconds", "run_seconds", "frames_per_second")  # differ from one run to the next, the rest must not


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--preset", default="test", help="the recording (default: test, ~3 s)")
    parser.add_argument("--workers", type=int, default=os.cpu_count(), help="local workers (default: one per core)")
    parser.add_argument("--repeats", type=int, default=5, help="times each way is measured (default 5; medians)")
    parser.add_argument("--write", type=Path, help="JSON file for the results")
    args = parser.parse_args()
    bag = str(recording(args.preset))
    runs = [Run(bag, args.preset, overrides=dict(zip(GRID, v, strict=True))) for v in itertools.product(*GRID.values())]
    load_before = os.getloadavg()

    default_threads = cv2.getNumThreads()
    started = time.perf_counter()
    with cluster_client(workers=args.workers) as client:
        ready_s = time.perf_counter() - started
        times = {"sequential": [], "one_thread": [], "sweep": []}
        for _ in range(args.repeats):  # interleaved, so that a change in the machine's load touches all three
            elapsed, sequential = _one_after_another(runs, default_threads)
            times["sequential"].append(elapsed)
            times["one_thread"].append(_one_after_another(runs, 1)[0])
            cv2.setNumThreads(default_threads)
            with tempfile.TemporaryDirectory() as out:
                started = time.perf_counter()
                result = sweep(runs, out, client, progress=False)
                times["sweep"].append(time.perf_counter() - started)
    sequential_s, one_thread_s, sweep_s = (float(np.median(times[name])) for name in times)
    table = result.table.set_index("key")
    load_after = os.getloadavg()

    mismatched = [
        (key, column)
        for key, row in sequential.items()
        for column, value in row.items()
        if column not in TIMINGS and not _same(value, table.at[key, column] if column != "key" else key)
    ]
    overhead_s = (sweep_s * args.workers - table["run_seconds"].sum()) / len(runs)
    numbers = {
        "runs": len(runs),
        "preset": args.preset,
        "workers": args.workers,
        "cores": os.cpu_count(),
        "opencv_threads": default_threads,
        "repeats": args.repeats,
        "failed": int((table["status"] != "ok").sum()),
        "sequential_s": round(sequential_s, 2),
        "sweep_s": round(sweep_s, 2),
        "cluster_start_s": round(ready_s, 2),
        "speedup": round(sequential_s / sweep_s, 2),
        "speedup_with_cluster_start": round(sequential_s / (sweep_s + ready_s), 2),
        "sequential_one_thread_s": round(one_thread_s, 2),
        "speedup_over_one_thread": round(one_thread_s / sweep_s, 2),
        "speedup_bound": round(args.workers * sequential_s / one_thread_s, 2),
        "mean_run_s_sequential": round(float(np.mean([r["run_seconds"] for r in sequential.values()])), 3),
        "mean_run_s_on_workers": round(float(table["run_seconds"].mean()), 3),
        "overhead_per_run_s": round(overhead_s, 3),
        "overhead_percent_of_a_minute": round(100 * overhead_s / 60, 2),
        "identical_results": not mismatched,
        "speedups_each_repeat": [round(a / b, 2) for a, b in zip(times["sequential"], times["sweep"], strict=True)],
        "load_average_before": [round(v, 1) for v in load_before],
        "load_average_after": [round(v, 1) for v in load_after],
        "autogroup_scheduling": _autogroup(),
    }
    for name, value in numbers.items():
        print(f"{name:30s} {value}")
    verdict = "ok" if numbers["speedup"] >= 1.8 else "MISSED"
    print(f"speed-up {numbers['speedup']} (target >= 1.8 on 2 cores): {verdict}")
    print(f"overhead {numbers['overhead_percent_of_a_minute']} % of a one-minute run (target < 5 %): "
          f"{'ok' if numbers['overhead_percent_of_a_minute'] < 5 else 'MISSED'}")
    for key, column in mismatched[:10]:
        print(f"differs: run {key}, {column}: {sequential[key][column]!r} one after another, "
              f"{table.at[key, column]!r} in the sweep")
    if args.write:
        print(f"wrote {write_json(args.write, numbers)}")


def _one_after_another(runs: list[Run], threads: int) -> tuple[float, dict[str, dict]]:
    """The runs one after another in this process with OpenCV on ``threads`` threads, each exactly as a worker
    makes it (``gpo.batch.runs.execute``): the wall time, seconds, and each run's row by its key."""
    cv2.setNumThreads(threads)
    started = time.perf_counter()
    digest, version = recording_digest(runs[0].recording), code_version()
    rows = {}
    for run_ in runs:
        config = configured(run_)
        key = run_key(digest, config_to_dict(config), version)
        rows[key] = execute(run_, config, key).row | {"recording_sha256": digest}
    return time.perf_counter() - started, rows


def _autogroup() -> bool | None:
    """Whether Linux shares the CPU between sessions rather than processes (then a loaded machine gives this
    benchmark's processes together one session's share, and no parallel speed-up can show)."""
    flag = Path("/proc/sys/kernel/sched_autogroup_enabled")
    return flag.read_text().strip() == "1" if flag.exists() else None


def _same(one, other) -> bool:
    """Equal, NaN and None alike counting as missing."""
    missing = [v is None or (isinstance(v, float) and np.isnan(v)) for v in (one, other)]
    return all(missing) if any(missing) else one == other


if __name__ == "__main__":
    main()
