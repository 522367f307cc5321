"""Files as the chapters show them: every decimal number at the precision its computation supports.

A file the suite writes keeps every digit of its floats (a calibration, a rig, a trajectory). Those last digits
follow the machine's floating-point path (its BLAS kernel, its SIMD level), so a chapter that printed them would
print another text on another machine. The chapters print such files through ``rounded``: the same text with each
decimal number rounded, so that what a reader sees, and what CI compares, is what any machine computes.
"""

from __future__ import annotations

import re

STAMP_DIGITS = 6  # a number with more integer digits is a stamp, shown whole
DECIMAL = re.compile(r"(?<![\w.])-?\d+\.\d+(?:[eE][-+]?\d+)?|(?<![\w.])-?\d+[eE][-+]?\d+")


def rounded(text: str, significant: int | None = None, decimals: int | None = None) -> str:
    """``text`` with every decimal number rounded to ``significant`` digits or to ``decimals`` places.

    Whole numbers are kept, and so are numbers with more integer digits than ``significant`` or than six (a stamp in
    seconds such as ``1700000000.033333333``). A number that rounds to zero is written without its sign.
    """
    if (significant is None) == (decimals is None):
        raise ValueError("give either significant or decimals")

    def replace(match: re.Match) -> str:
        number = match.group()
        value = float(number)
        integer_digits = len(re.split(r"[.eE]", number.lstrip("-"))[0])
        if integer_digits > min(significant or STAMP_DIGITS, STAMP_DIGITS):
            return number
        shown = f"{value:.{significant}g}" if significant is not None else f"{value:.{decimals}f}"
        if not any(mark in shown for mark in ".en"):
            shown += ".0"  # still a decimal number, as in the file
        return shown[1:] if shown.startswith("-") and float(shown) == 0.0 else shown

    return DECIMAL.sub(replace, text)
