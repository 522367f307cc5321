"""The second paper's Table 2 over its experiments I-IX, reproduced on the simulated downward camera, and the
road from its method as published to the shipped pipeline (``ablation_configs``).

Each experiment (``EXPERIMENTS``) is a recording of ``gpo.sim.record`` (``paper2-i`` ... ``paper2-ix``, in the
conditions of the paper's Table 1: a cart pushed at random over wood, along a raised-floor corridor, the linear and
rotational stages over the glossy industrial floor, the omnidirectional AGV's 81 m) and the way the paper took its
ground truth, which decides the samples its metrics are computed at (``gpo.metrics.paper_table2``):

- ``continuous``: motion capture (I-II): every frame;
- ``markers``: marks on the floor at known places (III): the frames nearest to where the path passes each mark,
  every ``MARKER_SPACING_M`` along it (``marker_stamps_ns``); the odometer sees every frame;
- ``steps``: the stage's position after each step, the images taken at rest (IV, V, VII): the odometer sees only
  the frame in the middle of each rest, as the paper's camera did;
- ``end``: the run's end alone (VI, VIII, and IX, whose ground markers gave only its final error).

Every row also carries the same run against the simulator's continuous truth (``Table2Row.continuous``).

A run (``experiment_run``) reads every frame of a long recording, up to a few minutes for IX; each is kept on disk
under ``$GPO_CACHE_DIR/runs``, keyed by the recording (whose name holds the simulator's fingerprint, so the rests
of a stepped plan too), the frames used (all or at rest), the whole config and the source of every module a run
goes through, so that ``python -m gpo table2`` computes them once (as ``python -m gpo table4`` does for the first
paper's table) and lab C's module (``python -m gpo.book.lab_c_second_paper``) reads them back; it also keeps chapter
08's runs over the three floors (``floor_runs``).
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

import gpo
import gpo.io.cache
from gpo.experiments.runs import RUN_MODULES, floor_run
from gpo.io.bag import Recording
from gpo.io.fingerprint import sources
from gpo.io.trajectory import Trajectory
from gpo.metrics import PaperTable2, evaluate, paper_table2
from gpo.motion.keyframes import FRAME_TO_FRAME
from gpo.pipeline.config import OdometryConfig, config_to_dict, load_config
from gpo.pipeline.odometer import FloorOdometer
from gpo.pipeline.run import FloorRun, OdometryResult
from gpo.sim.paths import named_plan
from gpo.sim.record import GROUND_TRUTH_TOPIC, START_NS, preset, recording
from gpo.sim.rigs import RIGS
from gpo.sim.segments import Stop

DOWNWARD_CONFIG = Path(gpo.__file__).parent / "configs" / "sim_downward.yaml"


@dataclass(frozen=True)
class Experiment:
    """One of the paper's experiments: its ``number`` (I-IX), the ``preset`` recording, how its ground truth was
    taken (``truth``: continuous, steps or end) and the paper's own row of Table 2 (``paper``; None where it
    printed a dash)."""

    number: str
    preset: str
    truth: str
    paper: PaperTable2


def _paper(distance, rmse, heading_rmse, final_mm, final_percent, final_heading, relative) -> PaperTable2:
    return PaperTable2(distance, rmse, heading_rmse, final_mm, final_percent, final_heading, relative, 0)


NONE = float("nan")  # the paper's dash
EXPERIMENTS = (
    Experiment("I", "paper2-i", "continuous", _paper(17.83, 56.3, 2.3, 109.8, 0.16, 3.4, 4.8)),
    Experiment("II", "paper2-ii", "continuous", _paper(19.27, 56.5, 1.4, 114.7, 0.3, 0.9, 9.6)),
    Experiment("III", "paper2-iii", "markers", _paper(14.48, 42.8, NONE, 80.7, 0.17, NONE, 0.8)),
    Experiment("IV", "paper2-iv", "steps", _paper(0.5, 0.49, NONE, 0.35, 0.07, NONE, 4.15)),
    Experiment("V", "paper2-v", "steps", _paper(1.24, 5.27, NONE, 13.76, 0.22, NONE, 1.69)),
    Experiment("VI", "paper2-vi", "end", _paper(3.18, NONE, NONE, 40.64, 1.18, NONE, 1.18)),
    Experiment("VII", "paper2-vii", "steps", _paper(0.44, 2.84, 0.4, 4.01, 0.12, 0.72, 3.9)),
    Experiment("VIII", "paper2-viii", "end", _paper(0.87, NONE, NONE, 7.07, 0.77, 0.67, 0.77)),
    Experiment("IX", "paper2-ix", "end", _paper(80.21, NONE, NONE, 600.81, 0.94, NONE, 0.94)),
)
MARKER_SPACING_M = 1.0  # III's marks on the floor: one a metre along the path (the paper does not say how many)


def experiment(number: str) -> Experiment:
    """The experiment numbered ``number`` (I ... IX)."""
    for chosen in EXPERIMENTS:
        if chosen.number == number:
            return chosen
    raise ValueError(f"unknown experiment {number!r}; the experiments are {', '.join(e.number for e in EXPERIMENTS)}")


SUITE_CHANGES = (
    ("half image, region", {"scale": 1.0, "roi": None}),
    ("ratio test", {"ratio": 1.0}),
    ("circular binning", {"circular_binning": False}),
    ("band floor", {"band_floor_px": 0.0}),
    ("short sides pass", {"short_side_px": 0.0}),
    ("refit", {"refit_px": 0.0}),
    ("keyframes", {"keyframe": FRAME_TO_FRAME}),
    ("keypoints followed by LK", {"follow": "match", "max_features": 300}),
)
"""The suite's changes to the paper's method, in the order the ablation adds them, each with the feature settings
that undo it (the paper's): SIFT on the image halved in a region of interest (the paper: the full image), Lowe's
ratio test (the paper: the nearest descriptor), the orientation histogram about the vectors' circular mean with
short vectors passing (the paper: the joining line's orientation over 0-180 degrees, every vector binned), the
bands' floor (the paper: mu +- sigma alone), loop sides too short to judge passing (the paper: every side judged),
the refit (the paper: one fit), keyframes (the paper: every frame matched with the one before) and the keyframe's
200 keypoints followed into later frames by Lucas-Kanade (the paper: 300 detected, described and matched in every
frame)."""


def published_config(base: OdometryConfig | None = None) -> OdometryConfig:
    """The paper's method as published, with one substitution: SIFT for SURF (not in OpenCV's PyPI wheels), run on
    the full 752 x 480 image with the shipped config's SIFT settings (a contrast threshold of 0.01: the paper gives
    no SURF settings, and SIFT's usual 0.04 finds no keypoint on the screed) and its 300 strongest keypoints.
    Every one of ``SUITE_CHANGES`` is undone; the rest of ``base`` (default: the shipped downward config) fills what
    the paper leaves open (the loops' threshold, cardinality and rounds, the fewest matches)."""
    base = base or load_config(DOWNWARD_CONFIG)
    undone = {name: value for _, fields in SUITE_CHANGES for name, value in fields.items()}
    return base.replace(features=dataclasses.replace(base.features, **undone))


def ablation_configs(base: OdometryConfig | None = None) -> dict[str, OdometryConfig]:
    """``{name: config}`` from the paper's method (``published_config``, "as published") to ``base`` (default: the
    shipped downward config, "shipped"): each of ``SUITE_CHANGES`` added in turn to the ones before it
    ("+ ratio test" ...), the last being ``base`` itself."""
    base = base or load_config(DOWNWARD_CONFIG)
    configs, config = {"as published": published_config(base)}, published_config(base)
    for name, fields in SUITE_CHANGES:
        config = config.replace(features=dataclasses.replace(config.features, **{
            field: getattr(base.features, field) for field in fields
        }))  # fmt: skip
        configs[f"+ {name}"] = config
    configs["shipped"] = configs.pop(f"+ {SUITE_CHANGES[-1][0]}")
    return configs


def marker_stamps_ns(chosen: Experiment, spacing_m: float = MARKER_SPACING_M) -> np.ndarray:
    """The stamps (ns) at which the experiment's path passes a mark on the floor, one every ``spacing_m`` metres of
    path from the start (the start and the end are samples of every truth besides)."""
    plan = named_plan(preset(chosen.preset).path)
    times = np.linspace(0.0, plan.duration_s, int(plan.duration_s * 1000) + 1)  # a millisecond apart
    state = plan.sample(times)
    along = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(state.x), np.diff(state.y)))])
    marks = np.arange(spacing_m, along[-1], spacing_m)
    return START_NS + np.round(np.interp(marks, along, times) * 1e9).astype(np.int64)


def rest_stamps_ns(chosen: Experiment) -> np.ndarray:
    """The stamps (ns) of the middle of each rest of a stepped experiment's plan: where the paper took an image and
    its ground truth."""
    plan = named_plan(preset(chosen.preset).path)
    bounds = plan.boundaries_s
    middles = [(bounds[i] + bounds[i + 1]) / 2 for i, seg in enumerate(plan.segments) if isinstance(seg, Stop)]
    return START_NS + np.round(np.array(middles) * 1e9).astype(np.int64)


def _frames(bag: Path, chosen: Experiment) -> Iterator[tuple[int, np.ndarray]]:
    """(stamp ns, grey image) of the frames the experiment's odometer sees: all, or one in the middle of each rest."""
    rests = rest_stamps_ns(chosen) if chosen.truth == "steps" else None
    half_period_ns = 0.5e9 / RIGS[preset(chosen.preset).rig]().rate_hz
    with Recording(bag) as recorded:
        for frame in recorded.frames(gray=True, progress=False):
            if rests is None or np.abs(rests - frame.stamp_ns).min() <= half_period_ns:
                yield frame.stamp_ns, frame.image


@dataclass(frozen=True)
class ExperimentRun:
    """An experiment's estimated path of base_link (``trajectory``), the frames it used, its speed and the
    recording's ground truth (``truth``, base_link in world, kept with the run so that it is read once)."""

    trajectory: Trajectory
    frames: int
    frames_per_second: float
    truth: Trajectory


DETECTION_FIELDS = ("detector", "max_features", "contrast_threshold", "fast_threshold", "scale", "roi")


def experiment_runs(chosen: Experiment, configs: dict[str, OdometryConfig], cache: bool = True):
    """``{name: ExperimentRun}``: the floor feature odometer over the experiment's frames with each of ``configs``,
    read from the disk cache when kept. The ones computed here share one pass over the frames and, when they detect
    alike (``DETECTION_FIELDS`` and the route) and match the keypoints detected in every frame (``features.follow``
    ``match``), one detection a frame; each run's rate counts the detection and its own matching, filters and fit.
    A config that follows keypoints between keyframes (``follow: lk``) detects on its own keyframes: it is given
    the frames themselves."""
    bag = recording(chosen.preset, progress=False)
    paths = {name: _run_path(bag, chosen, config) for name, config in configs.items()}
    runs = {name: _load(path) for name, path in paths.items() if cache and gpo.io.cache.intact(path)}
    runs = {name: run for name, run in runs.items() if run is not None}
    missing = {name: config for name, config in configs.items() if name not in runs}
    groups: dict[tuple, dict[str, OdometryConfig]] = {}
    for name, config in missing.items():
        key = (config.route, config.features.follow, *(getattr(config.features, field) for field in DETECTION_FIELDS))
        groups.setdefault(key, {})[name] = config
    for group in groups.values():
        for name, run in _run_together(bag, chosen, group).items():
            runs[name] = run
            if cache:
                _save(paths[name], run)
    return {name: runs[name] for name in configs}


def experiment_run(chosen: Experiment, config: OdometryConfig, cache: bool = True) -> ExperimentRun:
    """``experiment_runs`` of one config."""
    return experiment_runs(chosen, {"run": config}, cache)["run"]


def _run_together(bag: Path, chosen: Experiment, configs: dict[str, OdometryConfig]) -> dict[str, ExperimentRun]:
    """Every config of ``configs`` (which detect and follow alike) over the experiment's frames in one pass, each
    frame's keypoints detected once (for configs that follow keypoints between keyframes, each given the frame).
    Raises ValueError when a frame cannot be read."""
    detector = FloorOdometer(next(iter(configs.values())))
    follows = detector.config.features.follow == "lk"
    odometers = {name: FloorOdometer(config) for name, config in configs.items()}
    records = {name: [] for name in configs}
    seconds = dict.fromkeys(configs, 0.0)
    detecting = 0.0
    with Recording(bag) as recorded:
        truth = recorded.trajectory(GROUND_TRUTH_TOPIC)
    for stamp_ns, image in _frames(bag, chosen):
        started = time.perf_counter()
        keypoints = image if follows else detector.keypoints(image)
        detecting += time.perf_counter() - started
        for name, odometer in odometers.items():
            started = time.perf_counter()
            records[name].append(odometer.step(stamp_ns, keypoints))
            seconds[name] += time.perf_counter() - started
    return {
        name: ExperimentRun(
            OdometryResult(records[name], detecting + seconds[name], configs[name], bag.name, "").trajectory,
            len(records[name]),
            len(records[name]) / (detecting + seconds[name]),
            truth,
        )
        for name in configs
    }


def _load(path: Path) -> ExperimentRun | None:
    """The kept run, or None when the file holds no ground truth (kept before it did)."""
    with np.load(path) as kept:
        if "truth_poses" not in kept:
            return None
        trajectory = Trajectory.from_planar(kept["stamps_ns"], *kept["poses"].T, frame_id="odom")
        truth = Trajectory.from_planar(kept["truth_stamps_ns"], *kept["truth_poses"].T)
        return ExperimentRun(trajectory, int(kept["frames"]), float(kept["frames_per_second"]), truth)


def _save(path: Path, run: ExperimentRun) -> None:
    """Keep ``run`` in the cache file ``path`` (``gpo.io.cache.keep``: a name of its own, then renamed; on a full disk,
    not kept)."""
    planar, truth = (np.column_stack([t.positions[:, :2], t.yaw]) for t in (run.trajectory, run.truth))
    arrays = {
        "stamps_ns": run.trajectory.stamps_ns,
        "poses": planar,
        "frames": run.frames,
        "frames_per_second": run.frames_per_second,
        "truth_stamps_ns": run.truth.stamps_ns,
        "truth_poses": truth,
    }
    gpo.io.cache.keep(path, lambda partial: np.savez(partial, **arrays))


def _run_path(bag: Path, chosen: Experiment, config: OdometryConfig) -> Path:
    """The cache file of the run of ``config`` on ``bag``: keyed by the recording, the truth's sampling, the whole
    config and the sources of every module a run goes through."""
    key = gpo.io.cache.key(bag.name, chosen.truth, config_to_dict(config), sources=sources(*RUN_MODULES))
    return gpo.io.cache.path("runs", f"{bag.stem}-{chosen.truth}", key, ".npz")


@dataclass(frozen=True)
class Table2Row:
    """An experiment run under the paper's definitions (``paper``, at its ground truth's samples), the same against
    every frame's truth (``continuous``) and the suite's drift per metre (``Evaluation.drift_percent_per_m``, %;
    None when the truth travels less than a metre)."""

    experiment: Experiment
    paper: PaperTable2
    continuous: PaperTable2
    drift_percent_per_m: float | None
    frames: int
    frames_per_second: float


def table2_rows(chosen: Experiment, configs: dict[str, OdometryConfig], cache: bool = True) -> dict[str, Table2Row]:
    """The experiment's run with each of ``configs`` against its ground truth, sampled as the paper's was."""
    runs = experiment_runs(chosen, configs, cache)
    samples = {
        "continuous": None, "markers": marker_stamps_ns(chosen), "steps": rest_stamps_ns(chosen),
        "end": np.zeros(0, np.int64),
    }[chosen.truth]  # fmt: skip
    return {
        name: Table2Row(
            chosen,
            paper_table2(run.trajectory, run.truth, samples),
            paper_table2(run.trajectory, run.truth),
            evaluate(run.trajectory, run.truth).drift_percent_per_m,
            run.frames,
            run.frames_per_second,
        )
        for name, run in runs.items()
    }


def table2_row(chosen: Experiment, config: OdometryConfig, cache: bool = True) -> Table2Row:
    """``table2_rows`` of one config."""
    return table2_rows(chosen, {"run": config}, cache)["run"]


def reproduce_table2(configs: dict[str, OdometryConfig] | None = None, experiments=EXPERIMENTS, cache: bool = True):
    """``{name: [Table2Row per experiment]}`` for each config (default: the pipeline as published and as shipped)."""
    if configs is None:
        shipped = load_config(DOWNWARD_CONFIG)
        configs = {"as published": published_config(shipped), "shipped": shipped}
    table = {name: [] for name in configs}
    for chosen in experiments:
        for name, row in table2_rows(chosen, configs, cache).items():
            table[name].append(row)
    return table


HEADER = (
    f"{'':14}{'distance':>9}{'position':>10}{'heading':>9}{'final error':>16}{'final':>9}{'relative':>10}\n"
    f"{'':14}{'[m]':>9}{'RMSE[mm]':>10}{'RMSE[°]':>9}{'[mm]':>9}{'[%]':>7}{'head.[°]':>9}{'error[%]':>10}"
)


def _number(value: float, width: int, digits: int, significant: int | None = None) -> str:
    if value is None or np.isnan(value):
        return f"{'-':>{width}}"
    if significant is not None:  # 876.3 -> '900' (1), 0.524 -> '0.5' (1)
        return f"{float(f'{value:.{significant}g}'):>{width}g}"
    return f"{value:{width}.{digits}f}"


def format_row(label: str, row: PaperTable2, significant: int | None = None) -> str:
    """One line of Table 2 in the paper's column order ('-' for what is not given), each number to two decimals or,
    with ``significant``, to that many significant digits (the distance, which the truth gives, to two decimals
    always): for a run whose last digits depend on the processor's floating-point path, only the digits every path
    agrees on."""
    return (
        f"{label:14}{_number(row.distance_m, 9, 2)}{_number(row.positioning_rmse_mm, 10, 2, significant)}"
        f"{_number(row.heading_rmse_deg, 9, 2, significant)}{_number(row.final_error_mm, 9, 2, significant)}"
        f"{_number(row.final_error_percent, 7, 2, significant)}{_number(row.final_heading_deg, 9, 2, significant)}"
        f"{_number(row.relative_error_percent, 10, 2, significant)}"
    )


FLOORS = {"wood": "downward-wood", "raised": "downward-raised", "industrial": "downward-industrial"}


def floor_runs(base: OdometryConfig | None = None) -> dict[str, FloorRun]:
    """Chapter 08's runs of the shipped config over the three floors' recordings (``FLOORS``), and over the
    industrial floor with SIFT's usual contrast threshold (0.04, OpenCV's default: ``"industrial, threshold 0.04"``),
    each kept on disk by ``gpo.experiments.runs.floor_run``."""
    base = base or load_config(DOWNWARD_CONFIG)
    usual = base.replace(features=dataclasses.replace(base.features, contrast_threshold=0.04))
    runs = {kind: floor_run(recording(name, progress=False), base) for kind, name in FLOORS.items()}
    runs["industrial, threshold 0.04"] = floor_run(recording(FLOORS["industrial"], progress=False), usual)
    return runs


FLOORS_RUNS = "floors"  # the name that asks ``gpo table2`` for chapter 08's runs over the three floors
