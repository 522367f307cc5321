"""The range a motion stage's parameter may take on a real rig, checked with the words an error shows: its bounds and
its unit (``KLTParameters``, ``FeatureParameters``; the config's schema reports their errors by key)."""

from __future__ import annotations

import numbers


def in_range(value, low, high, unit: str = "", whole: bool = False, low_open: bool = False) -> tuple[bool, str]:
    """Whether ``value`` is a number (an integer when ``whole``; True and False are not numbers here) from ``low`` (over
    it when ``low_open``) to ``high``, and that range in words with its ``unit`` (e.g. " px")."""
    kind = numbers.Integral if whole else numbers.Real
    ok = isinstance(value, kind) and not isinstance(value, bool)
    ok = bool(ok and (low < value if low_open else low <= value) and value <= high)
    return ok, f"{'a whole number ' if whole else 'a number '}{'over' if low_open else 'from'} {low} to {high}{unit}"
