"""Recordings: read ROS1 and ROS2 bags as frames, trajectories, transforms and cameras.

``Recording`` opens a bag and reads it; ``describe`` summarises one as ``python -m gpo info`` prints it.
Bags are written by ``gpo.io.bag_writer``; the messages' types, image encodings and frame and camera
conventions, which both directions share, are in ``gpo.io.ros_messages``.

Formats
-------
``ros1``
    One ``.bag`` file (rosbag format 2.0).
``ros2-sqlite3``, ``ros2-mcap``
    A rosbag2 folder: ``metadata.yaml`` next to ``.db3`` (sqlite3) or ``.mcap`` storage files. A path to
    a ``.db3`` or ``.mcap`` file opens its folder when that holds ``metadata.yaml``, the file alone
    otherwise.

All of them are read with `rosbags <https://gitlab.com/ternaris/rosbags>`_.

Time
----
Timestamps are integer nanoseconds since the Unix epoch at this boundary. A message carries two:
its *log time*, when the recorder received it, and its *header stamp*, when its data were taken.
Bags are indexed by log time, and every reader here yields messages in log-time order ("bag order").
Frames, trajectories and transforms are stamped with header stamps; ``Recording.start_ns``,
``end_ns`` and ``duration_s`` are log times.

Images
------
An image is returned in the message's own channel order, and ``Frame.encoding`` names it. Raw
images are read-only views of the message buffer (no copy): copy one before drawing on it.
"""

from __future__ import annotations

import contextlib
import difflib
import logging
import sqlite3
import struct
import warnings
from collections.abc import Iterator
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path

import apsw
import cv2
import numpy as np
from rosbags import rosbag1, rosbag2
from rosbags.highlevel import AnyReader, AnyReaderError
from rosbags.typesys import Stores, get_typestore
from tqdm.auto import tqdm

from gpo.cameras.files import Camera, camera_from_camera_info
from gpo.io.ros_messages import (
    CAMERA_INFO,
    CODECS,
    COMPRESSED_IMAGE,
    ENCODINGS,
    IMAGE,
    IMAGE_TYPES,
    ODOMETRY,
    POSE_STAMPED,
    POSE_TYPES,
    TF_MESSAGE,
    check_encoding,
)
from gpo.io.trajectory import NS_PER_S, Trajectory

_log = logging.getLogger(__name__)

_TO_GRAY = {
    "rgb8": cv2.COLOR_RGB2GRAY,
    "bgr8": cv2.COLOR_BGR2GRAY,
    "rgba8": cv2.COLOR_RGBA2GRAY,
    "bgra8": cv2.COLOR_BGRA2GRAY,
}
_FROM_BGR = {("bgr8", "rgb8"): cv2.COLOR_BGR2RGB, ("bgra8", "rgba8"): cv2.COLOR_BGRA2RGBA}

_READERS = (AnyReaderError, rosbag1.ReaderError, rosbag2.ReaderError, sqlite3.Error, apsw.Error, struct.error)
_MISREAD = (ValueError, KeyError, IndexError, TypeError, AttributeError, AssertionError, OverflowError, EOFError)
_DAMAGED = (*_READERS, *_MISREAD, MemoryError, RecursionError)
"""What rosbags (and apsw, through which it reads a ROS 2 sqlite3 database) raises reading the bytes of a damaged bag
(cut short, bits flipped, records out of order, a topic declaring another type than its messages hold; found by
tests/fuzzing), each turned into a ValueError naming the bag: a MemoryError comes of a length read as gigabytes, a
RecursionError of a ROS 2 ``metadata.yaml`` nested hundreds deep."""


class StampWarning(UserWarning):
    """Header stamps that go backwards or repeat."""


@dataclass(frozen=True)
class TopicInfo:
    """A topic of a recording: its name, message type and number of messages."""

    name: str
    msgtype: str
    count: int


@dataclass(frozen=True, eq=False)
class Frame:
    """One image: header stamp (ns), the image, the camera frame it was taken in, and its encoding.

    ``image`` is (H, W) for mono8/mono16 or (H, W, C) with channels in the order ``encoding``
    names (rgb8, bgr8, rgba8, bgra8); dtype uint8, or uint16 for mono16. A frame that could not be
    read (``Recording.frames`` with ``flag_unreadable``) has no image and says why in ``problem``.
    """

    stamp_ns: int
    image: np.ndarray | None
    frame_id: str
    encoding: str
    problem: str | None = None


class Recording:
    """A recorded bag, open for reading; a context manager that closes it.

    ``path``: a ROS1 ``.bag`` file, a ROS2 bag folder, or a ROS2 ``.db3``/``.mcap`` file. Raises
    ``FileNotFoundError`` when it does not exist and ``ValueError`` when it is not a readable
    recording (damaged, cut short, no messages). ``reader`` is the rosbags ``AnyReader`` it reads through.
    """

    def __init__(self, path):
        self.path = Path(path)
        self.format, source = _locate(self.path)
        try:
            self.reader = AnyReader([source], default_typestore=get_typestore(Stores.ROS2_HUMBLE))
            self.reader.open()
        except (*_DAMAGED, OSError) as error:  # an OSError: a damaged offset sought past what the file system allows
            hint = _repair_hint(self.path)
            reason = error.strerror if isinstance(error, OSError) and error.strerror else error
            raise ValueError(f"{self.path} is not a readable {self.format} recording ({reason}).{hint}") from error
        self._check_index()
        if self.reader.message_count == 0:
            self.close()
            raise ValueError(f"{self.path} holds no messages: expected a recording with at least one")

    def _check_index(self) -> None:
        """Topics named by text, of types named by text, they and all messages counted by whole numbers from 0, the
        first and last times whole numbers of nanoseconds: a damaged ROS 2 ``metadata.yaml`` may say otherwise."""
        problem = None
        for count in (reader.message_count for reader in self.reader.readers):
            if not (type(count) is int and count >= 0):  # no flag, no text
                problem = f"it counts {count!r:.30} messages; expected a whole number from 0"
        for connection in self.reader.connections:
            name, kind, count = connection.topic, connection.msgtype, connection.msgcount
            if not (isinstance(name, str) and isinstance(kind, str) and type(count) is int and count >= 0):
                problem = (
                    f"a topic {name!r:.60} of type {kind!r:.60} with {count!r:.20} messages; "
                    "expected names and a count, a whole number from 0"
                )
        times = (self.reader.start_time, self.reader.end_time)
        if not all(isinstance(time, int) and -(2**63) <= time < 2**63 for time in times):
            problem = f"its first and last times are {times[0]!r:.30} and {times[1]!r:.30}; expected nanoseconds"
        if problem:
            self.close()
            raise ValueError(f"{self.path} is damaged: {problem}.{_repair_hint(self.path)}")

    def close(self) -> None:
        """Close the recording's files. A damaged ROS 2 ``metadata.yaml`` (its ``files`` no list) makes rosbags fail as
        it closes: what was read stands, and the files close as the reader is let go."""
        with contextlib.suppress(*_DAMAGED):
            self.reader.close()

    def __enter__(self) -> Recording:
        return self

    def __exit__(self, *exc_info) -> None:
        self.close()

    def topics(self) -> list[TopicInfo]:
        """Every topic, sorted by name."""
        return [
            TopicInfo(name, info.msgtype or " | ".join(sorted({c.msgtype for c in info.connections})), info.msgcount)
            for name, info in self.reader.topics.items()
        ]

    @property
    def start_ns(self) -> int:
        """Log time of the first message, ns."""
        return self.reader.start_time

    @property
    def end_ns(self) -> int:
        """Log time of the last message, ns."""
        return self.reader.end_time - 1  # rosbags' end time is one past the last message

    @property
    def duration_s(self) -> float:
        """Seconds from the first message to the last, in log time."""
        return (self.end_ns - self.start_ns) / NS_PER_S

    def image_topic(self, topic: str | None = None) -> str:
        """``topic`` checked to be an image topic, or with None the recording's only image topic.

        Raises ValueError when the topic is missing or holds no images, or, with None, when the
        recording has no image topic or several (name one of them then).
        """
        if topic is not None:
            self._connections(topic, IMAGE_TYPES)
            return topic
        candidates = [t for t in self.topics() if t.msgtype in IMAGE_TYPES]
        if len(candidates) == 1:
            _log.info("%s: reading images from %s, its only image topic", self.path, candidates[0].name)
            return candidates[0].name
        if not candidates:
            raise ValueError(f"{self.path} has no image topic ({' or '.join(IMAGE_TYPES)}); {self._topic_list()}")
        listed = ", ".join(f"{t.name} ({t.msgtype})" for t in candidates)
        raise ValueError(f"{self.path} has {len(candidates)} image topics: {listed}; name the one to read (--topic)")

    def frames(
        self,
        topic: str | None = None,
        start_ns: int | None = None,
        end_ns: int | None = None,
        *,
        gray: bool = False,
        progress: bool = True,
        flag_unreadable: bool = False,
    ) -> Iterator[Frame]:
        """Stream the images of ``topic`` (see ``image_topic``) in bag order, one message at a time.

        ``start_ns`` (inclusive) and ``end_ns`` (exclusive) select by header stamp; the whole topic
        is read, and messages outside are skipped before decoding. ``gray=True`` converts colour
        to mono8 (mono8 and mono16 stay as they are). Header stamps that go backwards or repeat
        issue a ``StampWarning`` (the first of each kind); the frames are still yielded in bag
        order, untouched. A tqdm bar counts the topic's messages unless ``progress`` is False.
        The topic is checked at the call, each message's encoding when it is read: a message that
        cannot be read (damaged, a short buffer, a corrupt JPEG) raises ValueError, or with
        ``flag_unreadable`` is yielded as a Frame without image whose ``problem`` says why (stamped
        with its log time when even its header cannot be read), and the frames after it follow.
        """
        topic = self.image_topic(topic)
        connections = self._connections(topic, IMAGE_TYPES)
        return self._frames(topic, connections, start_ns, end_ns, gray, progress, flag_unreadable)

    def _frames(self, topic, connections, start_ns, end_ns, gray, progress, flag_unreadable) -> Iterator[Frame]:
        total = sum(c.msgcount for c in connections)
        raw_messages = self.raw_messages(connections)
        messages = tqdm(raw_messages, total=total, desc=topic, unit="msg", disable=not progress)
        context = f"{self.path}, topic {topic}"
        previous, warned = None, set()
        for index, (connection, log_ns, raw) in enumerate(messages):
            try:
                message = self._deserialize(connection, raw)
            except ValueError as error:
                if not flag_unreadable:
                    raise
                yield Frame(log_ns, None, "", "", problem=f"message {index}: {error}")
                continue
            stamp = _stamp_ns(message.header)
            if (start_ns is not None and stamp < start_ns) or (end_ns is not None and stamp >= end_ns):
                continue
            problem = _order_problem(previous, stamp)
            if problem and problem not in warned:
                warned.add(problem)
                warnings.warn(
                    f"{context}: header stamp {problem} at message {index} ({previous} ns, then {stamp} ns); "
                    "frames are yielded in bag order, as recorded",
                    StampWarning,
                    stacklevel=2,
                )
            previous = stamp
            try:
                image, encoding = _decode(message, context)
            except ValueError as error:
                if not flag_unreadable:
                    raise
                yield Frame(stamp, None, message.header.frame_id, "", problem=f"message {index}: {error}")
                continue
            if gray:
                image, encoding = _to_gray(image, encoding)
            yield Frame(stamp, image, message.header.frame_id, encoding)

    def trajectory(self, topic: str) -> Trajectory:
        """The poses on ``topic``: nav_msgs/Odometry, geometry_msgs/PoseStamped or TransformStamped.

        Stamped by header stamps, framed by the messages' frame ids (PoseStamped names no child
        frame: ``base_link`` then). Stamps that go backwards are sorted (stably) and of poses with
        the same stamp the first is kept, each with a ``StampWarning``.
        """
        connections = self._connections(topic, POSE_TYPES)
        return _trajectory([_pose(message) for message in self._messages(connections)], f"{self.path}, topic {topic}")

    def pose_frames(self, topic: str) -> tuple[str, str]:
        """(frame id, child frame id) of the first pose on ``topic``, as ``trajectory`` names them (PoseStamped
        names no child frame: ``base_link``), without reading the other messages."""
        _, frame_id, child_frame_id, _, _ = _pose(self._first_message(topic, POSE_TYPES))
        return frame_id, "base_link" if child_frame_id is None else child_frame_id

    def transform(self, parent: str, child: str, topic: str = "/tf") -> Trajectory:
        """The dynamic transform ``parent`` -> ``child`` over time, from tf2_msgs/TFMessage on ``topic``.

        Frame names match with or without a leading "/". Raises ValueError listing the pairs on
        ``topic`` when this one is not among them.
        """
        transforms, pairs = self._transforms(parent, child, topic)
        if not transforms:
            raise ValueError(f"{self.path}: {topic} has no transform {parent} -> {child}; it has {pairs}")
        return _trajectory([_pose(t) for t in transforms], f"{self.path}, {topic} {parent} -> {child}")

    def static_transform(self, parent: str, child: str) -> tuple[np.ndarray, np.ndarray]:
        """Translation (3,) in metres and quaternion (4,) (x, y, z, w) of ``child`` in ``parent``, from /tf_static.

        The last one recorded wins, as for a latched topic.
        """
        transforms, pairs = self._transforms(parent, child, "/tf_static")
        if not transforms:
            raise ValueError(f"{self.path}: /tf_static has no transform {parent} -> {child}; it has {pairs}")
        _, _, _, translation, rotation = _pose(transforms[-1])
        return np.array(translation), np.array(rotation)

    def static_transforms(self) -> dict[str, tuple[str, np.ndarray, np.ndarray]]:
        """The static tree on /tf_static: each child frame's (parent, translation (3,) m, quaternion (4,) x, y, z, w),
        the last one recorded of each child winning, as for a latched topic; frame names without a leading "/".
        Empty when the bag has no /tf_static."""
        if "/tf_static" not in {topic.name for topic in self.topics()}:
            return {}
        tree = {}
        for message in self._messages(self._connections("/tf_static", (TF_MESSAGE,))):
            for transform in message.transforms:
                _, parent, child, translation, rotation = _pose(transform)
                tree[_frame_name(child)] = (_frame_name(parent), np.array(translation), np.array(rotation))
        return tree

    def camera_info(self, topic: str) -> Camera:
        """The camera of the first sensor_msgs/CameraInfo on ``topic`` (conventions in ``gpo.io.ros_messages``)."""
        return _camera_from_info(self._first_message(topic, (CAMERA_INFO,)), f"{self.path}, topic {topic}")

    def _first_image_text(self, topic: TopicInfo) -> str:
        """Size and encoding of the first image of ``topic``, e.g. ``848x800 mono8``."""
        try:
            message = self._first_message(topic.name, IMAGE_TYPES)
            if topic.msgtype == IMAGE:
                return f"{message.width}x{message.height} {message.encoding}"
            image, _ = _decode(message, f"{self.path}, topic {topic.name}")
        except ValueError:
            return "unreadable"
        return f"{image.shape[1]}x{image.shape[0]} {message.format}"

    def _first_message(self, topic: str, msgtypes: tuple[str, ...]):
        message = next(self._messages(self._connections(topic, msgtypes)), None)
        if message is None:
            raise ValueError(f"{self.path}: topic {topic} has no messages")
        return message

    def _connections(self, topic: str, msgtypes: tuple[str, ...]) -> list:
        """The connections of ``topic``, checked to carry one of ``msgtypes``."""
        connections = [c for c in self.reader.connections if c.topic == topic]
        if not connections:
            close = difflib.get_close_matches(topic, [t.name for t in self.topics()], n=1)
            hint = f" (did you mean {close[0]}?)" if close else ""
            raise ValueError(f"{self.path} has no topic {topic}{hint}; {self._topic_list()}")
        wrong = sorted({c.msgtype for c in connections} - set(msgtypes))
        if wrong:
            raise ValueError(
                f"{self.path}: topic {topic} carries {', '.join(wrong)}; expected one of: {', '.join(msgtypes)}"
            )
        return connections

    def _topic_list(self) -> str:
        return "its topics: " + ", ".join(f"{t.name} ({t.msgtype})" for t in self.topics())

    def raw_messages(self, connections=()) -> Iterator[tuple[object, int, bytes]]:
        """(connection, log time ns, serialised message) in bag order; all topics when ``connections`` is empty. A
        message of another connection than those asked for (a damaged index) raises ValueError, as any damage does."""
        wanted = {id(connection) for connection in connections}
        try:
            for connection, log_ns, raw in self.reader.messages(connections):
                if wanted and id(connection) not in wanted:
                    raise ValueError(f"a message of {connection.topic} among those of another topic")
                yield connection, log_ns, raw
        except _DAMAGED as error:
            raise ValueError(f"{self.path} is damaged: {type(error).__name__}: {error}") from error
        except OSError as error:  # a damaged offset sought past what the file system allows, or a failing disk
            raise ValueError(f"{self.path} is damaged or cannot be read: {error.strerror or error}") from error

    def _messages(self, connections) -> Iterator[object]:
        """The deserialised messages of ``connections`` in bag order."""
        for connection, _, raw in self.raw_messages(connections):
            yield self._deserialize(connection, raw)

    def _deserialize(self, connection, raw: bytes):
        """One message; ValueError naming the bag and topic when its bytes cannot be read."""
        try:
            return self.reader.deserialize(raw, connection.msgtype)
        except _DAMAGED as error:
            raise ValueError(f"{self.path}: a {connection.msgtype} on {connection.topic} is damaged") from error

    def _transforms(self, parent: str, child: str, topic: str) -> tuple[list, str]:
        """The TransformStamped of ``parent`` -> ``child`` on ``topic`` in bag order, and every pair there as text."""
        wanted = (_frame_name(parent), _frame_name(child))
        found, pairs = [], set()
        for message in self._messages(self._connections(topic, (TF_MESSAGE,))):
            for transform in message.transforms:
                pair = (_frame_name(transform.header.frame_id), _frame_name(transform.child_frame_id))
                pairs.add(pair)
                if pair == wanted:
                    found.append(transform)
        return found, ", ".join(f"{p} -> {c}" for p, c in sorted(pairs)) or "none"


def describe(path) -> str:
    """A summary of the recording at ``path``, as ``python -m gpo info`` prints it.

    Path, format, duration, start time, then each topic's type, message count, mean rate over the
    whole recording, and for image topics the size and encoding of the first message ("unreadable" when it
    cannot be read).
    """
    with Recording(path) as recording:
        start = datetime.fromtimestamp(recording.start_ns // NS_PER_S, tz=UTC)
        rows = [("topic", "type", "count", "Hz", "first image")]
        for topic in recording.topics():
            rate = (topic.count - 1) / recording.duration_s if recording.duration_s > 0 else 0.0
            image = recording._first_image_text(topic) if topic.msgtype in IMAGE_TYPES else ""
            rows.append((topic.name, topic.msgtype, str(topic.count), f"{rate:.1f}" if rate else "-", image))
        header = [
            f"path:     {recording.path}",
            f"format:   {recording.format}",
            f"duration: {recording.duration_s:.3f} s",
            f"start:    {start:%Y-%m-%d %H:%M:%S}.{recording.start_ns % NS_PER_S:09d} UTC ({recording.start_ns} ns)",
            "",
        ]
    widths = [max(len(row[i]) for row in rows) for i in range(len(rows[0]))]
    aligns = ("<", "<", ">", ">", "<")
    table = [
        "  ".join(f"{cell:{a}{w}}" for cell, a, w in zip(row, aligns, widths, strict=True)).rstrip() for row in rows
    ]
    return "\n".join(header + table) + "\n"


def recording_format(path) -> str:
    """The format of the recording at ``path`` (``ros1``, ``ros2-sqlite3`` or ``ros2-mcap``), without reading it;
    an error naming ``path`` when it is not a recording."""
    return _locate(Path(path))[0]


def _locate(path: Path) -> tuple[str, Path]:
    """The format of the recording at ``path`` and the path to open it by."""
    if not path.exists():
        raise FileNotFoundError(f"no recording at {path}: expected a ROS1 .bag file, a ROS2 bag folder or .db3/.mcap")
    if path.is_dir():
        if not (path / "metadata.yaml").is_file():
            raise FileNotFoundError(f"{path} is a folder without metadata.yaml: expected a ROS2 bag folder")
        return ("ros2-mcap" if any(path.glob("*.mcap*")) else "ros2-sqlite3"), path
    formats = {".bag": "ros1", ".db3": "ros2-sqlite3", ".mcap": "ros2-mcap"}
    if path.suffix not in formats:
        raise ValueError(f"{path} is not a recording: expected a ROS1 .bag file, a ROS2 bag folder or .db3/.mcap")
    in_folder = path.suffix != ".bag" and (path.parent / "metadata.yaml").is_file()
    return formats[path.suffix], path.parent if in_folder else path


def _repair_hint(path: Path) -> str:
    """How a recording cut short may be repaired, when ``path`` starts as a bag of its format does."""
    if path.is_dir():
        return " A ROS2 recording cut short (crash, full disk) may be repaired by `ros2 bag reindex`."
    with path.open("rb") as file:
        start = file.read(16)
    if start.startswith(b"#ROSBAG V2.0"):
        return " A ROS1 bag cut short (crash, full disk) lacks its index: `rosbag reindex` may repair it."
    if start.startswith(b"SQLite format 3") or start.startswith(b"\x89MCAP"):
        return " A ROS2 recording cut short (crash, full disk) may be repaired by `ros2 bag reindex`."
    return " It does not start as a bag does: not a recording at all, or the wrong file."


def _stamp_ns(header) -> int:
    return header.stamp.sec * NS_PER_S + header.stamp.nanosec


def _order_problem(previous: int | None, stamp: int) -> str | None:
    """'goes backwards' or 'repeats' when ``stamp`` does so after ``previous``."""
    if previous is None or stamp > previous:
        return None
    return "repeats" if stamp == previous else "goes backwards"


def _frame_name(name: str) -> str:
    """A tf frame name without the leading "/" that ROS1 allowed."""
    return name.lstrip("/")


def _pose(message) -> tuple[int, str, str | None, tuple[float, ...], tuple[float, ...]]:
    """Header stamp, frame, child frame (None for PoseStamped), position and quaternion (x, y, z, w)."""
    if message.__msgtype__ == ODOMETRY:
        child, pose = message.child_frame_id, message.pose.pose
        position, orientation = pose.position, pose.orientation
    elif message.__msgtype__ == POSE_STAMPED:
        child, position, orientation = None, message.pose.position, message.pose.orientation
    else:
        child, transform = message.child_frame_id, message.transform
        position, orientation = transform.translation, transform.rotation
    return (
        _stamp_ns(message.header),
        message.header.frame_id,
        child,
        (position.x, position.y, position.z),
        (orientation.x, orientation.y, orientation.z, orientation.w),
    )


def _trajectory(poses: list, context: str) -> Trajectory:
    """A Trajectory of ``_pose`` tuples: stably sorted by stamp, the first of equal stamps kept."""
    if not poses:
        raise ValueError(f"{context}: no poses")
    stamps, frames, children, positions, quaternions = zip(*poses, strict=True)
    frame_pairs = sorted(set(zip(frames, children, strict=True)), key=str)
    if len(frame_pairs) > 1:
        raise ValueError(f"{context}: the poses change frames, (frame, child) = {frame_pairs}; expected one pair")
    stamps = np.array(stamps, dtype=np.int64)
    finite = np.isfinite(np.hstack([np.array(positions, dtype=float), np.array(quaternions, dtype=float)])).all(axis=1)
    if not finite.all():
        first = int(np.argmin(finite))
        raise ValueError(
            f"{context}: {np.count_nonzero(~finite)} of {len(finite)} poses hold NaN or infinite numbers, the first at "
            f"message {first + 1}, stamp {stamps[first] // NS_PER_S}.{stamps[first] % NS_PER_S:09d} s; expected finite "
            "positions and orientations"
        )
    order = np.argsort(stamps, kind="stable")
    backwards = np.flatnonzero(np.diff(stamps) < 0)
    if backwards.size:
        i = backwards[0] + 1
        warnings.warn(
            f"{context}: header stamps go backwards {backwards.size} times, first at message {i} "
            f"({stamps[i - 1]} ns, then {stamps[i]} ns); the poses are sorted by stamp",
            StampWarning,
            stacklevel=3,
        )
    repeated = np.flatnonzero(np.diff(stamps[order]) == 0) + 1
    if repeated.size:
        warnings.warn(
            f"{context}: {repeated.size} poses repeat an earlier header stamp, first at message "
            f"{order[repeated[0]]} ({stamps[order[repeated[0]]]} ns); of each stamp the first pose is kept",
            StampWarning,
            stacklevel=3,
        )
    keep = np.delete(order, repeated)
    frame_id, child = frame_pairs[0]
    try:  # what Trajectory refuses of finite poses (a quaternion of zero length) is named with the bag and topic
        return Trajectory(stamps[keep], np.array(positions)[keep], np.array(quaternions)[keep], frame_id,
                          "base_link" if child is None else child)
    except ValueError as error:
        raise ValueError(f"{context}: {error}") from error


def _camera_from_info(message, context: str) -> Camera:
    """The camera of a sensor_msgs/CameraInfo (ROS1 spells its matrices D, K; ROS2 d, k)."""
    k = getattr(message, "k", None)
    k, d = (message.K, message.D) if k is None else (k, message.d)
    return camera_from_camera_info(message.distortion_model, d, k, message.width, message.height, context)


def _decode(message, context: str) -> tuple[np.ndarray, str]:
    """The image of an Image or CompressedImage message, and its encoding."""
    if message.__msgtype__ == COMPRESSED_IMAGE:
        return _decode_compressed(message, context)
    return _decode_raw(message, context)


def _decode_raw(message, context: str) -> tuple[np.ndarray, str]:
    """A view of a sensor_msgs/Image's buffer as an (H, W[, C]) array; copied only to swap bytes."""
    encoding = message.encoding
    if encoding not in ENCODINGS:
        raise ValueError(f"{context}: image encoding {encoding!r} is not supported; supported: {', '.join(ENCODINGS)}")
    element, channels = ENCODINGS[encoding]
    dtype = np.dtype(element).newbyteorder(">" if message.is_bigendian else "<")
    row = message.width * channels * dtype.itemsize
    if message.step < row or len(message.data) < message.step * (message.height - 1) + row:
        raise ValueError(f"{context}: a {message.width}x{message.height} {encoding} image with a short buffer")
    shape = (message.height, message.width, channels)[: 2 if channels == 1 else 3]
    strides = (message.step, channels * dtype.itemsize, dtype.itemsize)[: len(shape)]
    image = np.ndarray(shape, dtype, buffer=message.data, strides=strides)
    return (image if dtype.isnative else image.astype(dtype.newbyteorder("="))), encoding


def _decode_compressed(message, context: str) -> tuple[np.ndarray, str]:
    """Decode a jpeg or png CompressedImage (image_transport's ``format`` conventions, ``gpo.io.ros_messages``)."""
    original, _, coding = message.format.rpartition(";")
    codec = next(iter(coding.split()), "").replace("jpg", "jpeg")
    if codec not in CODECS:
        raise ValueError(
            f"{context}: compressed image format {message.format!r} is not supported; supported: {', '.join(CODECS)}"
        )
    image = cv2.imdecode(message.data, cv2.IMREAD_UNCHANGED)
    if image is None:
        raise ValueError(f"{context}: the {codec} data of a compressed image cannot be decoded")
    encoding = check_encoding(image, None, context, colour="bgr")
    conversion = _FROM_BGR.get((encoding, original.strip()))
    if conversion is not None:
        return cv2.cvtColor(image, conversion), original.strip()
    return image, encoding


def _to_gray(image: np.ndarray, encoding: str) -> tuple[np.ndarray, str]:
    if encoding in ("mono8", "mono16"):
        return image, encoding
    return cv2.cvtColor(image, _TO_GRAY[encoding]), "mono8"
