"""``python -m gpo recording``: the cached bags of simulated presets, made when needed, their paths printed."""

from __future__ import annotations

from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path

NAME = "recording"
HELP = "print the cached bags of presets, making them if needed"


def add_arguments(parser) -> None:
    from gpo.sim.record import PRESETS

    parser.add_argument("names", nargs="*", default=["sample"], choices=sorted(PRESETS), metavar="NAME")
    parser.add_argument(
        "--jobs", type=int, default=1, help="presets rendered at once, one process each (default 1: with progress bars)"
    )


def run(args) -> int:
    for path in recordings(args.names, args.jobs):
        print(path)
    return 0


def recordings(names: list[str], jobs: int = 1) -> list[Path]:
    """The bags of presets ``names`` (``gpo.sim.record.recording``); with ``jobs`` > 1 those not yet cached are rendered
    that many at a time in processes of their own, without frame progress bars, each printed when done."""
    from gpo.sim.record import recording

    if jobs < 1:
        raise ValueError(f"--jobs must be at least 1, not {jobs}")
    if jobs == 1:
        return [recording(name) for name in names]
    with ProcessPoolExecutor(max_workers=jobs) as pool:
        pending = {pool.submit(recording, name, progress=False): name for name in names}
        for done in as_completed(pending):
            print(f"{pending[done]}: ready", flush=True)
        return [job.result() for job in pending]
