"""Accuracy of Ground Plane Odometry on the simulated recordings: final position and heading error per method.

    python benchmarks/odometry_accuracy.py [--presets long1 long2 long3] [--methods camera gpo ... fused]
                                           [--write benchmarks/results/odometry_accuracy.json]

Each preset's recording is rendered on first use (the 12-17 m ``long`` paths take minutes each) and cached.
For every method ``gpo.pipeline.run`` with the shipped config gives a trajectory (``camera``: the tracking camera's
own odometry in the bag, turned into base_link); ``gpo.metrics.final_error`` compares it with the recording's
ground truth (the estimate's first pose placed on the truth's). The targets: final position error at most 0.5 % of
the distance for ``gpo``, 0.3 % for ``gpo-exact``, ``gpo-rigid`` and ``fused``; none for the camera.
``--write`` keeps the numbers as JSON (``benchmarks/results/odometry_accuracy.json``).
"""

import argparse
import json
import math
from pathlib import Path

from gpo.bag import Recording
from gpo.metrics import final_error
from gpo.pipeline import METHODS, load_config, run, tracking_path
from gpo.sim.record import GROUND_TRUTH_TOPIC, PRESETS, recording

TARGET_PERCENT = {"camera": math.inf, "gpo": 0.5, "gpo-exact": 0.3, "gpo-rigid": 0.3, "fused": 0.3}
CHOICES = ("camera", *METHODS)


def measure(preset: str, method: str) -> dict:
    bag = recording(preset)
    flagged, speed = None, None
    with Recording(bag) as recorded:
        truth = recorded.trajectory(GROUND_TRUTH_TOPIC)
        if method == "camera":
            trajectory = tracking_path(recorded, load_config().fusion)
    if method != "camera":
        result = run(bag, load_config().replace(method=method), progress=False)
        if result.error:
            raise RuntimeError(f"{preset}, {method}: the run stopped early {result.error}")
        summary = result.summary()
        trajectory, speed = result.trajectory, summary["frames_per_second"]
        flagged = summary["frames"] - summary["frames_measured"] - 1
    error = final_error(trajectory, truth)
    return {
        "preset": preset,
        "method": method,
        "distance_m": round(error.distance_m, 3),
        "final_error_m": round(error.position_m, 4),
        "final_error_percent": round(error.percent, 3),
        "heading_error_deg": round(math.degrees(error.heading_rad), 3),
        "frames_flagged": flagged,
        "frames_per_second": speed,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--presets", nargs="+", default=["long1", "long2", "long3"], choices=sorted(PRESETS))
    parser.add_argument("--methods", nargs="+", default=list(CHOICES), choices=CHOICES)
    parser.add_argument("--write", type=Path, help="JSON file for the results")
    args = parser.parse_args()
    rows = []
    print(f"{'preset':8s} {'method':10s} {'distance':>9s} {'final error':>12s} {'%':>7s} {'target':>7s} "
          f"{'heading':>9s} {'flagged':>8s}")
    for preset in args.presets:
        for method in args.methods:
            row = measure(preset, method)
            rows.append(row)
            target = TARGET_PERCENT[method]
            verdict = "" if math.isinf(target) else "ok" if row["final_error_percent"] <= target else "MISSED"
            target_text = "-" if math.isinf(target) else f"{target:.1f}%"
            flagged = "-" if row["frames_flagged"] is None else row["frames_flagged"]
            print(f"{preset:8s} {method:10s} {row['distance_m']:8.2f}m {row['final_error_m'] * 1e3:10.1f}mm "
                  f"{row['final_error_percent']:7.3f} {target_text:>7} {row['heading_error_deg']:+8.2f}° "
                  f"{flagged:>8}  {verdict}")
    if args.write:
        args.write.parent.mkdir(parents=True, exist_ok=True)
        args.write.write_text(json.dumps(rows, indent=1) + "\n")
        print(f"wrote {args.write}")


if __name__ == "__main__":
    main()
