"""``python -m gpo sample-data``: the small sample files kept in ``data/``, made again (``gpo.sim.record``)."""

from __future__ import annotations

from pathlib import Path

NAME = "sample-data"
HELP = "regenerate the small sample files kept in data/"


def add_arguments(parser) -> None:
    parser.add_argument("--out", type=Path, default=Path("data"), help="output folder (default: data)")


def run(args) -> int:
    from gpo.sim.record import write_sample_data

    for path in write_sample_data(args.out):
        print(f"wrote {path}")
    return 0
