"""``python -m gpo table2``: the second paper's Table 2 over its experiments (``gpo.experiments.table2``), and
chapter 08's runs over the three floors, computed once and kept in the cache."""

from __future__ import annotations

NAME = "table2"
HELP = "the second paper's Table 2 over its simulated experiments, and chapter 08's floor runs"


def add_arguments(parser) -> None:
    from gpo.experiments.table2 import EXPERIMENTS, FLOORS_RUNS

    names = [e.number for e in EXPERIMENTS] + [FLOORS_RUNS]
    parser.add_argument(
        "runs", nargs="*", default=names, choices=names, metavar="RUNS",
        help=f"experiments I ... IX and {FLOORS_RUNS} (chapter 08's runs over the three floors); default: all",
    )  # fmt: skip


def run(args) -> int:
    from gpo.experiments.table2 import FLOORS_RUNS, HEADER, experiment, floor_runs, format_row, reproduce_table2

    if FLOORS_RUNS in args.runs:
        floor_runs()
    chosen = [experiment(number) for number in args.runs if number != FLOORS_RUNS]
    for name, rows in reproduce_table2(experiments=chosen).items() if chosen else ():
        print(name)
        print(HEADER)
        for row in rows:
            print(format_row(row.experiment.number, row.paper))
    return 0
