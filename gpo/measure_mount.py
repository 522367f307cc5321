"""``python -m gpo mount``: the camera's mount measured from one image of a chessboard lying on the floor.

``measure`` finds the board (once: a second board in view is an error), fits its pose with
``gpo.mount.mount_from_corners`` and turns the numbers into a ``CameraMount``: with the board's place on the
floor (``--at X Y YAW``) the whole mount, without it the camera above base_link's origin, its yaw taken as zero.
``mount_yaml`` writes it as a config's ``mount`` section (``position_m``, ``rpy_deg``, commented with each value's
one-sigma uncertainty and where it came from); ``draw_mount`` draws the corners found and base_link's floor grid,
seen through the measured mount, back on the image (cv2), so that a wrong mount shows as a grid off the board.

Frames as ``gpo.rig``: base_link x forward, y left, z up on the floor; angles of the camera's body frame
(REP-103 roll, pitch, yaw); the kind (``forward`` or ``downward``) names which floor angles ``gpo.mount`` reports.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from gpo.calibfiles import Camera, load_basalt, load_kalibr
from gpo.calibrate import parse_board
from gpo.config import load_rig, read_yaml
from gpo.mount import MountError, MountEstimate, detect_corners, mount_from_corners
from gpo.outputs import check_output, destination, flagged_path, write_text, write_with
from gpo.rig import CameraMount
from gpo.targets import Chessboard

DOWNWARD_BELOW_DEG = 45.0
"""With ``kind="auto"``, a camera whose optical axis lies within this many degrees of straight down is ``downward``."""
GRID_STEP_M = 0.05
"""Spacing of the floor grid drawn on the picture, metres."""
GRID_REACH_M = 1.5
"""How far from the camera's foot the floor grid is drawn, metres."""


@dataclass(frozen=True, eq=False)
class MeasuredMount:
    """A measured ``mount`` (base_link <- optical) and the ``estimate`` it comes from; ``placed`` is True when the
    board's place on the floor was given (x, y and yaw are measured, not assumed)."""

    estimate: MountEstimate
    mount: CameraMount
    placed: bool


def load_camera(path) -> Camera:
    """The camera of a calibration file: a Basalt JSON (its first camera), a Kalibr camchain (its first camera) or a
    gpo run config (its ``camera``). Errors name the file."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"no file {path}: expected a camera calibration (Kalibr YAML, Basalt JSON or config)")
    if path.suffix.lower() == ".json":
        return load_basalt(path)[0]
    document = read_yaml(path)
    if isinstance(document, dict) and "mount" in document and ("camera" in document or "camchain" in document):
        return load_rig(path).camera
    return next(iter(load_kalibr(path).values()))


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


def measure(
    image: np.ndarray, camera: Camera, board: Chessboard, at: tuple[float, float, float] | None = None,
    kind: str = "auto",
) -> MeasuredMount:
    """The mount of ``camera`` from its ``image`` of ``board`` lying printed side up on the floor.

    ``at``: (x m, y m, yaw rad) of the board frame's origin in base_link, or None. ``kind``: ``forward``,
    ``downward`` or ``auto`` (``downward`` when the optical axis is within ``DOWNWARD_BELOW_DEG`` of straight
    down). Raises ``MountError`` when the board is not found, is found twice, or no mount fits.
    """
    if image.shape[:2] != (camera.height, camera.width):
        raise MountError(
            f"the image is {image.shape[1]} x {image.shape[0]} pixels but the camera calibration is "
            f"{camera.width} x {camera.height}: give the calibration of the camera that took this image"
        )
    try:  # found in the image itself, the checks look there alone; else in the perspective views too
        corners, rectify = detect_corners(image, camera, board, rectify=False), False
    except MountError:
        corners, rectify = detect_corners(image, camera, board), None
    _check_whole_board(image, camera, board, rectify)
    _check_found_once(image, camera, board, corners, rectify)
    estimate = mount_from_corners(corners, camera, board, at, "forward")
    if kind == "auto":
        kind = "downward" if _looks_down(estimate) else "forward"
    if kind != "forward":
        estimate = mount_from_corners(corners, camera, board, at, kind)
    if estimate.height_m <= 0:
        raise MountError(f"the camera comes out {estimate.height_m:.3f} m above the floor: not a board on the floor")
    if estimate.mount is not None:
        return MeasuredMount(estimate, estimate.mount, True)
    level = CameraMount.forward if kind == "forward" else CameraMount.downward
    angles = (estimate.pitch_rad, estimate.roll_rad) if kind == "forward" else (estimate.roll_rad, estimate.pitch_rad)
    return MeasuredMount(estimate, level(0.0, 0.0, estimate.height_m, *angles), False)


def _looks_down(estimate: MountEstimate) -> bool:
    """Whether the optical axis (camera z) lies within ``DOWNWARD_BELOW_DEG`` of the floor's downward normal."""
    up_in_camera = estimate.board_in_camera[0].apply([0.0, 0.0, 1.0])
    return -up_in_camera[2] > np.cos(np.radians(DOWNWARD_BELOW_DEG))


def _check_whole_board(image: np.ndarray, camera: Camera, board: Chessboard, rectify: bool | None) -> None:
    """Raise ``MountError`` when a board of one more row or column of squares is in view: ``board`` is then a part
    of the board lying there, and its corners would be read in the wrong places. ``rectify`` as
    ``gpo.mount.detect_corners``: where the board itself was found."""
    nx, ny = board.squares
    for larger in ((nx + 1, ny), (nx, ny + 1)):
        try:
            detect_corners(image, camera, Chessboard(larger, board.square, board.margin), rectify)
        except MountError:
            continue
        raise MountError(
            f"the board in view has more inner corners than {nx - 1} x {ny - 1} (at least {larger[0] - 1} x "
            f"{larger[1] - 1}): give --board as the whole board's inner corners per row x per column"
        )


def _check_found_once(
    image: np.ndarray, camera: Camera, board: Chessboard, corners: np.ndarray, rectify: bool | None
) -> None:
    """Raise ``MountError`` when a second board of the same size is found with the first one painted over."""
    covered = image.copy()
    hull = cv2.convexHull(corners.astype(np.float32)).astype(np.int32)
    grown = cv2.dilate(cv2.fillConvexPoly(np.zeros(image.shape[:2], np.uint8), hull, 1), np.ones((15, 15), np.uint8))
    covered[grown.astype(bool)] = 128
    try:
        detect_corners(covered, camera, board, rectify)
    except MountError:
        return
    nx, ny = board.pattern_size
    raise MountError(
        f"two chessboards of {nx} x {ny} inner corners are in the image: leave one board in view, or cover the other"
    )


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


def mount_command(args) -> int:
    """``python -m gpo mount``: inputs and outputs checked, the mount measured, printed, written and drawn."""
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
    """What to check when the board was not found."""
    if "not found" in str(error):
        return (
            "; check --board (the inner corners per row x per column: a board of 8 x 6 squares is 7x5), that the "
            "whole board is in view and sharp, and that --camera is this camera's calibration"
        )
    return ""
