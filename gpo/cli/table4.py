"""``python -m gpo table4``: the first paper's Table 4 on the simulated 15-16 m paths (``gpo.experiments.table4``),
its floor runs kept in the cache."""

from __future__ import annotations

NAME = "table4"
HELP = "the first paper's Table 4 on the simulated 15-16 m paths"


def add_arguments(parser) -> None:
    parser.add_argument("paths", nargs="*", metavar="PRESET", help="presets (default: long1 long2 long3)")


def run(args) -> int:
    from gpo.experiments.table4 import PATHS, reproduce_table4

    table = reproduce_table4(tuple(args.paths or PATHS))
    print(table.format(), table.format_table2(), sep="\n\n")
    return 0
