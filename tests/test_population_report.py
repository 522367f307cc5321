"""The population benchmark's report: which listed runs name their cause."""

import importlib.util
import json
import sys
from pathlib import Path

import pandas as pd
import pytest

BENCHMARKS = Path(__file__).resolve().parents[1] / "benchmarks"


@pytest.fixture(scope="module")
def population():
    sys.path.insert(0, str(BENCHMARKS))  # population.py imports its sibling correlation_peer
    try:
        spec = importlib.util.spec_from_file_location("population_benchmark", BENCHMARKS / "population.py")
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
    finally:
        sys.path.remove(str(BENCHMARKS))
    return module


def row(**columns) -> pd.Series:
    return pd.Series({"key": "k", "status": "ok", "error": None, "distance_m": 10.0, "flags": "{}",
                      "frames_coasted": 0, "frames_slower_layer": 0, **columns})


@pytest.mark.parametrize(
    ("columns", "explained"),
    [
        ({}, False),
        ({"frames_slower_layer": 40}, False),  # seen on runs that end right too: not a cause by itself
        ({"flags": json.dumps({"too few tracks kept": 3})}, True),
        ({"frames_coasted": 2}, True),
        ({"status": "failed", "error": "cannot read the bag"}, True),
    ],
)
def test_a_run_is_explained_by_a_flag_a_frame_not_measured_or_its_status(population, tmp_path, columns, explained):
    assert population.explanation(row(**columns), tmp_path)["explained"] is explained


def test_a_caution_in_the_runs_summary_explains_it(population, tmp_path):
    summary = tmp_path / "runs" / "k" / "trajectory.summary.yaml"
    summary.parent.mkdir(parents=True)
    summary.write_text("distance_m: 9.5\ncautions: [the filter refused 3 increments]\n")
    explained = population.explanation(row(), tmp_path)
    assert explained["explained"] and explained["distance_ratio"] == 0.95
