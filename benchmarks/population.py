"""Every method over a population of drawn worlds, not one tuned world: its final-error distribution and its failures.

    python benchmarks/population.py [--draws 30] [--first-seed 0] [--kind fisheye|downward] [--fused] [--matte]
                                    [--workers N] [--scheduler ADDRESS] [--out SWEEP_FOLDER]
                                    [--write benchmarks/results/population.json]

``--draws`` worlds (seeds ``--first-seed`` on, ``gpo.sim.population.draw``: half fisheye rigs of the T265's
family at any height 0.08-0.30 m, pitch 0-15 degrees, roll +-2 degrees and lever 0.3-0.9 m, with a drifting
tracking camera; half downward pinhole cameras of other lenses, heights, tilts and places; floors of every kind,
mixed and of other grains, glossy (mirroring a drawn hall's ceiling lamps, 2.5-12 m up) or matte; paths of the
papers' lengths, 4-16 m for the fisheye and 4-20 m for the downward camera, with reverse legs, spins on the spot,
and slides and quarter turns for the downward camera's omnidirectional robot) are rendered on a Dask
cluster (``gpo.sim.population.render_draws``; cached) and swept with ``gpo.batch.sweep.sweep`` (resumable in
``--out``): ``gpo``, ``gpo-exact`` and ``gpo-rigid`` on the fisheye rigs (and
``fused``, with ``--fused``), ``features`` on the downward ones.

Each run reads the shipped config of its kind of rig (``gpo/configs/``) changed only as a user adapting it to
their robot would (``adapted``): the camera's calibration and mount, and the floor region, which keeps the
shipped view of the floor: moved with the camera and scaled by its height over its focal length (the same
pixels of floor per image pixel, so the floor image stays the shipped size in pixels); for the fisheye, the
bicycle model's wheel at the region's centre, as the shipped config has it. Nothing is tuned per draw.

Printed and written: per method the final position error in % of the distance (median, p90, worst) against the
issue's targets (p90 at most 0.3 % for gpo-exact, 0.5 % for gpo-rigid, 0.3 % for features and for fused; ``gpo``, the
paper's, has none), and every run over its method's target (for ``gpo``: over 1 %) or not finished, with its
draw and what the run's summary says of it: frames coasted, held and skipped, the flags by reason, and the measured
frames whose flow held a slower layer of vectors (``gpo.motion.klt``: the reflections of a glossy floor, which pull the
median short without failing any check); for ``gpo``, whether the path holds a leg the paper's bicycle reads wrong
(reverse driving read as forward, a spin's sense flipping: ``gpo.odometry.kinematics``, chapter 06); and, measured
against the draw's true path (kept in the sweep folder's ``truth``), how the run's heading error grew metre by metre
(``heading_steps``): a steady drift, such as turns read short every time, or a random walk of each step's own noise.
With ``--fused``, the fused route beside its two sources on each draw, the floor odometry it fuses and the tracking
camera's own odometry, and the draws where it ends further off than the better of them (``sources_report``).

``--kind`` keeps the draws of one kind of rig among those seeds (even seeds draw a fisheye, odd ones a downward
camera): ``--draws 60 --kind downward`` runs only the 30 downward draws of the first 60 seeds, and their ``features``
runs only.

``--matte`` runs the same draws with every floor matte (``gpo.sim.population.matte``: the same rigs, paths, drifts
and textures, without the glossy screed's reflections of the ceiling lamps), so that what the reflections cost each
method is the difference between the two reports (``--write benchmarks/results/population_matte.json``).
"""

import argparse
import json
import math
import sys
import time
from pathlib import Path

import cloudpickle
import correlation_peer
import numpy as np
import pandas as pd
import yaml

from gpo.batch.cluster import add_cluster_arguments, cluster_client
from gpo.batch.runs import FINISHED, TRUTH_TOPIC, Run, code_version, configured, recording_digest, run_key
from gpo.batch.sweep import sweep
from gpo.batch.table import read_table
from gpo.cameras.files import camera_to_kalibr
from gpo.io import cache
from gpo.io.bag import Recording
from gpo.io.outputs import write_text
from gpo.io.trajectory import Trajectory
from gpo.metrics import associate, final_error, heading_errors
from gpo.pipeline.config import config_to_dict, load_config
from gpo.pipeline.run import tracking_path
from gpo.sim.floors import FLOOR_KINDS
from gpo.sim.population import Draw, draw, matte, render_draws
from gpo.sim.record import recording_path

CONFIGS = Path(__file__).resolve().parents[1] / "gpo" / "configs"
CONFIG = {"fisheye": CONFIGS / "sim_t265.yaml", "downward": CONFIGS / "sim_downward.yaml"}
METHODS = {"fisheye": ["gpo", "gpo-exact", "gpo-rigid"], "downward": ["features"]}
TARGETS = {"gpo-exact": 0.3, "gpo-rigid": 0.5, "features": 0.3, "fused": 0.3}  # p90 of the final error, % of distance
REPORTED_OVER = {"gpo": 1.0}  # the method without a target (the paper's): runs over this are listed, %
MANIFEST = "draws.json"  # in the sweep folder: each draw's recording and its digest (see ``batches``)
TRUTH = "truth"  # in the sweep folder: each draw's true path, ``<label>.tum``, for the measures against it
HEADING_STEP_M = 1.0  # ``heading_steps``: the heading error's change over each metre the truth drives
STEADY_T = 3.0  # ... a mean step this many standard errors from zero is a steady drift, not a random walk
PAPER_MODEL_MISSES = ("reverse", "spin")  # legs the paper's bicycle (``gpo``) reads wrong: eqs. 25-26, chapter 06


def adapted(chosen: Draw) -> dict:
    """The overrides of the shipped config of ``chosen``'s kind of rig that describe its rig (see the module)."""
    rig = chosen.setup.rig
    shipped = load_config(CONFIG[chosen.kind]).rig
    entry = camera_to_kalibr(rig.camera, rig.name)
    scale = (rig.mount.height / rig.camera.fx) / (shipped.mount.height / shipped.camera.fx)
    base = load_config(CONFIG[chosen.kind])
    x_min, x_max, y_min, y_max = base.floor.extent
    (x0, y0), (x, y) = shipped.mount.position[:2], rig.mount.position[:2]
    step = round(float(base.floor.metres_per_pixel * scale), 6)  # a micrometre is as fine as people write it
    x_range = _whole_pixels([x + scale * (v - x0) for v in (x_min, x_max)], step)
    y_range = _whole_pixels([y + scale * (v - y0) for v in (y_min, y_max)], step)
    overrides = {
        "camera.intrinsics": [float(v) for v in entry["intrinsics"]],
        "camera.distortion_coeffs": [float(v) for v in entry["distortion_coeffs"]],
        "mount.position_m": [float(v) for v in rig.mount.position],
        "mount.rpy_deg": [float(np.degrees(angle)) for angle in rig.mount.body_rpy],
        "floor_image.x_range_m": x_range,
        "floor_image.y_range_m": y_range,
        "floor_image.metres_per_pixel": step,
    }
    if chosen.kind == "fisheye":
        centre = round(float(np.mean(x_range)), 6)
        overrides |= {"kinematics.wheelbase_m": centre, "kinematics.rear_to_reference_m": centre}
    return overrides


def _whole_pixels(edges: list[float], step: float) -> list[float]:
    """(low, high) metres a whole number of ``step`` pixels apart, keeping ``high`` (as the floor image keeps its
    far-left corner: ``gpo.floor_image.image.FloorImage.top_view``)."""
    high = round(float(edges[1]), 6)
    return [round(high - round((high - edges[0]) / step) * step, 9), high]


def run_of(chosen: Draw, bag: Path, method: str) -> Run:
    """``method``'s run of ``chosen`` on ``bag``, with its adapted config (the fused route's names the tracking
    camera's topic and mount)."""
    return Run(str(bag), chosen.label, str(CONFIG[chosen.kind]), adapted(chosen) | {"odometry.method": method})


def runs_of(draws: list[Draw], bags: dict[str, Path], fused: bool) -> list[Run]:
    """Every method of each draw's kind, on its bag, with its adapted config."""
    runs = []
    for chosen in draws:
        methods = METHODS[chosen.kind] + (["fused"] if fused and chosen.setup.drift is not None else [])
        runs += [run_of(chosen, bags[chosen.label], method) for method in methods]
    return runs


def distribution(errors: pd.Series) -> dict:
    """Median, p90 (linear interpolation) and worst of the final errors, %."""
    values = errors.dropna().to_numpy(dtype=float)
    if not len(values):
        return {"median": None, "p90": None, "worst": None}
    return {
        "median": round(float(np.median(values)), 4),
        "p90": round(float(np.percentile(values, 90)), 4),
        "worst": round(float(values.max()), 4),
    }


def truth_and_camera(bag: str, config) -> tuple[Trajectory, dict | None]:
    """``bag``'s true path, and (for a rig with a tracking camera, ``config`` the fused run's) the camera's own
    odometry's final error against it (``final_error_percent``, ``final_heading_deg``): the fused route's other
    source beside the floor."""
    with Recording(bag) as recording:
        truth = recording.trajectory(TRUTH_TOPIC)
        if config is None:
            return truth, None
        error = final_error(tracking_path(recording, config.fusion), truth)
    return truth, {"final_error_percent": float(error.percent), "final_heading_deg": math.degrees(error.heading_rad)}


def heading_steps(estimate: Trajectory, truth: Trajectory, step_m: float = HEADING_STEP_M) -> dict | None:
    """How the heading error of ``estimate`` grew, against ``truth``: its change over each ``step_m`` the truth drives
    (the last step shorter), their mean and standard deviation (degrees), and ``t``, the mean over its standard error
    (the final heading error over what a random walk of such steps would reach, one standard deviation of it). A
    ``t`` of ``STEADY_T`` or more is a ``steady`` drift (a turn read short every time, a bias), less a random walk
    (each step's own noise). None for fewer than three steps."""
    estimated, reference = associate(estimate, truth)
    error = np.unwrap(heading_errors(estimated, reference))
    driven = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(reference.positions_xyz[:, :2], axis=0), axis=1))]
    marks = np.r_[np.searchsorted(driven, np.arange(0.0, driven[-1], step_m)), len(driven) - 1]
    steps = np.degrees(np.diff(error[marks]))
    if len(steps) < 3:
        return None
    sd = float(steps.std(ddof=1))
    t = float(steps.mean() / sd * math.sqrt(len(steps))) if sd > 0 else math.inf
    return {
        "steps": len(steps),
        "mean_deg": round(float(steps.mean()), 4),
        "sd_deg": round(sd, 4),
        "t": round(t, 2),
        "steady": abs(t) >= STEADY_T,
    }


def runs_heading_steps(table: pd.DataFrame, out: Path) -> dict[str, dict | None]:
    """``heading_steps`` of each run of the sweep folder ``out`` (by its key) against its draw's true path, each
    draw's truth read once; None where either file is missing (a run that failed, a sweep made before the truth was
    kept)."""
    truths, steps = {}, {}
    for _, row in table.iterrows():
        path, truth = out / "runs" / row["key"] / "trajectory.tum", out / TRUTH / f"{row['recording']}.tum"
        if not (path.is_file() and truth.is_file()):
            steps[row["key"]] = None
            continue
        if row["recording"] not in truths:
            truths[row["recording"]] = Trajectory.read_tum(truth)
        steps[row["key"]] = heading_steps(Trajectory.read_tum(path), truths[row["recording"]])
    return steps


def explanation(row: pd.Series, out: Path) -> dict:
    """What a run's summary (in the sweep folder ``out``) says of it: its status, error, flags by reason, frames not
    measured, measured frames whose flow held a slower layer (``gpo.motion.klt``: reflections on a glossy floor), and
    the distance it measured over the distance driven; ``explained`` when a caution, a flag, a frame not measured or
    a status other than ok names a cause (a slower layer alone does not: it is seen on runs that end right too)."""
    flags = json.loads(row["flags"]) if isinstance(row.get("flags"), str) else {}
    frames = {
        name: int(row[f"frames_{name}"])
        for name in ("coasted", "held", "skipped")
        if f"frames_{name}" in row and pd.notna(row[f"frames_{name}"]) and row[f"frames_{name}"]
    }
    slower = row.get("frames_slower_layer")
    slower = int(slower) if slower is not None and pd.notna(slower) else 0
    summary_path = out / "runs" / row["key"] / "trajectory.summary.yaml"
    summary = yaml.safe_load(summary_path.read_text()) if summary_path.is_file() else {}
    measured = summary.get("distance_m")
    cautions = summary.get("cautions", []) + ([summary["flagged"]] if summary.get("flagged") else [])
    return {
        "status": row["status"],
        **({"error": row["error"]} if isinstance(row.get("error"), str) and row["error"] else {}),
        "distance_ratio": None if measured is None else round(measured / row["distance_m"], 4),
        "flags": flags,
        "frames_not_measured": frames,
        "frames_slower_layer": slower,
        "cautions": cautions,
        "explained": bool(cautions or flags or frames or row["status"] != "ok"),
    }


def steps_summary(steps: list[dict | None]) -> dict:
    """Over a method's runs, how their heading errors grew (``heading_steps``): the runs measured, the median of
    their steps' standard deviations (degrees a metre) and how many drifted steadily."""
    measured = [s for s in steps if s is not None]
    median = float(np.median([s["sd_deg"] for s in measured])) if measured else None
    return {"runs": len(measured), "median_sd_deg": _rounded(median, 4), "steady": sum(s["steady"] for s in measured)}


def report(table: pd.DataFrame, draws: list[Draw], out: Path) -> dict:
    """The methods' distributions against their targets (over all draws and over the draws whose floor holds each
    kind), and the runs over them with their explanations and, measured against the draw's true path, how their
    heading errors grew (``heading_steps``: a steady drift or a random walk, which a run itself cannot know; ``out``:
    the sweep's folder)."""
    steps = runs_heading_steps(table, out)
    parameters = {d.label: d.parameters for d in draws}
    kinds = {d.label: d.setup.floor.kinds for d in draws}
    glossy = {d.label: d.parameters["sheen"] == "on" for d in draws}
    methods, failing = {}, []
    for method, rows in table.groupby("method", sort=False):
        limit = TARGETS.get(method, REPORTED_OVER.get(method))
        stats = distribution(rows["final_error_percent"])
        finished = rows[rows["status"] != "failed"]
        worst = finished.loc[finished["final_error_percent"].idxmax()] if len(finished) else None
        methods[method] = {
            "runs": len(rows),
            "failed": int((rows["status"] == "failed").sum()),
            "partial": int((rows["status"] == "partial").sum()),
            **stats,
            "worst_draw": None if worst is None else worst["recording"],
            "p90_target": TARGETS.get(method),
            "target_met": None if method not in TARGETS or stats["p90"] is None else stats["p90"] <= TARGETS[method],
            "median_heading_deg": round(float(finished["final_heading_deg"].abs().median()), 3),
            "heading_steps": steps_summary([steps[key] for key in finished["key"]]),
            "by_floor_kind": {
                kind: {"draws": int(on.sum()), **distribution(rows.loc[on, "final_error_percent"])}
                for kind in FLOOR_KINDS
                if (on := rows["recording"].map(lambda label, kind=kind: kind in kinds[label])).any()
            },
            "by_finish": {
                finish: {"draws": int(on.sum()), **distribution(rows.loc[on, "final_error_percent"])}
                for finish, shiny in (("glossy", True), ("matte", False))
                if (on := rows["recording"].map(lambda label, shiny=shiny: glossy[label] == shiny)).any()
            },
        }
        for _, row in rows.sort_values("final_error_percent", ascending=False).iterrows():
            over = not (row["final_error_percent"] <= limit)  # NaN (failed) counts as over
            if over or row["status"] != "ok":
                drawn = parameters[row["recording"]]
                run_ = {
                    "draw": row["recording"],
                    "method": method,
                    "final_error_percent": _rounded(row["final_error_percent"], 4),
                    "final_error_mm": _rounded(row["final_error_m"] * 1e3, 1),
                    "final_heading_deg": _rounded(row["final_heading_deg"], 3),
                    "over": limit,
                    **explanation(row, out),
                    "heading_steps": steps[row["key"]],
                    "outside_paper_model": method == "gpo" and any(leg in drawn["path"] for leg in PAPER_MODEL_MISSES),
                    "parameters": drawn,
                }
                run_["explained"] = run_["explained"] or run_["outside_paper_model"]
                failing.append(run_)
    for method, stats in methods.items():
        listed = [f for f in failing if f["method"] == method]
        stats["listed"] = len(listed)
        stats["listed_without_flags"] = sum(not f["explained"] for f in listed)
    return {"methods": methods, "failing": failing}


def batches(client, draws: list[Draw], out: Path, args) -> float:
    """Render, run and forget the draws ``--batch`` at a time, so that the cache holds one batch's recordings (a
    paper-length draw's bag is 0.3-1.4 GB): each batch's bags are rendered (``render_draws``), their content's digest
    written to the sweep folder's manifest (``MANIFEST``), their runs swept into ``out`` (and the peer's, with
    ``--peer``), then the bags deleted unless ``--keep-bags``. A draw whose manifest entry names its recording as the
    simulator makes it now and whose runs are all finished in ``out`` is not rendered again, so an interrupted
    benchmark resumes where it stopped. Returns the seconds spent rendering."""
    manifest = read_manifest(out)
    pending = [d for d in draws if not _finished(d, manifest, out, args)]
    rendering = 0.0
    for first in range(0, len(pending), args.batch):
        batch = pending[first : first + args.batch]
        print(f"draws {first + 1}-{first + len(batch)} of the {len(pending)} to run: rendering", file=sys.stderr)
        started = time.perf_counter()
        bags = render_draws(client, batch)
        rendering += time.perf_counter() - started
        digests = client.gather(client.map(recording_digest, [str(bags[d.label]) for d in batch], pure=False))
        for chosen, digest in zip(batch, digests, strict=True):
            manifest[chosen.label] = {"recording": str(bags[chosen.label]), "sha256": digest}
        sweep(runs_of(batch, bags, args.fused), out, client, progress=sys.stderr.isatty())
        fused = [None if d.setup.drift is None else configured(run_of(d, bags[d.label], "fused")) for d in batch]
        futures = client.map(truth_and_camera, [str(bags[d.label]) for d in batch], fused, pure=False)
        (out / TRUTH).mkdir(exist_ok=True)
        for chosen, (truth, camera) in zip(batch, client.gather(futures), strict=True):
            truth.write_tum(out / TRUTH / f"{chosen.label}.tum")
            manifest[chosen.label] |= {"camera": camera} if camera is not None else {}
        if args.peer:
            for label, error in peer_errors(client, batch, bags).items():
                manifest[label]["peer"] = error
        write_text(out / MANIFEST, json.dumps(manifest, indent=1) + "\n")
        if not args.keep_bags:
            for path in bags.values():
                path.unlink(missing_ok=True)
    return rendering


def read_manifest(out: Path) -> dict:
    """The sweep folder's manifest: per draw label, its recording's path, content digest and (``--peer``) the
    peer's errors."""
    path = out / MANIFEST
    return json.loads(path.read_text()) if path.is_file() else {}


def run_keys(runs: list[Run], manifest: dict) -> list[str]:
    """The sweep's key of each run (``gpo.batch.runs.run_key``), from its recording's digest in the manifest."""
    version = code_version()
    by_path = {entry["recording"]: entry["sha256"] for entry in manifest.values()}
    return [run_key(by_path[r.recording], config_to_dict(configured(r)), version) for r in runs]


def _finished(chosen: Draw, manifest: dict, out: Path, args) -> bool:
    """Whether ``chosen``'s recording, as the simulator makes it now, was run by every method in ``out``."""
    entry = manifest.get(chosen.label)
    if entry is None or entry["recording"] != str(recording_path(chosen.setup, label=chosen.label)):
        return False
    if args.peer and chosen.kind == "fisheye" and "peer" not in entry:
        return False
    if not (out / TRUTH / f"{chosen.label}.tum").is_file():
        return False
    if chosen.setup.drift is not None and "camera" not in entry:
        return False
    runs = runs_of([chosen], {chosen.label: entry["recording"]}, args.fused)
    rows = [out / "runs" / key / "row.json" for key in run_keys(runs, manifest)]
    return all(row.is_file() and json.loads(row.read_text())["status"] in FINISHED for row in rows)


def peer_errors(client, draws: list[Draw], bags: dict[str, Path]) -> dict[str, dict]:
    """The correlation peer's final errors (``benchmarks/correlation_peer.py``) on each fisheye draw, by its label,
    computed on ``client``'s workers."""
    cloudpickle.register_pickle_by_value(correlation_peer)  # the workers need not import the benchmarks folder
    fisheyes = [d for d in draws if d.kind == "fisheye"]
    configs = [configured(Run(str(bags[d.label]), d.label, str(CONFIG[d.kind]), adapted(d))) for d in fisheyes]
    futures = client.map(correlation_peer.peer_error, [str(bags[d.label]) for d in fisheyes], configs, pure=False)
    return dict(zip([d.label for d in fisheyes], client.gather(futures), strict=True))


def peer_report(table: pd.DataFrame, draws: list[Draw], peer: dict[str, dict]) -> dict:
    """The peer's median final error per floor kind and finish (glossy, matte) beside each fisheye method's on the same
    draws, and whether the method is ahead (a lower median) on every group."""
    groups = {}
    for d in draws:
        if d.label in peer:
            finish = "glossy" if d.parameters["sheen"] == "on" else "matte"
            for kind in d.setup.floor.kinds:
                groups.setdefault(f"{kind}, {finish}", []).append(d.label)
    report_ = {"runs": {label: {k: round(v, 4) for k, v in e.items()} for label, e in peer.items()}, "groups": {}}
    for group, labels in sorted(groups.items()):
        peer_median = float(np.median([peer[label]["final_error_percent"] for label in labels]))
        row = {"draws": len(labels), "peer": round(peer_median, 4)}
        for method in METHODS["fisheye"][1:]:
            errors = table[(table["method"] == method) & table["recording"].isin(labels)]["final_error_percent"]
            row[method] = _rounded(float(errors.median()), 4) if errors.notna().any() else None
        report_["groups"][group] = row
    report_["ahead_everywhere"] = {
        method: all(r[method] is not None and r[method] < r["peer"] for r in report_["groups"].values())
        for method in METHODS["fisheye"][1:]
    }
    return report_


def sources_report(table: pd.DataFrame, draws: list[Draw], cameras: dict[str, dict]) -> dict:
    """The fused route beside its two sources on each draw with a tracking camera: the floor odometry it fuses
    (the config's ``fusion.floor_method``) and the camera's own odometry (``cameras``: by draw label, as
    ``truth_and_camera`` gives it), final error %; the draws where the fused path ends further off than the better
    source, and by how much; and the three final heading errors (degrees), with the source whose heading the fused
    path's is nearer (``heading_nearer``): the one the filter followed in the turns."""
    floor = load_config(CONFIG["fisheye"]).fusion.floor_method
    errors, headings = (
        table.pivot_table(index="recording", columns="method", values=column, aggfunc="first")
        for column in ("final_error_percent", "final_heading_deg")
    )
    rows = {}
    for d in draws:
        if d.label in cameras and d.label in errors.index and "fused" in errors.columns:
            fused, ground = errors.at[d.label, "fused"], errors.at[d.label, floor]
            camera = cameras[d.label]["final_error_percent"]
            better = min(ground, camera)
            turned = {"fused": headings.at[d.label, "fused"], floor: headings.at[d.label, floor],
                      "camera": cameras[d.label]["final_heading_deg"]}
            nearer = min((floor, "camera"), key=lambda source: abs(turned["fused"] - turned[source]))
            rows[d.label] = {"fused": _rounded(fused, 4), floor: _rounded(ground, 4), "camera": _rounded(camera, 4),
                             "over_better": _rounded(fused - better, 4), "ratio": _rounded(fused / better, 2),
                             "heading_deg": {k: _rounded(v, 3) for k, v in turned.items()},
                             "heading_nearer": None if math.isnan(turned["fused"]) else nearer}
    over = {label: math.inf if row["over_better"] is None else row["over_better"] for label, row in rows.items()}
    worse = [label for label, points in over.items() if points > 0]
    worst = max(worse, key=over.get, default=None)
    return {"floor_method": floor, "draws": len(rows), "worse": len(worse), "worst_draw": worst, "runs": rows}


def _rounded(value, digits):
    return None if value is None or not math.isfinite(value) else round(float(value), digits)


def print_report(result: dict) -> None:
    print(
        f"{'method':10s} {'runs':>4s} {'failed':>6s} {'median %':>9s} {'p90 %':>7s} {'worst %':>8s} "
        f"{'target p90':>10s}  worst draw"
    )
    for method, stats in result["methods"].items():
        target = (
            "-"
            if stats["p90_target"] is None
            else f"{stats['p90_target']:.1f} " + ("met" if stats["target_met"] else "MISSED")
        )
        print(
            f"{method:10s} {stats['runs']:4d} {stats['failed']:6d} {_cell(stats['median']):>9s} "
            f"{_cell(stats['p90']):>7s} {_cell(stats['worst']):>8s} {target:>10s}  {stats['worst_draw']}"
        )
    print("\nper floor kind (draws whose floor holds it; a mix counts under both kinds): median / p90 / worst %")
    for method, stats in result["methods"].items():
        cells = [
            f"{kind} ({s['draws']}) {_cell(s['median'])} / {_cell(s['p90'])} / {_cell(s['worst'])}"
            for kind, s in stats["by_floor_kind"].items()
        ]
        print(f"{method:10s} " + "; ".join(cells))
    print("\nglossy floors (mirroring the ceiling's lamps) and matte ones: median / p90 / worst %")
    for method, stats in result["methods"].items():
        cells = [
            f"{finish} ({s['draws']}) {_cell(s['median'])} / {_cell(s['p90'])} / {_cell(s['worst'])}"
            for finish, s in stats["by_finish"].items()
        ]
        print(f"{method:10s} " + "; ".join(cells))
    print("\nthe heading error's growth against the truth, metre by metre (heading_steps): median standard deviation "
          "of a metre's step, and the runs whose steps drift steadily (a bias) rather than walk")
    for method, stats in result["methods"].items():
        steps = stats["heading_steps"]
        print(f"{method:10s} {_cell(steps['median_sd_deg']):>7s} deg a metre; {steps['steady']} of {steps['runs']} "
              "runs steady")
    unexplained = sum(not f["explained"] for f in result["failing"])
    print(
        f"\n{len(result['failing'])} runs over their method's target (gpo: over 1 %) or not finished, "
        f"{unexplained} of them without a caution (steps not measured, a slower layer, the filter refusing), a flag, "
        "a leg outside the paper's model (gpo) or an error to say why:"
    )
    for run_ in result["failing"]:
        p = run_["parameters"]
        rig = (
            f"h {p['height_m']:.3f} m pitch {p['pitch_deg']:.1f} lever {p['lever_m']:.2f}"
            if "pitch_deg" in p
            else f"h {p['height_m']:.3f} m f {p['f_px']:.0f} px"
        )
        why = ", ".join(f"{reason} {count}" for reason, count in run_["flags"].items()) or "no flags"
        frames = ", ".join(f"{count} {name}" for name, count in run_["frames_not_measured"].items())
        slower = run_["frames_slower_layer"]
        why += f"; a slower layer in {slower} frames" if slower else ""
        why += "; reverse or spin: the paper's model reads them wrong" if run_["outside_paper_model"] else ""
        steps = run_["heading_steps"]
        if steps is not None:
            kind = "a steady drift" if steps["steady"] else "a random walk"
            why += (f"; against the truth the heading's error grew {steps['mean_deg']:+.3f} +- {steps['sd_deg']:.3f} "
                    f"deg a metre over {steps['steps']} steps: {kind} (t {steps['t']:+.1f})")
        print(
            f"  {run_['draw']} {run_['method']:9s} {_cell(run_['final_error_percent']):>7s} % "
            f"distance x{_cell(run_['distance_ratio'])} heading {_cell(run_['final_heading_deg'])} deg | {rig}, "
            f"{p['floor']} ({p['photos']}) | {why}"
            f"{'; frames ' + frames if frames else ''}{'; ' + run_['error'] if 'error' in run_ else ''}"
            f" | {p['path']}"
        )


def print_peer(peer: dict) -> None:
    methods = METHODS["fisheye"][1:]
    print("\nthe correlation peer beside the suite's fisheye methods, median final error % per floor kind and finish:")
    print(f"{'floor':22s} {'draws':>5s} {'peer':>7s} " + " ".join(f"{m:>9s}" for m in methods))
    for group, row in peer["groups"].items():
        cells = " ".join(f"{_cell(row[m]):>9s}" for m in methods)
        print(f"{group:22s} {row['draws']:5d} {_cell(row['peer']):>7s} {cells}")
    print("ahead of the peer on every group: " + ", ".join(f"{m} {v}" for m, v in peer["ahead_everywhere"].items()))


def print_sources(sources: dict) -> None:
    floor = sources["floor_method"]
    print(f"\nthe fused route beside its sources ({floor} and the tracking camera alone), final error %: worse than "
          f"the better source on {sources['worse']} of {sources['draws']} draws")
    for label, row in sorted(sources["runs"].items(), key=lambda item: -(item[1]["over_better"] or 0)):
        if row["over_better"] is not None and row["over_better"] > 0:
            turned = row["heading_deg"]
            print(f"  {label} fused {_cell(row['fused']):>6s} {floor} {_cell(row[floor]):>7s} camera "
                  f"{_cell(row['camera']):>6s}: {row['over_better']:+.3f} points, x{row['ratio']:.2f} the better; "
                  f"heading {turned['fused']:+.2f} / {turned[floor]:+.2f} / {turned['camera']:+.2f} deg, nearer the "
                  f"{row['heading_nearer']}'s")


def _cell(value) -> str:
    return "-" if value is None else f"{value:.3f}"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--draws", type=int, default=30, help="worlds drawn (default 30: 15 of each kind of rig)")
    parser.add_argument("--first-seed", type=int, default=0)
    parser.add_argument("--fused", action="store_true", help="also the fused method on the fisheye rigs")
    parser.add_argument("--kind", choices=list(METHODS), help="only the draws of this kind of rig (default: both)")
    add_cluster_arguments(parser)
    parser.add_argument("--matte", action="store_true", help="the same draws with every floor matte (no sheen)")
    parser.add_argument("--out", type=Path, help="the sweep's folder (default: population or population-matte in "
                        "the cache's runs)")
    parser.add_argument("--write", type=Path, help="JSON file for the results")
    parser.add_argument("--batch", type=int, default=8, help="draws rendered and run at a time (default 8)")
    parser.add_argument("--keep-bags", action="store_true", help="keep each batch's recordings in the cache")
    parser.add_argument("--peer", action="store_true", help="also the correlation odometer a user might write "
                        "(benchmarks/correlation_peer.py) on the fisheye draws, compared per floor kind and finish")
    args = parser.parse_args()
    if args.draws < 1 or args.first_seed < 0 or args.batch < 1:
        parser.error("--draws and --batch must be at least 1 and --first-seed at least 0")
    if args.write is not None and args.write.is_dir():
        parser.error(f"--write {args.write} is a folder; expected a JSON file's path")
    draws = [draw(seed) for seed in range(args.first_seed, args.first_seed + args.draws)]
    draws = [chosen for chosen in draws if args.kind in (None, chosen.kind)]
    if not draws:
        parser.error(f"no {args.kind} draw among seeds {args.first_seed}-{args.first_seed + args.draws - 1}")
    if args.matte:
        draws = [matte(chosen) for chosen in draws]
    out = args.out or cache.folder("runs") / ("population-matte" if args.matte else "population")
    started = time.perf_counter()
    with cluster_client(args.scheduler, args.workers) as client:
        workers = len(client.scheduler_info()["workers"])
        rendered_s = batches(client, draws, out, args)
    finished = time.perf_counter()
    manifest = read_manifest(out)
    runs = runs_of(draws, {d.label: manifest[d.label]["recording"] for d in draws}, args.fused)
    table = read_table(out)
    table = table[table["key"].isin(run_keys(runs, manifest))]
    result = report(table, draws, out)
    if args.peer:
        peer = {d.label: manifest[d.label]["peer"] for d in draws if d.kind == "fisheye"}
        result["peer"] = peer_report(table, draws, peer)
    if args.fused:
        cameras = {d.label: manifest[d.label]["camera"] for d in draws if "camera" in manifest[d.label]}
        result["sources"] = sources_report(table, draws, cameras)
    print_report(result)
    if args.peer:
        print_peer(result["peer"])
    if args.fused:
        print_sources(result["sources"])
    print(
        f"\n{len(draws)} draws, {len(runs)} runs in {finished - started:.0f} s on {workers} workers (rendering "
        f"{rendered_s:.0f} s of it); sweep folder {out}"
    )
    if args.write:
        document = {
            "command": "python benchmarks/population.py " + " ".join(sys.argv[1:]),
            "draws": len(draws),
            "seeds": [args.first_seed, args.first_seed + args.draws - 1],
            "workers": workers,
            "render_s": round(rendered_s, 1),
            "runs_s": round(finished - started - rendered_s, 1),
            **result,
            "draw_parameters": {d.label: d.parameters for d in draws},
            "runs": [
                {
                    "draw": row["recording"],
                    "method": row["method"],
                    "status": row["status"],
                    "final_error_percent": _rounded(row["final_error_percent"], 4),
                    "final_heading_deg": _rounded(row["final_heading_deg"], 3),
                    "distance_m": _rounded(row["distance_m"], 3),
                }
                for _, row in table.sort_values(["recording", "method"]).iterrows()
            ],
        }
        args.write.parent.mkdir(parents=True, exist_ok=True)
        args.write.write_text(json.dumps(document, indent=1) + "\n")
        print(f"wrote {args.write}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
