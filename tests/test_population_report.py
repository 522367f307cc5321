"""The population benchmark's report: which listed runs name their cause."""

import importlib.util
import json
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from gpo.io.trajectory import Trajectory

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
    return pd.Series({"key": "k", "recording": "draw000-fisheye", "status": "ok", "error": None, "distance_m": 10.0,
                      "flags": "{}",
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


def straight(steps_deg) -> tuple[Trajectory, Trajectory]:
    """A truth driving 1 m/s along x for one metre a step, and an estimate on it whose heading error grows by each of
    ``steps_deg`` over its metre."""
    metres = len(steps_deg)
    x = np.linspace(0.0, metres, 100 * metres + 1)
    stamps = np.round(x * 1e9).astype(np.int64)
    error = np.interp(x, np.arange(metres + 1), np.radians(np.r_[0.0, np.cumsum(steps_deg)]))
    return Trajectory.from_planar(stamps, x, 0 * x, error), Trajectory.from_planar(stamps, x, 0 * x, 0 * x)


def test_heading_steps_tell_a_steady_drift_from_a_random_walk(population):
    drift = population.heading_steps(*straight([0.1 + 0.03 * (-1) ** k for k in range(11)]))
    assert drift["steps"] == 11 and drift["steady"]
    assert drift["mean_deg"] == pytest.approx(0.1 + 0.03 / 11, abs=1e-3)  # six steps of +0.03, five of -0.03
    assert drift["sd_deg"] == pytest.approx(0.03 * np.sqrt(11 / 10), abs=1e-3)  # alternating +-0.03, ddof 1
    walk = population.heading_steps(*straight([0.2 * (-1) ** k for k in range(11)]))
    assert not walk["steady"] and abs(walk["t"]) < 1  # final error 0.2 deg, one step's worth: a walk
    # the final heading error is the steps' sum: t is it over the walk's standard deviation, sd sqrt(n)
    assert walk["t"] == pytest.approx(0.2 / (walk["sd_deg"] * np.sqrt(11)), rel=0.02)
    assert population.heading_steps(*straight([0.1, 0.1])) is None  # too few steps to say


def test_each_runs_heading_steps_read_its_path_and_its_draws_truth(population, tmp_path):
    estimate, truth = straight([0.1 + 0.03 * (-1) ** k for k in range(11)])
    (tmp_path / "runs" / "k").mkdir(parents=True)
    (tmp_path / "truth").mkdir()
    estimate.write_tum(tmp_path / "runs" / "k" / "trajectory.tum")
    truth.write_tum(tmp_path / "truth" / "draw000-fisheye.tum")
    table = pd.DataFrame([row(), row(key="j", recording="draw001-downward")])
    steps = population.runs_heading_steps(table, tmp_path)
    assert steps["k"]["steady"] and steps["k"]["steps"] == 11
    assert steps["j"] is None  # neither its path nor its draw's truth


def test_the_fused_route_is_compared_with_the_better_of_its_sources(population):
    draws = [population.draw(seed) for seed in (0, 2, 4)]  # fisheye draws, each with a drifting tracking camera
    table = pd.DataFrame(
        [(d.label, method, error, 2 * error) for d, errors in zip(draws, ((0.05, 0.04), (0.20, 0.90), (0.30, 1.00)),
                                                                   strict=True)
         for method, error in zip(("fused", "gpo-exact"), errors, strict=True)],
        columns=["recording", "method", "final_error_percent", "final_heading_deg"],
    )
    cameras = {d.label: {"final_error_percent": camera, "final_heading_deg": -camera}
               for d, camera in zip(draws, (0.3, 0.1, 0.4), strict=True)}
    report = population.sources_report(table, draws, cameras)
    assert report["floor_method"] == "gpo-exact" and report["draws"] == 3
    assert report["worse"] == 2  # 0.05 over the floor's 0.04, 0.20 over the camera's 0.1; 0.30 under both
    assert report["worst_draw"] == draws[1].label
    assert report["runs"][draws[1].label]["over_better"] == pytest.approx(0.10)
    assert report["runs"][draws[1].label]["ratio"] == pytest.approx(2.0)
    # headings (degrees): fused 0.4, the floor 1.8, the camera -0.1: the fused path's is nearer the camera's
    assert report["runs"][draws[1].label]["heading_deg"] == {"fused": 0.4, "gpo-exact": 1.8, "camera": -0.1}
    assert report["runs"][draws[1].label]["heading_nearer"] == "camera"
    assert report["runs"][draws[0].label]["heading_nearer"] == "gpo-exact"  # 0.1 beside 0.08, not -0.3


def test_the_methods_heading_steps_are_summed_up_over_the_runs_measured(population):
    steps = [None, {"sd_deg": 0.1, "steady": False}, {"sd_deg": 0.3, "steady": True}]
    assert population.steps_summary(steps) == {"runs": 2, "median_sd_deg": 0.2, "steady": 1}
    assert population.steps_summary([None]) == {"runs": 0, "median_sd_deg": None, "steady": 0}
