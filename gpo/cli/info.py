"""``python -m gpo info``: a bag's topics, message types, counts, rates and image sizes."""

from __future__ import annotations

from pathlib import Path

from gpo.io.bag import describe

NAME = "info"
HELP = "describe a ROS1 or ROS2 bag"


def add_arguments(parser) -> None:
    parser.add_argument("bag", type=Path)


def run(args) -> int:
    print(describe(args.bag))
    return 0
