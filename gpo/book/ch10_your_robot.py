"""Chapter 10, your robot: the commands run as a user runs them, and what a mount measured wrong does to a run."""

from __future__ import annotations

import dataclasses
import subprocess
import sys

import numpy as np

from gpo.cameras.rig import CameraMount
from gpo.io.bag import Recording
from gpo.metrics import final_error
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


def mistaken_mounts(mount: CameraMount) -> dict[str, CameraMount]:
    """``mount`` as measured and with the mistakes people make: squares 25 mm taken for 20 mm (every length, the
    height included, 1.25 times), the pitch 1 or 3 degrees off, the roll 3 degrees off."""
    roll, pitch, yaw = mount.body_rpy

    def tilted(d_roll_deg=0.0, d_pitch_deg=0.0, scale=1.0) -> CameraMount:
        position = mount.position * [1.0, 1.0, scale]
        return CameraMount.from_rpy(position, roll + np.radians(d_roll_deg), pitch + np.radians(d_pitch_deg), yaw)

    return {
        "as measured": mount,
        "squares 25 mm, not 20": tilted(scale=1.25),
        "pitch +1 deg": tilted(d_pitch_deg=1.0),
        "pitch +3 deg": tilted(d_pitch_deg=3.0),
        "pitch -3 deg": tilted(d_pitch_deg=-3.0),
        "roll +3 deg": tilted(d_roll_deg=3.0),
    }


def mistakes_table(bag, config: OdometryConfig, truth_topic: str = "/mocap/base_link") -> str:
    """``config`` run on ``bag`` with each of ``mistaken_mounts`` of its mount: the distance the run travelled (m),
    its final position error (mm, and % of the truth's distance) and final heading error (deg), as text."""
    with Recording(bag) as recording:
        truth = recording.trajectory(truth_topic)
    lines = [f"{'mount':<24}{'distance':>10}{'final error':>14}{'heading':>10}"]
    for name, mount in mistaken_mounts(config.rig.mount).items():
        wrong = config.replace(rig=dataclasses.replace(config.rig, mount=mount))
        result = run(bag, wrong, progress=False)
        error = final_error(result.trajectory, truth)
        travelled = np.sum(np.linalg.norm(np.diff(result.trajectory.positions[:, :2], axis=0), axis=1))
        lines.append(f"{name:<24}{travelled:>8.3f} m{1e3 * error.position_m:>10.1f} mm"
                     f"{np.degrees(error.heading_rad):>8.2f} deg  ({error.percent:.1f} % of {error.distance_m:.2f} m)")
    return "\n".join(lines)
