"""TUM files to fuzz the trajectory reader with: ``Trajectory.read_tum`` and the command line's ``read_tum``.

The seeds are the first 30 poses of the sample's ground truth and tracking odometry (``data/``), mutated line by line
and field by field (odd numbers and words in a field, fields added or taken away, lines dropped, doubled or swapped,
other separators and line ends), as text (``fuzzing.documents.text_mutated``) or as bytes. A trajectory read is
correct when it holds every pose line, each number as Python's ``Decimal`` and ``float`` read it.
"""

from __future__ import annotations

import functools
from decimal import Decimal, InvalidOperation

import numpy as np
from hypothesis import strategies as st

from fuzzing.documents import DATA, file_mutants, seed, text_mutated
from fuzzing.harness import Mutant, Target, bytes_mutated
from gpo.cli.evaluate import read_tum
from gpo.io.trajectory import Trajectory

TOKENS = ("nan", "inf", "-inf", "1e400", "-1e400", "1e30", "1e19", "9" * 30, "-1", "-0", "0x10", "1_000", "", "abc",
          "1.2.3", "+", "-", ".", "1e", "1e-400", "\u0661\u0662", "1,5", "1700000000.1234567891234", "+1.5e+3")
"""Fields put into a TUM line."""


@functools.cache
def tum_seeds() -> dict[str, Mutant]:
    """The first 30 poses of the sample's truth and of its tracking odometry (with its comment line)."""
    return {
        name: seed(name, {"poses.tum": "".join((DATA / name).read_text().splitlines(keepends=True)[:31])}, "poses.tum")
        for name in ("sample_groundtruth.tum", "sample_tracking_odometry.tum")
    }


@st.composite
def tum_mutated(draw, mutant: Mutant, name: str) -> Mutant:
    """``mutant``'s TUM file with a line dropped, doubled or moved, a field replaced, added or taken away, its
    separators or line ends changed, or its bytes mutated."""
    kind = draw(st.sampled_from(("field", "field", "line", "separators", "text", "bytes")))
    if kind == "bytes":
        return draw(bytes_mutated(mutant, name=name))
    text = mutant.content(name).decode("utf-8", errors="replace")
    if kind == "text":
        changed, step = draw(text_mutated(text))
        return mutant.replaced(name, changed.encode(), f"{name}: {step}")
    lines = text.splitlines(keepends=True) or [""]
    at = draw(st.integers(0, len(lines) - 1))
    if kind == "field":
        fields = lines[at].split()
        token = draw(st.one_of(st.sampled_from(TOKENS), st.text(max_size=8), st.floats().map(repr)))
        where = draw(st.integers(0, len(fields)))
        how = draw(st.sampled_from(("replace", "add", "remove")))
        if how == "replace" and where < len(fields):
            fields[where] = token
        elif how == "remove" and where < len(fields):
            del fields[where]
        else:
            fields.insert(where, token)
        lines[at] = " ".join(fields) + "\n"
        step = f"line {at + 1}, field {where}: {how} {token!r}"
    elif kind == "line":
        other = draw(st.integers(0, len(lines) - 1))
        how = draw(st.sampled_from(("drop", "double", "swap")))
        if how == "drop":
            del lines[at]
        elif how == "double":
            lines.insert(at, lines[at])
        else:
            lines[at], lines[other] = lines[other], lines[at]
        step = f"line {at + 1}: {how} (with {other + 1})"
    else:
        separator = draw(st.sampled_from(("\t", ",", ", ", "  ", ";", "\r\n", "\r", "\x0c", "\u2028")))
        lines = [line.replace(" ", separator) if "\n" not in separator and "\r" not in separator
                 else line.rstrip("\n") + separator for line in lines]
        step = f"separators or line ends {separator!r}"
    return mutant.replaced(name, "".join(lines).encode(), f"{name}: {step}")


def _data_lines(content: bytes) -> list[list[str]]:
    """The fields of every line that is neither blank nor a comment, as Python splits text into lines and words."""
    text = content.decode("utf-8").replace("\r\n", "\n").replace("\r", "\n")
    lines = [line.strip() for line in text.splitlines()]
    return [line.replace(",", " ").split() for line in lines if line and not line.startswith("#")]


def _stamp_ns(text: str) -> Decimal:
    """A stamp in seconds as nanoseconds, by ``Decimal``; AssertionError for what is no number."""
    try:
        stamp = Decimal(text) * 10**9
    except InvalidOperation:
        raise AssertionError(f"the stamp {text!r} is no number, but was read") from None
    assert stamp.is_finite(), f"the stamp {text!r} is not finite, but was read"
    return stamp


def check_tum(trajectory: Trajectory, mutant: Mutant, once: bool = False) -> None:
    """Every pose line read, none skipped (``once``: of a pose repeated at one stamp, the first, as the command
    line's reader does); each number as Python's ``Decimal`` and ``float`` read it."""
    lines = _data_lines(mutant.content("poses.tum"))
    if once:
        lines = [fields for k, fields in enumerate(lines)
                 if k == 0 or int(_stamp_ns(fields[0])) != int(_stamp_ns(lines[k - 1][0]))]
    assert len(trajectory) == len(lines), f"{len(lines)} pose lines, {len(trajectory)} poses read"
    for k, fields in enumerate(lines):
        assert np.array_equal(trajectory.positions[k], [float(v) for v in fields[1:4]]), f"pose {k}: position"
        quaternion = np.array([float(v) for v in fields[4:8]])
        assert np.allclose(trajectory.quaternions[k], quaternion / np.linalg.norm(quaternion), rtol=0, atol=1e-12), (
            f"pose {k}: quaternion")
        stamp = _stamp_ns(fields[0])
        assert abs(Decimal(int(trajectory.stamps_ns[k])) - stamp) <= max(1, abs(stamp) * Decimal("1e-15")), (
            f"pose {k}: the stamp {fields[0]!r} was read as {trajectory.stamps_ns[k]} ns")


def tum_mutants():
    """A seed TUM file with up to three mutations."""
    return file_mutants(tum_seeds(), mutators={".tum": tum_mutated})


TUM_TARGETS = [
    Target("tum", st.deferred(tum_mutants), Trajectory.read_tum, check_tum, names_file=False),
    Target("tum (evaluate)", st.deferred(tum_mutants), read_tum,
           lambda trajectory, mutant: check_tum(trajectory, mutant, once=True)),
]
"""The TUM readers. ``Trajectory.read_tum`` leaves naming the file to its callers (the command line's ``read_tum``
names it)."""
