"""Frame-to-frame against keyframe tracking: the suite's fisheye methods' final error and heading, run by run.

    python benchmarks/keyframe_heading.py [--noise-draws 3] [--draws 2 4 6 8] [--methods gpo-rigid gpo-exact]

Two sets of recordings, each run twice per method: the shipped config as it is (its ``keyframe`` policy,
``gpo.motion.keyframes``) and with ``keyframe.max_frames: 1`` (every frame measured from the one before, as the
suite tracked before keyframes, record for record):

- the path on which ``gpo-rigid``'s heading was found fragile to noise: the fisheye rig (``t265``) 1.6 m ahead, a half
  turn on the spot, 1.9 m ahead and 1.2 m in reverse (4.7 m) over a matte industrial screed, rendered
  ``--noise-draws`` times with only the sensor's noise drawn anew (``NoiseOnly``: one floor texture, noise seeds
  1, 2, ...);
- the matte twins of population draws (``gpo.sim.population.draw``, even seeds: fisheye rigs no method was tuned
  on), each run with the config the population benchmark adapts to its rig (``population.adapted``).

Each row: the final position error in % of the distance and the final heading error (``gpo.metrics.final_error``,
first pose on the truth), the frames not measured, frames per second. Recordings are rendered on first use and
cached (a 4.7 m path takes about a minute on two cores).
"""

import argparse
import math
from dataclasses import dataclass

from population import adapted

from gpo.batch.runs import Run, configured
from gpo.io.bag import Recording
from gpo.metrics import final_error
from gpo.pipeline.run import run
from gpo.sim.drift import T265_DRIFT
from gpo.sim.floors import FloorDesign
from gpo.sim.plans import MotionPlan
from gpo.sim.population import draw, matte
from gpo.sim.record import FLOOR_MARGIN_M, GROUND_TRUTH_TOPIC, TEXEL_M, Setup, recording
from gpo.sim.rigs import t265_rig
from gpo.sim.segments import Spin, Straight

PATH = (Straight(1.6), Spin(math.pi), Straight(1.9), Straight(-1.2))
FLOOR_SEED = 7  # the screed's texture, the same in every noise draw
POLICIES = {"frame-to-frame": {"keyframe.max_frames": 1}, "keyframes": {}}


@dataclass(frozen=True)
class NoiseOnly(FloorDesign):
    """A floor whose texture is drawn from ``texture_seed`` whatever the setup's seed, so that setups differing in
    their seed differ in the sensor's noise alone (``gpo.sim.record.Setup`` seeds both from one number)."""

    texture_seed: int = 0

    def texture(self, extent, texel, seed):
        return super().texture(extent, texel, self.texture_seed)


def noise_draw(seed: int) -> tuple[str, Setup]:
    """The 4.7 m path over the matte screed, the sensor's noise drawn from ``seed``."""
    floor = NoiseOnly(("industrial",), sheen=False, texture_seed=FLOOR_SEED)
    setup = Setup(t265_rig(), MotionPlan(PATH), floor, seed, T265_DRIFT, TEXEL_M["t265"], FLOOR_MARGIN_M["t265"])
    return f"keyframe-path-noise{seed}", setup


def print_runs(label: str, bag, overrides: dict, methods: list[str]) -> None:
    """Each method on ``bag`` frame-to-frame and with keyframes, its config the shipped one with ``overrides``: one
    printed row each."""
    with Recording(bag) as recorded:
        truth = recorded.trajectory(GROUND_TRUTH_TOPIC)
    for method in methods:
        for policy, changes in POLICIES.items():
            config = configured(Run(str(bag), label, overrides={**overrides, "odometry.method": method, **changes}))
            result = run(bag, config, progress=False, threads=1)
            error = final_error(result.trajectory, truth)
            not_measured = len(result.records) - 1 - result.summary()["frames_measured"]
            print(
                f"{label:34s} {method:10s} {policy:15s} {error.distance_m:5.2f} m {error.percent:8.3f} % "
                f"{math.degrees(error.heading_rad):+7.2f}° {not_measured:8d} {result.frames_per_second:8.0f}",
                flush=True,
            )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--noise-draws", type=int, default=3)
    parser.add_argument("--draws", type=int, nargs="*", default=[2, 4, 6, 8], help="even seeds: fisheye draws")
    parser.add_argument("--methods", nargs="+", default=["gpo-rigid", "gpo-exact"])
    args = parser.parse_args()
    if any(seed % 2 for seed in args.draws):
        parser.error("--draws takes even seeds (the fisheye rigs)")
    print(f"{'run':34s} {'method':10s} {'tracking':15s} distance  final error  heading  unmeasured  frames/s")
    for seed in range(1, args.noise_draws + 1):
        label, setup = noise_draw(seed)
        print_runs(label, recording(setup, label=label, progress=False), {}, args.methods)
    for seed in args.draws:
        chosen = matte(draw(seed))
        label = f"{chosen.label}-matte"
        print_runs(label, recording(chosen.setup, label=label, progress=False), adapted(chosen), args.methods)


if __name__ == "__main__":
    main()
