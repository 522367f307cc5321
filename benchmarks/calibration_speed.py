"""Speed of intrinsic calibration: corner detection and the least-squares fits, on simulated board views.

    python benchmarks/calibration_speed.py [--views N] [--repeat R]

Renders N views of the default board by the T265-like fisheye (not timed), then times, best of R:
finding the corners in all N images, the EUCM fit of the corners found (0.3 px of noise added), the
pinhole fit by OpenCV of the downward camera's corners, and the whole of ``calibrate_views``.
Target: 24 views calibrated, images to result, in under 20 s on a 2-core machine.
"""

import argparse
import timeit

import numpy as np

from gpo.cameras.calibrate import calibrate_corners, calibrate_views, initial_eucm
from gpo.cameras.chessboard import find_corners
from gpo.sim.boardviews import CALIBRATION_BOARD, board_poses, board_views
from gpo.sim.rigs import downward_rig, t265_rig


def best_of(repeat: int, function) -> float:
    """The shortest of ``repeat`` runs of ``function()``, seconds."""
    return min(timeit.repeat(function, number=1, repeat=repeat))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--views", type=int, default=24)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()

    fisheye = t265_rig().camera
    views = board_views(fisheye, args.views, seed=0)
    images = [view.image for view in views]
    size = (fisheye.width, fisheye.height)
    guess = initial_eucm(*size)
    corners = [find_corners(image, CALIBRATION_BOARD.pattern_size, guess) for image in images]
    rng = np.random.default_rng(0)
    noisy = [c + rng.normal(0.0, 0.3, c.shape) for c in corners]

    downward = downward_rig().camera
    poses = board_poses(downward, args.views, CALIBRATION_BOARD, seed=0)
    pinhole_corners = [
        downward.project(rotation.apply(CALIBRATION_BOARD.inner_corners()) + position)[0]
        + rng.normal(0.0, 0.3, (35, 2))
        for rotation, position in poses
    ]

    steps = (
        ("find corners (fisheye)", lambda: [find_corners(i, CALIBRATION_BOARD.pattern_size, guess) for i in images]),
        ("EUCM fit", lambda: calibrate_corners(noisy, CALIBRATION_BOARD, size)),
        ("pinhole fit (OpenCV)", lambda: calibrate_corners(pinhole_corners, CALIBRATION_BOARD, (752, 480), "pinhole")),
        ("calibrate_views, EUCM", lambda: calibrate_views(images, CALIBRATION_BOARD)),
    )
    print(f"{args.views} views, best of {args.repeat}")
    print(f"{'step':<26}{'s':>8}{'ms / view':>12}")
    for name, function in steps:
        seconds = best_of(args.repeat, function)
        print(f"{name:<26}{seconds:>8.2f}{seconds / args.views * 1e3:>12.1f}")


if __name__ == "__main__":
    main()
