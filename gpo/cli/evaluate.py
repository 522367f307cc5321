"""``python -m gpo evaluate``: a TUM trajectory's errors against the ground truth (a TUM file or a bag's topic)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from gpo.cli.common import positive, save_figure
from gpo.io.bag import Recording
from gpo.io.outputs import check_output
from gpo.io.ros_messages import POSE_TYPES
from gpo.io.trajectory import Trajectory
from gpo.metrics import RPE_DELTA_M, Alignment, Evaluation, evaluate

if TYPE_CHECKING:
    from matplotlib.figure import Figure

NAME = "evaluate"
HELP = "errors of a TUM trajectory against the ground truth"
PLOT_DPI = 110  # --plot's resolution, dots per inch


def add_arguments(parser) -> None:
    parser.add_argument("estimate", type=Path, help="the estimated trajectory, a TUM file")
    parser.add_argument("truth", type=Path, help="ground truth: a TUM file, or a bag with --gt-topic")
    parser.add_argument("--gt-topic", help="the bag's PoseStamped, Odometry or TransformStamped topic")
    parser.add_argument("--align", default="origin", choices=[a.value for a in Alignment], help="(default: origin)")
    parser.add_argument("--delta", type=positive, default=RPE_DELTA_M, help="RPE segment length, m (default 1)")
    parser.add_argument("--plot", type=Path, help="PNG to write: both paths and the error along the path")


def run(args) -> int:
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
    return 0


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
    """``Trajectory.read_tum`` (its errors name the file and the line: stamps that go backwards too), with the file
    named in every error; a stamp repeated with another pose is refused (a pose repeated as it was is read once)."""
    if path.is_dir():
        raise ValueError(f"{path} is a folder; expected a TUM file (t tx ty tz qx qy qz qw per line)")
    try:
        trajectory = Trajectory.read_tum(path)
    except ValueError as error:
        if str(path) in str(error):
            raise
        raise ValueError(f"{path}: {error}") from None
    if len(trajectory) == 0:
        raise ValueError(f"{path} holds no poses; expected a TUM file (t tx ty tz qx qy qz qw per line)")
    stamps = trajectory.stamps_ns
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
            stamps[keep],
            trajectory.positions[keep],
            trajectory.quaternions[keep],
            trajectory.frame_id,
            trajectory.child_frame_id,
        )
    return trajectory


def save_evaluation_plot(evaluation: Evaluation, out: Path) -> Path:
    """``evaluation_figure`` written to a temporary name and renamed to ``out`` (its suffix names the format)."""
    return save_figure(evaluation_figure(evaluation), out, dpi=PLOT_DPI)


def evaluation_figure(evaluation: Evaluation) -> Figure:
    """A figure of both paths (the estimate aligned) and the position error along the truth's distance."""
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
    return fig


def check_plot(path: Path, inputs: list[Path]) -> Path:
    """``--plot`` checked before the evaluation: a writable file (``check_output``) of a format matplotlib writes."""
    from matplotlib.figure import Figure

    check_output(path, inputs, "--plot")
    formats = Figure().canvas.get_supported_filetypes()
    if path.suffix.lstrip(".").lower() not in formats:
        raise ValueError(f"--plot {path}: name a file ending in one of .{', .'.join(sorted(formats))}")
    return path
