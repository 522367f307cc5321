"""Speed and memory of ``python -m gpo run``: a bag on disk to a trajectory, raw mono8 848 x 800 frames.

    python benchmarks/odometry_speed.py [--method gpo-exact] [--threads T] [--repeat N]

In one process, on the ``sample`` recording (441 frames, rendered on first use), best of N:

- end to end: ``gpo.pipeline.run`` (read, decode, rectify, track, integrate), frames per second;
- its unavoidable parts, each over the same frames: reading and decoding every frame (``Recording.frames``),
  one ``cv2.remap`` of each frame to the floor image, and one ``cv2.calcOpticalFlowPyrLK`` call per frame pair
  with the config's window and pyramid on the tracks ``FloorFlow`` had for that pair;
- the ratio of the end-to-end time per frame to the sum of the parts: what the rest (the backward check,
  re-detection, the estimator, Python) costs;
- streaming: the latency of ``FloorOdometer.step`` (a frame already in memory, as a robot's node receives it, to its
  pose), median and 99th percentile over the recording's frames.

Memory: peak resident set size of a fresh process running the ``test`` recording (90 frames) and the same frames
repeated ten times in one bag (900 frames, written to a temporary folder), so that growth with length shows.
"""

import argparse
import subprocess
import sys
import tempfile
import time
import timeit
from pathlib import Path

import cv2
import numpy as np

from gpo.io.bag import Recording
from gpo.io.bag_writer import BagWriter
from gpo.pipeline.config import load_config
from gpo.pipeline.odometer import FloorOdometer
from gpo.pipeline.run import run
from gpo.sim.record import recording


def best_seconds(function, repeat: int) -> float:
    """The shortest of ``repeat`` runs of ``function()``, seconds."""
    return min(timeit.repeat(function, number=1, repeat=repeat))


def parts(bag: Path, config, repeat: int) -> dict[str, float]:
    """Seconds for decoding, remapping and one LK call per frame over the whole recording."""

    def decode():
        with Recording(bag) as recorded:
            return [frame.image for frame in recorded.frames(progress=False)]

    images = decode()
    odometer = FloorOdometer(config)
    floors = [odometer.table.apply(image) for image in images]
    tracked = [record.tracked for record in run(bag, config, progress=False).records[1:]]
    klt = config.klt
    pairs = []  # each frame pair with as many corners as the tracker followed for it
    for previous, current, count in zip(floors[:-1], floors[1:], tracked, strict=True):
        corners = cv2.goodFeaturesToTrack(previous, klt.max_corners, klt.quality_level, klt.min_distance_px)
        pairs.append((previous, current, corners[:count]))
    criteria = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, klt.max_iterations, klt.epsilon_px)

    def track():
        for previous, current, points in pairs:
            cv2.calcOpticalFlowPyrLK(
                previous, current, points.reshape(-1, 1, 2), None, winSize=(klt.window_px,) * 2,
                maxLevel=klt.pyramid_levels, criteria=criteria,
            )

    return {
        "read + decode": best_seconds(decode, repeat),
        "one remap": best_seconds(lambda: [odometer.table.apply(image) for image in images], repeat),
        "one LK call": best_seconds(track, repeat),
    }


def step_latencies_ms(bag: Path, config) -> np.ndarray:
    """Milliseconds of each ``FloorOdometer.step`` over the recording's frames, decoded beforehand."""
    with Recording(bag) as recorded:
        frames = [(frame.stamp_ns, frame.image) for frame in recorded.frames(progress=False)]
    odometer = FloorOdometer(config)
    latencies = []
    for stamp_ns, image in frames:
        started = time.perf_counter()
        odometer.step(stamp_ns, image)
        latencies.append(time.perf_counter() - started)
    return np.array(latencies[1:]) * 1e3  # the first frame measures nothing


def peak_rss_mb(bag: Path, method: str) -> float:
    """Peak resident memory (MB) of a fresh process that runs the odometry on ``bag``."""
    code = (  # VmHWM, not ru_maxrss: the latter keeps the parent's peak across fork and exec
        "from pathlib import Path\n"
        "from gpo.pipeline.config import load_config\n"
        "from gpo.pipeline.run import run\n"
        f"run({str(bag)!r}, load_config().replace(method={method!r}), progress=False)\n"
        "print(next(line for line in Path('/proc/self/status').read_text().splitlines() if line.startswith('VmHWM')))\n"
    )
    output = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    return int(output.split()[-2]) / 1024


def repeated(source: Path, times: int, out: Path) -> Path:
    """A bag with the images of ``source`` repeated ``times`` times, stamps running on."""
    with Recording(source) as recorded:
        frames = list(recorded.frames(progress=False))
    step = frames[1].stamp_ns - frames[0].stamp_ns
    span = frames[-1].stamp_ns - frames[0].stamp_ns + step
    with BagWriter(out) as bag:
        for k in range(times):
            for frame in frames:
                bag.add_image("/camera/fisheye1/image_raw", frame.stamp_ns + k * span, frame.image, frame.frame_id)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--method", default="gpo-exact")
    parser.add_argument("--threads", type=int, default=-1, help="OpenCV threads (default: OpenCV's choice)")
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    if args.threads >= 0:
        cv2.setNumThreads(args.threads)
    config = load_config().replace(method=args.method)
    bag = recording("sample", progress=False)
    with Recording(bag) as recorded:
        count = sum(1 for _ in recorded.frames(progress=False))

    whole = best_seconds(lambda: run(bag, config, progress=False), args.repeat)
    costs = parts(bag, config, args.repeat)
    print(f"sample recording: {count} frames of 848 x 800 mono8, method {args.method}, "
          f"OpenCV threads {cv2.getNumThreads()}, best of {args.repeat}")
    print(f"  end to end            {whole / count * 1e3:6.2f} ms/frame  {count / whole:6.0f} frames/s")
    for name, seconds in costs.items():
        print(f"  {name:20s}  {seconds / count * 1e3:6.2f} ms/frame")
    floor = sum(costs.values())
    print(f"  sum of the parts      {floor / count * 1e3:6.2f} ms/frame; end to end is {whole / floor:.2f} x that")
    latency = step_latencies_ms(bag, config)
    print(f"  streaming (FloorOdometer.step on a decoded frame): median {np.median(latency):.2f} ms, "
          f"p99 {np.percentile(latency, 99):.2f} ms")

    short = recording("test", progress=False)
    with tempfile.TemporaryDirectory() as folder:
        long = repeated(short, 10, Path(folder) / "test-x10.bag")
        print(f"peak RSS: test recording {peak_rss_mb(short, args.method):.0f} MB, "
              f"ten times longer {peak_rss_mb(long, args.method):.0f} MB")


if __name__ == "__main__":
    main()
