"""The floor feature odometer's configurations side by side over the population's downward draws: final error and
heading RMSE of each, on the draws its constants were chosen on and on held-out ones.

    python benchmarks/features_population.py [--seeds FIRST LAST] [--variants NAME ...] [--out SWEEP_FOLDER]
                                             [--batch 4] [--workers N] [--scheduler ADDRESS] [--write FILE.json]

The draws are the odd seeds from FIRST to LAST (``gpo.sim.population.draw``: an odd seed draws a downward camera):
by default 1-59, the population benchmark's 30 downward draws (``benchmarks/population.py``), on which every
constant of the shipped ``features`` config was chosen; 61-119 are held out, run for the report and never for a
choice. Each is rendered on the cluster (cached, ``--batch`` draws at a time, so that the cache need hold no more)
and run with each variant (``VARIANTS``): the shipped downward config (``gpo/configs/sim_downward.yaml``) adapted to
the draw's rig as a user would adapt it (``population.adapted``), with the variant's keys set. ``keyframes + LK``
detects and describes SIFT keypoints on keyframes only and follows them between keyframes by Lucas-Kanade
(``features.follow: lk``, 200 keypoints); ``per-frame detector`` detects and describes them in every frame and
matches them with a keyframe's (``follow: match``, 300 keypoints: the second paper's way).

Printed and written per variant: the runs, those that failed, the final position error (% of the distance) and the
heading RMSE (degrees) as median, p90 (linear interpolation) and worst, and the frames a second each run read on its
worker (reading included; on a shared machine a rough guide: ``benchmarks/features_odometry.py`` and
``benchmarks/odometry_speed.py`` measure speed on one core); then each draw's errors by variant.
"""

import argparse
import shlex
import sys
from pathlib import Path

import numpy as np
import pandas as pd
from population import CONFIG, adapted, distribution

from gpo.batch.cluster import add_cluster_arguments, cluster_client
from gpo.batch.runs import Run
from gpo.batch.sweep import sweep
from gpo.io import cache
from gpo.io.outputs import write_json
from gpo.sim.population import draw, render_draws

PER_FRAME = {"features.follow": "match", "features.max_features": 300}  # SIFT in every frame, matched with a keyframe's
FOLLOWED = {"features.follow": "lk", "features.max_features": 200}  # SIFT on keyframes, followed between them by LK
VARIANTS = {  # name -> the config keys set on the shipped downward config (both named, whichever it ships)
    "keyframes + LK": FOLLOWED,
    "per-frame detector": PER_FRAME,
}


def run_of(seed: int, bag: Path, variant: str) -> Run:
    """``variant``'s run of the draw of ``seed`` on ``bag``."""
    chosen = draw(seed)
    return Run(str(bag), label(chosen.label, variant), str(CONFIG["downward"]), adapted(chosen) | VARIANTS[variant])


def label(draw_label: str, variant: str) -> str:
    """A run's name in the sweep's table: the draw and the variant."""
    return f"{draw_label}: {variant}"


def measure(seeds: list[int], variants: list[str], out: Path, client, batch: int) -> pd.DataFrame:
    """Every (draw, variant) run, ``batch`` draws rendered and swept at a time; the sweep's table of these runs."""
    keys = set()
    for first in range(0, len(seeds), batch):
        chosen = seeds[first : first + batch]
        print(f"seeds {chosen}: rendering", file=sys.stderr)
        bags = render_draws(client, [draw(seed) for seed in chosen])
        runs = [run_of(seed, bags[draw(seed).label], variant) for seed in chosen for variant in variants]
        done = sweep(runs, out, client, progress=sys.stderr.isatty())
        keys |= {*done.executed, *done.reused}
    table = done.table[done.table["key"].isin(keys)].copy()  # this code's runs, not those of an earlier one
    table["draw"], table["variant"] = zip(*(name.split(": ", 1) for name in table["recording"]), strict=True)
    return table


def summarise(table: pd.DataFrame, variants: list[str]) -> dict:
    """Per variant: the runs, the failed, the final error and heading RMSE distributions, the median frames a second."""
    result = {}
    for variant in variants:
        rows = table[table["variant"] == variant]
        result[variant] = {
            "runs": len(rows),
            "failed": int((rows["status"] == "failed").sum()),
            "final_error_percent": distribution(rows["final_error_percent"]),
            "heading_rmse_deg": distribution(rows["heading_rmse_deg"]),
            "frames_per_second": round(float(rows["frames_per_second"].median()), 1),
        }
    return result


def print_summary(summary: dict, table: pd.DataFrame, seeds: list[int]) -> None:
    print(f"{len(seeds)} downward draws, seeds {seeds[0]}-{seeds[-1]} (odd)")
    print(f"{'variant':22s} {'runs':>4s} {'failed':>6s}   final error %: median    p90  worst   heading RMSE deg: "
          f"median    p90  worst  frames/s")
    for variant, s in summary.items():
        e, h = s["final_error_percent"], s["heading_rmse_deg"]
        print(f"{variant:22s} {s['runs']:4d} {s['failed']:6d} {'':16s}{_cell(e['median'])} {_cell(e['p90'])} "
              f"{_cell(e['worst'])} {'':19s}{_cell(h['median'])} {_cell(h['p90'])} {_cell(h['worst'])} "
              f"{s['frames_per_second']:9.1f}")
    errors = table.pivot_table(index="draw", columns="variant", values="final_error_percent", aggfunc="first")
    print("\nfinal error % by draw:")
    print(errors[list(summary)].round(4).to_string())


def _cell(value) -> str:
    return f"{'-':>6s}" if value is None else f"{value:6.3f}"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs=2, default=[1, 59], metavar=("FIRST", "LAST"),
                        help="the odd seeds from FIRST to LAST (default 1 59; 61 119 are held out)")
    parser.add_argument("--variants", nargs="+", default=list(VARIANTS), choices=list(VARIANTS))
    parser.add_argument("--out", type=Path, help="the sweep's folder (default: features-population in the cache)")
    parser.add_argument("--batch", type=int, default=4, help="draws rendered and run at a time (default 4)")
    add_cluster_arguments(parser)
    parser.add_argument("--write", type=Path, help="JSON file for the results")
    args = parser.parse_args()
    seeds = [seed for seed in range(args.seeds[0], args.seeds[1] + 1) if seed % 2 == 1]
    if not seeds or args.batch < 1:
        parser.error("--seeds must hold an odd seed and --batch be at least 1")
    out = args.out or cache.folder("runs") / "features-population"
    with cluster_client(args.scheduler, args.workers) as client:
        table = measure(seeds, args.variants, out, client, args.batch)
    summary = summarise(table, args.variants)
    print_summary(summary, table, seeds)
    if args.write:
        runs = [
            {"draw": row["draw"], "variant": row["variant"], "status": row["status"],
             "final_error_percent": _rounded(row["final_error_percent"]),
             "heading_rmse_deg": _rounded(row["heading_rmse_deg"]),
             "distance_m": _rounded(row["distance_m"]), "frames_per_second": _rounded(row["frames_per_second"])}
            for _, row in table.sort_values(["draw", "variant"]).iterrows()
        ]
        document = {"command": "python benchmarks/features_population.py " + shlex.join(sys.argv[1:]),
                    "seeds": [seeds[0], seeds[-1]], "draws": len(seeds), "variants": summary, "runs": runs}
        print(f"wrote {write_json(args.write, document)}")
    return 0


def _rounded(value, digits: int = 4):
    return None if value is None or not np.isfinite(value) else round(float(value), digits)


if __name__ == "__main__":
    sys.exit(main())
