"""Rendering speed of the simulator, and what the renderer of an earlier revision made of the same frames.

    python benchmarks/render_speed.py [--frames N] [--baseline REV] [--presets sample downward-wood]
                                      [--write benchmarks/results/render_speed.json]

Two renderers run side by side, each in a process of its own with its own ``gpo`` package: this working tree's
and the one of git revision ``--baseline`` (by default the last commit before the renderer worked in float32
tables), unpacked with ``git archive``. For each rig and floor kind each renders the same ``--frames`` poses; per
rig the rays, floor points and mip levels are computed once (set-up time), a frame then turns the floor points by
the robot's pose, looks them up in the texture and adds the sensor. Reported:

- frames per second (the median frame time, wall clock) of both, and their ratio (target: 3 or more), and the
  median CPU time a frame (all threads), which a machine busy with other work changes less;
- the noise-free frames (``Sensor`` without noise and flicker) compared pixel by pixel: max and mean absolute grey
  difference over all frames (the scene's geometry and shading);
- the sensor noise of each, the standard deviation of a frame minus its noise-free twin, grey levels (the noise is
  drawn by different generators, so noisy frames differ pixel by pixel, not in kind);
- the odometry of each ``--presets`` recording rendered by both (``gpo.sim.record.simulate``) and run through
  this tree's pipeline with the rig's shipped config: each final position error against the ground truth, and the
  largest distance between the two trajectories. Tolerance: the two final errors within 0.2 % of the distance
  travelled of each other.
"""

import argparse
import json
import os
import subprocess
import sys
import tarfile
import tempfile
import time
from io import BytesIO
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
BASELINE = "9e82ef9"  # the renderer before its float32 tables, OpenCV noise and wrapped wall lookups
CONFIGS = {rig: ROOT / "gpo" / "configs" / f"sim_{rig}.yaml" for rig in ("t265", "downward")}
TOLERANCE_PERCENT = 0.2
TEXEL_M = {"t265": 1e-3, "downward": 5e-4}  # as the recordings' floors (gpo.sim.record)
KINDS = ("wood", "raised", "industrial")  # gpo.sim.floors.FLOOR_KINDS


def render_frames(rig_name: str, kind: str, frames: int, out: Path) -> dict:
    """In a worker: time ``frames`` renders of ``rig_name`` over a ``kind`` floor with the ``gpo`` on the path; keep
    the frames, noisy and noise-free, in ``out``."""
    from gpo.sim.floors import make_floor
    from gpo.sim.render import FloorRenderer, Sensor
    from gpo.sim.rigs import RIGS

    rig = RIGS[rig_name]()
    floor = make_floor(kind, (-1.5, 3.5, -2.5, 2.5), texel=TEXEL_M[rig_name], seed=0)
    poses = np.column_stack([np.linspace(0, 1, frames), np.zeros(frames), np.linspace(0, 0.5, frames)])
    start = time.perf_counter()
    renderer = FloorRenderer(rig, floor)
    set_up = time.perf_counter() - start
    walls, cpus, noisy = [], [], []
    for index, pose in enumerate(poses):
        wall, cpu = time.perf_counter(), time.process_time()
        noisy.append(renderer.render(pose, frame_seed=index))
        walls.append(time.perf_counter() - wall)
        cpus.append(time.process_time() - cpu)
    clean = FloorRenderer(rig, floor, Sensor(read_noise=0.0, shot_noise=0.0, flicker=0.0))
    np.savez(out, noisy=np.stack(noisy), clean=np.stack([clean.render(pose) for pose in poses]))
    return {
        "size": f"{rig.camera.width}x{rig.camera.height}",
        "set_up_s": set_up,
        "frames_per_second": 1.0 / float(np.median(walls)),
        "cpu_ms_per_frame": 1e3 * float(np.median(cpus)),
    }


def simulate_presets(presets: list[str], folder: Path) -> dict:
    """In a worker: render each preset's bag into ``folder`` with the ``gpo`` on the path."""
    from gpo.sim.record import PRESETS, simulate

    folder.mkdir(parents=True, exist_ok=True)
    return {name: [PRESETS[name].rig, str(simulate(name, folder / f"{name}.bag", progress=False))] for name in presets}


def in_worker(package_root: Path, job: str, *arguments) -> dict:
    """Run ``job`` of this script in a new process whose ``gpo`` is the one under ``package_root``."""
    environment = {**os.environ, "PYTHONPATH": str(package_root)}
    command = [sys.executable, __file__, "--worker", job, *map(str, arguments)]
    finished = subprocess.run(command, env=environment, check=True, capture_output=True, text=True)
    return json.loads(finished.stdout.splitlines()[-1])


def unpack(revision: str, folder: Path) -> Path:
    """The ``gpo`` package of git ``revision``, unpacked into ``folder``; returns ``folder``."""
    archive = subprocess.run(["git", "-C", str(ROOT), "archive", revision, "gpo"], check=True, capture_output=True)
    with tarfile.open(fileobj=BytesIO(archive.stdout)) as tar:
        tar.extractall(folder, filter="data")
    return folder


def odometry(bag: str, rig: str) -> tuple[np.ndarray, dict]:
    """This tree's odometry of ``bag`` with the rig's shipped config: positions (N, 2) and the final error."""
    from gpo.io.bag import Recording
    from gpo.metrics import final_error
    from gpo.pipeline.config import load_config
    from gpo.pipeline.run import run
    from gpo.sim.record import GROUND_TRUTH_TOPIC

    result = run(bag, load_config(CONFIGS[rig]), progress=False)
    with Recording(bag) as recorded:
        truth = recorded.trajectory(GROUND_TRUTH_TOPIC)
    error = final_error(result.trajectory, truth)
    final = {"distance_m": error.distance_m, "final_error_m": error.position_m, "final_error_percent": error.percent}
    return result.trajectory.positions[:, :2], final


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=30)
    parser.add_argument("--baseline", default=BASELINE, help="git revision of the renderer to compare with")
    parser.add_argument("--presets", nargs="*", default=["sample", "downward-wood"])
    parser.add_argument("--write", type=Path, help="JSON file for the results")
    parser.add_argument("--worker", nargs="+", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.worker:
        job, *arguments = args.worker
        if job == "frames":
            rig_name, kind, frames, out = arguments
            print(json.dumps(render_frames(rig_name, kind, int(frames), Path(out))))
        else:
            print(json.dumps(simulate_presets(arguments[1:], Path(arguments[0]))))
        return

    results = {"baseline": args.baseline, "frames": args.frames, "renderers": {}, "odometry": {}}
    with tempfile.TemporaryDirectory() as scratch:
        scratch = Path(scratch)
        roots = {"baseline": unpack(args.baseline, scratch / "baseline"), "now": ROOT}
        print(f"frames/s (median frame time, wall clock), CPU ms a frame; baseline {args.baseline} against this tree")
        header = f"{'rig-floor':<20}{'image':>9}{'before':>8}{'after':>8}{'x':>6}{'CPU ms before/after':>21}{'x':>6}"
        print(f"{header}{'clean diff max/mean':>21}{'noise sd before/after':>23}")
        for rig_name in TEXEL_M:
            for kind in KINDS:  # the two renderers alternate, so that both see the machine's load alike
                key = f"{rig_name}-{kind}"
                before, now = (
                    in_worker(root, "frames", rig_name, kind, args.frames, scratch / f"{name}.npz")
                    for name, root in roots.items()
                )
                frames = {name: np.load(scratch / f"{name}.npz") for name in roots}
                old, new = (frames[name]["clean"].astype(float) for name in roots)
                noise = [float(np.std(frames[name]["noisy"].astype(float) - frames[name]["clean"])) for name in roots]
                row = {
                    "frames_per_second_before": round(before["frames_per_second"], 1),
                    "frames_per_second_after": round(now["frames_per_second"], 1),
                    "speed_up": round(now["frames_per_second"] / before["frames_per_second"], 2),
                    "cpu_ms_before": round(before["cpu_ms_per_frame"], 1),
                    "cpu_ms_after": round(now["cpu_ms_per_frame"], 1),
                    "cpu_speed_up": round(before["cpu_ms_per_frame"] / now["cpu_ms_per_frame"], 2),
                    "clean_difference_max": float(np.abs(old - new).max()),
                    "clean_difference_mean": round(float(np.abs(old - new).mean()), 4),
                    "noise_sd_before": round(noise[0], 3),
                    "noise_sd_after": round(noise[1], 3),
                }
                results["renderers"][key] = row
                print(
                    f"{key:<20}{now['size']:>9}{row['frames_per_second_before']:>8.1f}"
                    f"{row['frames_per_second_after']:>8.1f}{row['speed_up']:>6.2f}"
                    f"{row['cpu_ms_before']:>12.1f} / {row['cpu_ms_after']:<6.1f}{row['cpu_speed_up']:>6.2f}"
                    f"{row['clean_difference_max']:>11.0f} / {row['clean_difference_mean']:<7.4f}"
                    f"{row['noise_sd_before']:>12.2f} / {row['noise_sd_after']:.2f}",
                    flush=True,
                )
        if args.presets:
            bags = {
                name: in_worker(root, "bags", scratch / f"{name}-bags", *args.presets) for name, root in roots.items()
            }
            print("\nodometry (this tree's pipeline, shipped configs) on recordings rendered by each renderer")
            print(f"{'preset':<16}{'distance m':>11}{'final error before':>20}{'after':>16}{'max apart mm':>14}")
            for preset in args.presets:
                rig = bags["now"][preset][0]
                (path_before, before), (path_after, after) = (
                    odometry(bags[name][preset][1], rig) for name in ("baseline", "now")
                )
                apart = float(np.max(np.linalg.norm(path_before - path_after, axis=1)))
                within = abs(before["final_error_percent"] - after["final_error_percent"]) <= TOLERANCE_PERCENT
                results["odometry"][preset] = {"before": before, "after": after, "max_apart_m": apart, "within": within}
                print(
                    f"{preset:<16}{after['distance_m']:>11.2f}"
                    f"{before['final_error_m'] * 1e3:>11.1f} mm {before['final_error_percent']:.2f} %"
                    f"{after['final_error_m'] * 1e3:>7.1f} mm {after['final_error_percent']:.2f} %"
                    f"{apart * 1e3:>14.1f}  {'within' if within else 'NOT within'} {TOLERANCE_PERCENT} %"
                )
    if args.write:
        from gpo.io.outputs import write_json  # here: a worker's gpo is another revision's

        print(f"wrote {write_json(args.write, results)}")


if __name__ == "__main__":
    main()
