"""Speed of calibrating every camera model on BoofCV-Data's 26 real fisheye views (chapter 01's real check).

    GPO_DATA_DIR=../shared/real_data python benchmarks/calibration_models.py [--repeat R]

Times, median of R runs: finding the 6 x 4 inner corners in the 26 images, the EUCM fit, then each other
model started from the EUCM (``prior``), and the omni with p1 = p2 = 0 held. Prints seconds and, for reference,
each fit's RMS reprojection error. Chapter 01 does all of this once; it must stay well under a minute.
"""

import argparse
import statistics
import time

import cv2

from gpo.cameras.calibrate import MODELS, calibrate_corners
from gpo.cameras.chessboard import find_corners
from gpo.cameras.targets import Chessboard
from gpo.io.datasets import boofcv_fisheye_chessboard

BOARD = Chessboard((7, 5), 1.0)
SIZE = (640, 720)


def median_seconds(repeat: int, function):
    """Median seconds of ``repeat`` runs of ``function()``, and its last result."""
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        result = function()
        times.append(time.perf_counter() - start)
    return statistics.median(times), result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=1)
    args = parser.parse_args()
    paths, _ = boofcv_fisheye_chessboard()
    images = [cv2.imread(str(path), cv2.IMREAD_GRAYSCALE) for path in paths]
    seconds, corners = median_seconds(args.repeat, lambda: [find_corners(image, (6, 4)) for image in images])
    print(f"corner detection, {len(images)} images: {seconds:6.2f} s")
    total = seconds
    seconds, eucm = median_seconds(args.repeat, lambda: calibrate_corners(corners, BOARD, SIZE, "eucm"))
    print(f"eucm fit:                     {seconds:6.2f} s  (RMS {eucm.rms_px:.3f} px)")
    total += seconds
    runs = [(model, ()) for model in MODELS[1:]] + [("omni", ("p1", "p2"))]
    for model, zero in runs:
        seconds, fit = median_seconds(
            args.repeat, lambda m=model, z=zero: calibrate_corners(corners, BOARD, SIZE, m, zero=z, prior=eucm)
        )
        label = f"{model} fit" + (" (p1 = p2 = 0)" if zero else "")
        print(f"{label:30}{seconds:6.2f} s  (RMS {fit.rms_px:.3f} px)")
        total += seconds
    print(f"all of it:                    {total:6.2f} s")


if __name__ == "__main__":
    main()
