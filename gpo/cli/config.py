"""``python -m gpo config``: a run config proposed from a bag (``gpo.pipeline.propose``) and what is given in place
of what it lacks, every choice explained in its comments."""

from __future__ import annotations

from pathlib import Path

from gpo.io.outputs import check_output, write_with
from gpo.pipeline.config import load_config
from gpo.pipeline.propose import print_sources, proposal_yaml, propose

NAME = "config"
HELP = "a run config proposed from a bag and what is given"


def add_arguments(parser) -> None:
    parser.add_argument("bag", type=Path, help="a ROS1 .bag, a ROS2 bag folder, or a .db3/.mcap file")
    parser.add_argument("--camera", type=Path, help="calibration in place of the bag's camera_info")
    parser.add_argument("--mount", type=Path, help="a mount YAML (gpo mount) in place of the bag's /tf_static")
    parser.add_argument("--topic", help="image topic (default: the only one, or the first with camera_info)")
    parser.add_argument("--out", type=Path, default=Path("rig.yaml"), help="config YAML to write")


def run(args) -> int:
    """The proposal for the bag, printed and written to ``--out``; checked to load."""
    inputs = [args.bag, args.camera, args.mount]
    check_output(args.out, inputs, "--out")
    proposal = propose(args.bag, args.camera, args.mount, args.topic)
    print_sources(proposal)
    text = proposal_yaml(proposal, str(args.bag))
    print(f"wrote {write_with(args.out, lambda temporary: (temporary.write_text(text), load_config(temporary)))}")
    return 0
