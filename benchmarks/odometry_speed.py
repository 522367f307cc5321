"""Speed and memory of ``python -m gpo run``: a bag on disk to a trajectory, raw mono8 848 x 800 frames.

    python benchmarks/odometry_speed.py [--method gpo-exact] [--repeat N]

In one process, on the ``sample`` recording (441 frames, rendered on first use):

- end to end: ``gpo.pipeline.run`` (read, decode, rectify, track, integrate) on one thread and on two
  (``threads=2``: the next frames read and prepared in a second thread, OpenCV's work shared), the two alternated
  ``N`` times; medians, and the median of the pairs' ratios;
- its unavoidable parts on one thread, each over the same frames (best of N): reading and decoding every frame
  (``Recording.frames``), one ``cv2.remap`` of each frame to the floor image, and one ``cv2.calcOpticalFlowPyrLK``
  call per frame pair with the config's window and pyramid on the tracks the run had for that pair;
- the ratio of the one-thread end-to-end time per frame to the sum of the parts: what the rest (the backward check,
  re-detection, the normalisation, the estimator, Python) costs;
- streaming (``gpo.pipeline.live.LiveOdometer``, one thread): the latency of each ``step`` on a frame already in
  memory, as a robot's node receives it, to its pose, median and 99th percentile; for ``fused``, with the tracking
  camera's 200 Hz messages between the frames, each ``step`` and each ``track``.

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

from gpo.fusion import FusionSettings
from gpo.io.bag import Recording
from gpo.io.bag_writer import BagWriter
from gpo.pipeline.config import load_config
from gpo.pipeline.live import LiveOdometer
from gpo.pipeline.odometer import FloorOdometer
from gpo.pipeline.run import run, tracking_mount
from gpo.sim.record import recording


def best_seconds(function, repeat: int) -> float:
    """The shortest of ``repeat`` runs of ``function()``, seconds."""
    return min(timeit.repeat(function, number=1, repeat=repeat))


def end_to_end(bag: Path, config, repeat: int) -> dict[int, np.ndarray]:
    """Seconds of ``repeat`` whole runs on one thread and on two, alternated so that the machine's drift hits both."""
    seconds = {1: [], 2: []}
    for _ in range(repeat):
        for threads in seconds:
            started = time.perf_counter()
            run(bag, config, progress=False, threads=threads)
            seconds[threads].append(time.perf_counter() - started)
    return {threads: np.array(values) for threads, values in seconds.items()}


def parts(bag: Path, config, repeat: int) -> dict[str, float]:
    """Seconds for decoding, remapping and one LK call per frame over the whole recording, on one thread."""

    def decode():
        with Recording(bag) as recorded:
            return [frame.image for frame in recorded.frames(progress=False)]

    images = decode()
    odometer = FloorOdometer(config)
    floors = [odometer.table.apply(image) for image in images]
    tracked = [record.tracked for record in run(bag, config, progress=False, threads=1).records[1:]]
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

    cv2.setNumThreads(1)
    return {
        "read + decode": best_seconds(decode, repeat),
        "one remap": best_seconds(lambda: [odometer.table.apply(image) for image in images], repeat),
        "one LK call": best_seconds(track, repeat),
    }


def latencies_ms(bag: Path, config) -> dict[str, np.ndarray]:
    """Milliseconds of each ``LiveOdometer.step`` over the recording's frames, decoded beforehand, and for ``fused``
    of each ``track`` of the tracking camera's messages, fed between the frames in stamp order."""
    settings = FusionSettings()
    with Recording(bag) as recorded:
        frames = [(frame.stamp_ns, 1, frame.image) for frame in recorded.frames(gray=True, progress=False)]
        odometry = recorded.trajectory(settings.tracking_topic)
        mount, _ = tracking_mount(recorded, settings)
    messages = frames
    if config.method == "fused":
        messages += [(int(s), 0, (p, q)) for s, p, q in zip(odometry.stamps_ns, odometry.positions,
                                                            odometry.quaternions, strict=True)]
    odometer = LiveOdometer(config, mount)
    spent = {"step": [], "track": []}
    cv2.setNumThreads(1)
    for stamp_ns, kind, payload in sorted(messages, key=lambda message: message[:2]):
        started = time.perf_counter()
        if kind == 1:
            odometer.step(stamp_ns, payload)
        else:
            odometer.track(stamp_ns, *payload)
        spent["step" if kind == 1 else "track"].append(time.perf_counter() - started)
    spent["step"] = spent["step"][1:]  # the first frame measures nothing
    return {name: np.array(values) * 1e3 for name, values in spent.items() if values}


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
    parser.add_argument("--repeat", type=int, default=7)
    args = parser.parse_args()
    config = load_config().replace(method=args.method)
    bag = recording("sample", progress=False)
    with Recording(bag) as recorded:
        count = sum(1 for _ in recorded.frames(progress=False))

    whole = end_to_end(bag, config, args.repeat)
    one, two = (np.median(whole[threads]) / count * 1e3 for threads in (1, 2))
    print(f"sample recording: {count} frames of 848 x 800 mono8, method {args.method}, {args.repeat} runs each")
    print(f"  end to end, one thread   {one:6.2f} ms/frame  {1e3 / one:6.0f} frames/s  (median)")
    print(f"  end to end, two threads  {two:6.2f} ms/frame  {1e3 / two:6.0f} frames/s  (median)")
    print(f"  two threads against one: {one / two:.2f} x faster (median of the pairs: "
          f"{np.median(whole[1] / whole[2]):.2f} x)")
    costs = parts(bag, config, args.repeat)
    for name, seconds in costs.items():
        print(f"  {name:22s}  {seconds / count * 1e3:6.2f} ms/frame  (best of {args.repeat}, one thread)")
    floor = sum(costs.values()) / count * 1e3
    print(f"  sum of the parts        {floor:6.2f} ms/frame; end to end on one thread is {one / floor:.2f} x that")
    for method in (args.method, "fused"):
        for name, latency in latencies_ms(bag, config.replace(method=method)).items():
            print(f"  streaming {method} {name}: median {np.median(latency):.2f} ms, "
                  f"p99 {np.percentile(latency, 99):.2f} ms, max {latency.max():.2f} ms ({len(latency)} calls)")

    short = recording("test", progress=False)
    with tempfile.TemporaryDirectory() as folder:
        long = repeated(short, 10, Path(folder) / "test-x10.bag")
        print(f"peak RSS: test recording {peak_rss_mb(short, args.method):.0f} MB, "
              f"ten times longer {peak_rss_mb(long, args.method):.0f} MB")


if __name__ == "__main__":
    main()
