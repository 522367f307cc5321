"""Speed of an 848 x 800 fisheye frame -> ortho-rectified ground plane image (400 x 400 by default).

    python benchmarks/ground_speed.py [--repeat N] [--threads T] [--metres-per-pixel M]

Times, best of N runs in milliseconds per frame:

- staged: the paper's route, three resamplings (fisheye -> front and bottom faces by ``cv2.remap``, front face ->
  GPI by ``cv2.warpPerspective`` with the bottom face's crop stacked below, GPI -> ortho-GPI by
  ``cv2.warpPerspective``);
- composed: the one table (``RemapTable.apply``), with float maps and with fixed-point maps;
- bare: ``cv2.remap`` of the same output size with an identity-like map (a window of the fisheye), float and
  fixed-point: what one remap of that size costs at least.

The route is calibrated on the simulator's floor-board frame (``floor_board_image("t265")``); its tables come
from the disk cache after the first run. ``--threads`` sets OpenCV's thread count (default 1: one core).
"""

import argparse
import timeit

import cv2
import numpy as np

from gpo.floor_image.image import FloorImage
from gpo.floor_image.ortho import chessboard_route
from gpo.sim.record import FLOOR_BOARDS, floor_board_image
from gpo.sim.rigs import t265_rig


def bare_maps(width: int, height: int, source: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """float32 maps reading a ``width`` x ``height`` window at the middle of a ``source`` (width, height) image."""
    left, top = (source[0] - width) / 2.0, (source[1] - height) / 2.0
    u, v = np.meshgrid(np.arange(width, dtype=np.float32) + left, np.arange(height, dtype=np.float32) + top)
    return u, v


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=7)
    parser.add_argument("--threads", type=int, default=1, help="OpenCV threads (default 1: one core)")
    parser.add_argument("--metres-per-pixel", type=float, default=0.5e-3, help="of the 0.2 x 0.2 m ortho-GPI")
    args = parser.parse_args()
    cv2.setNumThreads(args.threads)

    rig, board = t265_rig(), FLOOR_BOARDS["t265"]
    frame = floor_board_image("t265")
    floor = FloorImage.top_view(metres_per_pixel=args.metres_per_pixel)
    ortho = chessboard_route(frame, rig.camera, board, floor)
    table = ortho.table
    bare = bare_maps(floor.width, floor.height, table.source_size)
    bare_fixed = cv2.convertMaps(*bare, cv2.CV_16SC2)

    def bare_remap(maps) -> np.ndarray:
        return cv2.remap(frame, *maps, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT)

    runs = {
        "staged (3 resamplings)": lambda: ortho.staged(frame),
        "composed table, float maps": lambda: table.apply(frame),
        "composed table, fixed-point maps": lambda: table.apply(frame, fixed=True),
        "bare cv2.remap, float maps": lambda: bare_remap(bare),
        "bare cv2.remap, fixed-point maps": lambda: bare_remap(bare_fixed),
    }
    times = {}
    for name, run in runs.items():
        run()  # warm the caches
        number = 20 if name.startswith("staged") else 200
        times[name] = 1e3 * min(timeit.repeat(run, number=number, repeat=args.repeat)) / number

    print(
        f"fisheye {rig.camera.width}x{rig.camera.height} -> ortho-GPI {floor.width}x{floor.height} "
        f"({floor.metres_per_pixel * 1e3:.2f} mm/px), GPI {ortho.gpi.size[0]}x{ortho.gpi.size[1]}, "
        f"OpenCV threads {cv2.getNumThreads()}"
    )
    for name, milliseconds in times.items():
        print(f"{name:<36}{milliseconds:>8.3f} ms / frame ({1e3 / milliseconds:>7.0f} frames/s)")
    staged = times["staged (3 resamplings)"]
    for kind in ("float", "fixed-point"):
        composed, plain = times[f"composed table, {kind} maps"], times[f"bare cv2.remap, {kind} maps"]
        print(
            f"{kind + ' maps:':<20}staged / composed {staged / composed:5.1f}x (target >= 3), "
            f"composed / bare {composed / plain:4.2f}x (target <= 1.5), {1e3 / composed:.0f} frames/s (target >= 1000)"
        )


if __name__ == "__main__":
    main()
