"""Fuzzing as a test: every reader of what users give gpo (ROS1 and ROS2 bags, run configs, Kalibr, Basalt, BoofCV
and camera_info calibrations, sweep specs, TUM files) and the commands that read bags and TUM files, fed mutated
inputs (``tests/fuzzing``): each gives a clear error or a correct result, never a traceback, never a hang over
``HANG_S`` seconds, never a changed input.

A bounded number of inputs per reader, drawn by hypothesis with the suite's derandomised profile (tests/conftest.py):
the same inputs on every run. benchmarks/fuzz_campaign.py draws many more.
"""

import pytest
from fuzzing import TARGETS, Finding, examine
from fuzzing.bags import bag_mutants
from fuzzing.commands import run_process
from fuzzing.harness import Mutant, Target
from fuzzing.tum import tum_mutants
from hypothesis import HealthCheck, given, settings

EXAMPLES = {
    "ros1": 30, "ros2-sqlite3": 30, "ros2-mcap": 30, "config": 60, "kalibr": 60, "basalt": 60, "boofcv": 60,
    "camera_info": 60, "sweep spec": 60, "tum": 60, "tum (evaluate)": 60, "gpo info": 20, "gpo evaluate": 20,
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


@pytest.mark.parametrize(
    ("command", "mutants"), [("info", bag_mutants("ros1")), ("evaluate", tum_mutants())]
)
def test_a_command_as_a_process_exits_cleanly(command, mutants):
    """The command run as users run it, its own process ended after HANG_S seconds."""
    target = Target(f"python -m gpo {command}", mutants, lambda path: run_process(command, path), names_file=False)

    @settings(max_examples=2, suppress_health_check=SLOW_TO_DRAW)
    @given(target.mutants)
    def run(mutant: Mutant) -> None:
        _, finding = examine(target, mutant)
        assert finding is None, shown(finding)

    run()
