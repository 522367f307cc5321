"""``python -m gpo table3``: the first paper's Table 3 on the simulated short paths (``gpo.experiments.table3``), on
the paper's floor image (the ortho-GPI from a floor board) unless another route is named, each cell beside the
paper's."""

from __future__ import annotations

from gpo.pipeline.config import Route

NAME = "table3"
HELP = "the first paper's Table 3 (median against mean vector) on the simulated short paths, the paper's beside"


def add_arguments(parser) -> None:
    images = [route.value for route in Route if route is not Route.KEYPOINTS]  # the fisheye's floor images
    parser.add_argument("--route", default=Route.ORTHO_GPI.value, choices=images,
                        help="the floor image (default: ortho-gpi, the paper's)")


def run(args) -> int:
    from gpo.experiments.table3 import reproduce_table3

    print(reproduce_table3(args.route).format())
    return 0
