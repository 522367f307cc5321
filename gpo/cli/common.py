"""What every command shares: the exit codes, how Ctrl-C and SIGTERM stop it (``Interruption``), an option's positive
number, a figure written through a temporary name."""

from __future__ import annotations

import argparse
import math
import os
import sys
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from gpo.io.outputs import write_with

if TYPE_CHECKING:
    from matplotlib.figure import Figure

EXIT_CODES = """exit codes:
  0    done
  1    bad input (the error names the file, field or topic), or a result the command flags
  2    usage: an unknown command or option, or an option's value of the wrong kind
  130  interrupted (Ctrl-C, SIGTERM): run writes the frames done, marked interrupted
--debug shows the traceback of an error."""


INTERRUPTED = 130


class Interruption:
    """The handler of Ctrl-C (SIGINT) and SIGTERM while a command runs. The first raises KeyboardInterrupt where the
    command is (a run then writes the frames it did, marked interrupted; the command exits ``INTERRUPTED``); every
    later one is counted and waited out, so that what the first left to write is written whole whatever they do
    (``kill -9`` still stops at once, and leaves the files already there whole: ``gpo.io.outputs``)."""

    def __init__(self):
        self.count = 0

    def __call__(self, signum, frame) -> None:
        self.count += 1
        if self.count == 1:
            raise KeyboardInterrupt
        if self.count == 2:
            print(
                "interrupted again: what was computed is being written first (kill -9 stops at once, and leaves the "
                "files already there whole)",
                file=sys.stderr,
            )


def figure_writer(fig: Figure, dpi: int) -> Callable[[Path], object]:
    """What writes ``fig`` at a path (of the suffix that names its format), as ``gpo.io.outputs`` writers do."""
    return lambda path: fig.savefig(path, dpi=dpi, bbox_inches="tight")


def save_figure(fig: Figure, path: Path, dpi: int) -> Path:
    """``fig`` written to ``path`` through a temporary name of the same suffix (which names the format)."""
    return write_with(path, figure_writer(fig, dpi))


def positive(text: str) -> float:
    """An option's number: finite and > 0 (argparse turns the error into a usage error)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number > 0, got {text!r}") from None
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"expected a finite number > 0, got {text!r}")
    return value


def whole_number(text: str) -> int:
    """An option's whole number >= 1 (argparse turns the error into a usage error)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number >= 1, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected a whole number >= 1, got {text!r}")
    return value


def available_cores() -> int:
    """The processor cores this process may run on."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1
