"""Many runs at once: sweeps over recordings x configs on Dask, resumable, gathered into one table.

A ``Run`` is a recording, a config and the ``overrides`` changed in it (dotted keys of the config's YAML document,
``{"klt.window_px": 31, "odometry.method": "gpo"}``). A sweep is a list of runs, usually the grid a ``SweepSpec``
expands to. ``sweep(runs, out, client)`` sends every run to a Dask cluster; each run (``execute``, on a worker)
goes through ``gpo.pipeline.run`` and is evaluated against the recording's ground truth by
``gpo.metrics.evaluate`` (the estimate's first pose placed on the truth's); the client writes, in ``out``:

- ``runs/KEY/trajectory.tum``, ``runs/KEY/trajectory.summary.yaml`` (``OdometryResult.write``),
  ``runs/KEY/config.yaml`` (the run's whole config after its overrides) and ``runs/KEY/row.json`` (its metrics),
  written into ``runs/KEY.partial`` and renamed once complete, and sealed (``runs/KEY.crc32``, ``gpo.io.checksum``);
- ``results.parquet`` and ``results.csv``: one row per run, rewritten as runs finish (at most every
  ``TABLE_EVERY_S``) and at the end, also when the sweep is interrupted.

KEY is a hash of the recording's content, the run's whole config and the code version (``code_version``: the
method layer's sources), so a sweep started again skips every run already finished with that key (``row.json``
with status ``ok`` or ``partial``, intact against its seal) and never repeats it; runs that failed are tried again,
and so is a run whose folder was cut short or corrupted since. A run that fails (a config the schema refuses, an
unreadable bag, a recording without the truth topic) gets a row with status ``failed`` and its ``error`` and the
sweep goes on. A worker lost mid-run is replaced by Dask, which runs the task again elsewhere
(``distributed.scheduler.allowed-failures`` times). A sweep that cannot go on stops with an error that says what
to do, every run finished before kept: the scheduler gone (``ConnectionError``), a run's files that cannot be written
(``OSError``: a full disk, a folder made read-only), Ctrl-C. Run it again to resume.

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
``drift_percent_per_m`` (``gpo.metrics.Evaluation.drift_percent_per_m``), ``heading_rmse_deg``; the frames
``frames``, ``frames_measured``, ``frames_coasted``, ``frames_held``, ``frames_skipped``, ``flags`` (JSON: count of
flagged frames by reason), ``frames_slower_layer``
(measured frames whose flow held a slower layer, ``gpo.motion.klt``), ``frames_overview`` (measured by the whole-view
check, ``gpo.motion.overview``); ``frames_per_second``,
``seconds`` (the odometry's wall time), ``run_seconds`` (the whole run's on its worker: reading the truth, the
odometry, the evaluation) and ``code_version``.
"""

from __future__ import annotations

import contextlib
import json
import shutil
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import pandas as pd
import yaml
from distributed import as_completed
from distributed.client import FutureCancelledError
from tqdm.auto import tqdm

from gpo.batch.runs import (
    FINISHED,
    Outcome,
    Run,
    base_row,
    code_version,
    configured,
    execute,
    recording_digest,
    run_key,
)
from gpo.batch.table import json_number, read_rows, write_table
from gpo.io import checksum
from gpo.pipeline.config import config_to_dict

TABLE_EVERY_S = 10.0  # while a sweep runs its table is rewritten at most this often (each run's row.json at once)
PARTIAL = ".partial"  # a run's folder while its files are written


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
    ``out``. Ctrl-C, a scheduler gone (ConnectionError) or a run's files that cannot be written (OSError) stop the
    sweep with every finished run kept; the same sweep started again resumes."""
    out = Path(out)
    (out / "runs").mkdir(parents=True, exist_ok=True)
    rows = {row["key"]: row for row in read_rows(out)}
    finished = {key for key, row in rows.items() if row["status"] in FINISHED}
    paths = sorted({r.recording for r in runs})
    try:
        digests = dict(zip(paths, client.gather(client.map(_digest_or_error, paths, pure=False)), strict=True))
    except FutureCancelledError as error:
        raise _scheduler_gone(error, out, 0) from None
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
            except FutureCancelledError as error:
                raise _scheduler_gone(error, out, len(executed)) from None
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
    except BaseException:
        _stop(futures, bar)
        with contextlib.suppress(OSError):  # a table that cannot be written now is made from the rows next time
            write_table(out, rows.values())
        raise
    _stop(futures, bar)
    return SweepResult(write_table(out, rows.values()), executed, reused)


def _stop(futures, bar) -> None:
    """Cancel the runs not finished (their workers drop them) and close the progress bar."""
    bar.close()
    for future in futures:
        future.cancel()


def _scheduler_gone(error: FutureCancelledError, out: Path, done: int) -> Exception:
    """The error of a sweep whose client lost its scheduler (Dask cancels every run it waits on), or the
    cancellation itself when it had another reason."""
    if getattr(error, "reason", None) != "scheduler-connection-lost":
        return error
    return ConnectionError(
        f"the Dask scheduler went away ({done} of this sweep's runs finished before): every finished run is kept "
        f"in {out}; start the cluster again and run the same sweep to resume"
    )


def _digest_or_error(path: str) -> str:
    """``recording_digest`` on a worker, or ``error:`` and why it cannot be read there."""
    try:
        return recording_digest(path)
    except OSError as error:
        return f"error:{error}"


def _keep(out: Path, outcome: Outcome, document: dict | None) -> None:
    """Write a run's files into ``out/runs/KEY``: a new folder, sealed and renamed into place. Raises OSError naming
    the folder, with nothing of the run left, when its files cannot be written (a full disk, a read-only folder)."""
    final = out / "runs" / outcome.row["key"]
    partial = final.with_name(final.name + PARTIAL)
    try:
        shutil.rmtree(partial, ignore_errors=True)
        partial.mkdir(parents=True)
        if outcome.trajectory is not None:
            outcome.trajectory.write_tum(partial / "trajectory.tum")
            (partial / "trajectory.summary.yaml").write_text(yaml.safe_dump(outcome.summary, sort_keys=False))
        if document is not None:
            (partial / "config.yaml").write_text(yaml.safe_dump(document, sort_keys=False, default_flow_style=None))
        (partial / "row.json").write_text(json.dumps(outcome.row, indent=1, default=json_number) + "\n")
        checksum.seal(final, of=partial)
        shutil.rmtree(final, ignore_errors=True)
        partial.rename(final)
    except OSError as error:
        shutil.rmtree(partial, ignore_errors=True)
        stopped = OSError(
            f"{final}: the run's files cannot be written ({error.strerror or error}); every run finished before it "
            f"is kept in {out}: make room (or make the folder writable) and run the same sweep again to resume"
        )
        stopped.errno = error.errno
        raise stopped from error
