"""The floor feature odometer (the second paper's) on the downward camera: accuracy and speed per configuration.

    python benchmarks/features_odometry.py [--presets downward-long downward-wood ...] [--threads 1]
                                           [--write benchmarks/results/features_odometry.json]

Each preset's recording is rendered on first use and cached. For each configuration the shipped config
(``gpo/configs/sim_downward.yaml``: SIFT on the image scaled by 0.5, a 480 x 320 region of interest, 300 keypoints,
both filters, the refit) is run by ``gpo.pipeline.run`` with only the named fields changed, and compared with the
ground truth (``gpo.metrics``: final position error after placing the first pose on the truth's, heading RMSE).
``--threads`` sets OpenCV's threads (1: one core, the speed target's terms); the rate is the whole run's, reading
the bag included. Targets: on the high-texture ``downward-long`` (16.5 m) a final error at most 0.2 % of the
distance and a heading RMSE at most 1.4 degrees; the default configuration at least 35 frames per second.
"""

import argparse
import dataclasses
import math
from pathlib import Path

import cv2

from gpo.bag import Recording
from gpo.metrics import evaluate, final_error
from gpo.outputs import write_json
from gpo.pipeline import load_config, run
from gpo.sim.record import GROUND_TRUTH_TOPIC, recording

CONFIG = Path(__file__).resolve().parents[1] / "gpo" / "configs" / "sim_downward.yaml"
VARIANTS = {  # name -> the fields of FeatureParameters that differ from the shipped config's
    "default": {},
    "paper's fit (no refit)": {"refit_px": 0.0},
    "SIFT full image": {"scale": 1.0, "roi": None},
    "SIFT scale 0.5, no roi": {"roi": None},
    "ORB full image": {"detector": "orb", "scale": 1.0, "roi": None, "max_features": 500},
    "ORB, paper's fit": {"detector": "orb", "scale": 1.0, "roi": None, "max_features": 500, "refit_px": 0.0},
}
TARGETS = {"final_error_percent": 0.2, "heading_rmse_deg": 1.4, "frames_per_second": 35.0}


def measure(preset: str, variant: str) -> dict:
    bag = recording(preset)
    base = load_config(CONFIG)
    config = base.replace(features=dataclasses.replace(base.features, **VARIANTS[variant]))
    with Recording(bag) as recorded:
        truth = recorded.trajectory(GROUND_TRUTH_TOPIC)
    result = run(bag, config, progress=False)
    if result.error:
        raise RuntimeError(f"{preset}, {variant}: the run stopped early {result.error}")
    summary = result.summary()
    error = final_error(result.trajectory, truth)
    return {
        "preset": preset,
        "variant": variant,
        "distance_m": round(error.distance_m, 3),
        "final_error_mm": round(error.position_m * 1e3, 1),
        "final_error_percent": round(error.percent, 3),
        "heading_rmse_deg": round(evaluate(result.trajectory, truth).heading_rmse_deg, 3),
        "final_heading_deg": round(math.degrees(error.heading_rad), 3),
        "frames_flagged": summary["frames"] - summary["frames_measured"] - 1,
        "flags": summary["flags"],
        "frames_per_second": summary["frames_per_second"],
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--presets", nargs="+", default=["downward-long", "downward-wood", "downward-raised"])
    parser.add_argument("--variants", nargs="+", default=list(VARIANTS), choices=list(VARIANTS))
    parser.add_argument("--threads", type=int, default=1, help="OpenCV threads (default 1: one core)")
    parser.add_argument("--write", type=Path, help="JSON file for the results")
    args = parser.parse_args()
    cv2.setNumThreads(args.threads)
    rows = []
    print(f"{'preset':16s} {'configuration':24s} {'distance':>9s} {'final error':>12s} {'%':>7s} {'heading rmse':>13s}"
          f" {'flagged':>8s} {'frames/s':>9s}")
    for preset in args.presets:
        for variant in args.variants:
            row = measure(preset, variant)
            rows.append(row)
            print(f"{preset:16s} {variant:24s} {row['distance_m']:8.2f}m {row['final_error_mm']:10.1f}mm "
                  f"{row['final_error_percent']:7.3f} {row['heading_rmse_deg']:11.3f}° {row['frames_flagged']:8d} "
                  f"{row['frames_per_second']:9.1f}")
    print("targets (downward-long, default):", ", ".join(f"{k} {v}" for k, v in TARGETS.items()))
    if args.write:
        print(f"wrote {write_json(args.write, rows)}")


if __name__ == "__main__":
    main()
