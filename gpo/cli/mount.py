"""``python -m gpo mount``: the camera's mount measured from one image of a chessboard lying on the floor.

``gpo.cameras.mount.measure`` finds the board (once: a second board in view is an error), fits its pose with
``gpo.cameras.mount.mount_from_corners`` and turns the numbers into a ``CameraMount``: with the board's place on the
floor (``--at X Y YAW``) the whole mount, without it the camera above base_link's origin, its yaw taken as zero.
``mount_yaml`` writes it as a config's ``mount`` section (``position_m``, ``rpy_deg``, commented with each value's
one-sigma uncertainty and where it came from); ``draw_mount`` draws the corners found and base_link's floor grid,
seen through the measured mount, back on the image (cv2), so that a wrong mount shows as a grid off the board.

Frames as ``gpo.cameras.rig``: base_link x forward, y left, z up on the floor; angles of the camera's body frame
(REP-103 roll, pitch, yaw); the kind (``forward`` or ``downward``) names which floor angles ``gpo.cameras.mount``
reports.
"""

from __future__ import annotations

import sys
from pathlib import Path

import cv2
import numpy as np

from gpo.cameras.chessboard import parse_board
from gpo.cameras.files import Camera
from gpo.cameras.mount import MeasuredMount, MountError, measure
from gpo.cameras.rig import CameraMount
from gpo.cameras.targets import Chessboard
from gpo.cli.common import positive
from gpo.io.outputs import check_output, destination, flagged_path, write_text, write_with
from gpo.pipeline.schema import load_camera

GRID_STEP_M = 0.05


"""Spacing of the floor grid drawn on the picture, metres."""


GRID_REACH_M = 1.5


"""How far from the camera's foot the floor grid is drawn, metres."""


NAME = "mount"
HELP = "the camera's mount from an image of a chessboard on the floor"


def add_arguments(parser) -> None:
    parser.add_argument("image", type=Path, help="the camera's image of a board lying on the floor")
    parser.add_argument(
        "--camera", type=Path, required=True, help="its calibration: Kalibr YAML, Basalt JSON or a run config"
    )
    parser.add_argument("--board", required=True, help="inner corners per row x per column, e.g. 7x5")
    parser.add_argument("--square", required=True, type=positive, help="square size in metres")
    parser.add_argument(
        "--at", nargs=3, type=float, metavar=("X", "Y", "YAW"),
        help="the board's outer corner in base_link (m) and its x axis's yaw (degrees): then x, y, yaw are measured",
    )
    parser.add_argument(
        "--kind", default="auto", choices=("auto", "forward", "downward"),
        help="how the camera looks at the floor (default: auto, from the measured tilt, which a kind given must match)",
    )
    parser.add_argument("--out", type=Path, default=Path("mount.yaml"), help="mount YAML to write")
    parser.add_argument("--picture", type=Path, help="PNG of the board and floor grid (default: beside --out)")
    parser.add_argument("--force", action="store_true", help="a flagged mount replaces --out too")


def read_image(path) -> np.ndarray:
    """The 8-bit image of the file ``path`` (grey or colour); a clear error when it cannot be read."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"no file {path}: expected an image of the board on the floor")
    image = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    if image is None:
        raise ValueError(f"{path}: not an image OpenCV can read (PNG, JPEG, ...)")
    if image.dtype != np.uint8:
        raise ValueError(f"{path}: an image of {image.dtype}; expected 8 bits per channel")
    return image[..., :3] if image.ndim == 3 else image


def mount_yaml(measured: MeasuredMount, source: str) -> str:
    """The YAML text of a config's ``mount`` section for ``measured``, with comments: the values' one-sigma
    uncertainties and which values were assumed; ``source`` says what it was measured from."""
    estimate, mount = measured.estimate, measured.mount
    roll, pitch, yaw = np.degrees(mount.body_rpy)
    std = estimate.std
    angle_names = ("pitch", "roll") if estimate.kind == "forward" else ("tilt about y", "tilt about x")
    x, y, z = mount.position
    if measured.placed:
        where = f"x {x:.4f} ± {std['x_m']:.4f} m, y {y:.4f} ± {std['y_m']:.4f} m from the board's place (--at)"
        turned = f"yaw ± {np.degrees(std['yaw_rad']):.3f} deg (from the board's place)"
    else:
        where = "x, y not measured (the board's place was not given, --at X Y YAW): 0 assumed, measure them"
        turned = "yaw not measured: 0 assumed"
    lines = [
        f"# camera mount measured by gpo mount from {source}",
        f"# {len(estimate.corners_px)} corners, RMS reprojection error {estimate.rms_px:.3f} px; the ± are one sigma"
        " from the corners' scatter (they leave out errors of the calibration and of the board's size)",
        f"# {angle_names[0]} {np.degrees(estimate.pitch_rad):.3f} ± {np.degrees(std['pitch_rad']):.3f} deg,"
        f" {angle_names[1]} {np.degrees(estimate.roll_rad):.3f} ± {np.degrees(std['roll_rad']):.3f} deg"
        f" ({estimate.kind}-looking camera)",
        *(f"# warning: {warning}" for warning in estimate.warnings),
        "mount:",
        f"  # the camera's optical centre in base_link (x forward, y left, z up), metres: {where}",
        f"  position_m: [{x:.5f}, {y:.5f}, {z:.5f}]  # z: height {z:.5f} ± {std['height_m']:.5f} m",
        "  # the camera's body frame (x forward, y left, z up) in base_link: roll, pitch (positive looks down), yaw,"
        " degrees, REP-103 fixed axes x, y, z",
        f"  rpy_deg: [{roll:.4f}, {pitch:.4f}, {yaw:.4f}]  # {turned}",
        *(
            ["  # looking nearly straight down, roll and yaw turn about almost the same axis: read the tilts above"]
            if abs(pitch) > 80.0 else []
        ),
        f"  height_m: {z:.5f}",
        f"  pitch_deg: {pitch:.4f}",
        f"  roll_deg: {roll:.4f}",
    ]
    return "\n".join(lines) + "\n"


def report(measured: MeasuredMount) -> str:
    """What ``gpo mount`` prints: the numbers with their one-sigma uncertainties."""
    estimate, std = measured.estimate, measured.estimate.std
    pitch, roll = ("pitch", "roll") if estimate.kind == "forward" else ("tilt_y", "tilt_x")
    lines = [
        f"board found: {len(estimate.corners_px)} corners, RMS reprojection error {estimate.rms_px:.3f} px",
        f"height  {estimate.height_m:.4f} ± {std['height_m']:.4f} m",
        f"{pitch:<7} {np.degrees(estimate.pitch_rad):.3f} ± {np.degrees(std['pitch_rad']):.3f} deg",
        f"{roll:<7} {np.degrees(estimate.roll_rad):.3f} ± {np.degrees(std['roll_rad']):.3f} deg",
    ]
    if measured.placed:
        x, y, _ = measured.mount.position
        lines += [
            f"x       {x:.4f} ± {std['x_m']:.4f} m",
            f"y       {y:.4f} ± {std['y_m']:.4f} m",
            f"yaw     {np.degrees(estimate.yaw_rad):.3f} ± {np.degrees(std['yaw_rad']):.3f} deg",
        ]
    else:
        lines.append("x, y, yaw: not measured (give the board's place with --at X Y YAW)")
    lines += [f"warning: {warning}" for warning in estimate.warnings]
    return "\n".join(lines)


def draw_mount(image: np.ndarray, camera: Camera, measured: MeasuredMount) -> np.ndarray:
    """A colour copy of ``image`` with the corners found (green), the board's corners where the fitted pose puts
    them (red crosses) and base_link's floor grid every ``GRID_STEP_M`` seen through the measured mount (yellow;
    the x axis red, the y axis blue when the board's place was given)."""
    picture = cv2.cvtColor(image, cv2.COLOR_GRAY2BGR) if image.ndim == 2 else image.copy()
    mount = measured.mount
    centre = np.round(mount.position[:2] / GRID_STEP_M) * GRID_STEP_M
    ticks = np.arange(-GRID_REACH_M, GRID_REACH_M + 1e-9, GRID_STEP_M)
    along = np.linspace(-GRID_REACH_M, GRID_REACH_M, 600)
    for tick in ticks:
        for axis in (0, 1):
            points = np.zeros((along.size, 3))
            points[:, axis] = centre[axis] + tick
            points[:, 1 - axis] = centre[1 - axis] + along
            on_axis = measured.placed and abs(centre[axis] + tick) < 1e-9
            colour = ((255, 0, 0) if axis == 0 else (0, 0, 255)) if on_axis else (0, 200, 255)
            _polyline(picture, camera, mount, points, colour)
    for corner in measured.estimate.corners_px:
        cv2.circle(picture, _point(corner), 4, (0, 200, 0), 1, cv2.LINE_AA)
    estimate = measured.estimate
    for corner in estimate.corners_px + estimate.residuals_px:
        cv2.drawMarker(picture, _point(corner), (0, 0, 255), cv2.MARKER_CROSS, 7, 1, cv2.LINE_AA)
    return picture


def _polyline(picture: np.ndarray, camera: Camera, mount: CameraMount, points_base: np.ndarray, colour) -> None:
    """Floor points (N, 3) in base_link drawn as lines where they lie ahead of the camera and project."""
    pixels, valid = camera.project(mount.to_camera(points_base))
    valid &= np.isfinite(pixels).all(axis=1)
    valid &= (np.abs(pixels) < 4 * max(camera.width, camera.height)).all(axis=1)
    for run in np.split(np.arange(len(valid)), np.flatnonzero(np.diff(valid.astype(int))) + 1):
        if valid[run[0]] and len(run) > 1:
            cv2.polylines(picture, [np.round(pixels[run] * 16).astype(np.int32)], False, colour, 1, cv2.LINE_AA, 4)


def _point(pixel) -> tuple[int, int]:
    return round(float(pixel[0])), round(float(pixel[1]))


def run(args) -> int:
    """Inputs and outputs checked, the mount measured, printed, written and drawn."""
    picture_path = args.picture or args.out.with_suffix(".png")
    inputs = [args.image, args.camera]
    check_output(args.out, inputs, "--out")
    check_output(picture_path, [*inputs, args.out], "--picture")
    if picture_path.suffix.lower() != ".png":
        raise ValueError(f"--picture {picture_path}: name a .png file")
    image, camera = read_image(args.image), load_camera(args.camera)
    nx, ny = parse_board(args.board)
    board = Chessboard((nx + 1, ny + 1), args.square, 0.0)
    at = None if args.at is None else (args.at[0], args.at[1], np.radians(args.at[2]))
    try:
        measured = measure(image, camera, board, at, args.kind)
    except MountError as error:
        raise ValueError(f"{args.image}: {error}{_hint(error)}") from None
    print(report(measured))
    out = destination(args.out, not measured.estimate.ok, args.force)
    if out != args.out:
        print(f"{args.out} is kept: this mount is flagged and goes beside it (--force replaces it)", file=sys.stderr)
        picture_path = flagged_path(picture_path)
    written = write_text(out, mount_yaml(measured, f"{args.image} ({nx}x{ny} corners, {args.square} m squares)"))
    print(f"wrote {written}")
    picture = draw_mount(image, camera, measured)
    print(f"wrote {write_with(picture_path, lambda temporary: cv2.imwrite(str(temporary), picture))}")
    return 0 if measured.estimate.ok else 1


def _hint(error: MountError) -> str:
    """What to check when the board was not found, or the kind given is not the one measured."""
    if "not found" in str(error):
        return (
            "; check --board (the inner corners per row x per column: a board of 8 x 6 squares is 7x5), that the "
            "whole board is in view and sharp, and that --camera is this camera's calibration"
        )
    if "give kind" in str(error):
        return " (--kind)"
    return ""
