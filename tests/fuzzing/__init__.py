"""Fuzzing gpo's readers: mutated bags, configs, calibrations, sweep specs and TUM files, and the property each
reader keeps on them (``harness``: a clear error or a correct result; never a traceback, never a hang over
``HANG_S`` seconds, never a changed input).

``TARGETS`` holds every reader with its strategy of mutants. tests/test_fuzz.py draws a bounded, seeded number of
them in CI; benchmarks/fuzz_campaign.py draws many more and prints what it tried and found. Test code only: gpo
never imports it, nor hypothesis.
"""

from fuzzing.bags import BAG_TARGETS
from fuzzing.commands import COMMAND_TARGETS
from fuzzing.harness import DOCUMENTED_ERRORS, HANG_S, KINDS, Finding, Mutant, Target, examine
from fuzzing.readers import READER_TARGETS
from fuzzing.tum import TUM_TARGETS

TARGETS = {target.name: target for target in (*BAG_TARGETS, *READER_TARGETS, *TUM_TARGETS, *COMMAND_TARGETS)}
"""Every reader fuzzed, and the commands that read bags and TUM files, by name."""

__all__ = ["DOCUMENTED_ERRORS", "HANG_S", "KINDS", "TARGETS", "Finding", "Mutant", "Target", "examine"]
