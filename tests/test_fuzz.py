"""Fuzzing as a test: every reader of what users give gpo (ROS1 and ROS2 bags, run configs, Kalibr, Basalt, BoofCV
and camera_info calibrations, sweep specs, TUM files) and the commands that read bags and TUM files, fed mutated
inputs (``tests/fuzzing``): each gives a clear error or a correct result, never a traceback, never a hang over
``HANG_S`` seconds, never a changed input.

A bounded number of inputs per reader, drawn by hypothesis with the suite's derandomised profile (tests/conftest.py):
the same inputs on every run. benchmarks/fuzz_campaign.py draws many more.
"""

import os
import subprocess
import sys
import time
from pathlib import Path

import pytest
from fuzzing import TARGETS, Finding, examine
from fuzzing.bags import bag_mutants
from fuzzing.commands import run_process
from fuzzing.harness import Hang, Mutant, Target, time_limit
from fuzzing.tum import tum_mutants
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

EXAMPLES = {
    "ros1": 30,
    "ros2-sqlite3": 30,
    "ros2-mcap": 30,
    "config": 60,
    "kalibr": 60,
    "basalt": 60,
    "boofcv": 60,
    "camera_info": 60,
    "sweep spec": 60,
    "tum": 60,
    "tum (evaluate)": 60,
    "gpo info": 20,
    "gpo evaluate": 20,
}
"""Inputs per reader in CI, so that the whole file takes well under 60 s: measured 22 s of processor time (43 s in
pytest, 56 s with its start, at a load of 8.5 on this machine's two cores)."""
SLOW_TO_DRAW = [HealthCheck.too_slow, HealthCheck.data_too_large]  # bags are drawn from seeds of tens of kB


def shown(finding: Finding) -> str:
    mutant = finding.mutant
    return f"{finding.kind} in {finding.target}, seed {mutant.seed}, entry {mutant.entry}:\n" + "\n".join(
        [*mutant.how, finding.detail]
    )


def test_every_reader_is_fuzzed():
    assert set(EXAMPLES) == set(TARGETS)


@pytest.mark.parametrize("name", list(EXAMPLES))
def test_a_reader_gives_a_clear_error_or_a_correct_result(name):
    target = TARGETS[name]

    @settings(max_examples=EXAMPLES[name], suppress_health_check=SLOW_TO_DRAW)
    @given(target.mutants)
    def read(mutant: Mutant) -> None:
        _, finding = examine(target, mutant)
        assert finding is None, shown(finding)

    read()


@pytest.mark.parametrize(("command", "mutants"), [("info", bag_mutants("ros1")), ("evaluate", tum_mutants())])
def test_a_command_as_a_process_exits_cleanly(command, mutants):
    """The command run as users run it, its own process ended after HANG_S seconds."""
    target = Target(f"python -m gpo {command}", mutants, lambda path: run_process(command, path), names_file=False)

    @settings(max_examples=2, suppress_health_check=SLOW_TO_DRAW)
    @given(target.mutants)
    def run(mutant: Mutant) -> None:
        _, finding = examine(target, mutant)
        assert finding is None, shown(finding)

    run()


def _raising_check(error: Exception):
    def check(result, mutant):
        raise error

    return check


@pytest.mark.parametrize(
    ("error", "kind"),
    [(ValueError("the saved config does not load again"), "wrong result"), (KeyError("no such part"), "traceback")],
)
def test_a_check_that_fails_otherwise_than_by_assertion_is_a_finding(error, kind):
    """What goes wrong inside the harness (the config target's round trip raising ValueError) is reported as a
    finding of its kind, with the check named, never raised into the campaign."""
    target = Target("one file", st.nothing(), lambda path: path.read_text(), _raising_check(error))
    result, finding = examine(target, Mutant("seed", (("file.txt", b"text"),), "file.txt"))
    assert result == "text"
    assert finding is not None and finding.kind == kind
    assert "checking the result" in finding.detail and str(error.args[0]) in finding.detail


def test_the_campaign_takes_several_seeds_and_prints_each_targets_inputs_and_findings(tmp_path):
    campaign = Path(__file__).parents[1] / "benchmarks" / "fuzz_campaign.py"
    done = subprocess.run(
        [
            sys.executable,
            str(campaign),
            "--examples",
            "4",
            "--seed",
            "7",
            "8",
            "--target",
            "tum",
            "--target",
            "camera_info",
            "--out",
            str(tmp_path),
        ],
        capture_output=True,
        text=True,
        timeout=300,
        env={**os.environ, "PYTHONPATH": str(campaign.parents[1])},
    )
    assert done.returncode == 0, done.stdout + done.stderr
    lines = done.stdout.splitlines()
    assert "4 inputs per target and seed, seeds 7, 8" in lines[0]
    for name in ("tum", "camera_info"):
        closing = next(line for line in lines if line.startswith(f"{name}: "))
        assert "8 inputs (seeds 7, 8)" in closing and "findings 0" in closing, closing
    assert lines[-1].startswith("16 inputs in ") and "traceback 0, hang 0, changed input 0, wrong result 0" in lines[-1]


def test_a_hang_is_processor_time_or_a_read_waiting_far_longer():
    """A machine busy with other work slows a read without making it hang: the limit is the reader's processor time,
    and six times as long of wall time for a read that waits without working."""
    with pytest.raises(Hang, match="processor"), time_limit(0.1):
        while True:
            pass
    with time_limit(0.1):
        time.sleep(0.3)  # waiting, not working, and within six times the limit
    with pytest.raises(Hang, match="waited"), time_limit(0.1):
        time.sleep(5)
