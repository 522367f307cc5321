"""The floor feature odometer (the second paper's) on the downward camera: accuracy and speed per configuration.

    python benchmarks/features_odometry.py [--presets downward-long downward-wood ...] [--variants ...]
                                           [--out DIR] [--scheduler tcp://HOST:PORT] [--workers N]
                                           [--write benchmarks/results/features_odometry.json]

Each preset's recording is rendered on first use (on the cluster, ``gpo.sim.population.render``) and cached. Each
(preset, configuration) is one run of a sweep (``gpo.batch``, on a local Dask cluster or the one at ``--scheduler``;
locally one worker by default): the shipped config (``gpo/configs/sim_downward.yaml``: SIFT on the image scaled by
0.5, a 480 x 320 region of interest, 200 keypoints detected on keyframes and followed by Lucas-Kanade between them,
both filters, the refit) with only the named ``features`` fields changed, compared with the ground truth
(``gpo.metrics``: final position error after placing the first pose on the truth's, heading RMSE); ``per-frame
detector`` and ``keyframes + LK`` name both ways of finding the keyframe's keypoints in later frames
(``features.follow``: detected and described in every frame and matched, or followed by Lucas-Kanade from keyframes)
whichever the config ships (that one is the ``default`` run); the detector's and the fit's variants (``paper's
fit``, ``SIFT ...``, ``ORB ...``) change the per-frame detector, where the detector's cost is every frame's. With
``--out`` the sweep's folder is kept and a second call reuses its runs. Every
worker runs OpenCV on one thread (one core, the speed target's terms); the rate is the whole odometry's, reading the
bag included, in wall-clock time (on a machine shared with other work ``benchmarks/odometry_speed.py`` gives the
process's CPU time too). Two workers finish the runs sooner, but two processes share the cores' caches and the
memory's bandwidth and each then reads a few per cent fewer frames per second than one alone: the one worker keeps
the rate one core's. Targets: on the high-texture ``downward-long`` (16.5 m) a final error at most 0.2 % of the
distance and a heading RMSE at most 1.4 degrees; the default configuration at least 35 frames per second.
"""

import argparse
import json
import tempfile
from pathlib import Path

from gpo.batch.cluster import add_cluster_arguments, cluster_client
from gpo.batch.runs import Run
from gpo.batch.sweep import sweep
from gpo.io.outputs import write_json
from gpo.pipeline.config import load_config
from gpo.sim.population import render

CONFIG = Path(__file__).resolve().parents[1] / "gpo" / "configs" / "sim_downward.yaml"
ORB_FULL_IMAGE = {"detector": "orb", "scale": 1.0, "roi": None, "max_features": 500}
PER_FRAME = {"follow": "match", "max_features": 300}  # SIFT in every frame, matched with a keyframe's (the paper's way)
VARIANTS = {  # name -> the fields of the config's features section that differ from the shipped config's
    "default": {},
    "per-frame detector": PER_FRAME,
    "keyframes + LK": {"follow": "lk", "max_features": 200},  # SIFT on keyframes, followed between them by LK
    # the detector's and the fit's settings, on the per-frame detector, where the detector runs in every frame
    "paper's fit (no refit)": PER_FRAME | {"refit_px": 0.0},
    "SIFT full image": PER_FRAME | {"scale": 1.0, "roi": None},
    "SIFT scale 0.5, no roi": PER_FRAME | {"roi": None},
    "ORB full image": PER_FRAME | ORB_FULL_IMAGE,
    "ORB, paper's fit": PER_FRAME | ORB_FULL_IMAGE | {"refit_px": 0.0},
}
TARGETS = {"final_error_percent": 0.2, "heading_rmse_deg": 1.4, "frames_per_second": 35.0}


def label(preset: str, variant: str) -> str:
    """A run's name in the sweep's table: the variants of one recording differ only there and in their config."""
    return f"{preset}: {variant}"


def result_row(preset: str, variant: str, row) -> dict:
    """A sweep's row in this benchmark's terms; a run that failed or stopped early is an error of the benchmark."""
    if row["status"] != "ok":
        raise RuntimeError(f"{preset}, {variant}: {row['status']}: {row['error']}")
    return {
        "preset": preset,
        "variant": variant,
        "distance_m": round(row["distance_m"], 3),
        "final_error_mm": round(row["final_error_m"] * 1e3, 1),
        "final_error_percent": round(row["final_error_percent"], 3),
        "heading_rmse_deg": round(row["heading_rmse_deg"], 3),
        "final_heading_deg": round(row["final_heading_deg"], 3),
        "frames_flagged": int(row["frames"] - row["frames_measured"] - 1),
        "flags": json.loads(row["flags"]),
        "frames_per_second": round(row["frames_per_second"], 1),
    }


def shipped_as(variant: str, shipped) -> str:
    """The variant whose run stands for ``variant``: ``default`` when ``variant`` only sets the ``shipped`` features
    section's own values (one of the two ways of following, whichever the config ships), else ``variant`` itself."""
    same = all(getattr(shipped, name) == value for name, value in VARIANTS[variant].items())
    return "default" if same else variant


def measure(presets: list[str], variants: list[str], out: Path, scheduler: str | None, workers: int | None) -> list:
    """Every (preset, configuration) row, in that order; a variant that is the shipped config is the default's run."""
    shipped = load_config(CONFIG).features
    stands_for = {variant: shipped_as(variant, shipped) for variant in variants}
    with cluster_client(scheduler, workers) as client:
        bags = {name: path for (name, _), path in render(client, [(name, None) for name in presets]).items()}
        runs = [
            Run(
                str(bags[preset]),
                label(preset, variant),
                config=str(CONFIG),
                overrides={f"features.{name}": value for name, value in VARIANTS[variant].items()},
            )
            for preset in presets
            for variant in dict.fromkeys(stands_for.values())
        ]
        table = sweep(runs, out, client).table
    found = {row["recording"]: row for _, row in table.iterrows()}
    return [
        result_row(preset, variant, found[label(preset, stands_for[variant])])
        for preset in presets
        for variant in variants
    ]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--presets", nargs="+", default=["downward-long", "downward-wood"])
    parser.add_argument("--variants", nargs="+", default=list(VARIANTS), choices=list(VARIANTS))
    parser.add_argument("--out", type=Path, help="the sweep's folder, kept (default: a temporary one)")
    add_cluster_arguments(parser)
    parser.set_defaults(workers=1)  # the rate on one core, the machine otherwise idle
    parser.add_argument("--write", type=Path, help="JSON file for the results")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as temporary:
        rows = measure(args.presets, args.variants, args.out or Path(temporary), args.scheduler, args.workers)
    print(f"{'preset':16s} {'configuration':24s} {'distance':>9s} {'final error':>12s} {'%':>7s} {'heading rmse':>13s}"
          f" {'flagged':>8s} {'frames/s':>9s}")
    for row in rows:
        print(f"{row['preset']:16s} {row['variant']:24s} {row['distance_m']:8.2f}m {row['final_error_mm']:10.1f}mm "
              f"{row['final_error_percent']:7.3f} {row['heading_rmse_deg']:11.3f}° {row['frames_flagged']:8d} "
              f"{row['frames_per_second']:9.1f}")
    print("targets (downward-long, default):", ", ".join(f"{k} {v}" for k, v in TARGETS.items()))
    if args.write:
        print(f"wrote {write_json(args.write, rows)}")


if __name__ == "__main__":
    main()
