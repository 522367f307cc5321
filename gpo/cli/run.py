"""``python -m gpo run``: the odometry of a recording, its TUM trajectory and summary (and a copy of the bag)."""

from __future__ import annotations

import sys
from pathlib import Path

from gpo.cli.common import INTERRUPTED, available_cores, whole_number
from gpo.io.bag import recording_format
from gpo.io.bag_writer import check_new_bag, copy_with_trajectory
from gpo.io.outputs import check_output, destination, held_signals, write_together
from gpo.pipeline.config import VECTORS, load_config, methods
from gpo.pipeline.propose import config_from_bag
from gpo.pipeline.run import OdometryResult, summary_path_of
from gpo.pipeline.run import run as run_odometry

NAME = "run"
HELP = "odometry of a recording: a TUM trajectory and a summary"


def add_arguments(parser) -> None:
    parser.add_argument("bag", type=Path, help="a ROS1 .bag, a ROS2 bag folder, or a .db3/.mcap file")
    parser.add_argument("--config", type=Path, help="run config YAML (default: from what the bag holds)")
    parser.add_argument("--out", type=Path, default=Path("traj.tum"), help="TUM file to write (default traj.tum)")
    parser.add_argument("--method", choices=methods(), help="motion estimator (default: the config's)")
    parser.add_argument("--vector", choices=VECTORS, help="motion vector statistic (default: the config's)")
    parser.add_argument("--topic", help="image topic (default: the config's, else the bag's only one)")
    parser.add_argument("--write-bag", type=Path, help="a copy of the bag with the estimate on /gpo/odom")
    parser.add_argument("--force", action="store_true", help="a flagged result replaces --out too")
    parser.add_argument(
        "--threads",
        type=whole_number,
        default=min(2, available_cores()),
        help="threads: from 2 on, the next frames are read and prepared while one is tracked, and OpenCV shares its "
        "work among them (default 2, or 1 on a one-core machine)",
    )


def print_run(result: OdometryResult) -> None:
    """A run's summary for people."""
    summary = result.summary()
    print(
        f"{summary['frames']} frames of {summary['topic']} in {result.seconds:.1f} s "
        f"({summary['frames_per_second']} frames/s), method {summary['method']}, {summary['vector']} vector"
    )
    print(f"distance travelled: {summary['distance_m']:.3f} m over {summary['duration_s']:.1f} s")
    print("frames: " + ", ".join(f"{summary[f'frames_{s}']} {s}" for s in ("measured", "coasted", "held", "skipped")))
    for reason, count in summary["flags"].items():
        print(f"  flagged {count}: {reason}")
    if "frames_slower_layer" in summary:
        print(
            f"  {summary['frames_slower_layer']} measured frames held a slower layer of vectors (reflections on a "
            "glossy floor?): their median is short"
        )
    for caution in result.cautions:
        print(f"caution: {caution}")
    if result.shortfall:
        print(f"flagged: {result.shortfall}; the trajectory is mostly coasted or held, not measured", file=sys.stderr)
    if result.interrupted:
        print(f"interrupted after {len(result.records)} frames; the frames before were kept", file=sys.stderr)
        if "not_fused" in (result.fusion or {}):
            print(f"not fused: {result.fusion['not_fused']}", file=sys.stderr)
    elif result.error and result.error.startswith("after"):
        print(f"stopped early {result.error}; the frames before were kept", file=sys.stderr)
    elif result.error:
        print(result.error, file=sys.stderr)


def run(args) -> int:
    """Everything checked, the odometry, then its files: the trajectory, its summary and the bag's copy replace the
    files there as one set, or none of them does (``gpo.io.outputs.write_together``), Ctrl-C and SIGTERM held
    meanwhile."""
    if args.config is None:
        config, origin = config_from_bag(args.bag, args.topic)
    else:
        config, origin = load_config(args.config), str(args.config)
    changes = {k: v for k, v in (("method", args.method), ("vector", args.vector)) if v}
    config = config.replace(**changes) if changes else config
    inputs = [args.bag, args.config]
    check_output(args.out, inputs, "--out")
    check_output(summary_path_of(args.out), inputs, "--out (its summary)")
    if args.write_bag:
        check_new_bag(args.write_bag, recording_format(args.bag), f"--write-bag (a copy of {args.bag})")
        outputs = [*inputs, args.out, summary_path_of(args.out)]
        check_output(args.write_bag, outputs, "--write-bag", needed_bytes=_bytes(args.bag))
    try:
        result = run_odometry(args.bag, config, args.topic, threads=args.threads)
    except ValueError as error:
        raise ValueError(f"{error} (config: {origin})") from None
    print_run(result)
    out = destination(args.out, result.flagged, args.force)
    if out != args.out:
        check_output(out, inputs, "--out (beside it)")
        check_output(summary_path_of(out), inputs, "--out (beside it, its summary)")
        print(f"{args.out} is kept: this result is flagged and goes beside it (--force replaces it)", file=sys.stderr)
    files = result.files(out)
    if args.write_bag and not result.flagged:
        files[args.write_bag] = lambda temporary: copy_with_trajectory(args.bag, temporary, result.trajectory)
    elif args.write_bag:
        print(f"{args.write_bag} not written: the result is flagged", file=sys.stderr)
    with held_signals():  # what was computed is written whole: a signal meanwhile is met once it is
        for path in write_together(files):
            print(f"wrote {path}" + (" (/gpo/odom)" if path == args.write_bag else ""))
    if result.interrupted:
        return INTERRUPTED
    return 1 if result.flagged else 0


def _bytes(path: Path) -> int:
    """The size of a file, or of every file in a folder, bytes."""
    if path.is_dir():
        return sum(p.stat().st_size for p in path.rglob("*") if p.is_file())
    return path.stat().st_size if path.is_file() else 0
