"""Chapter 10, your robot: the commands run as a user runs them, and what a mount measured wrong does to a run (its
paths drawn over the truth)."""

from __future__ import annotations

import dataclasses
import subprocess
import sys
from dataclasses import dataclass

import matplotlib.pyplot as plt
import numpy as np

from gpo.book.figures import draw_placed_paths
from gpo.cameras.rig import CameraMount
from gpo.io.trajectory import Trajectory
from gpo.metrics import FinalError, final_error, place_on_truth
from gpo.pipeline.config import OdometryConfig
from gpo.pipeline.run import run


def command(*arguments) -> None:
    """``python -m gpo ARGUMENTS``, run as a user runs it (a process of its own): print what it prints, then its errors
    (progress bars left out) and its exit code."""
    finished = subprocess.run(
        [sys.executable, "-m", "gpo", *(str(argument) for argument in arguments)], capture_output=True, text=True
    )
    print(finished.stdout, end="")
    for line in finished.stderr.splitlines():
        if "%|" not in line:  # the progress bars
            print(line)
    print(f"(exit code {finished.returncode})")


def mistaken_mounts(mount: CameraMount, board_xy: tuple[float, float]) -> dict[str, CameraMount]:
    """``mount`` as measured from a board whose corner lies at ``board_xy`` (metres in base_link, as ``gpo mount --at``
    was told), and with the mistakes people make: squares of 25 mm taken for 20 mm (the board's pose in the camera
    1.25 times further off, so the camera's place 1.25 times further from the board's corner: its height, and its x and
    y about the corner), the pitch 1 or 3 degrees off, the roll 3 degrees off."""
    roll, pitch, yaw = mount.body_rpy
    corner = np.array([*board_xy, 0.0])

    def tilted(d_roll_deg=0.0, d_pitch_deg=0.0, scale=1.0) -> CameraMount:
        position = corner + scale * (mount.position - corner)
        return CameraMount.from_rpy(position, roll + np.radians(d_roll_deg), pitch + np.radians(d_pitch_deg), yaw)

    return {
        "as measured": mount,
        "squares 25 mm, not 20": tilted(scale=1.25),
        "pitch +1 deg": tilted(d_pitch_deg=1.0),
        "pitch +3 deg": tilted(d_pitch_deg=3.0),
        "pitch -3 deg": tilted(d_pitch_deg=-3.0),
        "roll +3 deg": tilted(d_roll_deg=3.0),
    }


@dataclass(frozen=True)
class MistakenRun:
    """A run with a mistaken mount: its ``trajectory``, its ``error`` at the end against the truth
    (``gpo.metrics.final_error``) and the distance it ``travelled_m`` (metres)."""

    trajectory: Trajectory
    error: FinalError
    travelled_m: float


def mistaken_runs(
    bag, config: OdometryConfig, truth: Trajectory, board_xy: tuple[float, float]
) -> dict[str, MistakenRun]:
    """``config`` run on ``bag`` with each of ``mistaken_mounts`` of its mount (measured from a board whose corner
    lies at ``board_xy``), each against ``truth``; the config's floor image and lever stay as they are."""
    runs = {}
    for name, mount in mistaken_mounts(config.rig.mount, board_xy).items():
        wrong = config.replace(rig=dataclasses.replace(config.rig, mount=mount))
        trajectory = run(bag, wrong, progress=False).trajectory
        travelled = float(np.sum(np.linalg.norm(np.diff(trajectory.positions[:, :2], axis=0), axis=1)))
        runs[name] = MistakenRun(trajectory, final_error(trajectory, truth), travelled)
    return runs


def draw_mistakes(runs: dict[str, MistakenRun], truth: Trajectory, ax=None) -> plt.Axes:
    """Top view of ``mistaken_runs``' paths, each placed on ``truth`` by its first pose, over the truth."""
    if ax is None:
        _, ax = plt.subplots(figsize=(9, 6))
    placed = {name: place_on_truth(mistaken.trajectory, truth)[0].positions[:, :2] for name, mistaken in runs.items()}
    styles = {"as measured": {"color": "k", "lw": 2}}
    draw_placed_paths(placed, truth, ax=ax, styles=styles, truth_end=True)
    ax.set_title("the same bag, the mount measured with each mistake")
    return ax
