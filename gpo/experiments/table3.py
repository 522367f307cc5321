"""The first paper's Table 3 on the simulated short paths: GPO's relative translation error with the median motion
vector against the mean, on three recordings standing for the paper's Test1-Test3.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gpo.io.bag import Recording
from gpo.metrics import final_error, relative_translation_errors
from gpo.pipeline.run import run
from gpo.sim.record import GROUND_TRUTH_TOPIC, recording

TABLE3_TESTS = {"Test1": "short1", "Test2": "short2", "Test3": "short3"}  # the paper's tests -> the presets run here


TABLE3_VECTORS = ("mean", "median")

STATISTICS = (("min", np.min), ("max", np.max), ("avg", np.mean))  # of a test's relative translation errors


@dataclass(frozen=True)
class PaperTable3:
    """The first paper's Table 3 as it prints it: GPO's relative translation error (metres) with the mean and with the
    median motion vector, its minimum, maximum and average on each test (``tests``, of ``lengths_m``) and over the
    three (``values[vector, statistic]``: the three tests, then the average column)."""

    tests: tuple[str, ...]
    lengths_m: tuple[float, ...]
    values: dict[tuple[str, str], tuple[float, ...]]

    def average(self, vector: str) -> float:
        """The table's average relative translation error with ``vector`` over the tests, metres."""
        return self.values[vector, "avg"][-1]

    def format(self) -> str:
        """The paper's Table 3 in the layout of ``Table3.format``."""
        blocks = {vector: {label: self.values[vector, label] for label, _ in STATISTICS} for vector in TABLE3_VECTORS}
        title = "the paper's Table 3: relative translation error [m] of GPO; path length [m] in parentheses"
        return "\n".join(format_blocks(title, self.tests, self.lengths_m, blocks))


def format_blocks(title: str, tests, lengths_m, blocks: dict[str, dict[str, tuple]]) -> list[str]:
    """Table 3's layout: ``title``, the tests with their path lengths (m), then per vector its rows of
    ``blocks[vector][label]``: one value per test and the average last (metres, four decimals)."""
    lines = [title]
    lengths = "".join(f"{test:>9} ({length:.2f})" for test, length in zip(tests, lengths_m, strict=True))
    lines.append(f"{'':20}{lengths}{'Average':>10}")
    for vector, rows in blocks.items():
        for k, (label, (*cells, average)) in enumerate(rows.items()):
            name = f"GPO ({vector})" if k == 0 else ""
            lines.append(f"{name:<14}{label:<11}{''.join(f'{value:15.4f}' for value in cells)}{average:10.4f}")
    return lines


PAPER_TABLE3 = PaperTable3(
    tests=("Test1", "Test2", "Test3"),
    lengths_m=(3.8832, 2.2896, 5.4559),
    values={
        ("mean", "min"): (0.0018, 0.0115, 0.0533, 0.0222),
        ("mean", "max"): (0.1694, 0.1736, 0.1194, 0.1541),
        ("mean", "avg"): (0.0435, 0.0876, 0.0886, 0.0732),
        ("median", "min"): (0.0019, 0.0040, 0.0182, 0.0080),
        ("median", "max"): (0.0787, 0.0329, 0.0731, 0.0615),
        ("median", "avg"): (0.0337, 0.0165, 0.0485, 0.0329),
    },
)
"""The first paper's Table 3, every row and test as printed."""


@dataclass(frozen=True)
class Table3:
    """The first paper's Table 3 on the simulated 2-5 m paths: GPO (``method``, the paper's ``gpo`` unless another is
    chosen) with the mean and with the median motion vector on each test. ``results[test, vector]`` the runs
    (``gpo.pipeline.run.OdometryResult``), ``truths[test]`` their ground truth, ``errors[test, vector]`` the final
    errors (``gpo.metrics.FinalError``) and ``relative[test, vector]`` the relative translation errors of 1 m segments,
    metres."""

    tests: dict[str, str]
    results: dict
    truths: dict
    errors: dict
    relative: dict
    method: str = "gpo"

    def format(self) -> str:
        """The table as the paper lays it out, the average beside, and the ratio of the two vectors' averages."""
        tests = self.tests
        blocks = {}
        for vector in TABLE3_VECTORS:
            relative = [self.relative[test, vector] for test in tests]
            rows = {label: [statistic(errors) for errors in relative] for label, statistic in STATISTICS}
            rows["final error"] = [self.errors[test, vector].position_m for test in tests]
            blocks[vector] = {label: (*values, np.mean(values)) for label, values in rows.items()}
        title = (f"Table 3: relative translation error [m] of GPO (method {self.method}, 1 m segments); path length "
                 "[m] in parentheses")
        lengths = [self.errors[test, "median"].distance_m for test in tests]
        lines = format_blocks(title, tests, lengths, blocks)
        averages = {v: np.mean([self.relative[test, v].mean() for test in tests]) for v in TABLE3_VECTORS}
        paper = {vector: PAPER_TABLE3.average(vector) for vector in TABLE3_VECTORS}
        lines.append(
            f"the paper: average {paper['median']:.4f} m with the median against {paper['mean']:.4f} m with the mean "
            f"({paper['median'] / paper['mean']:.2f} x); here {averages['median']:.4f} m against "
            f"{averages['mean']:.4f} m ({averages['median'] / averages['mean']:.2f} x)"
        )
        flagged = {v: sum(sum(self.results[test, v].summary()["flags"].values()) for test in tests)
                   for v in TABLE3_VECTORS}
        lines.append(f"frames flagged over the three tests: median {flagged['median']}, mean {flagged['mean']}")
        return "\n".join(lines)


def reproduce_table3(config, tests: dict[str, str] = TABLE3_TESTS, method: str = "gpo") -> Table3:
    """``Table3`` of ``config`` (a ``gpo.pipeline.config.OdometryConfig``; its method set to ``method``, the paper's
    ``gpo``
    unless another is chosen, and its vector to each of ``TABLE3_VECTORS``) on the recordings of ``tests`` (rendered
    on first use)."""
    results, truths, errors, relative = {}, {}, {}, {}
    for test, name in tests.items():
        bag = recording(name, progress=False)
        with Recording(bag) as recorded:
            truths[test] = recorded.trajectory(GROUND_TRUTH_TOPIC)
        for vector in TABLE3_VECTORS:
            results[test, vector] = run(bag, config.replace(method=method, vector=vector), progress=False)
            errors[test, vector] = final_error(results[test, vector].trajectory, truths[test])
            relative[test, vector] = relative_translation_errors(results[test, vector].trajectory, truths[test])
    return Table3(dict(tests), results, truths, errors, relative, method)
