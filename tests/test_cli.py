"""The command line: ``python -m gpo demo`` writes what it says it writes."""

import errno
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import gpo.cli.demo
from gpo.cameras import T265_LIKE
from gpo.cli import main
from gpo.io.bag import Recording
from gpo.io.trajectory import Trajectory
from gpo.sim.record import GROUND_TRUTH_TOPIC, recording


def test_demo_writes_figures_and_the_field_of_view_table(tmp_path):
    result = subprocess.run(
        [sys.executable, "-m", "gpo", "demo", "--out", str(tmp_path)], capture_output=True, text=True, check=True
    )
    assert str(tmp_path) in result.stdout
    for name in ("fisheye_room_grid.png", "projection_curves.png"):
        assert (tmp_path / name).read_bytes().startswith(b"\x89PNG")
    table = (tmp_path / "field_of_view.txt").read_text().splitlines()
    horizontal = np.degrees(T265_LIKE.field_of_view()[0])
    assert table[0].startswith("EUCM alpha=0.6, beta=1.1:") and f"horizontal {horizontal:.1f} deg" in table[0]


def test_the_demo_replaces_a_run_s_trajectory_summary_and_plot_as_one_set(tmp_path, monkeypatch):
    """The disk fills as the demo's plot of its gpo-exact run is written: the trajectory, summary and plot of an
    earlier demo stay as they were, all three, and nothing is left half written."""
    names = ("sample_gpo_exact.tum", "sample_gpo_exact.summary.yaml", "sample_gpo_exact.png")
    for name in names:
        (tmp_path / name).write_text(f"an earlier demo's {name}\n")

    def full(path):
        Path(path).write_bytes(b"\x89PNG half")
        raise OSError(errno.ENOSPC, "No space left on device", str(path))

    monkeypatch.setattr(gpo.cli.demo, "figure_writer", lambda figure, dpi: full)
    expected = rf"{re.escape(str(tmp_path / names[2]))}: the disk is full .* the files already there are kept as"
    with pytest.raises(OSError, match=expected):
        gpo.cli.demo.sample_odometry(tmp_path)
    assert {path.name: path.read_text() for path in tmp_path.iterdir()} == {
        name: f"an earlier demo's {name}\n" for name in names
    }


def test_unknown_command_fails_with_usage():
    result = subprocess.run([sys.executable, "-m", "gpo", "fly"], capture_output=True, text=True)
    assert result.returncode == 2 and "invalid choice: 'fly'" in result.stderr


def test_the_command_line_starts_without_what_only_some_commands_use():
    """The fusion's filterpy (which imports scipy.stats) and scipy.optimize (the calibration's, the mount's and the
    simulator's fits) are imported by what uses them, not by every process that starts the command line."""
    heavy = ("filterpy", "scipy.stats", "scipy.optimize", "matplotlib", "distributed")
    code = f"import sys, gpo.cli, gpo.sim.record; print(*[name for name in {heavy!r} if name in sys.modules])"
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert result.stdout.split() == []


def _write_scaled_pair(truth, folder, scale: float):
    """TUM files of ``truth`` and of an estimate that covers ``scale`` times its ground from the same start; return
    (estimate, truth) paths and the final position error in mm that origin alignment must find."""
    start = truth.positions[0]
    estimate = Trajectory(truth.stamps_ns, start + scale * (truth.positions - start), truth.quaternions)
    chord_m = np.hypot(*(truth.positions[-1, :2] - start[:2]))
    paths = (estimate.write_tum(folder / "estimate.tum"), truth.write_tum(folder / "truth.tum"))
    return paths, (scale - 1.0) * chord_m * 1e3


def test_evaluate_prints_the_table_and_plots_two_tum_files(tmp_path):
    t = np.linspace(0.0, 10.0, 101)
    truth = Trajectory.from_planar(np.round(t * 1e9).astype(np.int64), 2.0 * np.sin(0.3 * t), t, 0.3 * t)
    (estimate, truth_tum), final_mm = _write_scaled_pair(truth, tmp_path, 1.02)
    plot = tmp_path / "evaluation.png"
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "gpo",
            "evaluate",
            str(estimate),
            str(truth_tum),
            "--align",
            "origin",
            "--plot",
            str(plot),
        ],
        capture_output=True,
        text=True,
        check=True,
    )
    assert "alignment               origin" in result.stdout and "poses associated        101" in result.stdout
    assert f"final position error    {final_mm:.1f} mm" in result.stdout
    assert "RPE per 1 m [mm]" in result.stdout and f"wrote {plot}" in result.stdout
    # the suite's drift, by its name: 2 % of each segment's chord; a segment ends at the first pose past 1 m of travel,
    # at most 0.12 m past it (1.17 m/s at most, poses 0.1 s apart), and its chord is at most its arc: 2-2.4 %
    drift = float(re.search(r"drift per metre +([0-9.]+) % \(RPE mean / 1 m\)", result.stdout).group(1))
    assert 1.9 <= drift <= 2.4
    assert plot.read_bytes().startswith(b"\x89PNG")


def test_evaluate_reads_the_truth_from_a_bag(tmp_path, capsys):
    bag = recording("test", progress=False)
    with Recording(bag) as recorded:
        truth = recorded.trajectory(GROUND_TRUTH_TOPIC)
    (estimate, _), final_mm = _write_scaled_pair(truth, tmp_path, 1.05)
    assert main(["evaluate", str(estimate), str(bag), "--gt-topic", GROUND_TRUTH_TOPIC, "--align", "se2"]) == 0
    out = capsys.readouterr().out
    assert "alignment               se2" in out and f"poses associated        {len(truth)}" in out
    assert "none: the truth travels less than 1 m" in out  # the test recording covers 0.8 m
    assert main(["evaluate", str(estimate), str(bag), "--gt-topic", GROUND_TRUTH_TOPIC, "--delta", "0.2"]) == 0
    out = capsys.readouterr().out
    assert f"final position error    {final_mm:.1f} mm" in out and "RPE per 0.2 m [mm]" in out


@pytest.mark.parametrize(
    ("arguments", "message"),
    [
        ([], "is a recording: name its ground-truth topic with --gt-topic (pose topics: /camera/odom/sample, /mocap"),
        (["--gt-topic", "/camera/fisheye1/camera_info"], "carries sensor_msgs/msg/CameraInfo; expected one of"),
        (["--gt-topic", "/mocap/base_lnk"], "has no topic /mocap/base_lnk (did you mean /mocap/base_link?)"),
    ],
)
def test_evaluate_names_what_is_wrong_with_the_bag(tmp_path, capsys, arguments, message):
    bag = recording("test", progress=False)
    with Recording(bag) as recorded:
        (estimate, _), _ = _write_scaled_pair(recorded.trajectory(GROUND_TRUTH_TOPIC), tmp_path, 1.0)
    assert main(["evaluate", str(estimate), str(bag), *arguments]) == 1
    error = capsys.readouterr().err
    assert error.startswith("error: ") and message in error


def test_evaluate_names_the_file_with_bad_numbers(tmp_path, capsys):
    t = np.linspace(0.0, 1.0, 11)
    truth = Trajectory.from_planar(np.round(t * 1e9).astype(np.int64), t, 0 * t, 0 * t).write_tum(tmp_path / "gt.tum")
    estimate = tmp_path / "estimate.tum"
    estimate.write_text(truth.read_text().replace("1.0 0.0 0.0", "nan 0.0 0.0"))
    assert main(["evaluate", str(estimate), str(truth)]) == 1
    assert capsys.readouterr().err == (  # line 12: the header comment, then the eleventh pose
        f"error: {estimate}:12: '1.000000000 nan 0.0 0.0 0.0 0.0 0.0 1.0': positions and quaternions must be finite "
        "numbers\n"
    )


def test_recordings_rendered_at_once_are_the_bag_rendered_alone(tmp_path, monkeypatch, capsys):
    """Two processes rendering the same preset at once leave one bag, byte for byte the one rendered alone (the
    cache's, which one process rendered)."""
    alone = recording("test", progress=False)
    monkeypatch.setenv("GPO_CACHE_DIR", str(tmp_path / "at-once"))
    assert main(["recording", "test", "test", "--jobs", "2"]) == 0
    printed = capsys.readouterr().out.splitlines()
    assert printed[:2] == ["test: ready", "test: ready"]
    assert printed[2] == printed[3] == str(tmp_path / "at-once" / "recordings" / alone.name)
    assert Path(printed[2]).read_bytes() == alone.read_bytes()
    assert sorted(path.name for path in (tmp_path / "at-once" / "recordings").iterdir()) == [
        alone.name, f"{alone.name}.crc32"  # the bag and its seal
    ]


def test_recording_refuses_fewer_than_one_job(capsys):
    assert main(["recording", "test", "--jobs", "0"]) != 0
    assert "--jobs must be at least 1, not 0" in capsys.readouterr().err
