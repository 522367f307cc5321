"""``python -m gpo table4``: the first paper's Table 4 on the simulated 15-16 m paths (``gpo.experiments.table4``),
the paper's own table first, then the suite's runs in the paper's measure, its rows ranked as the paper's, and the
suite's measures beside; the floor runs kept in the cache."""

from __future__ import annotations

NAME = "table4"
HELP = "the first paper's Table 4 on the simulated 15-16 m paths, the paper's beside"


def add_arguments(parser) -> None:
    parser.add_argument("paths", nargs="*", metavar="PRESET", help="presets (default: long1 long2 long3)")


def run(args) -> int:
    from gpo.experiments.table4 import PAPER_TABLE4, PATHS, reproduce_table4

    table = reproduce_table4(tuple(args.paths or PATHS))
    print(PAPER_TABLE4.format(), table.format(), table.format_ranks(), table.format_measures(),
          table.format_ape_mean(), sep="\n\n")
    return 0
