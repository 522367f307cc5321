"""Rendering speed of the simulator: frames per second for each rig and floor kind, anti-aliased.

    python benchmarks/render_speed.py [--frames N]

Per rig the rays, floor points and mip levels are computed once (reported as set-up time); a frame
then turns the floor points by the robot's pose, looks them up in the texture and adds the sensor.
Target: at least 5 frames per second at 848 x 800 on a 2-core machine.
"""

import argparse
import time

import numpy as np

from gpo.sim.floors import FLOOR_KINDS, make_floor
from gpo.sim.render import FloorRenderer
from gpo.sim.rigs import downward_rig, t265_rig


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=30)
    args = parser.parse_args()

    print(f"{'rig':<10}{'floor':<12}{'image':>10}{'set-up s':>10}{'frames/s':>10}")
    for rig, texel in ((t265_rig(), 1e-3), (downward_rig(), 5e-4)):
        for kind in FLOOR_KINDS:
            floor = make_floor(kind, (-1.5, 3.5, -2.5, 2.5), texel=texel, seed=0)
            start = time.perf_counter()
            renderer = FloorRenderer(rig, floor)
            set_up = time.perf_counter() - start
            poses = np.column_stack(
                [np.linspace(0, 1, args.frames), np.zeros(args.frames), np.linspace(0, 0.5, args.frames)]
            )
            start = time.perf_counter()
            for index, pose in enumerate(poses):
                renderer.render(pose, frame_seed=index)
            rate = args.frames / (time.perf_counter() - start)
            size = f"{rig.camera.width}x{rig.camera.height}"
            print(f"{rig.name:<10}{kind:<12}{size:>10}{set_up:>10.2f}{rate:>10.1f}")


if __name__ == "__main__":
    main()
