"""One mutant through one reader: the property, the time limit, the input's hashes, and mutations of bytes.

A ``Target`` is a reader with what it reads from (a strategy of ``Mutant``s) and what a correct result is (``check``).
``examine`` writes a mutant into a fresh folder, reads it under ``time_limit`` and returns a ``Finding`` when the
property fails:

- ``traceback``: an exception other than ``DOCUMENTED_ERRORS`` left the reader (a MemoryError too: the reader runs
  with ``MEMORY_BYTES`` to spare), or the check of its result;
- ``hang``: the reader took more than ``HANG_S`` seconds of processor time, or a read waited ``WAITING`` times as
  long (``time_limit``);
- ``changed input``: a file of the input was changed, added or removed by reading it;
- ``wrong result``: the reader returned what ``check`` finds wrong (an AssertionError, or a documented error of what
  the check does with the result: a config saved and refused when read again);
- ``unclear error``: a refusal that does not name the input's file (checked for the targets that promise it,
  ``Target.names_file``; counted for every target by the campaign).
"""

from __future__ import annotations

import contextlib
import hashlib
import math
import resource
import signal
import struct
import tempfile
import traceback
import warnings
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

from hypothesis import strategies as st

DOCUMENTED_ERRORS = (ValueError, OSError)
"""What a reader may raise on bad input (the command line's exit 1): ValueError, or an OSError for a file it cannot
open."""
HANG_S = 10.0
"""The longest a reader may take on one input, seconds of processor time (``time_limit``)."""
MEMORY_BYTES = 2 * 2**30
"""The most memory a reader may take on one input beyond what the process holds: more is a MemoryError (a
traceback), not the machine's memory filled."""
KINDS = ("traceback", "hang", "changed input", "wrong result", "unclear error")


@dataclass(frozen=True)
class Mutant:
    """An input: its ``files`` (name relative to its folder, bytes), the one the reader is given (``entry``), the
    seed it was made from and what was done to it (``how``, one step a line)."""

    seed: str
    files: tuple[tuple[str, bytes], ...]
    entry: str
    how: tuple[str, ...] = ()

    def write(self, folder: Path) -> Path:
        """The files written into ``folder``; the entry's path."""
        for name, content in self.files:
            (folder / name).parent.mkdir(parents=True, exist_ok=True)
            (folder / name).write_bytes(content)
        return folder / self.entry

    def replaced(self, name: str, content: bytes, step: str) -> Mutant:
        """This mutant with file ``name`` holding ``content``, ``step`` added to ``how``."""
        files = tuple((n, content if n == name else c) for n, c in self.files)
        return Mutant(self.seed, files, self.entry, (*self.how, step))

    def content(self, name: str) -> bytes:
        return dict(self.files)[name]


@dataclass(frozen=True)
class Target:
    """A reader: ``read(path)`` returns its result or raises one of ``DOCUMENTED_ERRORS``; ``check(result, mutant)``
    raises AssertionError when a result is wrong; ``names_file``: every refusal names the input's file."""

    name: str
    mutants: st.SearchStrategy[Mutant]
    read: Callable[[Path], object]
    check: Callable[[object, Mutant], None] | None = None
    names_file: bool = True


@dataclass(frozen=True)
class Finding:
    """What went wrong (``kind``, one of ``KINDS``) reading ``mutant`` with ``target``, and the ``detail``."""

    target: str
    kind: str
    detail: str
    mutant: Mutant


class Hang(BaseException):
    """A reader ran past its time limit (a BaseException, so that no ``except Exception`` swallows it)."""


WAITING = 6
"""How many times ``HANG_S`` of wall time a read may take that waits rather than works."""


@contextlib.contextmanager
def time_limit(seconds: float) -> Iterator[None]:
    """Raise ``Hang`` in the main thread when the block takes more than ``seconds`` of the process's processor time,
    or ``WAITING`` times as long of wall time (a read blocked): a machine busy with other work slows a read down, and
    only the reader's own work tells a hang."""

    def worked(signum, frame):
        raise Hang(f"more than {seconds} s of processor time")

    def waited(signum, frame):
        raise Hang(f"waited more than {WAITING * seconds} s")

    timers = {
        signal.ITIMER_PROF: (signal.SIGPROF, worked, seconds),
        signal.ITIMER_REAL: (signal.SIGALRM, waited, WAITING * seconds),
    }
    previous = {signum: signal.signal(signum, handler) for signum, handler, _ in timers.values()}
    for timer, (_, _, limit) in timers.items():
        signal.setitimer(timer, limit)
    try:
        yield
    finally:
        for timer in timers:
            signal.setitimer(timer, 0)
        for signum, handler in previous.items():
            signal.signal(signum, handler)


@contextlib.contextmanager
def memory_limit(extra: int) -> Iterator[None]:
    """Limit the process's address space to what it maps now and ``extra`` bytes more (Linux), within the block."""
    soft, hard = resource.getrlimit(resource.RLIMIT_AS)
    status = Path("/proc/self/status")
    mapped = (
        next(
            (int(line.split()[1]) * 1024 for line in status.read_text().splitlines() if line.startswith("VmSize:")),
            None,
        )
        if status.exists()
        else None
    )
    if mapped is None:
        yield
        return
    limit = mapped + extra if hard == resource.RLIM_INFINITY else min(hard, mapped + extra)
    resource.setrlimit(resource.RLIMIT_AS, (limit, hard))
    try:
        yield
    finally:
        resource.setrlimit(resource.RLIMIT_AS, (soft, hard))


def parts(calls: dict[str, Callable[[], object]]) -> dict[str, object]:
    """Each call's result, or the documented error it raised: the parts of one input a reader reads one by one."""
    results = {}
    for name, call in calls.items():
        try:
            results[name] = call()
        except DOCUMENTED_ERRORS as error:
            results[name] = error
        except Exception as error:
            error.add_note(f"(reading {name})")
            raise
    return results


def refusals(result) -> list[BaseException]:
    """The documented errors in a result: the error itself, or those among a ``parts`` result's values."""
    if isinstance(result, DOCUMENTED_ERRORS):
        return [result]
    if isinstance(result, dict):
        return [value for value in result.values() if isinstance(value, DOCUMENTED_ERRORS)]
    return []


def hashes(folder: Path) -> dict[str, str]:
    """The sha256 of every file below ``folder``, by its path relative to it."""
    return {
        str(path.relative_to(folder)): hashlib.sha256(path.read_bytes()).hexdigest()
        for path in sorted(folder.rglob("*"))
        if path.is_file()
    }


def examine(target: Target, mutant: Mutant, unclear: bool | None = None) -> tuple[object, Finding | None]:
    """Read ``mutant`` with ``target`` in a folder of its own; (the result or the refusal, a Finding or None).
    ``unclear``: whether a refusal that does not name the file is a finding (default ``target.names_file``)."""
    with tempfile.TemporaryDirectory(prefix="gpo-fuzz-") as name:
        folder = Path(name)
        entry = mutant.write(folder)
        before = hashes(folder)
        result, finding = _read(target, mutant, entry)
        after = hashes(folder)
        if finding is None and after != before:
            changed = sorted(set(before.items()) ^ set(after.items()))
            finding = Finding(target.name, "changed input", f"files changed: {changed}", mutant)
        if finding is None and (target.names_file if unclear is None else unclear):
            vague = [error for error in refusals(result) if folder.name not in str(error)]
            if vague:
                detail = f"names no file: {type(vague[0]).__name__}: {vague[0]}"
                finding = Finding(target.name, "unclear error", detail, mutant)
    return result, finding


def _read(target: Target, mutant: Mutant, entry: Path) -> tuple[object, Finding | None]:
    """The reading under the time limit, warnings aside."""
    try:
        with time_limit(HANG_S), memory_limit(MEMORY_BYTES), warnings.catch_warnings():
            warnings.simplefilter("ignore")
            result = target.read(entry)
    except Hang as hang:
        return hang, Finding(target.name, "hang", str(hang), mutant)
    except DOCUMENTED_ERRORS as error:
        return error, None
    except Exception as error:
        return error, Finding(target.name, "traceback", "".join(traceback.format_exception(error)), mutant)
    if target.check is not None:
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                target.check(result, mutant)
        except AssertionError as wrong:
            return result, Finding(target.name, "wrong result", str(wrong), mutant)
        except DOCUMENTED_ERRORS as wrong:  # e.g. a config read, saved and refused when read again
            detail = f"checking the result: {type(wrong).__name__}: {wrong}"
            return result, Finding(target.name, "wrong result", detail, mutant)
        except Exception as error:
            detail = "checking the result: " + "".join(traceback.format_exception(error))
            return result, Finding(target.name, "traceback", detail, mutant)
    return result, None


# --------------------------------------------------------------------------------------------- mutations of bytes


@st.composite
def byte_mutation(draw, content: bytes, hot: tuple[int, ...] = ()) -> tuple[bytes, str]:
    """``content`` truncated, bit-flipped, overwritten, cut or doubled in a span, or a number no file holds written
    into it (NaN, infinity, a huge count); (the bytes, what was done). Offsets
    fall anywhere, or (half the time, when given) within 64 bytes after one of the ``hot`` offsets: where a record's
    lengths and header are."""
    size = len(content)

    def offset() -> int:
        if hot and draw(st.booleans()):
            return min(size, draw(st.sampled_from(hot)) + draw(st.integers(0, 63)))
        return draw(st.integers(0, size))

    kind = draw(st.sampled_from(("truncate", "flip", "overwrite", "cut", "double", "insert", "number")))
    start = offset()
    if kind == "truncate":
        return content[:start], f"truncated to {start} of {size} bytes"
    if kind == "number":  # a float64 or a count of records no file holds
        value = draw(st.sampled_from((math.nan, math.inf, -math.inf, 1e308, -0.0, 5e-324, 2**31 - 1, 2**32 - 1)))
        packed = struct.pack("<d", value) if isinstance(value, float) else struct.pack("<I", value)
        return content[:start] + packed + content[start + len(packed) :], f"{value!r} written at {start}"
    if kind == "flip":
        flips = [(offset(), draw(st.integers(0, 7))) for _ in range(draw(st.integers(1, 8)))]
        changed = bytearray(content)
        for at, bit in flips:
            if at < size:
                changed[at] ^= 1 << bit
        return bytes(changed), f"bits flipped at (byte, bit) {flips}"
    length = draw(st.integers(1, 256))
    if kind == "overwrite":
        noise = draw(st.binary(min_size=1, max_size=length))
        return content[:start] + noise + content[start + len(noise) :], f"{len(noise)} bytes overwritten at {start}"
    if kind == "cut":
        return content[:start] + content[start + length :], f"{length} bytes cut at {start}"
    if kind == "double":
        return content[:start] + content[start : start + length] * 2 + content[start + length :], (
            f"{length} bytes doubled at {start}"
        )
    noise = draw(st.binary(min_size=1, max_size=length))
    return content[:start] + noise + content[start:], f"{len(noise)} bytes inserted at {start}"


@st.composite
def bytes_mutated(
    draw, mutant: Mutant, hot: Callable[[str, bytes], tuple[int, ...]] | None = None, name: str | None = None
) -> Mutant:
    """``mutant`` with its file ``name`` (default: any of them) changed by ``byte_mutation``; ``hot(name, content)``
    gives the offsets of its records."""
    name = name or draw(st.sampled_from([n for n, _ in mutant.files]))
    content = mutant.content(name)
    changed, step = draw(byte_mutation(content, hot(name, content) if hot else ()))
    return mutant.replaced(name, changed, f"{name}: {step}")
