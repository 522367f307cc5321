"""Speed of the cubemap of an 848 x 800 fisheye: building the look-up tables, remapping a frame to the faces.

    python benchmarks/cubemap_speed.py [--repeat N] [--face-size N] [--threads T]

Prints the best of N runs in milliseconds: the tables of all five faces built from scratch (once per
camera and face size), one frame remapped to all five faces, and the cross of one frame. ``--threads``
sets OpenCV's thread count (1: one core; default: OpenCV's own choice).
"""

import argparse
import timeit

import cv2
import numpy as np

from gpo.cameras import T265_LIKE
from gpo.floor_image import cubemap
from gpo.floor_image.cubemap import FACE_NAMES, Cubemap


def build_tables(face_size: int | None) -> None:
    """All five faces' tables, ready for ``cv2.remap``, with the module's table caches emptied first."""
    cubemap._face_maps.cache_clear()
    cubemap._remap_tables.cache_clear()
    faces = Cubemap(T265_LIKE, face_size)
    for name in FACE_NAMES:
        faces.face_image(np.zeros((T265_LIKE.height, T265_LIKE.width), np.uint8), name)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=7)
    parser.add_argument("--face-size", type=int, default=None, help="pixels; default 2 f of the fisheye")
    parser.add_argument("--threads", type=int, default=None, help="OpenCV threads; default OpenCV's choice")
    args = parser.parse_args()
    if args.threads is not None:
        cv2.setNumThreads(args.threads)

    faces = Cubemap(T265_LIKE, args.face_size)
    frame = np.random.default_rng(0).integers(0, 256, (T265_LIKE.height, T265_LIKE.width), dtype=np.uint8)
    build_ms = 1e3 * min(timeit.repeat(lambda: build_tables(args.face_size), number=1, repeat=args.repeat))
    faces.cross(frame)  # warm the caches again
    runs = 20

    def best_ms(function) -> float:
        return 1e3 * min(timeit.repeat(function, number=runs, repeat=args.repeat)) / runs

    five_ms = best_ms(lambda: [faces.face_image(frame, name) for name in FACE_NAMES])
    cross_ms = best_ms(lambda: faces.cross(frame))
    n, threads = faces.face_size, cv2.getNumThreads()
    print(f"fisheye {T265_LIKE.width}x{T265_LIKE.height}, five faces of {n}x{n} px, OpenCV threads {threads}")
    print(f"{'build the tables of all five faces':<40}{build_ms:>10.1f} ms (once)")
    print(f"{'remap a frame to all five faces':<40}{five_ms:>10.2f} ms / frame ({1e3 / five_ms:.0f} frames/s)")
    print(f"{'draw the cross (3N x 3N)':<40}{cross_ms:>10.2f} ms / frame")


if __name__ == "__main__":
    main()
