"""``python -m gpo simulate``: a simulated recording (a preset of ``gpo.sim.record``) rendered into a new bag."""

from __future__ import annotations

from pathlib import Path

from gpo.io.bag_writer import check_new_bag
from gpo.io.outputs import check_output, write_with

NAME = "simulate"
HELP = "render a simulated recording into a ROS bag"
FORMATS = ("ros1", "ros2", "ros2-mcap")


def add_arguments(parser) -> None:
    from gpo.sim.record import PRESETS

    parser.add_argument("--preset", required=True, choices=sorted(PRESETS), help="what to record")
    parser.add_argument("--out", type=Path, required=True, help="the new bag (ros1: a .bag file)")
    parser.add_argument("--format", default="ros1", choices=FORMATS)


def run(args) -> int:
    check_new_bag(args.out, args.format, "--out")
    check_output(args.out)
    from gpo.sim.record import PRESETS, simulate

    print(f"{args.preset}: {PRESETS[args.preset].description}")
    write_with(args.out, lambda temporary: simulate(args.preset, temporary, args.format))
    print(f"wrote {args.out}")
    return 0
