"""The camera's mount on the robot from one image of a chessboard lying on the floor.

The first paper lays a chessboard in front of its robot to find the fisheye's view of the floor;
the second lays one under its downward camera to compensate the camera's tilt. Both need the
same numbers: how high the camera sits above the floor, how it is pitched and rolled against the
floor and, when the board's place on the robot's floor is known, where the camera sits on the
robot. ``estimate_mount`` finds them from an image; ``mount_from_corners`` from corner pixels.

Frames and conventions
----------------------
REP-103/105 as in ``gpo.sim.rigs``: ``base_link`` at the rear-axle centre on the floor, x forward,
y left, z up; the camera optical frame x right, y down, z forward; the floor is z = 0. The board
frame is the one of ``gpo.sim.render.Chessboard``: origin at the outer corner of the squares,
x and y along its rows, z out of the printed side, so a board lying printed side up has z = up.
Angles in radians, lengths in metres, image points in pixels.

Geometry
--------
The corners' pose gives the board in the camera frame: ``p_cam = R p_board + t`` (camera <- board).

- The floor's upward normal in the camera frame is the board's z axis, ``n = R e_z``.
- The floor is the plane ``{p : n . p = n . t}``. The optical centre is the origin, so its
  height above the floor is ``h = -n . t`` (positive when the camera sees the printed side).
- ``gpo.sim.rigs`` writes a mount's rotation (base <- optical) as
  ``R_bo = Rz(yaw) Ry(pitch) Rx(roll) R_level``, where ``R_level`` is the kind's level
  orientation: ``CameraMount.forward`` with zero angles (``R_level = OPTICAL_IN_BODY``, intrinsic
  "YX" = ``Ry(pitch) Rx(roll)``) or ``CameraMount.downward`` with zero tilts (looking straight
  down, image top towards the robot's front; extrinsic "xy" = ``Ry(tilt_y) Rx(tilt_x)``, so
  ``pitch`` is ``tilt_y`` and ``roll`` is ``tilt_x``). The floor normal is base z, so the normal
  seen in the level frame, ``m = R_level n = Rx(-roll) Ry(-pitch) e_z
  = (-sin pitch, cos pitch sin roll, cos pitch cos roll)``, does not depend on the yaw, and::

      pitch = atan2(-m_x, sqrt(m_y^2 + m_z^2)),    roll = atan2(m_y, m_z)

- With the board's placement on the floor of ``base_link`` known (origin (x_b, y_b, 0), turned
  by ``yaw_b`` about z, as ``gpo.sim.render.FloorBoard``), base <- board is ``Rz(yaw_b)``, so the
  mount is ``R_bo = Rz(yaw_b) R^T`` and the optical centre ``(x_b, y_b, 0) + Rz(yaw_b) (-R^T t)``;
  the yaw comes from ``R_bo R_level^T = Rz(yaw) Ry(pitch) Rx(roll)``.

Finding the corners
-------------------
``gpo.cameras.chessboard.find_corners`` with its ``MOUNT`` search (the sector detector's own sub-pixel corners), on
the image and, where the board is not found there, in distortion-free perspective views rendered from the camera
model; ``detect_corners`` raises ``MountError`` where it finds no board.

Solving the pose
----------------
The corners are unprojected to unit rays by the calibrated camera model (EUCM or pinhole alike).
``gpo.cameras.chessboard.planar_pose`` (IPPE in a virtual pinhole camera looking along the rays' mean, the same
start the calibration's fit takes) gives the initial pose. ``scipy.optimize.least_squares`` then refines the pose on the
reprojection error in pixels, through the camera model's ``project``. The one-sigma
uncertainties reported follow from the fit: the residuals' variance times ``(J^T J)^-1`` for the
pose, carried to height, angles and position by the numbers' central-difference Jacobian.

Which corner is the first
-------------------------
A detector returns the corner grid in one of four orders (eight for a square grid). Only the
orders in which the board frame is right-handed with z towards the camera are kept: with the
rays r_0 to the first corner, r_x to the last of the first row and r_y to the first of the last
row, ``det[r_x, r_y, r_0] < 0``. (The corners are ``P = lambda r`` with lambda > 0, and the
board's z axis, along ``(P_x - P_0) x (P_y - P_0)``, points back to the camera when
``(P_x - P_0) x (P_y - P_0) . P_0 = lambda_x lambda_y lambda_0 det[r_x, r_y, r_0]`` is negative.)
The orders left differ by turning the board 180 degrees (or 90 for a square grid) about its
centre. The rule: the order kept is the one for which the camera's yaw in ``base_link`` lies
nearest ``expected_yaw`` (0 by default: a forward camera looks along the robot's x, a downward
camera has its image top towards the robot's front). Without a placement the board's x axis is
taken along base x. Height, pitch and roll do not depend on this choice.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import cv2
import numpy as np
from scipy.spatial.transform import Rotation

from gpo.cameras.base import CameraModel
from gpo.cameras.chessboard import MOUNT, find_corners, larger_board, pattern_text, planar_pose
from gpo.cameras.files import Camera
from gpo.cameras.rig import CameraMount
from gpo.cameras.targets import Chessboard, FloorBoard

KINDS = ("forward", "downward")
MAX_RMS_PX = 1.0  # a good detection of a well calibrated camera stays well below this


class MountError(ValueError):
    """The mount cannot be measured from this image or these corners; the message says why."""


@dataclass(frozen=True, eq=False)
class MountEstimate:
    """The camera's mount measured from a chessboard on the floor.

    ``height_m``: optical centre above the floor, metres. ``pitch_rad`` and ``roll_rad``: the
    angles of ``CameraMount.forward`` (about the level camera's left and forward axes); for a
    ``downward`` camera they are ``tilt_y`` and ``tilt_x`` of ``CameraMount.downward``.
    ``board_in_camera``: (camera <- board rotation, board origin in the camera frame, metres).
    ``corners_px`` (N, 2): the corners in the board's order (``Chessboard.inner_corners``);
    ``residuals_px`` (N, 2): their reprojection errors, model minus measured; ``rms_px`` the RMS
    of the residuals' lengths. With the board's placement given: ``mount`` (the optical frame's
    pose in ``base_link``) and ``yaw_rad`` (about the floor normal), otherwise None.
    ``std``: one-sigma uncertainties of ``height_m``, ``pitch_rad``, ``roll_rad`` and, with the
    placement, of the camera's ``x_m``, ``y_m`` and ``yaw_rad`` in base_link, from the scatter of
    the corners' own residuals (so they leave out errors of the camera model or of the placement).
    ``warnings`` names what makes the estimate doubtful; ``ok`` is True when there is none.
    """

    kind: str
    height_m: float
    pitch_rad: float
    roll_rad: float
    board_in_camera: tuple[Rotation, np.ndarray]
    corners_px: np.ndarray
    residuals_px: np.ndarray
    rms_px: float
    std: dict[str, float]
    mount: CameraMount | None = None
    yaw_rad: float | None = None
    warnings: tuple[str, ...] = ()

    @property
    def ok(self) -> bool:
        return not self.warnings

    def to_dict(self) -> dict:
        """Plain numbers for a rig config and for people: angles in degrees (named as the kind's mount names
        them), one-sigma uncertainties, and with the placement the mount as translation (metres) and
        quaternion (x, y, z, w) of base_link <- optical."""
        values = {"height_m": self.height_m, "pitch_rad": self.pitch_rad, "roll_rad": self.roll_rad}
        if self.mount is not None:
            values["yaw_rad"] = self.yaw_rad
        result = {
            "kind": self.kind,
            **self._for_people(values),
            "std": self._for_people(self.std),
            "rms_px": self.rms_px,
            "ok": self.ok,
            "warnings": list(self.warnings),
        }
        if self.mount is not None:
            result["translation_m"] = self.mount.position.tolist()
            result["quaternion_xyzw"] = self.mount.rotation.as_quat().tolist()
        return result

    def _for_people(self, values: dict[str, float]) -> dict[str, float]:
        """``values`` with the angles in degrees, renamed ``pitch_deg``, ``roll_deg`` (forward) or
        ``tilt_y_deg``, ``tilt_x_deg`` (downward) and ``yaw_deg``."""
        pitch, roll = ("pitch", "roll") if self.kind == "forward" else ("tilt_y", "tilt_x")
        names = {"pitch_rad": f"{pitch}_deg", "roll_rad": f"{roll}_deg", "yaw_rad": "yaw_deg"}
        return {names.get(name, name): float(np.degrees(v) if name in names else v) for name, v in values.items()}


def estimate_mount(
    image: np.ndarray,
    camera: CameraModel,
    board: Chessboard,
    placement: FloorBoard | tuple[float, float, float] | None = None,
    kind: str = "forward",
    expected_yaw: float = 0.0,
    max_rms_px: float = MAX_RMS_PX,
) -> MountEstimate:
    """The mount of ``camera`` from its ``image`` of ``board`` lying printed side up on the floor.

    ``placement``: where the board lies in ``base_link`` — a ``FloorBoard`` of the same board,
    or (x, y, yaw) in metres and radians of the board frame's origin — to get the full mount.
    ``kind``: ``"forward"`` or ``"downward"``, which angles to report (see the module docstring).
    Raises ``MountError`` when the board is not found or no valid pose fits.
    """
    return mount_from_corners(
        detect_corners(image, camera, board), camera, board, placement, kind, expected_yaw, max_rms_px
    )


def mount_from_corners(
    corners_px,
    camera: CameraModel,
    board: Chessboard,
    placement: FloorBoard | tuple[float, float, float] | None = None,
    kind: str = "forward",
    expected_yaw: float = 0.0,
    max_rms_px: float = MAX_RMS_PX,
) -> MountEstimate:
    """The mount from the board's inner corners ``corners_px`` (N, 2) pixels.

    The corners form the board's grid of ``board.pattern_size`` in any order a detector returns
    (rows of the first size, or a grid flipped or turned); the order is fixed as the module
    docstring says. Other arguments as ``estimate_mount``.
    """
    _check_kind(kind)
    board_pose = _placement_pose(placement, board)
    rays = _corner_rays(corners_px, camera, board)
    yaw_board = board_pose[2] if board_pose is not None else 0.0
    order, initial = _choose_order(rays, board, kind, yaw_board, expected_yaw)
    corners = np.asarray(corners_px, dtype=float).reshape(-1, 2)[order]
    pose = _refine_pose(corners, camera, board, initial)
    points = pose[0].apply(board.inner_corners()) + pose[1]
    _check_in_front(points, rays[order])
    residuals = camera.project(points)[0] - corners
    rms = float(np.sqrt(np.mean(np.sum(residuals**2, axis=1))))
    numbers = _mount_numbers(pose, kind, board_pose)
    std = _uncertainties(corners, camera, board, pose, kind, board_pose)
    mount = None if board_pose is None else _mount_in_base(pose, board_pose)
    return MountEstimate(
        kind,
        numbers["height_m"],
        numbers["pitch_rad"],
        numbers["roll_rad"],
        pose,
        corners,
        residuals,
        rms,
        std,
        mount,
        numbers.get("yaw_rad"),
        () if rms <= max_rms_px else (_rms_warning(rms, max_rms_px),),
    )


def floor_angles(normal, kind: str = "forward") -> tuple[float, float]:
    """(pitch, roll) radians of a camera that sees the floor's upward unit normal as ``normal`` (3,).

    ``normal`` is in the camera optical frame; the angles are those of ``CameraMount.forward``, or
    (tilt_y, tilt_x) of ``CameraMount.downward`` for ``kind="downward"``.
    """
    _check_kind(kind)
    m = _level_rotation(kind).apply(np.asarray(normal, dtype=float))
    return float(np.arctan2(-m[0], np.hypot(m[1], m[2]))), float(np.arctan2(m[1], m[2]))


def detect_corners(image: np.ndarray, camera: CameraModel | None, board: Chessboard, rectify: bool | None = None):
    """The board's inner corners (N, 2) pixels in ``image`` (8-bit, of the camera's size), in the board's order.

    ``gpo.cameras.chessboard.find_corners`` with its ``MOUNT`` search; ``rectify`` as there: None on the image, then
    in perspective views rendered from the camera model; True in those views only; False on the image only. A
    ``camera`` of None (an image no camera model describes, such as a floor image) searches the image only. Raises
    ``MountError`` when the board is found nowhere.
    """
    corners = find_corners(image, board.pattern_size, camera, MOUNT, rectify)
    if corners is None:
        nx, ny = board.pattern_size
        where = "in the image" if rectify is False else "in the image or in its perspective views"
        raise MountError(
            f"chessboard of {nx} x {ny} inner corners ({board.squares[0]} x {board.squares[1]} squares) "
            f"not found {where}"
        )
    return corners


def _placement_pose(placement, board: Chessboard) -> tuple[float, float, float] | None:
    """(x, y, yaw) of the board frame in base_link, from a ``FloorBoard`` or a triple."""
    if placement is None:
        return None
    if isinstance(placement, FloorBoard):
        if placement.board != board:
            raise ValueError(f"the placement's board {placement.board} is not the board measured, {board}")
        return placement.x, placement.y, placement.yaw
    values = np.asarray(placement, dtype=float)
    if values.shape != (3,) or not np.isfinite(values).all():
        raise ValueError(f"placement must be a FloorBoard or (x, y, yaw) of the board in base_link, got {placement!r}")
    return tuple(values.tolist())


def _corner_rays(corners_px, camera: CameraModel, board: Chessboard) -> np.ndarray:
    """Unit rays (N, 3) of the corners, after checking their number and that each has a ray."""
    nx, ny = board.pattern_size
    if nx < 2 or ny < 2:
        raise ValueError(f"the board needs at least 2 x 2 inner corners to give a pose, it has {nx} x {ny}")
    corners = np.asarray(corners_px, dtype=float).reshape(-1, 2)
    if len(corners) != nx * ny:
        raise MountError(f"expected the board's {nx * ny} inner corners ({nx} x {ny}), got {len(corners)}")
    rays, valid = camera.unproject(corners)
    if not valid.all():
        raise MountError(f"corners {np.flatnonzero(~valid).tolist()} have no ray in the camera model")
    return rays


def _check_kind(kind: str) -> None:
    if kind not in KINDS:
        raise ValueError(f"kind must be one of {KINDS}, got {kind!r}")


def _level_rotation(kind: str) -> Rotation:
    """base <- optical of the kind's level mount, as ``gpo.cameras.rig.CameraMount`` defines it."""
    return (CameraMount.forward if kind == "forward" else CameraMount.downward)(0.0, 0.0, 0.0).rotation


def _grid_orders(board: Chessboard) -> list[np.ndarray]:
    """The corner orders a detector may return, each as indices into its list: flips (and turns if square)."""
    nx, ny = board.pattern_size
    grid = np.arange(nx * ny).reshape(ny, nx)
    orders = [grid, grid[::-1], grid[:, ::-1], grid[::-1, ::-1]]
    if nx == ny:
        orders += [order.T for order in orders]
    return [order.ravel() for order in orders]


def _choose_order(rays, board: Chessboard, kind: str, yaw_board: float, expected_yaw: float):
    """The corner order (indices) and its initial pose, by the rule of the module docstring."""
    nx, ny = board.pattern_size
    candidates = []
    for order in _grid_orders(board):
        first, along_x, along_y = rays[order[[0, nx - 1, (ny - 1) * nx]]]
        if np.linalg.det(np.array([along_x, along_y, first])) < 0:
            pose = _initial_pose(rays[order], board)
            yaw = _mount_numbers(pose, kind, (0.0, 0.0, yaw_board))["yaw_rad"]
            candidates.append((abs(np.angle(np.exp(1j * (yaw - expected_yaw)))), order, pose))
    return min(candidates, key=lambda candidate: candidate[0])[1:]


def _initial_pose(rays: np.ndarray, board: Chessboard) -> tuple[Rotation, np.ndarray]:
    """camera <- board from unit rays (N, 3) (``gpo.cameras.chessboard.planar_pose``)."""
    pose = planar_pose(rays, board.inner_corners())
    if pose is None:
        raise MountError("no initial pose of the board fits the corners (their rays span more than a hemisphere?)")
    return pose


def _perturbed(pose: tuple[Rotation, np.ndarray], delta: np.ndarray) -> tuple[Rotation, np.ndarray]:
    """camera <- board ``pose`` turned by the rotation vector ``delta[:3]`` (board frame) and moved by ``delta[3:]``."""
    return pose[0] * Rotation.from_rotvec(delta[:3]), pose[1] + delta[3:]


def _reprojection(corners: np.ndarray, camera: CameraModel, board: Chessboard, pose) -> np.ndarray:
    """Reprojection errors (2N,) pixels of the board at ``pose``; 1000 px where a corner does not project."""
    projected, valid = camera.project(pose[0].apply(board.inner_corners()) + pose[1])
    return np.where(valid[:, None], projected - corners, 1e3).ravel()


def _refine_pose(corners: np.ndarray, camera: CameraModel, board: Chessboard, initial):
    """camera <- board minimising the corners' reprojection error in pixels, from ``initial``."""
    from scipy.optimize import least_squares  # imported by what measures a mount, not by every command

    fit = least_squares(
        lambda delta: _reprojection(corners, camera, board, _perturbed(initial, delta)),
        np.zeros(6),
        x_scale="jac",
        xtol=1e-12,  # tolerances every floating-point path reaches (the pose is then fixed to about 1e-9 m)
        ftol=1e-12, gtol=1e-12,
    )
    return _perturbed(initial, fit.x)


def _check_in_front(points: np.ndarray, rays: np.ndarray) -> None:
    """Raise unless every corner of the fitted board lies ahead of the camera along its ray."""
    if (np.sum(points * rays, axis=1) <= 0).any():
        raise MountError("the fitted board lies behind the camera: no board in view fits the corners")


def _mount_numbers(pose, kind: str, board_pose) -> dict[str, float]:
    """Height, pitch and roll of the camera from the board's ``pose``; with ``board_pose``, also its x, y and yaw."""
    rotation, translation = pose
    normal = rotation.apply([0.0, 0.0, 1.0])
    pitch, roll = floor_angles(normal, kind)
    numbers = {"height_m": float(-normal @ translation), "pitch_rad": pitch, "roll_rad": roll}
    if board_pose is not None:
        mount = _mount_in_base(pose, board_pose)
        yaw = (mount.rotation * _level_rotation(kind).inv()).as_euler("ZYX")[0]
        numbers.update(x_m=float(mount.position[0]), y_m=float(mount.position[1]), yaw_rad=float(yaw))
    return numbers


def _mount_in_base(pose, board_pose) -> CameraMount:
    """The optical frame's pose in base_link from the board's ``pose`` in the camera and (x, y, yaw) in base."""
    rotation, translation = pose
    x, y, yaw_board = board_pose
    board_in_base = Rotation.from_euler("z", yaw_board)
    position = np.array([x, y, 0.0]) + board_in_base.apply(-rotation.inv().apply(translation))
    return CameraMount(position, board_in_base * rotation.inv())


def _uncertainties(corners, camera: CameraModel, board: Chessboard, pose, kind: str, board_pose) -> dict[str, float]:
    """One-sigma uncertainties of ``_mount_numbers`` at ``pose``: the pose's covariance, the residuals' variance
    times (J^T J)^-1, carried through the numbers' Jacobian."""
    residual_jacobian = _jacobian(lambda delta: _reprojection(corners, camera, board, _perturbed(pose, delta)))
    variance = np.sum(_reprojection(corners, camera, board, pose) ** 2) / max(2 * len(corners) - 6, 1)
    covariance = variance * np.linalg.pinv(residual_jacobian.T @ residual_jacobian)
    names = list(_mount_numbers(pose, kind, board_pose))
    gradient = _jacobian(
        lambda delta: np.array(list(_mount_numbers(_perturbed(pose, delta), kind, board_pose).values()))
    )
    return dict(zip(names, np.sqrt(np.diag(gradient @ covariance @ gradient.T)).tolist(), strict=True))


def _jacobian(function, step: float = 1e-6) -> np.ndarray:
    """Central-difference Jacobian of ``function`` (6,) -> (M,) at zero.

    Differences are wrapped to (-pi, pi], so that an angle near +-pi differentiates too; the other
    values change far less than pi over a step.
    """
    columns = []
    for axis in np.eye(6) * step:
        difference = function(axis) - function(-axis)
        columns.append(np.angle(np.exp(1j * difference)) / (2.0 * step))
    return np.column_stack(columns)


def _rms_warning(rms: float, limit: float) -> str:
    return (
        f"RMS reprojection error {rms:.2f} px exceeds {limit:.2f} px: the camera model, the board's size "
        "or the detection is wrong, or the board does not lie flat"
    )

DOWNWARD_BELOW_DEG = 45.0
"""A camera whose optical axis lies within this many degrees of straight down looks ``downward``, else ``forward``."""
HEIGHT_RANGE_M = {"forward": (0.03, 1.0), "downward": (0.03, 0.6)}
"""The heights a floor camera of each kind sits at on a real robot, metres: looking ahead, from a few centimetres (the
first paper's pallet robot carries its T265 at 0.12 m) to a tall platform's metre; looking down, under or beside a
robot's body (the second paper's AGV, about 0.25 m). One image cannot tell a board's scale: a height outside these is
most often a board's square size given ten times too large or too small, and the mount is flagged."""


@dataclass(frozen=True, eq=False)
class MeasuredMount:
    """A measured ``mount`` (base_link <- optical) and the ``estimate`` it comes from; ``placed`` is True when the
    board's place on the floor was given (x, y and yaw are measured, not assumed)."""

    estimate: MountEstimate
    mount: CameraMount
    placed: bool


def measure(
    image: np.ndarray, camera: Camera, board: Chessboard, at: tuple[float, float, float] | None = None,
    kind: str = "auto",
) -> MeasuredMount:
    """The mount of ``camera`` from its ``image`` of ``board`` lying printed side up on the floor.

    ``at``: (x m, y m, yaw rad) of the board frame's origin in base_link, or None. ``kind``: ``forward``,
    ``downward`` or ``auto`` (``downward`` when the optical axis is within ``DOWNWARD_BELOW_DEG`` of straight
    down); a kind the measured tilt contradicts is a ``MountError`` too. A height outside the kind's
    ``HEIGHT_RANGE_M`` is a warning of the estimate: the mount is flagged.
    """
    if kind != "auto":
        _check_kind(kind)
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
    seen = "downward" if _looks_down(estimate) else "forward"
    if kind not in ("auto", seen):
        raise MountError(
            f"the camera's optical axis lies {_from_down_deg(estimate):.0f} deg from straight down, so it looks "
            f"{seen} (a downward camera's axis lies within {DOWNWARD_BELOW_DEG:g} deg of it), not {kind}: give kind "
            f"'{seen}' or 'auto'"
        )
    if seen != "forward":
        estimate = mount_from_corners(corners, camera, board, at, seen)
    if estimate.height_m <= 0:
        raise MountError(f"the camera comes out {estimate.height_m:.3f} m above the floor: not a board on the floor")
    low, high = HEIGHT_RANGE_M[seen]
    if not low <= estimate.height_m <= high:
        estimate = replace(estimate, warnings=(*estimate.warnings, (
            f"the camera comes out {estimate.height_m:.3f} m above the floor, where a {seen}-looking floor camera "
            f"sits {low:g} to {high:g} m up: check the board's square size, whose scale one image cannot tell (a "
            "square ten times too large puts the camera ten times too high)"
        )))
    if estimate.mount is not None:
        return MeasuredMount(estimate, estimate.mount, True)
    level = CameraMount.forward if seen == "forward" else CameraMount.downward
    angles = (estimate.pitch_rad, estimate.roll_rad) if seen == "forward" else (estimate.roll_rad, estimate.pitch_rad)
    return MeasuredMount(estimate, level(0.0, 0.0, estimate.height_m, *angles), False)


def _looks_down(estimate: MountEstimate) -> bool:
    """Whether the optical axis (camera z) lies within ``DOWNWARD_BELOW_DEG`` of the floor's downward normal."""
    return _from_down_deg(estimate) < DOWNWARD_BELOW_DEG


def _from_down_deg(estimate: MountEstimate) -> float:
    """The angle between the optical axis (camera z) and the floor's downward normal, degrees."""
    up_in_camera = estimate.board_in_camera[0].apply([0.0, 0.0, 1.0])
    return float(np.degrees(np.arccos(np.clip(-up_in_camera[2], -1.0, 1.0))))


def _check_whole_board(image: np.ndarray, camera: Camera, board: Chessboard, rectify: bool | None) -> None:
    """Raise ``MountError`` when a board of more inner corners is in view: ``board`` is then a part of the board
    lying there, and its corners would be read in the wrong places. ``rectify`` as
    ``gpo.cameras.mount.detect_corners``: where the board itself was found."""
    larger = larger_board(image, board.pattern_size, camera, rectify)
    if larger is not None:
        (size, whole), given = larger, pattern_text(board.pattern_size)
        found = pattern_text(size) if whole else f"at least {pattern_text(size)}"
        raise MountError(
            f"the board in view has more inner corners than {given} ({found}): give --board as the whole board's "
            "inner corners per row x per column"
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
