"""Timestamped poses, and the TUM trajectory file format that every SLAM tool (and evo) reads.

A ``Trajectory`` holds the poses of one frame (``child_frame_id``, e.g. ``base_link``) in another
(``frame_id``, e.g. ``odom``), as ROS does: stamps in integer nanoseconds, positions in metres,
orientations as unit quaternions in ROS order (x, y, z, w).

TUM format: one pose per line, ``t tx ty tz qx qy qz qw``, t in seconds; lines starting with ``#``
are comments. Stamps are written with all nine decimals, so a round trip keeps every nanosecond. Each field read is
a decimal number and nothing else (``NUMBER``): Python's own literals (``1_000``, ``0x10``) and other scripts' digits
are not, nor is a stamp with anything after its digits.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from decimal import ROUND_HALF_EVEN, Decimal
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

NS_PER_S = 1_000_000_000
NUMBER = re.compile(r"[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?|[+-]?(?:nan|inf|infinity)", re.IGNORECASE)
"""A field of a TUM line: a decimal number, with an exponent or not (NaN and infinity are read, then refused as not
finite)."""


@dataclass(frozen=True, eq=False)
class Trajectory:
    """Poses of ``child_frame_id`` in ``frame_id`` at ``stamps_ns``.

    ``stamps_ns`` (N,) int64 nanoseconds, non-decreasing; ``positions`` (N, 3) metres;
    ``quaternions`` (N, 4) as (x, y, z, w), normalised on construction where their length is
    not 1 to rounding.
    """

    stamps_ns: np.ndarray
    positions: np.ndarray
    quaternions: np.ndarray
    frame_id: str = "world"
    child_frame_id: str = "base_link"

    def __post_init__(self):
        stamps = np.asarray(self.stamps_ns)
        if stamps.ndim != 1 or not (np.issubdtype(stamps.dtype, np.integer) or stamps.size == 0):
            raise ValueError(f"stamps_ns must be a 1-D array of integer nanoseconds, got {stamps.dtype} {stamps.shape}")
        stamps = stamps.astype(np.int64)
        n = len(stamps)
        positions = np.asarray(self.positions, dtype=np.float64).reshape(-1, 3) if n else np.zeros((0, 3))
        quaternions = np.asarray(self.quaternions, dtype=np.float64).reshape(-1, 4) if n else np.zeros((0, 4))
        if len(positions) != n or len(quaternions) != n:
            raise ValueError(
                f"a trajectory needs as many positions and quaternions as stamps: "
                f"{n} stamps, {len(positions)} positions, {len(quaternions)} quaternions"
            )
        if not (np.isfinite(positions).all() and np.isfinite(quaternions).all()):
            raise ValueError("positions and quaternions must be finite numbers")
        backwards = np.flatnonzero(np.diff(stamps) < 0)
        if backwards.size:
            i = backwards[0]
            raise ValueError(f"stamps go backwards at pose {i + 1}: {stamps[i]} ns then {stamps[i + 1]} ns")
        with np.errstate(over="ignore"):  # a length beyond the largest float is refused below, not warned about
            norms = np.linalg.norm(quaternions, axis=1, keepdims=True)
        if np.any(norms < 1e-9):
            raise ValueError(f"quaternion {int(np.argmin(norms))} has zero length")
        if not np.isfinite(norms).all():
            raise ValueError(f"quaternion {int(np.argmin(np.isfinite(norms)))} is too long to normalise (over 1e154)")
        object.__setattr__(self, "stamps_ns", stamps)
        object.__setattr__(self, "positions", positions)
        # normalise only what is off by more than rounding, so that file round trips stay exact
        quaternions = np.where(np.abs(norms - 1.0) > 1e-12, quaternions / norms, quaternions)
        object.__setattr__(self, "quaternions", quaternions)

    def __len__(self) -> int:
        return len(self.stamps_ns)

    @classmethod
    def from_planar(
        cls, stamps_ns, x, y, yaw, z: float = 0.0, frame_id: str = "world", child_frame_id: str = "base_link"
    ) -> Trajectory:
        """A trajectory in the plane: position (x, y, z) in metres, heading ``yaw`` in radians about +z."""
        x, y, yaw = (np.asarray(a, dtype=np.float64) for a in (x, y, yaw))
        positions = np.column_stack([x, y, np.full_like(x, z)])
        quaternions = Rotation.from_euler("z", np.atleast_1d(yaw)[:, None]).as_quat()
        return cls(np.asarray(stamps_ns), positions, quaternions, frame_id, child_frame_id)

    @property
    def times(self) -> np.ndarray:
        """Stamps in float seconds, shape (N,)."""
        return self.stamps_ns * 1e-9

    @property
    def rotations(self) -> Rotation:
        """Orientations as a scipy ``Rotation`` of N rotations."""
        return Rotation.from_quat(self.quaternions)

    @property
    def yaw(self) -> np.ndarray:
        """Heading about +z in radians, in (-pi, pi], shape (N,)."""
        return self.rotations.as_euler("ZYX")[:, 0]

    @property
    def path_length(self) -> float:
        """Distance travelled along the positions, metres."""
        return float(np.linalg.norm(np.diff(self.positions, axis=0), axis=1).sum())

    def compose(self, left=None, right=None, frame_id: str | None = None, child_frame_id: str | None = None):
        """The poses ``left * T_i * right``: a change of both frames, e.g. camera odometry into base_link.

        ``left`` and ``right`` are rigid transforms (scipy ``Rotation``, translation (3,) metres);
        None is the identity. With T_i the pose of B in A, ``left`` = pose of A in W and ``right`` =
        pose of C in B give the pose of C in W, named ``frame_id`` and ``child_frame_id``.
        """
        rotations, positions = self.rotations, self.positions
        if right is not None:
            positions = positions + rotations.apply(right[1])
            rotations = rotations * right[0]
        if left is not None:
            positions = left[0].apply(positions) + left[1]
            rotations = left[0] * rotations
        return Trajectory(
            self.stamps_ns,
            positions,
            rotations.as_quat(),
            frame_id or self.frame_id,
            child_frame_id or self.child_frame_id,
        )

    def write_tum(self, path) -> Path:
        """Write as a TUM file; return the path."""
        path = Path(path)
        seconds, nanoseconds = np.divmod(self.stamps_ns, NS_PER_S)
        lines = [f"# {self.frame_id} -> {self.child_frame_id}: t tx ty tz qx qy qz qw\n"]
        for s, ns, p, q in zip(seconds, nanoseconds, self.positions, self.quaternions, strict=True):
            values = " ".join(repr(float(v)) for v in (*p, *q))
            lines.append(f"{s}.{ns:09d} {values}\n")
        path.write_text("".join(lines))
        return path

    @classmethod
    def read_tum(cls, path, frame_id: str = "world", child_frame_id: str = "base_link") -> Trajectory:
        """Read a TUM file (8 numbers a line; ``#`` comments and blank lines skipped). Errors name the file and the
        line, counted from 1 as editors count them: a line that is not 8 numbers, a number that is not finite, a
        quaternion of zero length, a stamp before the one above it. A file that is not text (a bag, say) is named
        as such."""
        path = Path(path)
        try:
            text = path.read_text(encoding="utf-8")
        except UnicodeDecodeError:
            raise ValueError(
                f"{path} is {_what_it_is(path)}, not a TUM text file: expected one pose a line, "
                "t tx ty tz qx qy qz qw, as gpo run --out writes"
            ) from None
        stamps, values = [], []
        for number, line in enumerate(text.splitlines(), start=1):
            line = line.strip()
            if not line or line.startswith("#"):
                continue
            fields = line.replace(",", " ").split()
            if len(fields) != 8:
                raise ValueError(
                    f"{path}:{number}: a TUM line has 8 numbers (t tx ty tz qx qy qz qw), got {len(fields)}"
                )
            try:
                stamp = _seconds_text_to_ns(fields[0])
            except ValueError:
                raise ValueError(
                    f"{path}:{number}: the stamp {fields[0]!r} is not a time in seconds within 292 years of 1970"
                ) from None
            if not all(NUMBER.fullmatch(v) for v in fields[1:]):
                raise ValueError(f"{path}:{number}: not a number in {line!r}")
            pose = [float(v) for v in fields[1:]]
            problem = _pose_problem(pose, stamp, stamps[-1] if stamps else None)
            if problem:
                raise ValueError(f"{path}:{number}: {line!r}: {problem}")
            stamps.append(stamp)
            values.append(pose)
        values = np.array(values).reshape(-1, 7)
        return cls(np.array(stamps, dtype=np.int64), values[:, :3], values[:, 3:], frame_id, child_frame_id)


def _pose_problem(pose: list[float], stamp_ns: int, previous_ns: int | None) -> str:
    """What is wrong with a TUM line's pose (tx ty tz qx qy qz qw) and stamp after the stamp above it; "" if nothing."""
    if not np.isfinite(pose).all():
        return "positions and quaternions must be finite numbers"
    with np.errstate(over="ignore"):  # a length beyond the largest float is refused below, not warned about
        length = np.linalg.norm(pose[3:])
    if length < 1e-9:
        return "the quaternion (qx qy qz qw) has zero length; expected a rotation, e.g. 0 0 0 1"
    if not np.isfinite(length):
        return "the quaternion (qx qy qz qw) is too long to normalise (over 1e154); expected a rotation, e.g. 0 0 0 1"
    if previous_ns is not None and stamp_ns < previous_ns:
        return "the stamps go backwards (this one is before the one above it); expected the poses in time order"
    return ""


def _what_it_is(path: Path) -> str:
    """What a file that is not UTF-8 text is: "a ROS bag" when it starts as one or is named so, else "binary data"."""
    with path.open("rb") as file:
        start = file.read(16)
    bag = start.startswith((b"#ROSBAG", b"SQLite format 3", b"\x89MCAP")) or path.suffix in (".bag", ".db3", ".mcap")
    return "a ROS bag" if bag else "binary data"


def _seconds_text_to_ns(text: str) -> int:
    """Integer nanoseconds of a decimal number of seconds such as ``1403715273.262142976``, to the nearest one (half
    to even); ValueError for text that is no number (``NUMBER``), a number that is not finite, or a time int64
    nanoseconds cannot hold (more than 292 years from 1970)."""
    if not NUMBER.fullmatch(text):
        raise ValueError(text)
    seconds = Decimal(text)
    if not seconds.is_finite() or seconds.adjusted() > 12:  # beyond 1e13 s: no int64 of nanoseconds
        raise ValueError(text)
    stamp = int((seconds * NS_PER_S).to_integral_value(ROUND_HALF_EVEN))
    if not -(2**63) <= stamp < 2**63:
        raise ValueError(text)
    return stamp


def base_from_sensor_odometry(
    odometry: Trajectory, sensor_in_base: tuple[Rotation, np.ndarray], start: tuple[Rotation, np.ndarray]
) -> Trajectory:
    """A sensor's own odometry turned into the path of ``base_link`` in ``world``.

    ``odometry`` holds the sensor frame C in its odometry frame O, which is where C was at the
    first sample (as a T265 reports it); ``sensor_in_base`` is C's pose in ``base_link`` B (the
    mount: rotation, translation in metres) and ``start`` the pose of B in ``world`` W at the first
    sample. Then ``T_WB(t) = T_WB(0) T_BC T_OC(t) T_BC^-1``.
    """
    mount_rotation, mount_translation = sensor_in_base
    start_rotation, start_position = start
    odometry_in_world = (start_rotation * mount_rotation, start_rotation.apply(mount_translation) + start_position)
    base_in_sensor = (mount_rotation.inv(), -mount_rotation.inv().apply(mount_translation))
    return odometry.compose(odometry_in_world, base_in_sensor, "world", "base_link")
