"""The ``python -m gpo`` command line.

python -m gpo demo [--out DIR]    figures, tables and the sample recording's odometry, written to DIR
python -m gpo mount IMAGE --camera CALIB --board 7x5 --square S [--at X Y YAW] --out mount.yaml   the mount
python -m gpo config BAG [--camera CALIB] [--mount mount.yaml] --out rig.yaml   a run config from the bag, commented
python -m gpo run BAG --config RIG.yaml --out traj.tum [--method gpo|gpo-exact|gpo-rigid] [--topic T]
python -m gpo run BAG ...   without --config: the config proposed from what the bag holds (as gpo config)
python -m gpo run BAG ... --write-bag OUT.bag    also a copy of the bag with the estimate as nav_msgs/Odometry
python -m gpo evaluate EST.tum GT [--gt-topic T] [--align none|origin|se2|se3|posyaw] [--plot OUT.png]
python -m gpo table4 [PATH ...]   the first paper's Table 4 (and the second's Table 2 metrics) on long1-3
python -m gpo recording [NAME ...] [--jobs N]    the cached bags of simulated presets, rendered N at a time if needed
python -m gpo sweep SPEC.yaml --out DIR [--scheduler tcp://HOST:PORT] [--workers N]   many runs on Dask (gpo.batch)
python -m gpo sweep-report DIR    PNG plots of a sweep's errors against each parameter, per recording and overall

Every command checks its inputs and output paths before it works, never writes onto one of its inputs, and
writes each file to a temporary name and then renames it; a result it flags (an unreliable calibration, a run
stopped early or interrupted) does not replace a file already there but goes beside it (``NAME.flagged.EXT``),
unless ``--force``.
"""

from __future__ import annotations

import argparse
import math
import signal
import sys
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from gpo.bag import POSE_TYPES, Recording, copy_with_trajectory, describe
from gpo.calibrate import MODELS, CalibrationError, main_calibrate
from gpo.camera import EUCM, T265_LIKE, Pinhole
from gpo.measure_mount import mount_command
from gpo.metrics import RPE_DELTA_M, Alignment, Evaluation, evaluate
from gpo.outputs import check_output, destination, write_text, write_with
from gpo.pipeline import (
    METHODS,
    VECTORS,
    OdometryResult,
    load_config,
    run,
    summary_path_of,
    tracking_path,
)
from gpo.propose import config_command, config_from_bag
from gpo.trajectory import Trajectory

if TYPE_CHECKING:
    from matplotlib.figure import Figure

EXIT_CODES = """exit codes:
  0    done
  1    bad input (the error names the file, field or topic), or a result the command flags
  2    usage: an unknown command or option, or an option's value of the wrong kind
  130  interrupted (Ctrl-C, SIGTERM): run writes the frames done, marked interrupted
--debug shows the traceback of an error."""
INTERRUPTED = 130

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


def demo(out: Path) -> list[Path]:
    """Write the camera-model figures and a field-of-view table into ``out``; return the files."""
    from matplotlib.figure import Figure

    from gpo.book.ch01_eucm_model import draw_projection_curves, draw_room_in_image, field_of_view_text

    out.mkdir(parents=True, exist_ok=True)
    written = []

    fig = Figure(figsize=(7.0, 6.6))
    ax = fig.subplots()
    draw_room_in_image(T265_LIKE, ax=ax, height=0.12)
    ax.set_title("A room seen by a T265-like EUCM fisheye 0.12 m above the floor")
    written.append(out / "fisheye_room_grid.png")
    _save(fig, written[-1], dpi=110)

    f = T265_LIKE.fx
    cameras = {
        f"EUCM alpha={alpha}, beta={beta}": EUCM(f, f, T265_LIKE.cx, T265_LIKE.cy, alpha, beta, 848, 800)
        for alpha, beta in ((0.6, 1.1), (0.5, 1.0), (0.3, 1.0), (0.0, 1.0))
    }
    cameras["pinhole (no distortion)"] = Pinhole(f, f, T265_LIKE.cx, T265_LIKE.cy, (0.0,) * 4, 848, 800)
    fig = Figure(figsize=(7.0, 4.2))
    ax = fig.subplots()
    draw_projection_curves(cameras, ax=ax)
    ax.axhline(T265_LIKE.width - T265_LIKE.cx, color="k", lw=0.8, ls=":")
    ax.set_ylim(0, 1200)
    ax.set_title(f"How far from the image centre a ray lands (f = {f:.0f} px); dotted: image edge")
    written.append(out / "projection_curves.png")
    _save(fig, written[-1], dpi=110)

    written.append(out / "field_of_view.txt")
    write_text(written[-1], "".join(f"{label}: {field_of_view_text(camera)}\n" for label, camera in cameras.items()))
    return written + sample_recording_figures(out) + sample_odometry(out)


def sample_recording_figures(out: Path) -> list[Path]:
    """Frames and paths of the sample recording (rendered on first use): PNG figures and TUM files in ``out``."""
    from matplotlib.figure import Figure

    from gpo.book.figures import draw_paths
    from gpo.sim.record import GROUND_TRUTH_TOPIC, recording

    with Recording(recording("sample")) as bag:
        topic = bag.image_topic()
        start = bag.start_ns
        frames = [next(bag.frames(topic, start_ns=start + round(t * 1e9), progress=False)) for t in (0.0, 6.0, 12.0)]
        truth = bag.trajectory(GROUND_TRUTH_TOPIC)
        tracked = tracking_path(bag, load_config().fusion).compose((truth.rotations[0], truth.positions[0]))
    fig = Figure(figsize=(13, 4.2))
    for ax, frame in zip(fig.subplots(1, 3), frames, strict=True):
        ax.imshow(frame.image, cmap="gray", vmin=0, vmax=255)
        ax.set_title(f"{topic}, t = {(frame.stamp_ns - start) * 1e-9:.1f} s")
        ax.axis("off")
    frames_png = out / "sample_frames.png"
    _save(fig, frames_png, dpi=90)

    fig = Figure(figsize=(7, 5))
    draw_paths({"ground truth": truth, "tracking camera's odometry": tracked}, ax=fig.subplots())
    paths_png = out / "sample_paths.png"
    _save(fig, paths_png, dpi=110)
    return [
        frames_png,
        paths_png,
        write_with(out / "sample_groundtruth.tum", truth.write_tum),
        write_with(out / "sample_tracking_odometry_base.tum", tracked.write_tum),
    ]


def sample_odometry(out: Path) -> list[Path]:
    """The sample recording's odometry, ``gpo-exact`` alone and fused with the tracking camera by the EKF (the last
    files: ``sample_fused.evaluation.txt``, its evaluation table): trajectories, summaries, plots against truth."""
    from gpo.sim.record import GROUND_TRUTH_TOPIC, recording

    bag = recording("sample")
    with Recording(bag) as recorded:
        truth = recorded.trajectory(GROUND_TRUTH_TOPIC)
    written = []
    for method, name in (("gpo-exact", "sample_gpo_exact"), ("fused", "sample_fused")):
        result = run(bag, load_config().replace(method=method), progress=False)
        written += result.write(out / f"{name}.tum")
        evaluation = evaluate(result.trajectory, truth, "origin")
        written.append(save_evaluation_plot(evaluation, out / f"{name}.png"))
    written.append(out / "sample_fused.evaluation.txt")
    write_text(written[-1], f"EKF (gpo-exact + tracking camera) on the sample recording\n{evaluation.table()}\n")
    return written


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
    if result.interrupted:
        print(f"interrupted after {len(result.records)} frames; the frames before were kept", file=sys.stderr)
    elif result.error and result.error.startswith("after"):
        print(f"stopped early {result.error}; the frames before were kept", file=sys.stderr)
    elif result.error:
        print(result.error, file=sys.stderr)


def read_truth(path: Path, topic: str | None) -> Trajectory:
    """The ground truth in ``path``: a TUM file, or a bag (a .bag file, a folder, a .db3/.mcap file) and its pose
    ``topic`` (geometry_msgs PoseStamped or TransformStamped, nav_msgs Odometry)."""
    if not (path.is_dir() or path.suffix in (".bag", ".db3", ".mcap")):
        if topic:
            raise ValueError(f"--gt-topic {topic} names a bag's topic, but {path} is taken for a TUM file")
        return read_tum(path)
    with Recording(path) as bag:
        if not topic:
            poses = ", ".join(t.name for t in bag.topics() if t.msgtype in POSE_TYPES) or "none"
            raise ValueError(
                f"{path} is a recording: name its ground-truth topic with --gt-topic (pose topics: {poses})"
            )
        return bag.trajectory(topic)


def read_tum(path: Path) -> Trajectory:
    """``Trajectory.read_tum``, with the file named in every error; a stamp repeated with another pose, or stamps
    that go backwards, are refused (a pose repeated as it was is read once)."""
    if path.is_dir():
        raise ValueError(f"{path} is a folder; expected a TUM file (t tx ty tz qx qy qz qw per line)")
    try:
        trajectory = Trajectory.read_tum(path)
    except ValueError as error:
        if str(path) in str(error):
            raise
        raise ValueError(f"{path}: {error}") from None
    except UnicodeDecodeError:
        raise ValueError(f"{path} is not a text file; expected a TUM file") from None
    if len(trajectory) == 0:
        raise ValueError(f"{path} holds no poses; expected a TUM file (t tx ty tz qx qy qz qw per line)")
    stamps = trajectory.stamps_ns
    backwards = np.flatnonzero(np.diff(stamps) < 0)
    if backwards.size:
        raise ValueError(f"{path}: the stamps go backwards at pose {backwards[0] + 2}; expected them in time order")
    repeated = np.flatnonzero(np.diff(stamps) == 0) + 1
    poses = np.hstack([trajectory.positions, trajectory.quaternions])
    differ = [i for i in repeated if not np.allclose(poses[i], poses[i - 1])]
    if differ:
        i = differ[0]
        apart = np.linalg.norm(trajectory.positions[i] - trajectory.positions[i - 1])
        raise ValueError(
            f"{path}: stamp {stamps[i] / 1e9:.9f} s repeats with another pose ({apart:.3f} m away), "
            f"{len(differ)} time(s); expected one pose per stamp"
        )
    if repeated.size:
        keep = np.delete(np.arange(len(stamps)), repeated)
        trajectory = Trajectory(
            stamps[keep], trajectory.positions[keep], trajectory.quaternions[keep], trajectory.frame_id,
            trajectory.child_frame_id,
        )
    return trajectory


def save_evaluation_plot(evaluation: Evaluation, out: Path) -> Path:
    """A figure of both paths (the estimate aligned) and the position error along the truth's distance, written to
    a temporary name and renamed to ``out`` (its suffix names the format)."""
    from matplotlib.figure import Figure

    from gpo.book.figures import draw_paths

    fig = Figure(figsize=(12, 4.8))
    paths, errors = fig.subplots(1, 2, width_ratios=(1.2, 1))
    draw_paths(
        {"ground truth": evaluation.truth, f"estimate ({evaluation.alignment} aligned)": evaluation.estimate}, paths
    )
    errors.plot(evaluation.distances_m, evaluation.position_errors_m * 1e3)
    errors.set_xlabel("distance travelled by the truth [m]")
    errors.set_ylabel("position error [mm]")
    errors.set_title(f"APE rmse {evaluation.ape_m.rmse * 1e3:.1f} mm, final {evaluation.final}", fontsize="small")
    return _save(fig, out, dpi=110)


def _save(fig: Figure, path: Path, dpi: int) -> Path:
    """``fig`` written to ``path`` through a temporary name of the same suffix (which names the format)."""
    return write_with(path, lambda temporary: fig.savefig(temporary, dpi=dpi, bbox_inches="tight"))


def check_plot(path: Path, inputs: list[Path]) -> Path:
    """``--plot`` checked before the evaluation: a writable file (``check_output``) of a format matplotlib writes."""
    from matplotlib.figure import Figure

    check_output(path, inputs, "--plot")
    formats = Figure().canvas.get_supported_filetypes()
    if path.suffix.lstrip(".").lower() not in formats:
        raise ValueError(f"--plot {path}: name a file ending in one of .{', .'.join(sorted(formats))}")
    return path


def run_command(args) -> int:
    """``python -m gpo run``: everything checked, the odometry, then its files (see the module docstring)."""
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
        if args.write_bag.exists():
            raise ValueError(f"--write-bag {args.write_bag} exists; name a new bag (a bag is never replaced)")
        outputs = [*inputs, args.out, summary_path_of(args.out)]
        check_output(args.write_bag, outputs, "--write-bag", needed_bytes=_bytes(args.bag))
    try:
        result = run(args.bag, config, args.topic)
    except ValueError as error:
        raise ValueError(f"{error} (config: {origin})") from None
    print_run(result)
    out = destination(args.out, result.flagged, args.force)
    if out != args.out:
        check_output(out, inputs, "--out (beside it)")
        check_output(summary_path_of(out), inputs, "--out (beside it, its summary)")
        print(f"{args.out} is kept: this result is flagged and goes beside it (--force replaces it)", file=sys.stderr)
    for path in result.write(out):
        print(f"wrote {path}")
    if args.write_bag and not result.flagged:
        write_with(args.write_bag, lambda temporary: copy_with_trajectory(args.bag, temporary, result.trajectory))
        print(f"wrote {args.write_bag} (/gpo/odom)")
    elif args.write_bag:
        print(f"{args.write_bag} not written: the result is flagged", file=sys.stderr)
    if result.interrupted:
        return INTERRUPTED
    return 1 if result.error else 0


def _bytes(path: Path) -> int:
    """The size of a file, or of every file in a folder, bytes."""
    if path.is_dir():
        return sum(p.stat().st_size for p in path.rglob("*") if p.is_file())
    return path.stat().st_size if path.is_file() else 0


def _positive(text: str) -> float:
    """An option's number: finite and > 0 (argparse turns the error into a usage error)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number > 0, got {text!r}") from None
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"expected a finite number > 0, got {text!r}")
    return value


def _interrupt(signum, frame):
    """SIGTERM handled as Ctrl-C: a run keeps and writes what it computed."""
    raise KeyboardInterrupt


# ----------------------------------------------------------------------------------------------- sweeps (gpo.batch)

def add_sweep_commands(commands) -> None:
    """The ``sweep`` and ``sweep-report`` subcommands."""
    sweep_parser = commands.add_parser("sweep", help="many runs (recordings x configs) on a Dask cluster, resumable")
    sweep_parser.add_argument("spec", type=Path, help="the sweep's YAML: recordings, config, set, vary, runs")
    sweep_parser.add_argument("--out", type=Path, required=True, help="results folder (a sweep resumes in it)")
    sweep_parser.add_argument(
        "--scheduler", help="a running Dask scheduler, tcp://HOST:PORT (default: DASK_SCHEDULER_ADDRESS, else local)"
    )
    sweep_parser.add_argument("--workers", type=int, help="local worker processes (default: one per core)")
    report_parser = commands.add_parser("sweep-report", help="plots of a sweep's errors against its parameters")
    report_parser.add_argument("results", type=Path, help="the folder a sweep wrote")
    report_parser.add_argument("--out", type=Path, help="folder for the PNG files (default: RESULTS/report)")


def sweep_command(args) -> int:
    """``python -m gpo sweep``: the spec's presets rendered on the cluster (cached), then every run; the summary."""
    from gpo.batch import cluster_client, load_spec, summary_text, sweep
    from gpo.sim.population import render
    from gpo.sim.record import preset

    spec = load_spec(args.spec)
    load_config(spec.config)  # a base config that cannot be read stops the sweep before it starts
    for name, _ in spec.presets():
        preset(name)
    if args.workers is not None and args.workers < 1:
        raise ValueError(f"--workers must be at least 1, not {args.workers}")
    with cluster_client(args.scheduler, args.workers) as client:
        bags = render(client, spec.presets())
        result = sweep(spec.expand({pair: str(path) for pair, path in bags.items()}), args.out, client)
    print(summary_text(result.table))
    failed = result.failed
    print(
        f"{len(result.executed)} runs done now, {len(result.reused)} already done before, {len(failed)} failed; "
        f"table: {args.out / 'results.parquet'} and results.csv"
    )
    return 1 if len(failed) else 0


def sweep_report(results: Path, out: Path | None = None) -> list[Path]:
    """PNG figures of the sweep in ``results``: the final error against each parameter (per recording and the median
    of all), or per recording when nothing was varied."""
    from matplotlib.figure import Figure

    from gpo.batch import parameter_columns, read_table
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


def main(argv: list[str] | None = None) -> int:
    from gpo.sim.record import PRESETS  # the simulator, matplotlib and the book are imported by the commands using them

    parser = argparse.ArgumentParser(
        prog="python -m gpo",
        description=__doc__.splitlines()[0],
        epilog=EXIT_CODES,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--debug", action="store_true", help="show the traceback of an error")
    commands = parser.add_subparsers(dest="command", required=True)
    demo_parser = commands.add_parser("demo", help="write the suite's figures, tables and trajectories into a folder")
    demo_parser.add_argument("--out", type=Path, default=Path("out"), help="output folder (default: out)")
    simulate_parser = commands.add_parser("simulate", help="render a simulated recording into a ROS bag")
    simulate_parser.add_argument("--preset", required=True, choices=sorted(PRESETS), help="what to record")
    simulate_parser.add_argument("--out", type=Path, required=True, help="the new bag (ros1: a .bag file)")
    simulate_parser.add_argument("--format", default="ros1", choices=("ros1", "ros2", "ros2-mcap"))
    info_parser = commands.add_parser("info", help="describe a ROS1 or ROS2 bag")
    info_parser.add_argument("bag", type=Path)
    sample_parser = commands.add_parser("sample-data", help="regenerate the small sample files kept in data/")
    sample_parser.add_argument("--out", type=Path, default=Path("data"), help="output folder (default: data)")
    recording_parser = commands.add_parser("recording", help="print the cached bags of presets, making them if needed")
    recording_parser.add_argument("names", nargs="*", default=["sample"], choices=sorted(PRESETS), metavar="NAME")
    recording_parser.add_argument(
        "--jobs", type=int, default=1, help="presets rendered at once, one process each (default 1: with progress bars)"
    )
    calibrate_parser = commands.add_parser("calibrate", help="calibrate a camera from chessboard images")
    calibrate_parser.add_argument("images", nargs="+", type=Path, help="image files of the board")
    calibrate_parser.add_argument("--board", required=True, help="inner corners per row x per column, e.g. 7x5")
    calibrate_parser.add_argument("--square", required=True, type=_positive, help="square size in metres")
    calibrate_parser.add_argument("--model", default="eucm", choices=MODELS)
    calibrate_parser.add_argument("--out", type=Path, default=Path("calib.yaml"), help="Kalibr camchain to write")
    calibrate_parser.add_argument("--force", action="store_true", help="a fit flagged as bad replaces --out too")
    mount_parser = commands.add_parser("mount", help="the camera's mount from an image of a chessboard on the floor")
    mount_parser.add_argument("image", type=Path, help="the camera's image of a board lying on the floor")
    mount_parser.add_argument(
        "--camera", type=Path, required=True, help="its calibration: Kalibr YAML, Basalt JSON or a run config"
    )
    mount_parser.add_argument("--board", required=True, help="inner corners per row x per column, e.g. 7x5")
    mount_parser.add_argument("--square", required=True, type=_positive, help="square size in metres")
    mount_parser.add_argument(
        "--at", nargs=3, type=float, metavar=("X", "Y", "YAW"),
        help="the board's outer corner in base_link (m) and its x axis's yaw (degrees): then x, y, yaw are measured",
    )
    mount_parser.add_argument("--kind", default="auto", choices=("auto", "forward", "downward"))
    mount_parser.add_argument("--out", type=Path, default=Path("mount.yaml"), help="mount YAML to write")
    mount_parser.add_argument("--picture", type=Path, help="PNG of the board and floor grid (default: beside --out)")
    mount_parser.add_argument("--force", action="store_true", help="a flagged mount replaces --out too")
    config_parser = commands.add_parser("config", help="a run config proposed from a bag and what is given")
    config_parser.add_argument("bag", type=Path, help="a ROS1 .bag, a ROS2 bag folder, or a .db3/.mcap file")
    config_parser.add_argument("--camera", type=Path, help="calibration in place of the bag's camera_info")
    config_parser.add_argument("--mount", type=Path, help="a mount YAML (gpo mount) in place of the bag's /tf_static")
    config_parser.add_argument("--topic", help="image topic (default: the only one, or the first with camera_info)")
    config_parser.add_argument("--out", type=Path, default=Path("rig.yaml"), help="config YAML to write")
    run_parser = commands.add_parser("run", help="odometry of a recording: a TUM trajectory and a summary")
    run_parser.add_argument("bag", type=Path, help="a ROS1 .bag, a ROS2 bag folder, or a .db3/.mcap file")
    run_parser.add_argument("--config", type=Path, help="run config YAML (default: from what the bag holds)")
    run_parser.add_argument("--out", type=Path, default=Path("traj.tum"), help="TUM file to write (default traj.tum)")
    run_parser.add_argument("--method", choices=METHODS, help="motion estimator (default: the config's)")
    run_parser.add_argument("--vector", choices=VECTORS, help="motion vector statistic (default: the config's)")
    run_parser.add_argument("--topic", help="image topic (default: the config's, else the bag's only one)")
    run_parser.add_argument("--write-bag", type=Path, help="a copy of the bag with the estimate on /gpo/odom")
    run_parser.add_argument("--force", action="store_true", help="a flagged result replaces --out too")
    table4_parser = commands.add_parser("table4", help="the first paper's Table 4 on the simulated 15-16 m paths")
    table4_parser.add_argument("paths", nargs="*", metavar="PRESET", help="presets (default: long1 long2 long3)")
    evaluate_parser = commands.add_parser("evaluate", help="errors of a TUM trajectory against the ground truth")
    evaluate_parser.add_argument("estimate", type=Path, help="the estimated trajectory, a TUM file")
    evaluate_parser.add_argument("truth", type=Path, help="ground truth: a TUM file, or a bag with --gt-topic")
    evaluate_parser.add_argument("--gt-topic", help="the bag's PoseStamped, Odometry or TransformStamped topic")
    alignments = [a.value for a in Alignment]
    evaluate_parser.add_argument("--align", default="origin", choices=alignments, help="(default: origin)")
    evaluate_parser.add_argument(
        "--delta", type=_positive, default=RPE_DELTA_M, help="RPE segment length, m (default 1)"
    )
    evaluate_parser.add_argument("--plot", type=Path, help="PNG to write: both paths and the error along the path")
    add_sweep_commands(commands)
    try:
        args = parser.parse_args(argv)
    except SystemExit as exit:  # usage errors (2) and --help (0), returned like every other outcome
        return exit.code if isinstance(exit.code, int) else 2
    previous = signal.signal(signal.SIGTERM, _interrupt)
    try:
        return _command(args)
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return INTERRUPTED
    except Exception as error:
        if args.debug:
            raise
        known = isinstance(error, ValueError | OSError | CalibrationError)
        print(f"error: {error}" if known else f"error: {type(error).__name__}: {error}", file=sys.stderr)
        if not known:
            print("(--debug shows where it arose)", file=sys.stderr)
        return 1
    finally:
        signal.signal(signal.SIGTERM, previous)


def _command(args) -> int:
    """The chosen command; its exit code."""
    if args.command == "demo":
        written = demo(args.out)
        print(f"wrote {len(written)} files to {args.out.resolve()}:")
        for path in written:
            print(f"  {path}")
        print(written[-1].read_text(), end="")
    elif args.command == "simulate":
        if args.out.exists():
            raise ValueError(f"--out {args.out} exists; name a new bag (a bag is never replaced)")
        if (args.format == "ros1") != (args.out.suffix == ".bag"):
            raise ValueError(f"--out {args.out}: a ros1 bag is one file named *.bag, a ros2 bag a folder not so")
        check_output(args.out)
        from gpo.sim.record import PRESETS, simulate

        print(f"{args.preset}: {PRESETS[args.preset].description}")
        write_with(args.out, lambda temporary: simulate(args.preset, temporary, args.format))
        print(f"wrote {args.out}")
    elif args.command == "info":
        print(describe(args.bag))
    elif args.command == "recording":
        for path in recordings(args.names, args.jobs):
            print(path)
    elif args.command == "calibrate":
        check_output(args.out, args.images, "--out")
        result = main_calibrate(args.images, args.board, args.square, args.model, args.out, args.force)
        return 0 if result.ok else 1
    elif args.command == "config":
        return config_command(args)
    elif args.command == "mount":
        return mount_command(args)
    elif args.command == "run":
        return run_command(args)
    elif args.command == "evaluate":
        if args.plot:
            check_plot(args.plot, [args.estimate, args.truth])
        estimate, truth = read_tum(args.estimate), read_truth(args.truth, args.gt_topic)
        try:
            evaluation = evaluate(estimate, truth, args.align, args.delta)
        except ValueError as error:
            raise ValueError(f"{args.estimate} against {args.truth}: {error}") from None
        print(evaluation)
        if args.plot:
            print(f"wrote {save_evaluation_plot(evaluation, args.plot)}")
    elif args.command == "table4":
        from gpo.book.ch09_table4 import PATHS, reproduce_table4

        table = reproduce_table4(tuple(args.paths or PATHS))
        print(table.format(), table.format_table2(), sep="\n\n")
    elif args.command == "sample-data":
        from gpo.sim.record import write_sample_data

        for path in write_sample_data(args.out):
            print(f"wrote {path}")
    elif args.command == "sweep":
        return sweep_command(args)
    elif args.command == "sweep-report":
        for path in sweep_report(args.results, args.out):
            print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
