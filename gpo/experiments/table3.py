"""The first paper's Table 3 on the simulated short paths: GPO's relative translation error with the median motion
vector against the mean, on three recordings standing for the paper's Test1-Test3, on the floor image the paper
measured it on (the ortho-rectified GPI from a floor board, ``TABLE3_ROUTE``), the paper's numbers beside each.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gpo.experiments.runs import ROUTE_NAMES, floor_run, route_config
from gpo.io.bag import Recording
from gpo.metrics import final_error, relative_translation_errors
from gpo.pipeline.config import OdometryConfig
from gpo.sim.record import GROUND_TRUTH_TOPIC, recording

TABLE3_TESTS = {"Test1": "short1", "Test2": "short2", "Test3": "short3"}  # the paper's tests -> the presets run here
TABLE3_ROUTE = "ortho-gpi"  # the paper's floor image: the ortho-rectified GPI, calibrated on a board (chapter 04)

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
"""The first paper's Table 3, every row and test as printed (the paper's numbers, metres)."""


@dataclass(frozen=True)
class Table3:
    """The first paper's Table 3 on the simulated 3-4.5 m paths: GPO (``method``, the paper's ``gpo`` unless another is
    chosen) with the mean and with the median motion vector on each test, on the floor image of ``route``.
    ``results[test, vector]`` the floor runs (``gpo.pipeline.run.FloorRun``, kept on disk), ``truths[test]`` their
    ground truth,
    ``errors[test, vector]`` the final errors (``gpo.metrics.FinalError``: the suite's measure beside the paper's) and
    ``relative[test, vector]`` the relative translation errors of 1 m pairs, metres (the paper's measure)."""

    tests: dict[str, str]
    results: dict
    truths: dict
    errors: dict
    relative: dict
    method: str = "gpo"
    route: str = TABLE3_ROUTE

    def values(self) -> dict[tuple[str, str], tuple[float, ...]]:
        """``PaperTable3.values``' layout of this table: (vector, statistic) -> each test's, then their mean, metres."""
        table = {}
        for vector in TABLE3_VECTORS:
            for label, statistic in STATISTICS:
                cells = [float(statistic(self.relative[test, vector])) for test in self.tests]
                table[vector, label] = (*cells, float(np.mean(cells)))
        return table

    def format(self) -> str:
        """The paper's layout, each cell the paper's number and this table's ("paper | here"), the suite's final error
        below each vector, the ratio of the two vectors' averages and where the median is not below the mean."""
        ours, paper = self.values(), PAPER_TABLE3.values
        route = ROUTE_NAMES[self.route]
        lines = [f"Table 3 on the {route}: relative translation error [m] of GPO (method {self.method}, pairs 1 m "
                 "apart), each cell the paper's | here"]
        lengths = [self.errors[test, "median"].distance_m for test in self.tests]
        header = "".join(f"{f'{test} ({p:.2f} | {h:.2f} m)':>24}"
                         for test, p, h in zip(self.tests, PAPER_TABLE3.lengths_m, lengths, strict=True))
        lines.append(f"{'':24}{header}{'Average':>20}")
        for vector in TABLE3_VECTORS:
            for k, (label, _) in enumerate(STATISTICS):
                name = f"GPO ({vector})" if k == 0 else ""
                cells = "".join(f"{f'{p:.4f} | {h:.4f}':>24}" for p, h in zip(paper[vector, label][:-1],
                                                                            ours[vector, label][:-1], strict=True))
                average = f"{paper[vector, label][-1]:.4f} | {ours[vector, label][-1]:.4f}"
                lines.append(f"{name:<14}{label:<10}{cells}{average:>20}")
            finals = [self.errors[test, vector].position_m for test in self.tests]
            cells = "".join(f"{f'- | {value:.4f}':>24}" for value in finals)
            lines.append(f"{'':<14}{'final':<10}{cells}{f'- | {np.mean(finals):.4f}':>20}")
        averages = {vector: ours[vector, "avg"][-1] for vector in TABLE3_VECTORS}
        printed = {vector: PAPER_TABLE3.average(vector) for vector in TABLE3_VECTORS}
        lines.append(
            f"average with the median against the mean: the paper {printed['median']:.4f} m against "
            f"{printed['mean']:.4f} m ({printed['median'] / printed['mean']:.2f} x); here {averages['median']:.4f} m "
            f"against {averages['mean']:.4f} m ({averages['median'] / averages['mean']:.2f} x)"
        )
        lines.extend(self.orderings())
        coasted = {v: sum(int(np.sum(self.results[test, v].inliers[1:] == 0)) for test in self.tests)
                   for v in TABLE3_VECTORS}
        lines.append(f"steps not measured (coasted or held) over the three tests: median {coasted['median']}, mean "
                     f"{coasted['mean']}; final: the suite's final position error (first pose on the truth), which the "
                     "paper's Table 3 does not print")
        return "\n".join(lines)

    def orderings(self) -> list[str]:
        """One line per statistic: in how many tests (and the average) the median's number is below the mean's, in
        the paper and here, naming each cell where it is not."""
        ours, paper = self.values(), PAPER_TABLE3.values
        columns = (*self.tests, "Average")
        lines = []
        for label, _ in STATISTICS:
            found = []
            for name, table in (("the paper", paper), ("here", ours)):
                median, mean = table["median", label], table["mean", label]
                exceptions = [f"{column} {m:.4f} against {a:.4f}"
                              for column, m, a in zip(columns, median, mean, strict=True) if not m < a]
                kept = len(columns) - len(exceptions)
                found.append(f"{name} {kept} of {len(columns)}" + (f" (not: {'; '.join(exceptions)})"
                                                                   if exceptions else ""))
            lines.append(f"median < mean, {label}: {', '.join(found)}")
        return lines


def reproduce_table3(
    route: str = TABLE3_ROUTE,
    base: OdometryConfig | None = None,
    tests: dict[str, str] = TABLE3_TESTS,
    method: str = "gpo",
) -> Table3:
    """``Table3`` of ``method`` (the paper's ``gpo`` unless another is chosen) on the floor image of ``route`` (the
    paper's ortho-GPI by default; ``gpo.experiments.runs.route_config`` on ``base``, the shipped config unless given),
    with each of ``TABLE3_VECTORS``, on the recordings of ``tests`` (rendered on first use). The floor runs are kept
    on disk (``gpo.experiments.runs.floor_run``): computed once, read back on every floating-point path, as the
    chessboard route's table differs in its last bits from one path to another."""
    config = route_config(method, route, base)
    results, truths, errors, relative = {}, {}, {}, {}
    for test, name in tests.items():
        bag = recording(name, progress=False)
        with Recording(bag) as recorded:
            truths[test] = recorded.trajectory(GROUND_TRUTH_TOPIC)
        for vector in TABLE3_VECTORS:
            results[test, vector] = floor_run(bag, config.replace(vector=vector))
            errors[test, vector] = final_error(results[test, vector].trajectory, truths[test])
            relative[test, vector] = relative_translation_errors(results[test, vector].trajectory, truths[test])
    return Table3(dict(tests), results, truths, errors, relative, method, route)
