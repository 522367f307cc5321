"""A sweep's results as one table: ``results.parquet`` and ``results.csv``, a row per run, read and summarised.

Both files are sealed (``gpo.io.checksum``) and so is each run's folder: a run whose folder is cut short or corrupted
is not read (the sweep runs it again), and a table that is is made again from the runs' rows.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pandas as pd

from gpo.io import checksum

RESULTS = ("results.parquet", "results.csv")


def json_number(value):
    """``json.dumps``'s ``default`` for a row: a NumPy scalar as the Python number it holds."""
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(f"cannot write {value!r} into a row")


def read_rows(out) -> list[dict]:
    """Every run's row kept in ``out/runs``: of each run folder that is intact against its seal (one cut short or
    corrupted after it was written, or still being written, counts as not run)."""
    return [json.loads(path.read_text()) for path in sorted(Path(out).glob("runs/*/row.json"))
            if checksum.intact(path.parent)]


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
        try:
            write(temporary, index=False)
            checksum.seal(out / name, of=temporary)
            temporary.replace(out / name)
        except OSError as error:
            temporary.unlink(missing_ok=True)
            raise OSError(f"{out / name} cannot be written ({error.strerror or error}); the runs' rows are kept in "
                          f"{out / 'runs'}: make room and run the sweep again to write it") from error
    return table


def read_table(out) -> pd.DataFrame:
    """The table a sweep wrote into ``out`` (``results.parquet``). Raises FileNotFoundError naming the folder."""
    path = Path(out) / RESULTS[0]
    if not path.is_file() and not read_rows(out):
        raise FileNotFoundError(f"{path}: no sweep results here (python -m gpo sweep SPEC --out {out})")
    if not checksum.intact(path):  # cut short or corrupted since it was written: made again from the runs' rows
        write_table(out)
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
