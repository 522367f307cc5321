"""``python -m gpo sweep-report``: PNG plots of a sweep's final errors against each of its parameters."""

from __future__ import annotations

from pathlib import Path

NAME = "sweep-report"
HELP = "plots of a sweep's errors against its parameters"


def add_arguments(parser) -> None:
    parser.add_argument("results", type=Path, help="the folder a sweep wrote")
    parser.add_argument("--out", type=Path, help="folder for the PNG files (default: RESULTS/report)")


def run(args) -> int:
    for path in sweep_report(args.results, args.out):
        print(f"wrote {path}")
    return 0


def sweep_report(results: Path, out: Path | None = None) -> list[Path]:
    """PNG figures of the sweep in ``results``: the final error against each parameter (per recording and the median
    of all), or per recording when nothing was varied."""
    from matplotlib.figure import Figure

    from gpo.batch.table import parameter_columns, read_table
    from gpo.book.figures import draw_sweep

    table = read_table(results)
    out = out or results / "report"
    out.mkdir(parents=True, exist_ok=True)
    written = []
    for parameter in parameter_columns(table) or [None]:
        fig = Figure(figsize=(7, 4.2))
        draw_sweep(table, parameter, fig.subplots())
        name = "recording" if parameter is None else parameter.removeprefix("param.").replace(".", "_")
        written.append(out / f"error_vs_{name}.png")
        fig.savefig(written[-1], dpi=110, bbox_inches="tight")
    return written
