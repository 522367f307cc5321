"""Speed and memory of ``python -m gpo run``: a bag on disk to a trajectory, on one core here and on a slower one.

    python benchmarks/odometry_speed.py [--method gpo-exact] [--recording sample ...] [--set KEY=VALUE ...]
                                        [--repeat N] [--slower N --slower-source TEXT] [--write FILE.json]

In one process, on a simulated recording rendered on first use (by default the fisheye ``sample``: 441 frames of
848 x 800 mono8; ``downward-wood`` or ``downward-long`` for the floor feature odometer, 752 x 480), read with the
shipped config of its rig (``gpo/configs/``), the keys ``--set`` changes (as a sweep's overrides, e.g.
``features.follow=lk``) and ``--method``:

- end to end: ``gpo.pipeline.run`` (read, decode, rectify, track, integrate) on one thread and on two
  (``threads=2``: the next frames read and prepared in a second thread, OpenCV's work shared), the two alternated
  ``N`` times; wall-clock medians and the median of the pairs' ratios, and on one thread the process's CPU time
  (``time.process_time``) too: a machine shared with other work stretches the wall clock of every run, the CPU time
  far less, so on such a machine the CPU time is the one-core speed to read;
- a core ``--slower`` times slower (``--slower-source`` names where the ratio comes from): the one-thread rate
  divided by it and the streaming latencies multiplied by it. A ratio from a general CPU benchmark is an estimate: a
  core's caches, memory and SIMD width (AVX2 here, NEON's 128 bits on an ARM board) do not slow every part alike.
  One way to get it: the same single-thread CPU benchmark (e.g. ``sysbench cpu --threads=1 run``) here on a quiet
  machine and on the board, or a board's published result for the same command;
- for the KLT methods, the unavoidable parts on one thread, each over the same frames (CPU time, best of N):
  reading and decoding every frame (``Recording.frames``), one ``cv2.remap`` of each frame to the floor image, and
  one ``cv2.calcOpticalFlowPyrLK`` call per frame pair with the config's window and pyramid on the tracks the run
  had for that pair; and the ratio of the one-thread end-to-end CPU time per frame to their sum: what the rest (the
  backward check, re-detection, the normalisation, the whole-view check, the estimator, Python) costs;
- streaming (``gpo.pipeline.live.LiveOdometer``, one thread): the latency of each ``step`` on a frame already in
  memory, as a robot's node receives it, to its pose (wall clock and the thread's CPU time), median and 99th
  percentile; for a fisheye recording the ``fused`` method too, with the tracking camera's 200 Hz messages between
  the frames, each ``step`` and each ``track``.

Memory: peak resident set size of a fresh process running the first 90 frames of the recording and the same frames
repeated ten times in one bag (900 frames, written to a temporary folder), so that growth with length shows.
"""

import argparse
import shlex
import subprocess
import sys
import tempfile
import time
import timeit
from pathlib import Path

import cv2
import numpy as np
import yaml

from gpo.batch.runs import Run, configured
from gpo.fusion import FusionSettings
from gpo.io.bag import Recording
from gpo.io.bag_writer import BagWriter
from gpo.io.outputs import write_json
from gpo.pipeline.live import LiveOdometer
from gpo.pipeline.odometer import FloorOdometer
from gpo.pipeline.run import run, tracking_mount
from gpo.sim.record import preset, recording

CONFIGS = Path(__file__).resolve().parents[1] / "gpo" / "configs"
CONFIG = {"t265": CONFIGS / "sim_t265.yaml", "downward": CONFIGS / "sim_downward.yaml"}  # by the preset's rig
MEMORY_FRAMES = 90  # the memory is measured on this many frames of the recording, and on ten times as many


def best_cpu_seconds(function, repeat: int) -> float:
    """The shortest CPU time of ``repeat`` runs of ``function()``, seconds."""
    return min(timeit.repeat(function, number=1, repeat=repeat, timer=time.process_time))


def end_to_end(bag: Path, config, repeat: int) -> dict[str, np.ndarray]:
    """Seconds of ``repeat`` whole runs on one thread (wall clock and CPU time) and on two (wall clock), alternated so
    that the machine's drift hits both."""
    seconds = {"one": [], "one cpu": [], "two": []}
    for _ in range(repeat):
        started, cpu = time.perf_counter(), time.process_time()
        run(bag, config, progress=False, threads=1)
        seconds["one"].append(time.perf_counter() - started)
        seconds["one cpu"].append(time.process_time() - cpu)
        started = time.perf_counter()
        run(bag, config, progress=False, threads=2)
        seconds["two"].append(time.perf_counter() - started)
    return {name: np.array(values) for name, values in seconds.items()}


def parts(bag: Path, config, repeat: int) -> dict[str, float]:
    """CPU seconds for decoding, remapping and one LK call per frame over the whole recording, on one thread."""

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
        "read + decode": best_cpu_seconds(decode, repeat),
        "one remap": best_cpu_seconds(lambda: [odometer.table.apply(image) for image in images], repeat),
        "one LK call": best_cpu_seconds(track, repeat),
    }


def latencies_ms(bag: Path, config) -> dict[str, np.ndarray]:
    """Milliseconds of each ``LiveOdometer.step`` over the recording's frames, decoded beforehand, and for ``fused``
    of each ``track`` of the tracking camera's messages, fed between the frames in stamp order: wall clock
    (``step``, ``track``) and the thread's CPU time (``step cpu``, ``track cpu``)."""
    with Recording(bag) as recorded:
        messages = [(frame.stamp_ns, 1, frame.image) for frame in recorded.frames(gray=True, progress=False)]
        mount = None
        if config.method == "fused":
            settings = FusionSettings()
            odometry = recorded.trajectory(settings.tracking_topic)
            mount, _ = tracking_mount(recorded, settings)
            messages += [(int(s), 0, (p, q)) for s, p, q in zip(odometry.stamps_ns, odometry.positions,
                                                                odometry.quaternions, strict=True)]
    odometer = LiveOdometer(config, mount)
    spent = {"step": [], "track": [], "step cpu": [], "track cpu": []}
    cv2.setNumThreads(1)
    for stamp_ns, kind, payload in sorted(messages, key=lambda message: message[:2]):
        started, cpu = time.perf_counter(), time.thread_time()
        if kind == 1:
            odometer.step(stamp_ns, payload)
        else:
            odometer.track(stamp_ns, *payload)
        name = "step" if kind == 1 else "track"
        spent[name].append(time.perf_counter() - started)
        spent[f"{name} cpu"].append(time.thread_time() - cpu)
    spent["step"], spent["step cpu"] = spent["step"][1:], spent["step cpu"][1:]  # the first frame measures nothing
    return {name: np.array(values) * 1e3 for name, values in spent.items() if values}


def peak_rss_mb(bag: Path, config_path: Path, overrides: dict, method: str) -> float:
    """Peak resident memory (MB) of a fresh process that runs the odometry on ``bag``."""
    code = (  # VmHWM, not ru_maxrss: the latter keeps the parent's peak across fork and exec
        "from pathlib import Path\n"
        "from gpo.batch.runs import Run, configured\n"
        "from gpo.pipeline.run import run\n"
        f"config = configured(Run({str(bag)!r}, 'memory', {str(config_path)!r}, {overrides!r}))\n"
        f"run({str(bag)!r}, config.replace(method={method!r}), progress=False)\n"
        "print(next(line for line in Path('/proc/self/status').read_text().splitlines() if line.startswith('VmHWM')))\n"
    )
    output = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    return int(output.split()[-2]) / 1024


def repeated(source: Path, count: int, times: int, out: Path) -> Path:
    """A bag with the first ``count`` images of ``source`` (its only image topic) repeated ``times`` times, stamps
    running on."""
    with Recording(source) as recorded:
        topic = recorded.image_topic()
        frames = [frame for frame, _ in zip(recorded.frames(topic, progress=False), range(count), strict=False)]
    step = frames[1].stamp_ns - frames[0].stamp_ns
    span = frames[-1].stamp_ns - frames[0].stamp_ns + step
    with BagWriter(out) as bag:
        for k in range(times):
            for frame in frames:
                bag.add_image(topic, frame.stamp_ns + k * span, frame.image, frame.frame_id)
    return out


def measure(name: str, method: str, repeat: int, slower: float, overrides: dict) -> dict:
    """Every number of the module's list for the recording ``name`` and ``method``, its rig's config with
    ``overrides`` (dotted keys, as a sweep's)."""
    config_path = CONFIG[preset(name).rig]
    bag = recording(name, progress=False)
    config = configured(Run(str(bag), name, str(config_path), overrides)).replace(method=method)
    with Recording(bag) as recorded:
        count = sum(1 for _ in recorded.frames(progress=False))
        width, height = next(iter(recorded.frames(progress=False))).image.shape[::-1]
    whole = end_to_end(bag, config, repeat)
    per_frame = {name: float(np.median(seconds)) / count * 1e3 for name, seconds in whole.items()}
    result = {
        "recording": name, "frames": count, "size": [width, height], "method": method, "overrides": overrides,
        "runs": repeat,
        "ms_per_frame": {key: round(value, 3) for key, value in per_frame.items()},
        "frames_per_second": {key: round(1e3 / value, 1) for key, value in per_frame.items()},
        "two_threads_over_one": round(float(np.median(whole["one"] / whole["two"])), 2),
        "slower_core": {"ratio": slower, "frames_per_second": round(1e3 / per_frame["one cpu"] / slower, 1)},
    }
    if config.estimator.MOTION == "tracks":
        costs = {key: seconds / count * 1e3 for key, seconds in parts(bag, config, repeat).items()}
        result["parts_ms_per_frame"] = {key: round(value, 3) for key, value in costs.items()}
        result["over_parts"] = round(per_frame["one cpu"] / sum(costs.values()), 2)
    streamed = [method] + (["fused"] if preset(name).rig == "t265" else [])
    result["streaming_ms"] = {
        f"{streamed_method} {call}": {"median": round(float(np.median(ms)), 2),
                                      "p99": round(float(np.percentile(ms, 99)), 2), "calls": len(ms)}
        for streamed_method in streamed
        for call, ms in latencies_ms(bag, config.replace(method=streamed_method)).items()
    }
    with tempfile.TemporaryDirectory() as folder:
        short = repeated(bag, MEMORY_FRAMES, 1, Path(folder) / "short.bag")
        long = repeated(bag, MEMORY_FRAMES, 10, Path(folder) / "long.bag")
        result["peak_rss_mb"] = {str(MEMORY_FRAMES): round(peak_rss_mb(short, config_path, overrides, method)),
                                 str(10 * MEMORY_FRAMES): round(peak_rss_mb(long, config_path, overrides, method))}
    return result


def print_result(result: dict, slower_source: str | None) -> None:
    ms, rate = result["ms_per_frame"], result["frames_per_second"]
    width, height = result["size"]
    changed = "".join(f", {key}={value}" for key, value in result["overrides"].items())
    print(f"{result['recording']}: {result['frames']} frames of {width} x {height} mono8, method {result['method']}"
          f"{changed}, {result['runs']} runs each")
    print(f"  end to end, one thread   {ms['one']:6.2f} ms/frame {rate['one']:7.1f} frames/s  (wall clock, median)")
    print(f"  end to end, one thread   {ms['one cpu']:6.2f} ms/frame {rate['one cpu']:7.1f} frames/s  "
          "(CPU time, median)")
    print(f"  end to end, two threads  {ms['two']:6.2f} ms/frame {rate['two']:7.1f} frames/s  (wall clock, median)")
    print(f"  two threads against one: {result['two_threads_over_one']:.2f} x faster (median of the pairs)")
    slower = result["slower_core"]
    if slower["ratio"] != 1:
        print(f"  on a core {slower['ratio']:g} x slower ({slower_source or 'source not given'}): "
              f"{slower['frames_per_second']:.1f} frames/s")
    for name, value in result.get("parts_ms_per_frame", {}).items():
        print(f"  {name:22s}  {value:6.2f} ms/frame  (CPU time, best of {result['runs']}, one thread)")
    if "over_parts" in result:
        print(f"  sum of the parts        {sum(result['parts_ms_per_frame'].values()):6.2f} ms/frame; end to end on "
              f"one thread is {result['over_parts']:.2f} x that (CPU time)")
    for name, latency in result["streaming_ms"].items():
        p99 = latency["p99"] * slower["ratio"]
        scaled = "" if slower["ratio"] == 1 else f"; on the slower core p99 {p99:.2f} ms"
        print(f"  streaming {name}: median {latency['median']:.2f} ms, p99 {latency['p99']:.2f} ms "
              f"({latency['calls']} calls){scaled}")
    memory = result["peak_rss_mb"]
    print(f"  peak RSS: {MEMORY_FRAMES} frames {memory[str(MEMORY_FRAMES)]} MB, "
          f"{10 * MEMORY_FRAMES} frames {memory[str(10 * MEMORY_FRAMES)]} MB")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--method", default="gpo-exact")
    parser.add_argument("--recording", nargs="+", default=["sample"], help="simulated recordings (presets)")
    parser.add_argument("--set", nargs="+", default=[], metavar="KEY=VALUE",
                        help="config keys changed (dotted, the value in YAML), e.g. features.follow=lk")
    parser.add_argument("--repeat", type=int, default=7)
    parser.add_argument("--slower", type=float, default=1.0, help="how many times slower a robot's core is")
    parser.add_argument("--slower-source", help="where --slower comes from (a board, a benchmark)")
    parser.add_argument("--write", type=Path, help="JSON file for the results")
    args = parser.parse_args()
    if args.slower <= 0 or args.repeat < 1:
        parser.error("--slower must be positive and --repeat at least 1")
    try:
        overrides = {key: yaml.safe_load(value) for key, _, value in (item.partition("=") for item in args.set)}
    except yaml.YAMLError as error:
        parser.error(f"--set: {error}")
    results = []
    for name in args.recording:
        results.append(measure(name, args.method, args.repeat, args.slower, overrides))
        print_result(results[-1], args.slower_source)
    if args.write:
        document = {"command": "python benchmarks/odometry_speed.py " + shlex.join(sys.argv[1:]),
                    "slower_source": args.slower_source, "results": results}
        print(f"wrote {write_json(args.write, document)}")


if __name__ == "__main__":
    main()
