"""The range a parameter may take on a real rig, checked with the words an error shows: its bounds and its unit.

One mechanism for every number a run config holds: the motion stages' parameters (``KLTParameters``,
``FeatureParameters``), the fusion's (``FusionSettings``) and the config file's own sections
(``gpo.pipeline.schema``). ``in_range`` says whether a value lies in its range and the range in words;
``check_rules`` refuses the values outside theirs with ``OutOfRange``, whose every line reads
"``name`` must be ``what is expected``, got ``value``" (the schema puts the key's section in front of the name).
"""

from __future__ import annotations

import numbers

REACH_M = 50
"""A sensor, or the floor it sees, lies within this many metres of base_link's origin on a real robot."""
MAX_IMAGE_PX = 20_000
"""No camera's image is wider or taller, pixels."""


def in_range(value, low, high, unit: str = "", whole: bool = False, low_open: bool = False) -> tuple[bool, str]:
    """Whether ``value`` is a number (an integer when ``whole``; True and False are not numbers here) from ``low`` (over
    it when ``low_open``) to ``high``, and that range in words with its ``unit`` (e.g. " px")."""
    kind = numbers.Integral if whole else numbers.Real
    ok = isinstance(value, kind) and not isinstance(value, bool)
    ok = bool(ok and (low < value if low_open else low <= value) and value <= high)
    return ok, f"{'a whole number ' if whole else 'a number '}{'over' if low_open else 'from'} {low} to {high}{unit}"


class OutOfRange(ValueError):
    """Values outside what is allowed: ``problems``, each (name, value, what is expected); the name may be "" when
    the reader knows it (a config key)."""

    def __init__(self, problems: list[tuple[str, object, str]]):
        self.problems = problems
        super().__init__("; ".join(self.lines()))

    def lines(self, prefix: str = "") -> list[str]:
        """Each problem as "``prefix.name`` must be ..., got ..." (``prefix`` alone for a name of "")."""
        return [
            f"{'.'.join(part for part in (prefix, name) if part)} must be {expected}, got {value!r}"
            for name, value, expected in self.problems
        ]


def check_rules(rules: dict[str, tuple[bool, str]], owner, error: type[OutOfRange] = OutOfRange) -> None:
    """Raise ``error`` naming every rule of ``rules`` (name -> (whether the value is allowed, what is expected)) that
    ``owner``'s attribute of that name breaks."""
    problems = [(name, getattr(owner, name), expected) for name, (ok, expected) in rules.items() if not ok]
    if problems:
        raise error(problems)


def check_value(value, low, high, unit: str = "", whole: bool = False, low_open: bool = False):
    """``value`` when ``in_range``, else ``OutOfRange`` naming it with its range (for a reader that knows its name)."""
    ok, expected = in_range(value, low, high, unit, whole, low_open)
    if not ok:
        raise OutOfRange([("", value, expected)])
    return value
