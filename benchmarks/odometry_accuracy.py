"""Accuracy of Ground Plane Odometry on the simulated recordings: final position and heading error per method.

    python benchmarks/odometry_accuracy.py [--presets long1 long2 long3] [--methods camera gpo ... fused]
                                           [--out DIR] [--scheduler tcp://HOST:PORT] [--workers N]
                                           [--write benchmarks/results/odometry_accuracy.json]

Each preset's recording is rendered on first use (the 12-17 m ``long`` paths take minutes each) and cached; the
presets not yet cached are rendered at once on the cluster (``gpo.sim.population.render``). Every method but
``camera`` is one run of a sweep (``gpo.batch``: the shipped config with ``odometry.method`` set, on a local Dask
cluster or the one at ``--scheduler``), whose table keeps the final error after placing the estimate's first pose
on the truth's (``gpo.metrics``); with ``--out`` the sweep's folder is kept and a second call reuses its runs.
``camera`` is the tracking camera's own odometry in the bag, turned into base_link (no run). The targets: final
position error at most 0.5 % of the distance for ``gpo``, 0.3 % for ``gpo-exact``, ``gpo-rigid`` and ``fused``;
none for the camera. ``--write`` keeps the numbers as JSON (``benchmarks/results/odometry_accuracy.json``).
"""

import argparse
import math
import tempfile
from pathlib import Path

from gpo.batch.cluster import add_cluster_arguments, cluster_client
from gpo.batch.runs import Run
from gpo.batch.sweep import sweep
from gpo.io.bag import Recording
from gpo.io.outputs import write_json
from gpo.metrics import final_error
from gpo.pipeline.config import load_config, methods
from gpo.pipeline.run import tracking_path
from gpo.sim.population import render
from gpo.sim.record import GROUND_TRUTH_TOPIC, PRESETS

TARGET_PERCENT = {"camera": math.inf, "gpo": 0.5, "gpo-exact": 0.3, "gpo-rigid": 0.3, "fused": 0.3}
CHOICES = ("camera", *methods())


def camera_row(preset: str, bag: Path) -> dict:
    """The tracking camera's own odometry against the truth."""
    with Recording(bag) as recorded:
        truth = recorded.trajectory(GROUND_TRUTH_TOPIC)
        trajectory = tracking_path(recorded, load_config().fusion)
    error = final_error(trajectory, truth)
    return {
        "preset": preset,
        "method": "camera",
        "distance_m": round(error.distance_m, 3),
        "final_error_m": round(error.position_m, 4),
        "final_error_percent": round(error.percent, 3),
        "heading_error_deg": round(math.degrees(error.heading_rad), 3),
        "frames_flagged": None,
        "frames_per_second": None,
    }


def run_row(preset: str, row) -> dict:
    """A sweep's row in this benchmark's terms; a run that failed or stopped early is an error of the benchmark."""
    if row["status"] != "ok":
        raise RuntimeError(f"{preset}, {row['param.odometry.method']}: {row['status']}: {row['error']}")
    return {
        "preset": preset,
        "method": row["param.odometry.method"],
        "distance_m": round(row["distance_m"], 3),
        "final_error_m": round(row["final_error_m"], 4),
        "final_error_percent": round(row["final_error_percent"], 3),
        "heading_error_deg": round(row["final_heading_deg"], 3),
        "frames_flagged": int(row["frames"] - row["frames_measured"] - 1),
        "frames_per_second": round(row["frames_per_second"], 1),
    }


def measure(presets: list[str], methods: list[str], out: Path, scheduler: str | None, workers: int | None) -> list:
    """Every (preset, method) row, in that order."""
    with cluster_client(scheduler, workers) as client:
        bags = {name: path for (name, _), path in render(client, [(name, None) for name in presets]).items()}
        runs = [
            Run(str(bags[name]), name, overrides={"odometry.method": method})
            for name in presets
            for method in methods
            if method != "camera"
        ]
        table = sweep(runs, out, client).table
    found = {(row["recording"], row["param.odometry.method"]): row for _, row in table.iterrows()}
    return [
        camera_row(name, bags[name]) if method == "camera" else run_row(name, found[(name, method)])
        for name in presets
        for method in methods
    ]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--presets", nargs="+", default=["long1", "long2", "long3"], choices=sorted(PRESETS))
    parser.add_argument("--methods", nargs="+", default=list(TARGET_PERCENT), choices=CHOICES)
    parser.add_argument("--out", type=Path, help="the sweep's folder, kept (default: a temporary one)")
    add_cluster_arguments(parser)
    parser.add_argument("--write", type=Path, help="JSON file for the results")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as temporary:
        rows = measure(args.presets, args.methods, args.out or Path(temporary), args.scheduler, args.workers)
    print(f"{'preset':8s} {'method':10s} {'distance':>9s} {'final error':>12s} {'%':>7s} {'target':>7s} "
          f"{'heading':>9s} {'flagged':>8s}")
    for row in rows:
        target = TARGET_PERCENT.get(row["method"], math.inf)
        verdict = "" if math.isinf(target) else "ok" if row["final_error_percent"] <= target else "MISSED"
        target_text = "-" if math.isinf(target) else f"{target:.1f}%"
        flagged = "-" if row["frames_flagged"] is None else row["frames_flagged"]
        print(f"{row['preset']:8s} {row['method']:10s} {row['distance_m']:8.2f}m {row['final_error_m'] * 1e3:10.1f}mm "
              f"{row['final_error_percent']:7.3f} {target_text:>7} {row['heading_error_deg']:+8.2f}° "
              f"{flagged:>8}  {verdict}")
    if args.write:
        print(f"wrote {write_json(args.write, rows)}")


if __name__ == "__main__":
    main()
