"""What every command shares: the exit codes, an option's positive number, a figure written through a temporary
name."""

from __future__ import annotations

import argparse
import math
import os
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


def save_figure(fig: Figure, path: Path, dpi: int) -> Path:
    """``fig`` written to ``path`` through a temporary name of the same suffix (which names the format)."""
    return write_with(path, lambda temporary: fig.savefig(temporary, dpi=dpi, bbox_inches="tight"))


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
