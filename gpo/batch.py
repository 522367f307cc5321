"""Many runs at once: sweeps over recordings x configs on Dask, resumable, gathered into one table.

A ``Run`` is a recording, a config and the ``overrides`` changed in it (dotted keys of the config's YAML document,
``{"klt.window_px": 31, "odometry.method": "gpo"}``). A sweep is a list of runs, usually the grid a ``SweepSpec``
expands to. ``sweep(runs, out, client)`` sends every run to a Dask cluster; each run (``execute``, on a worker)
goes through ``gpo.pipeline.run`` and is evaluated against the recording's ground truth by
``gpo.metrics.evaluate`` (the estimate's first pose placed on the truth's); the client writes, in ``out``:

- ``runs/KEY/trajectory.tum``, ``runs/KEY/trajectory.summary.yaml`` (``OdometryResult.write``),
  ``runs/KEY/config.yaml`` (the run's whole config after its overrides) and ``runs/KEY/row.json`` (its metrics);
- ``results.parquet`` and ``results.csv``: one row per run, rewritten as runs finish (at most every
  ``TABLE_EVERY_S``) and at the end, also when the sweep is interrupted.

KEY is a hash of the recording's content, the run's whole config and the code version (``code_version``: the
method layer's sources), so a sweep started again skips every run already finished with that key (``row.json``
with status ``ok`` or ``partial``) and never repeats it; runs that failed are tried again. A run that fails (a
config the schema refuses, an unreadable bag, a recording without the truth topic) gets a row with status
``failed`` and its ``error`` and the sweep goes on. A worker lost mid-run is replaced by Dask, which runs the
task again elsewhere (``distributed.scheduler.allowed-failures`` times).

The cluster (``cluster_client``): a ``LocalCluster`` of one single-threaded worker process per core by default,
started without Dask's ``MALLOC_TRIM_THRESHOLD_`` (``WORKER_ENVIRONMENT_UNSET``); with a scheduler address
(``tcp://HOST:PORT``, or ``DASK_SCHEDULER_ADDRESS``) an existing cluster. The workers open the recordings by the
paths the runs name, so on a cluster those paths (and ``GPO_CACHE_DIR`` for the simulated presets) must lie on
storage every worker sees under the same path, such as a shared network folder.
Results travel back to the client, which alone writes ``out``.

Table columns: ``key``, ``recording`` (a label), ``recording_path``, ``recording_sha256``, ``config`` (the base
config file, or ``default``), ``param.<dotted key>`` for each override, ``method``, ``status`` (ok, partial:
reading stopped early, failed), ``error``; the metrics ``distance_m`` (travelled by the truth), ``final_error_m``,
``final_error_percent``, ``final_heading_deg``, ``ape_rmse_m``, ``rpe_mean_m`` (per ``RPE_DELTA_M`` metre),
``relative_error_percent``, ``heading_rmse_deg``; the frames ``frames``, ``frames_measured``, ``frames_coasted``,
``frames_held``, ``frames_skipped``, ``flags`` (JSON: count of flagged frames by reason), ``frames_slower_layer``
(measured frames whose flow held a slower layer, ``gpo.flow``); ``frames_per_second``,
``seconds`` (the odometry's wall time), ``run_seconds`` (the whole run's on its worker: reading the truth, the
odometry, the evaluation) and ``code_version``.
"""

from __future__ import annotations

import contextlib
import glob
import hashlib
import itertools
import json
import logging
import math
import os
import shutil
import tempfile
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import cv2
import dask
import numpy as np
import pandas as pd
import yaml
from distributed import Client, LocalCluster, as_completed, get_worker
from pydantic import BaseModel, ConfigDict, Field, ValidationError
from tqdm.auto import tqdm

from gpo.bag import Recording
from gpo.metrics import evaluate
from gpo.pipeline import OdometryConfig, config_to_dict, load_config, run
from gpo.trajectory import Trajectory

TRUTH_TOPIC = "/mocap/base_link"  # the simulator's ground truth; a spec names its own for other recordings
RESULTS = ("results.parquet", "results.csv")
FINISHED = ("ok", "partial")  # statuses a sweep started again does not repeat
TABLE_EVERY_S = 10.0  # while a sweep runs its table is rewritten at most this often (each run's row.json at once)
CONNECT_TIMEOUT_S = 20  # the longest wait for a scheduler given by its address
PRESENTATION_MODULES = ("__main__.py",)  # not part of the code version
# Dask's nannies start workers with MALLOC_TRIM_THRESHOLD_=65536 (distributed.nanny.pre-spawn-environ), which turns
# off glibc's adaptive mmap threshold: every image-sized array is then mapped and unmapped afresh. In
# benchmarks/sweep_speed.py a run on a worker took 0.58 s with it, against 0.39 s one after another on one thread,
# and 0.22 s against 0.24 s without it. A run keeps no memory between tasks that trimming would give back, so the
# local cluster's workers start without it.
WORKER_ENVIRONMENT_UNSET = ("MALLOC_TRIM_THRESHOLD_",)


# ----------------------------------------------------------------------------------------------- runs


@dataclass(frozen=True)
class Run:
    """One run: the bag at ``recording`` (a path the workers can open), named ``label`` in the table; the config
    file ``config`` (None: the shipped default) with ``overrides`` (dotted key -> value); the ground truth on
    ``truth_topic``; the image ``topic`` (None: the config's, else the bag's only one)."""

    recording: str
    label: str
    config: str | None = None
    overrides: dict[str, Any] = field(default_factory=dict)
    truth_topic: str = TRUTH_TOPIC
    topic: str | None = None


def configured(run_: Run) -> OdometryConfig:
    """The run's config: its file (or the default) with its overrides applied to the YAML document and read again
    through ``load_config``'s one schema. Raises ValueError naming the override that is refused or that the config
    does not read (e.g. ``mount.pitch_deg``, written for people, while the mount is read from its quaternion)."""
    base = load_config(None if run_.config is None else Path(run_.config).resolve())
    if not run_.overrides:
        return base
    document = config_to_dict(base)
    for key, value in run_.overrides.items():
        _set(document, key, value)
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "config.yaml"
        path.write_text(yaml.safe_dump(document, sort_keys=False))
        config = load_config(path)
    read_back = config_to_dict(config)
    for key, value in run_.overrides.items():
        if not _same(_get(read_back, key), value):
            raise ValueError(f"override {key}: {value!r} has no effect, the config reads {_get(read_back, key)!r}")
    return config


def _set(document: dict, key: str, value) -> None:
    *sections, name = key.split(".")
    for section in sections:
        document = document.setdefault(section, {})
        if not isinstance(document, dict):
            raise ValueError(f"override {key}: {section} is not a section of the config")
    document[name] = value


def _get(document: dict, key: str):
    for name in key.split("."):
        if not isinstance(document, dict) or name not in document:
            return None
        document = document[name]
    return document


def _same(read, wanted) -> bool:
    if isinstance(wanted, (int, float)) and not isinstance(wanted, bool) and isinstance(read, (int, float)):
        return math.isclose(read, wanted, rel_tol=1e-9, abs_tol=1e-12)
    if isinstance(wanted, (list, tuple)) and isinstance(read, (list, tuple)) and len(read) == len(wanted):
        return all(_same(r, w) for r, w in zip(read, wanted, strict=True))
    return read == wanted


def code_version() -> str:
    """A hash of the sources of the method layer (``gpo/*.py`` but the command line): what a run's
    numbers depend on besides its recording and config."""
    digest = hashlib.sha256()
    for source in sorted(Path(__file__).parent.glob("*.py")):
        if source.name not in PRESENTATION_MODULES:
            digest.update(source.name.encode() + source.read_bytes())
    return digest.hexdigest()[:12]


def recording_digest(path: str) -> str:
    """SHA-256 of a recording's content: the bag file, or every file of a ROS 2 bag folder in name order. Raises
    FileNotFoundError when it is missing."""
    path = Path(path)
    files = sorted(p for p in path.rglob("*") if p.is_file()) if path.is_dir() else [path]
    if not path.exists() or not files:
        raise FileNotFoundError(f"{path}: no such recording (the workers read it by this path)")
    digest = hashlib.sha256()
    for file in files:
        digest.update(str(file.relative_to(path) if path.is_dir() else "").encode())
        with file.open("rb") as stream:
            digest.update(hashlib.file_digest(stream, "sha256").digest())
    return digest.hexdigest()


def run_key(recording_sha256: str, config: dict, version: str) -> str:
    """The key of a run: a hash of its recording's content, its whole config document and the code version."""
    text = json.dumps([recording_sha256, config, version], sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


# ----------------------------------------------------------------------------------------------- one run


@dataclass
class Outcome:
    """What a worker sends back: the table's ``row``, and for a run that finished its ``trajectory`` and the
    pipeline's ``summary``."""

    row: dict
    trajectory: Trajectory | None = None
    summary: dict | None = None


def execute(run_: Run, config: OdometryConfig, key: str) -> Outcome:
    """Run ``run_`` with ``config`` (on a worker): the odometry, then its errors against the ground truth. Any
    error becomes the row's ``error`` with status ``failed``; a run whose reading stopped early is ``partial``. On a
    Dask worker OpenCV keeps to one thread: the cluster's parallelism is its processes (as Dask does for BLAS)."""
    started = time.perf_counter()
    with contextlib.suppress(ValueError):  # not on a worker: OpenCV as configured
        get_worker()
        cv2.setNumThreads(1)
    row = base_row(run_, key) | {"method": str(config.method)}
    try:
        with Recording(run_.recording) as recorded:
            truth = recorded.trajectory(run_.truth_topic)
        result = run(run_.recording, config, run_.topic, progress=False)
        evaluation = evaluate(result.trajectory, truth, "origin")
    except Exception as error:
        failure = {"status": "failed", "error": f"{type(error).__name__}: {error}"}
        return Outcome(row | failure | {"run_seconds": time.perf_counter() - started})
    summary = result.summary()
    final = evaluation.final
    row |= {
        "status": "partial" if result.error else "ok",
        "error": result.error,
        "distance_m": final.distance_m,
        "final_error_m": final.position_m,
        "final_error_percent": final.percent,
        "final_heading_deg": math.degrees(final.heading_rad),
        "ape_rmse_m": evaluation.ape_m.rmse,
        "rpe_mean_m": None if evaluation.rpe_m is None else evaluation.rpe_m.mean,
        "relative_error_percent": evaluation.relative_error_percent,
        "heading_rmse_deg": evaluation.heading_rmse_deg,
        **{name: summary[name] for name in ("frames", "frames_measured", "frames_coasted", "frames_held")},
        "frames_skipped": summary["frames_skipped"],
        "flags": json.dumps(summary["flags"], sort_keys=True),
        "frames_slower_layer": summary.get("frames_slower_layer", 0),
        "frames_per_second": result.frames_per_second,
        "seconds": result.seconds,
        "run_seconds": time.perf_counter() - started,
    }
    return Outcome(row, result.trajectory, summary)


def base_row(run_: Run, key: str, recording_sha256: str | None = None) -> dict:
    """The columns that name a run (the metrics' are added by ``execute``)."""
    return {
        "key": key,
        "recording": run_.label,
        "recording_path": run_.recording,
        "recording_sha256": recording_sha256,
        "config": run_.config or "default",
        **{f"param.{name}": _cell(value) for name, value in run_.overrides.items()},
        "code_version": code_version(),
    }


def _cell(value):
    """A table cell of an override: scalars as they are, anything else as JSON text."""
    return value if value is None or isinstance(value, (bool, int, float, str)) else json.dumps(value)


# ----------------------------------------------------------------------------------------------- the sweep


@dataclass
class SweepResult:
    """A finished sweep: the whole ``table`` of ``out`` (every run it holds, from this sweep and earlier ones), the
    keys of the runs this sweep ``executed`` and of those it ``reused`` from before."""

    table: pd.DataFrame
    executed: list[str]
    reused: list[str]

    @property
    def failed(self) -> pd.DataFrame:
        return self.table[self.table["status"] == "failed"]


def sweep(
    runs: Sequence[Run],
    out,
    client,
    progress: bool = True,
    on_result: Callable[[dict], None] | None = None,
) -> SweepResult:
    """Run every one of ``runs`` not yet finished in ``out`` on the Dask ``client``'s cluster; write each run's files
    and the table as runs finish (see the module docstring); call ``on_result(row)`` after each. Returns the table of
    ``out``. Ctrl-C stops the sweep with every finished run kept."""
    out = Path(out)
    (out / "runs").mkdir(parents=True, exist_ok=True)
    rows = {row["key"]: row for row in read_rows(out)}
    finished = {key for key, row in rows.items() if row["status"] in FINISHED}
    paths = sorted({r.recording for r in runs})
    digests = dict(zip(paths, client.gather(client.map(_digest_or_error, paths, pure=False)), strict=True))
    version = code_version()
    pending, reused, executed = {}, [], []
    for run_ in runs:
        digest = digests[run_.recording]
        try:
            if digest.startswith("error:"):
                raise FileNotFoundError(digest.removeprefix("error:"))
            config = configured(run_)
        except (ValueError, OSError) as error:
            key = run_key(str(digest), {"file": run_.config, "overrides": run_.overrides}, version)
            row = base_row(run_, key) | {"status": "failed", "error": f"{type(error).__name__}: {error}"}
            _keep(out, Outcome(row), None)
            rows[key] = row
            executed.append(key)
            continue
        document = config_to_dict(config)
        key = run_key(digest, document, version)
        if key in finished or key in pending:
            reused.append(key)
            continue
        pending[key] = (run_, config, document)
    futures = {
        client.submit(execute, run_, config, key, key=f"gpo-run-{key}", pure=False): (key, run_, document)
        for key, (run_, config, document) in pending.items()
    }
    bar = tqdm(total=len(futures), desc="runs", unit="run", disable=not progress)
    written = time.monotonic()
    try:
        for future in as_completed(futures):
            key, run_, document = futures[future]
            try:
                outcome = future.result()
            except Exception as error:
                failure = {"status": "failed", "error": f"{type(error).__name__}: {error}"}
                outcome = Outcome(base_row(run_, key) | failure)
            outcome.row["recording_sha256"] = digests[run_.recording]
            _keep(out, outcome, document)
            rows[key] = outcome.row
            executed.append(key)
            bar.update()
            if on_result is not None:
                on_result(outcome.row)
            if time.monotonic() - written > TABLE_EVERY_S:
                write_table(out, rows.values())
                written = time.monotonic()
    finally:
        bar.close()
        for future in futures:
            future.cancel()
        table = write_table(out, rows.values())
    return SweepResult(table, executed, reused)


def _digest_or_error(path: str) -> str:
    """``recording_digest`` on a worker, or ``error:`` and why it cannot be read there."""
    try:
        return recording_digest(path)
    except OSError as error:
        return f"error:{error}"


def _keep(out: Path, outcome: Outcome, document: dict | None) -> None:
    """Write a run's files into ``out/runs/KEY`` (a new folder renamed into place)."""
    final = out / "runs" / outcome.row["key"]
    partial = final.with_name(final.name + ".partial")
    shutil.rmtree(partial, ignore_errors=True)
    partial.mkdir(parents=True)
    if outcome.trajectory is not None:
        outcome.trajectory.write_tum(partial / "trajectory.tum")
        (partial / "trajectory.summary.yaml").write_text(yaml.safe_dump(outcome.summary, sort_keys=False))
    if document is not None:
        (partial / "config.yaml").write_text(yaml.safe_dump(document, sort_keys=False, default_flow_style=None))
    (partial / "row.json").write_text(json.dumps(outcome.row, indent=1, default=_json_number) + "\n")
    shutil.rmtree(final, ignore_errors=True)
    partial.rename(final)


def _json_number(value):
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(f"cannot write {value!r} into a row")


def read_rows(out) -> list[dict]:
    """Every run's row kept in ``out/runs``."""
    rows = []
    for path in sorted(Path(out).glob("runs/*/row.json")):
        rows.append(json.loads(path.read_text()))
    return rows


def write_table(out, rows=None) -> pd.DataFrame:
    """Gather ``rows`` (default: ``out/runs/*/row.json``) into ``results.parquet`` and ``results.csv`` in ``out``
    (each written to a temporary name, then renamed); return the table, sorted by recording and parameters."""
    out = Path(out)
    table = pd.DataFrame(list(read_rows(out) if rows is None else rows))
    if table.empty:
        return table
    parameters = parameter_columns(table)
    for column in parameters:  # a parameter that took numbers in one sweep and text in another: text
        kinds = {type(v) for v in table[column] if v is not None and not (isinstance(v, float) and math.isnan(v))}
        if len(kinds) > 1 and kinds != {int, float}:
            table[column] = table[column].map(lambda v: None if v is None else str(v))
    table[parameters] = table[parameters].convert_dtypes()  # whole numbers stay whole beside missing ones
    table = table.sort_values(["recording", *parameters, "key"], na_position="first", ignore_index=True)
    for name, write in zip(RESULTS, (table.to_parquet, table.to_csv), strict=True):
        temporary = out / f".{name}.partial"
        write(temporary, index=False)
        temporary.replace(out / name)
    return table


def read_table(out) -> pd.DataFrame:
    """The table a sweep wrote into ``out`` (``results.parquet``). Raises FileNotFoundError naming the folder."""
    path = Path(out) / RESULTS[0]
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no sweep results here (python -m gpo sweep SPEC --out {out})")
    return pd.read_parquet(path)


def parameter_columns(table: pd.DataFrame) -> list[str]:
    """The table's override columns (``param.<dotted key>``), in order."""
    return [c for c in table.columns if c.startswith("param.")]


def summary_text(table: pd.DataFrame, speed: bool = True) -> str:
    """The table for people: one line per run, errors in %, mm and degrees, and (``speed``) frames per second."""
    if table.empty:
        return "no runs"
    columns = ["recording", *parameter_columns(table), "status"]
    shown = table[columns].copy()
    shown.columns = [c.removeprefix("param.") for c in columns]
    metrics = {
        "final %": ("final_error_percent", 1.0, 3),
        "final mm": ("final_error_m", 1e3, 1),
        "heading deg": ("final_heading_deg", 1.0, 2),
        "APE rmse mm": ("ape_rmse_m", 1e3, 1),
        "frames/s": ("frames_per_second", 1.0, 1),
    }
    if not speed:
        del metrics["frames/s"]
    for label, (column, scale, digits) in metrics.items():
        values = table[column] if column in table else pd.Series([None] * len(table))
        shown[label] = (pd.to_numeric(values, errors="coerce") * scale).round(digits)
    lines = [shown.to_string(index=False, na_rep="-")]
    for _, row in table[table["status"] != "ok"].iterrows():
        lines.append(f"{row['recording']} {row['key']}: {row['status']}: {row['error']}")
    return "\n".join(lines)


# ----------------------------------------------------------------------------------------------- the cluster


@contextlib.contextmanager
def cluster_client(scheduler: str | None = None, workers: int | None = None) -> Iterator:
    """A Dask client: of the scheduler at ``scheduler`` (``tcp://HOST:PORT``), else at ``DASK_SCHEDULER_ADDRESS``,
    else of a new local cluster of ``workers`` single-threaded worker processes (default: one per core), closed on
    leaving. Raises ValueError naming the address of a scheduler that does not answer within ``CONNECT_TIMEOUT_S``.

    The local workers start without ``WORKER_ENVIRONMENT_UNSET``. Workers of a cluster given by its address keep
    their own environment: started by ``dask worker`` they run the odometry up to 1.8x slower unless started with
    ``--no-nanny`` or with a Dask config file that sets ``distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_``
    to ``null``."""
    address = scheduler or os.environ.get("DASK_SCHEDULER_ADDRESS")
    if address:
        try:
            client = Client(address, timeout=CONNECT_TIMEOUT_S)
        except (OSError, TimeoutError) as error:
            raise ValueError(f"cannot reach the Dask scheduler at {address}: {error}") from None
        with client:
            yield client
        return
    workers = workers or os.cpu_count() or 1
    unset = {f"distributed.nanny.pre-spawn-environ.{name}": None for name in WORKER_ENVIRONMENT_UNSET}
    with (
        dask.config.set(unset),
        LocalCluster(
            n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=":0", silence_logs=logging.ERROR
        ) as cluster,
        Client(cluster) as client,
    ):
        yield client


def add_cluster_arguments(parser) -> None:
    """``--scheduler`` and ``--workers`` on an ``argparse`` parser: the arguments of ``cluster_client``."""
    parser.add_argument(
        "--scheduler", help="a running Dask scheduler, tcp://HOST:PORT (default: DASK_SCHEDULER_ADDRESS, else local)"
    )
    parser.add_argument("--workers", type=int, help="local worker processes (default: one per core)")


# ----------------------------------------------------------------------------------------------- the spec


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid")


class FileSource(_Strict):
    """A recording file (or ROS 2 bag folder)."""

    file: str
    label: str | None = None


class GlobSource(_Strict):
    """Every recording a glob pattern matches (sorted), each labelled by its file name."""

    glob: str


class PresetSource(_Strict):
    """A simulator preset, rendered (or read from the cache) with each of ``seeds`` (none: its own seed)."""

    preset: str
    seeds: list[int] | None = None


class SweepSpec(_Strict):
    """A sweep as a YAML file says it (relative paths are relative to that file)::

        recordings:                      # files, globs and simulator presets
          - preset: test
            seeds: [1, 2]
          - file: /shared/bags/hall.bag
          - glob: /shared/bags/fleet/*.bag
        config: rig.yaml                 # the base config (default: the shipped simulated T265 rig)
        set: {odometry.method: gpo-exact}      # changes every run makes
        vary:                            # the grid: every combination of these
          klt.window_px: [15, 21, 31]
          odometry.method: [gpo, gpo-exact]
        runs: [{klt.max_corners: 100}, {klt.max_corners: 200}]   # a list of changes, each crossed with the grid
        truth_topic: /mocap/base_link    # the ground truth in every recording
        topic: null                      # the image topic (default: the config's)
    """

    recordings: list[FileSource | GlobSource | PresetSource] = Field(min_length=1)
    config: str | None = None
    set: dict[str, Any] = Field(default_factory=dict)
    vary: dict[str, list[Any]] = Field(default_factory=dict)
    runs: list[dict[str, Any]] = Field(default_factory=lambda: [{}])
    truth_topic: str = TRUTH_TOPIC
    topic: str | None = None

    def presets(self) -> list[tuple[str, int | None]]:
        """The (preset, seed) pairs the spec names, in order."""
        return [
            (source.preset, seed)
            for source in self.recordings
            if isinstance(source, PresetSource)
            for seed in (source.seeds or [None])
        ]

    def expand(self, preset_paths: dict[tuple[str, int | None], str] | None = None) -> list[Run]:
        """The runs: every recording x every set of overrides (``set``, then a ``runs`` entry, then a grid point).
        ``preset_paths`` gives the bag of each of ``presets()``. Raises ValueError for a glob that matches nothing."""
        recordings = []
        for source in self.recordings:
            if isinstance(source, FileSource):
                recordings.append((source.file, source.label or Path(source.file).name))
            elif isinstance(source, GlobSource):
                matched = sorted(glob.glob(source.glob))
                if not matched:
                    raise ValueError(f"recordings: glob {source.glob} matches no file")
                recordings += [(path, Path(path).name) for path in matched]
            else:
                for seed in source.seeds or [None]:
                    label = source.preset if seed is None else f"{source.preset}@{seed}"
                    recordings.append((str((preset_paths or {})[(source.preset, seed)]), label))
        grid = [dict(zip(self.vary, values, strict=True)) for values in itertools.product(*self.vary.values())]
        overrides = [{**self.set, **entry, **point} for entry in self.runs for point in grid]
        return [
            Run(path, label, self.config, changes, self.truth_topic, self.topic)
            for path, label in recordings
            for changes in overrides
        ]


def load_spec(path) -> SweepSpec:
    """The ``SweepSpec`` of a YAML file, with relative paths made relative to its folder. Raises ValueError naming
    the file and each wrong field."""
    path = Path(path)
    try:
        document = yaml.safe_load(path.read_text())
    except yaml.YAMLError as error:
        raise ValueError(f"{path}: not YAML: {error}") from None
    if not isinstance(document, dict):
        raise ValueError(f"{path}: a sweep spec is a mapping with recordings, config, set, vary, runs")
    try:
        spec = SweepSpec.model_validate(document)
    except ValidationError as error:
        problems = "; ".join(f"{'.'.join(map(str, e['loc'])) or 'spec'}: {e['msg']}" for e in error.errors())
        raise ValueError(f"{path}: {problems}") from None
    folder = path.resolve().parent
    for source in spec.recordings:
        if isinstance(source, FileSource):
            source.file = str(folder / source.file)
        elif isinstance(source, GlobSource):
            source.glob = str(folder / source.glob)
    if spec.config is not None:
        spec.config = str(folder / spec.config)
    return spec
