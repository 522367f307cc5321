"""``python -m gpo calibrate``: a camera's intrinsics from images of a chessboard (``gpo.cameras.calibrate``), written
as a Kalibr camchain."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from gpo.cameras import MODELS
from gpo.cameras.calibrate import CalibrationResult, calibrate_images
from gpo.cameras.chessboard import parse_board
from gpo.cameras.files import save_kalibr
from gpo.cli.common import positive
from gpo.io.outputs import check_output, destination, write_with

NAME = "calibrate"
HELP = "calibrate a camera from chessboard images"


def add_arguments(parser) -> None:
    parser.add_argument("images", nargs="+", type=Path, help="image files of the board")
    parser.add_argument("--board", required=True, help="inner corners per row x per column, e.g. 7x5")
    parser.add_argument("--square", required=True, type=positive, help="square size in metres")
    parser.add_argument("--model", default="eucm", choices=tuple(MODELS))
    parser.add_argument("--out", type=Path, default=Path("calib.yaml"), help="Kalibr camchain to write")
    parser.add_argument("--force", action="store_true", help="a fit flagged as bad replaces --out too")


def run(args) -> int:
    check_output(args.out, args.images, "--out")
    result = main_calibrate(args.images, args.board, args.square, args.model, args.out, args.force)
    return 0 if result.ok else 1


def main_calibrate(
    images: Sequence,
    board: str,
    square: float,
    model: str = "eucm",
    out: Path | str = "calib.yaml",
    force: bool = False,
) -> CalibrationResult:
    """``python -m gpo calibrate IMAGES... --board 7x5 --square 0.03 --model eucm --out calib.yaml``.

    Calibrates ``model`` from the image files, prints the summary and writes ``out`` as a Kalibr
    camchain (``cam0``), through a temporary name. Kalibr's radtan has no k3, so the pinhole is fitted
    with k3 = 0 here. The file is written even when the fit is not good; the summary then says so and
    why, ``result.ok`` is false (the command should exit non-zero), the file says so too in its first
    lines (comments: "flagged", then each warning), and a file already at ``out`` is kept unless
    ``force``: the fit goes beside it (``gpo.io.outputs.destination``).
    """
    result = calibrate_images(images, parse_board(board), square, model, progress=True, fix_k3=model == "pinhole")
    print(result.summary())
    path = destination(out, flagged=not result.ok, force=force)
    if path != Path(out):
        print(f"{out} is kept: this fit is not a good calibration (--force replaces it)")
    flags = [] if result.ok else [
        f"flagged by gpo calibrate: NOT A GOOD CALIBRATION ({result.summary().splitlines()[0]})",
        *(f"WARNING: {warning}" for warning in result.warnings),
    ]
    written = write_with(path, lambda temporary: save_kalibr(temporary, {"cam0": result.camera}, comments=flags))
    print(f"wrote {written}")
    return result
