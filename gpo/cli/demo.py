"""``python -m gpo demo``: the suite's figures, tables and the sample recording's odometry, written to a folder."""

from __future__ import annotations

from pathlib import Path

from gpo.cameras import EUCM, T265_LIKE, Pinhole
from gpo.cli.common import figure_writer, save_figure
from gpo.cli.evaluate import PLOT_DPI, evaluation_figure
from gpo.io.bag import Recording
from gpo.io.outputs import write_text, write_together, write_with
from gpo.metrics import evaluate
from gpo.pipeline.config import load_config
from gpo.pipeline.run import run as run_odometry
from gpo.pipeline.run import tracking_path

NAME = "demo"
HELP = "write the suite's figures, tables and trajectories into a folder"


def add_arguments(parser) -> None:
    parser.add_argument("--out", type=Path, default=Path("out"), help="output folder (default: out)")


def run(args) -> int:
    written = demo(args.out)
    print(f"wrote {len(written)} files to {args.out.resolve()}:")
    for path in written:
        print(f"  {path}")
    print(written[-1].read_text(), end="")
    return 0


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
    save_figure(fig, written[-1], dpi=110)

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
    save_figure(fig, written[-1], dpi=110)

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
    save_figure(fig, frames_png, dpi=90)

    fig = Figure(figsize=(7, 5))
    draw_paths({"ground truth": truth, "tracking camera's odometry": tracked}, ax=fig.subplots())
    paths_png = out / "sample_paths.png"
    save_figure(fig, paths_png, dpi=110)
    return [
        frames_png,
        paths_png,
        write_with(out / "sample_groundtruth.tum", truth.write_tum),
        write_with(out / "sample_tracking_odometry_base.tum", tracked.write_tum),
    ]


def sample_odometry(out: Path) -> list[Path]:
    """The sample recording's odometry, ``gpo-exact`` alone and fused with the tracking camera by the EKF (the last
    files: ``sample_fused.evaluation.txt``, its evaluation table): each run's trajectory, summary and plot against
    the truth, written as one set."""
    from gpo.sim.record import GROUND_TRUTH_TOPIC, recording

    bag = recording("sample")
    with Recording(bag) as recorded:
        truth = recorded.trajectory(GROUND_TRUTH_TOPIC)
    written = []
    for method, name in (("gpo-exact", "sample_gpo_exact"), ("fused", "sample_fused")):
        result = run_odometry(bag, load_config().replace(method=method), progress=False)
        evaluation = evaluate(result.trajectory, truth, "origin")
        plot = figure_writer(evaluation_figure(evaluation), PLOT_DPI)
        written += write_together({**result.files(out / f"{name}.tum"), out / f"{name}.png": plot})  # one set
    written.append(out / "sample_fused.evaluation.txt")
    write_text(written[-1], f"EKF (gpo-exact + tracking camera) on the sample recording\n{evaluation.table()}\n")
    return written
