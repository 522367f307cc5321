"""The command line on mutated inputs: ``gpo info BAG`` and ``gpo evaluate EST.tum TRUTH.tum``, run in this process
(``command_target``) or as a process of its own (``run_process``).

A command's outcome is its exit code and what it printed. It keeps the property when it exits 0 (done), 1 (bad input,
with a message) or 2 (usage), printing no traceback: the command line prints an error it did not expect as its type
and "(--debug shows where it arose)", which counts here as a traceback (``UnexpectedError``).
"""

from __future__ import annotations

import contextlib
import io
import os
import subprocess
import sys
from pathlib import Path

from hypothesis import strategies as st

from fuzzing.bags import bag_mutants
from fuzzing.documents import DATA
from fuzzing.harness import HANG_S, Hang, Target
from fuzzing.tum import tum_mutants
from gpo.cli import main

REPOSITORY = Path(__file__).resolve().parents[2]
UNEXPECTED = "(--debug shows where it arose)"
TRUTH = DATA / "sample_groundtruth.tum"
COMMANDS = {"info": lambda path: ["info", str(path)], "evaluate": lambda path: ["evaluate", str(path), str(TRUTH)]}
"""The arguments of each command given the mutated input's path."""


class UnexpectedError(Exception):
    """A command printed an error of a type it did not expect (a traceback, with --debug)."""


def outcome(code: int, printed: str) -> tuple[int, str]:
    """(exit code, what was printed), or UnexpectedError when it is not 0, 1 or 2 or the error was unexpected."""
    if code not in (0, 1, 2) or UNEXPECTED in printed or "Traceback" in printed:
        raise UnexpectedError(f"exit {code}:\n{printed[-3000:]}")
    if code == 1 and "error: " not in printed:
        raise UnexpectedError(f"exit 1 without a message:\n{printed[-3000:]}")
    return code, printed


def run_here(command: str, path: Path) -> tuple[int, str]:
    """``python -m gpo COMMAND`` on ``path`` in this process."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(COMMANDS[command](path))
    return outcome(code, out.getvalue() + err.getvalue())


def run_process(command: str, path: Path) -> tuple[int, str]:
    """``python -m gpo COMMAND`` on ``path`` as a process of its own, ended after ``HANG_S`` seconds (a hang)."""
    environment = {**os.environ, "PYTHONPATH": str(REPOSITORY)}
    try:
        done = subprocess.run(
            [sys.executable, "-m", "gpo", *COMMANDS[command](path)],
            capture_output=True, text=True, timeout=HANG_S, env=environment, errors="replace",
        )
    except subprocess.TimeoutExpired:
        raise Hang(f"python -m gpo {command} ran more than {HANG_S} s") from None
    return outcome(done.returncode, done.stdout + done.stderr)


def command_target(command: str) -> Target:
    """The command ``command`` in this process, on the mutants of what it reads."""
    mutants = bag_mutants("ros1") if command == "info" else st.deferred(tum_mutants)
    return Target(f"gpo {command}", mutants, lambda path: run_here(command, path), names_file=False)


COMMAND_TARGETS = [command_target(command) for command in COMMANDS]
