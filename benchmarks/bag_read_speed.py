"""Speed of reading raw images from a bag: ``Recording.frames`` in frames per second.

    python benchmarks/bag_read_speed.py [--frames N] [--repeat R]

Writes N raw mono8 848x800 frames (the T265 fisheye's size) into a temporary ROS1 bag and ROS2
bags (sqlite3 and mcap), then prints the best of R full passes of ``frames(progress=False)`` for
each. The files were just written, so they are read from the page cache: this measures gpo and
rosbags, not the disk. Raw frames are views of the message buffer, so a frame costs the read of
its bytes and the deserialisation of its header, never a copy of its pixels.
"""

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

from gpo.io.bag import Recording
from gpo.io.bag_writer import BagWriter

HEIGHT, WIDTH = 800, 848
PERIOD_NS = 33_333_333  # 30 Hz
FORMATS = {"ros1": "frames.bag", "ros2": "frames_sqlite3", "ros2-mcap": "frames_mcap"}


def write_bag(path: Path, bag_format: str, frames: int) -> None:
    rng = np.random.default_rng(0)
    image = rng.integers(0, 256, (HEIGHT, WIDTH), dtype=np.uint8)
    with BagWriter(path, bag_format) as writer:
        for i in range(frames):
            writer.add_image("/camera/fisheye1/image_raw", i * PERIOD_NS, image, "t265_fisheye1_optical_frame")


def seconds_to_read(path: Path) -> tuple[float, int]:
    """Seconds for one pass over every frame, and the number of frames read."""
    start = time.perf_counter()
    with Recording(path) as recording:
        count = sum(1 for _ in recording.frames(progress=False))
    return time.perf_counter() - start, count


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=300)
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()

    megabytes = HEIGHT * WIDTH / 1e6
    print(f"{args.frames} raw mono8 {WIDTH}x{HEIGHT} frames, best of {args.repeat} passes")
    print(f"{'format':<12}{'frames/s':>10}{'MB/s':>8}{'ms/frame':>10}")
    with tempfile.TemporaryDirectory() as folder:
        for bag_format, name in FORMATS.items():
            path = Path(folder) / name
            write_bag(path, bag_format, args.frames)
            seconds, count = min(seconds_to_read(path) for _ in range(args.repeat))
            assert count == args.frames, f"{path}: read {count} of {args.frames} frames"
            rate = count / seconds
            print(f"{bag_format:<12}{rate:>10.0f}{rate * megabytes:>8.0f}{1e3 / rate:>10.2f}")


if __name__ == "__main__":
    main()
