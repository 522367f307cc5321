"""Zero config against a hand-written one, on a rig the shipped configs do not describe.

    python benchmarks/zero_config.py [--rig t265-high] [--paths sample long1]
                                     [--write benchmarks/results/zero_config.json]

The rig (``gpo.sim.realsense.RIGS["t265-high"]``): a T265-like camera 0.18 m high, pitched 10 degrees down, rolled
-1 and turned 1 degree, 0.45 m ahead of the rear axle, with a lens of its own; rendered along each path into a
realsense-ros shaped bag (first use renders it: about a minute for ``long1``). Two runs of ``gpo-exact`` each:

- zero config: ``python -m gpo config BAG`` then ``python -m gpo run BAG --config`` that file (the same config ``gpo
  run BAG`` uses with none);
- by hand: what a person writes from the shipped ``sim_t265.yaml``: the lens and the mount copied from the rig's
  data sheet (here its truth), the shipped region moved with the camera (0.1 to 0.3 m ahead of it, 0.2 m wide
  about its line), 1 mm floor pixels, the lever at the region's centre.

The target: the zero config's final position error at most 1.5 times the hand-written one's (a ratio over 1.5 on
a path where both errors are below ``FLOOR_MM`` is below what the simulation can tell apart, and is reported so).
"""

import argparse
import json
import tempfile
from pathlib import Path

import numpy as np
import yaml

from gpo.cameras.files import camera_to_kalibr
from gpo.cli import main
from gpo.io.bag import Recording
from gpo.io.trajectory import Trajectory
from gpo.metrics import final_error
from gpo.pipeline.config import DEFAULT_CONFIG, config_to_dict, load_config
from gpo.sim.realsense import RIGS, realsense_recording
from gpo.sim.record import GROUND_TRUTH_TOPIC

TARGET_RATIO = 1.5
FLOOR_MM = 0.5  # final errors below this are within the simulated floor's own noise over these paths


def hand_written(rig_name: str, folder: Path) -> Path:
    """The config a person writes for ``rig_name`` from the shipped one (see the module docstring)."""
    rig = RIGS[rig_name].rig()
    document = config_to_dict(load_config())
    x, y, _ = (float(v) for v in rig.mount.position)
    document.update(
        name=f"{rig_name}-by-hand",
        camera=camera_to_kalibr(rig.camera, rig_name),
        mount={"position_m": [x, y, rig.mount.height], "rpy_deg": np.degrees(rig.mount.body_rpy).tolist()},
    )
    document["floor_image"] = {"x_range_m": [x + 0.1, x + 0.3], "y_range_m": [y - 0.1, y + 0.1]}
    document["floor_image"]["metres_per_pixel"] = 1e-3
    document["kinematics"] = {"wheelbase_m": x + 0.2, "rear_to_reference_m": x + 0.2}
    path = folder / "by_hand.yaml"
    path.write_text(yaml.safe_dump(document, sort_keys=False))
    return path


def final_mm(bag: Path, config: Path, folder: Path) -> tuple[float, float]:
    """The run's final position error (mm) and the distance (m), ``gpo-exact``."""
    out = folder / f"{config.stem}.tum"
    code = main(["run", str(bag), "--config", str(config), "--method", "gpo-exact", "--out", str(out), "--force"])
    if code != 0:
        raise SystemExit(f"gpo run {bag} --config {config} failed ({code})")
    with Recording(bag) as recording:
        truth = recording.trajectory(GROUND_TRUTH_TOPIC)
    error = final_error(Trajectory.read_tum(out), truth)
    return 1e3 * error.position_m, error.distance_m


def main_benchmark() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rig", default="t265-high", choices=sorted(RIGS))
    parser.add_argument("--paths", nargs="+", default=["sample", "long1"])
    parser.add_argument("--write", type=Path, help="JSON file for the numbers")
    args = parser.parse_args()
    rows = []
    for path in args.paths:
        bag = realsense_recording(args.rig, path)
        with tempfile.TemporaryDirectory() as scratch:
            folder = Path(scratch)
            proposed = folder / "zero_config.yaml"
            if main(["config", str(bag), "--out", str(proposed)]) != 0:
                raise SystemExit(f"gpo config {bag} failed")
            zero_mm, distance = final_mm(bag, proposed, folder)
            hand_mm, _ = final_mm(bag, hand_written(args.rig, folder), folder)
        ratio = zero_mm / hand_mm
        met = ratio <= TARGET_RATIO or max(zero_mm, hand_mm) < FLOOR_MM
        rows.append(
            {
                "path": path,
                "distance_m": round(distance, 3),
                "zero_config_mm": round(zero_mm, 2),
                "by_hand_mm": round(hand_mm, 2),
                "ratio": round(ratio, 3),
                "target_met": bool(met),
            }
        )
    print(f"\nrig {args.rig}, gpo-exact, final position error (target: zero config <= {TARGET_RATIO} x by hand)")
    print(f"{'path':<8} {'distance':>9} {'zero config':>12} {'by hand':>9} {'ratio':>6}")
    for row in rows:
        errors = f"{row['zero_config_mm']:>9.2f} mm {row['by_hand_mm']:>6.2f} mm {row['ratio']:>6.2f}"
        missed = "" if row["target_met"] else "  (target missed)"
        print(f"{row['path']:<8} {row['distance_m']:>7.2f} m {errors}{missed}")
    if args.write:
        numbers = {"rig": args.rig, "method": "gpo-exact", "base_config": DEFAULT_CONFIG, "rows": rows}
        args.write.write_text(json.dumps(numbers, indent=1) + "\n")
        print(f"wrote {args.write}")


if __name__ == "__main__":
    main_benchmark()
