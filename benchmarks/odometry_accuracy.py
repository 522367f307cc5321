"""Accuracy of Ground Plane Odometry on the simulated recordings: final position and heading error per method.

    python benchmarks/odometry_accuracy.py [--presets long1 long2 long3] [--methods gpo gpo-exact gpo-rigid]
                                           [--write benchmarks/results/odometry_accuracy.json]

Each preset's recording is rendered on first use (the 12-17 m ``long`` paths take minutes each) and cached.
For every method ``gpo.pipeline.run`` with the shipped config gives a trajectory; ``gpo.metrics.final_error``
compares it with the recording's ground truth (the estimate's first pose placed on the truth's). The targets:
final position error at most 0.5 % of the distance for ``gpo``, 0.3 % for ``gpo-exact`` and ``gpo-rigid``.
``--write`` keeps the numbers as JSON, which chapter 06 prints.
"""

import argparse
import json
import math
from pathlib import Path

from gpo.bag import Recording
from gpo.metrics import final_error
from gpo.pipeline import METHODS, load_config, run
from gpo.sim.record import GROUND_TRUTH_TOPIC, PRESETS, recording

TARGET_PERCENT = {"gpo": 0.5, "gpo-exact": 0.3, "gpo-rigid": 0.3}


def measure(preset: str, method: str) -> dict:
    bag = recording(preset)
    with Recording(bag) as recorded:
        truth = recorded.trajectory(GROUND_TRUTH_TOPIC)
    result = run(bag, load_config().replace(method=method), progress=False)
    if result.error:
        raise RuntimeError(f"{preset}, {method}: the run stopped early {result.error}")
    error = final_error(result.trajectory, truth)
    summary = result.summary()
    return {
        "preset": preset,
        "method": method,
        "distance_m": round(error.distance_m, 3),
        "final_error_m": round(error.position_m, 4),
        "final_error_percent": round(error.percent, 3),
        "heading_error_deg": round(math.degrees(error.heading_rad), 3),
        "frames": summary["frames"],
        "frames_flagged": summary["frames"] - summary["frames_measured"] - 1,
        "frames_per_second": summary["frames_per_second"],
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--presets", nargs="+", default=["long1", "long2", "long3"], choices=sorted(PRESETS))
    parser.add_argument("--methods", nargs="+", default=list(METHODS), choices=METHODS)
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
            verdict = "ok" if row["final_error_percent"] <= target else "MISSED"
            print(f"{preset:8s} {method:10s} {row['distance_m']:8.2f}m {row['final_error_m'] * 1e3:10.1f}mm "
                  f"{row['final_error_percent']:7.3f} {target:6.1f}% {row['heading_error_deg']:+8.2f}° "
                  f"{row['frames_flagged']:8d}  {verdict}")
    if args.write:
        args.write.parent.mkdir(parents=True, exist_ok=True)
        args.write.write_text(json.dumps(rows, indent=1) + "\n")
        print(f"wrote {args.write}")


if __name__ == "__main__":
    main()
