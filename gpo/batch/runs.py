"""One run of a sweep: a recording, a config and the overrides changed in it (``Run``), its key (the recording's
content, the whole config and the code), and its execution on a worker (``execute``): the odometry, evaluated against
the recording's ground truth.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import cv2
from distributed import get_worker

from gpo.io import cache
from gpo.io.bag import Recording
from gpo.io.fingerprint import PACKAGE_ROOT, sources
from gpo.io.trajectory import Trajectory
from gpo.metrics import evaluate
from gpo.pipeline.config import DEFAULT_CONFIG, OdometryConfig, config_from, config_to_dict, load_config
from gpo.pipeline.run import run
from gpo.pipeline.schema import check_config

TRUTH_TOPIC = "/mocap/base_link"  # the simulator's ground truth; a spec names its own for other recordings


FINISHED = ("ok", "partial")  # statuses a sweep started again does not repeat




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
    path = None if run_.config is None else Path(run_.config).resolve()
    base = load_config(path)
    if not run_.overrides:
        return base
    document = config_to_dict(base)
    for key, value in run_.overrides.items():
        _set(document, key, value)
    where = f"{run_.config or 'the default config'} with {', '.join(run_.overrides)} changed"
    config = config_from(check_config(document, where), path or Path(DEFAULT_CONFIG), where)
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
    """A hash of the sources a run goes through (``execute``: the odometry and its evaluation, every module they import,
    ``gpo.io.fingerprint.sources``): what a run's numbers depend on besides its recording and config."""
    digest = hashlib.sha256()
    for source in sources(__name__):
        digest.update(str(source.relative_to(PACKAGE_ROOT)).encode() + source.read_bytes())
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
    """The key of a run (``gpo.io.cache.key``): its recording's content, its whole config document and the code
    version."""
    return cache.key(recording_sha256, config, version)


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
        "drift_percent_per_m": evaluation.drift_percent_per_m,
        "heading_rmse_deg": evaluation.heading_rmse_deg,
        **{name: summary[name] for name in ("frames", "frames_measured", "frames_coasted", "frames_held")},
        "frames_skipped": summary["frames_skipped"],
        "flags": json.dumps(summary["flags"], sort_keys=True),
        "frames_slower_layer": summary.get("frames_slower_layer", 0),
        "frames_overview": summary.get("frames_overview", 0),
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
