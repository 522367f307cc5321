"""Recordings: read and write ROS1 and ROS2 bags as frames, trajectories, transforms and cameras.

One module for both directions and all three formats (about 900 lines): the reader and the writer share the message
types, the topic and frame conventions and the format detection, and the tests check them as one round trip.

Formats
-------
``ros1``
    One ``.bag`` file (rosbag format 2.0).
``ros2-sqlite3``, ``ros2-mcap``
    A rosbag2 folder: ``metadata.yaml`` next to ``.db3`` (sqlite3) or ``.mcap`` storage files. A path to
    a ``.db3`` or ``.mcap`` file opens its folder when that holds ``metadata.yaml``, the file alone
    otherwise. ``BagWriter`` calls the sqlite3 flavour ``ros2``.

All of them are read and written with `rosbags <https://gitlab.com/ternaris/rosbags>`_; message types
are named the ROS2 way (``sensor_msgs/msg/Image``) for ROS1 bags too.

Time
----
Timestamps are integer nanoseconds since the Unix epoch at this boundary. A message carries two:
its *log time*, when the recorder received it, and its *header stamp*, when its data were taken.
Bags are indexed by log time, and every reader here yields messages in log-time order ("bag order").
Frames, trajectories and transforms are stamped with header stamps; ``Recording.start_ns``,
``end_ns`` and ``duration_s`` are log times. ``BagWriter`` logs each message at its header stamp.
Messages may be added in any time order on any topic: all three storage formats index messages by
log time, so readers get them back sorted.

Frames and units
----------------
Frames follow REP-103/105. A transform or pose of ``child`` in ``parent`` (``frame_id``) maps
child-frame coordinates into the parent frame: translation in metres, rotation as a unit
quaternion (x, y, z, w), as tf does. Odometry twists are in the child frame, in m/s and rad/s.

Images
------
Raw ``sensor_msgs/msg/Image`` encodings read and written: mono8, mono16, rgb8, bgr8, rgba8, bgra8.
An image is returned in the message's own channel order, and ``Frame.encoding`` names it. Raw
images are read-only views of the message buffer (no copy): copy one before drawing on it.
``sensor_msgs/msg/CompressedImage`` in jpeg or png follows image_transport: ``format`` reads
``"<encoding>; <codec> compressed <coded encoding>"`` (older bags: just ``"jpeg"``); colour is coded
as BGR, so a colour frame comes back as bgr8/bgra8, or as rgb8/rgba8 when ``format`` names that as
the original encoding. 16-bit PNG keeps its 16 bits.

Cameras
-------
``sensor_msgs/msg/CameraInfo`` holds fx, fy, cx, cy in ``K``. Distortion models: ``plumb_bob`` and
``rational_polynomial`` give a ``Pinhole`` (D = k1, k2, p1, p2[, k3]; rational_polynomial only when
its k4, k5, k6 are zero); ``equidistant`` a ``KB4`` (D = k1, k2, k3, k4); ``eucm`` and ``ds``, this
project's conventions, an ``EUCM`` (D = alpha, beta) and a ``DoubleSphere`` (D = xi, alpha), as
`gpo.cameras.files.camera_from_camera_info` reads them.
"""

from __future__ import annotations

import difflib
import logging
import shutil
import struct
import sys
import warnings
from collections import Counter
from collections.abc import Iterator
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path

import cv2
import numpy as np
from rosbags import rosbag1, rosbag2
from rosbags.highlevel import AnyReader, AnyReaderError
from rosbags.interfaces import Qos, QosDurability, QosHistory, QosLiveliness, QosReliability, QosTime
from rosbags.typesys import Stores, get_types_from_msg, get_typestore
from tqdm.auto import tqdm

from gpo.cameras.files import Camera, camera_from_camera_info, camera_info_distortion
from gpo.io.trajectory import NS_PER_S, Trajectory

_log = logging.getLogger(__name__)

IMAGE = "sensor_msgs/msg/Image"
COMPRESSED_IMAGE = "sensor_msgs/msg/CompressedImage"
CAMERA_INFO = "sensor_msgs/msg/CameraInfo"
ODOMETRY = "nav_msgs/msg/Odometry"
POSE_STAMPED = "geometry_msgs/msg/PoseStamped"
TRANSFORM_STAMPED = "geometry_msgs/msg/TransformStamped"
TF_MESSAGE = "tf2_msgs/msg/TFMessage"
IMAGE_TYPES = (IMAGE, COMPRESSED_IMAGE)
POSE_TYPES = (ODOMETRY, POSE_STAMPED, TRANSFORM_STAMPED)

ENCODINGS: dict[str, tuple[type[np.integer], int]] = {
    "mono8": (np.uint8, 1),
    "mono16": (np.uint16, 1),
    "rgb8": (np.uint8, 3),
    "bgr8": (np.uint8, 3),
    "rgba8": (np.uint8, 4),
    "bgra8": (np.uint8, 4),
}
"""Raw image encodings read and written: element type and channels."""

CODECS = ("jpeg", "png")
"""CompressedImage codecs read and written."""

_TO_GRAY = {
    "rgb8": cv2.COLOR_RGB2GRAY,
    "bgr8": cv2.COLOR_BGR2GRAY,
    "rgba8": cv2.COLOR_RGBA2GRAY,
    "bgra8": cv2.COLOR_BGRA2GRAY,
}
_TO_BGR = {"rgb8": (cv2.COLOR_RGB2BGR, "bgr8"), "rgba8": (cv2.COLOR_RGBA2BGRA, "bgra8")}
_FROM_BGR = {("bgr8", "rgb8"): cv2.COLOR_BGR2RGB, ("bgra8", "rgba8"): cv2.COLOR_BGRA2RGBA}

_ROSBAGS_ERRORS = (AnyReaderError, rosbag1.ReaderError, rosbag2.ReaderError)
_WRITER_STORAGE = {
    "ros2": rosbag2.StoragePlugin.SQLITE3,
    "ros2-sqlite3": rosbag2.StoragePlugin.SQLITE3,
    "ros2-mcap": rosbag2.StoragePlugin.MCAP,
}
WRITE_FORMATS = ("ros1", *_WRITER_STORAGE)
_ROS1_TF_MESSAGE = "geometry_msgs/TransformStamped[] transforms"
_NO_DURATION = QosTime(0, 0)
_STATIC_TF_QOS = Qos(
    QosHistory.KEEP_LAST,
    1,
    QosReliability.RELIABLE,
    QosDurability.TRANSIENT_LOCAL,
    _NO_DURATION,
    _NO_DURATION,
    QosLiveliness.AUTOMATIC,
    _NO_DURATION,
    False,
)
"""The QoS that tf2_ros's static broadcaster offers: late subscribers still get /tf_static."""


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
    recording (damaged, cut short, no messages).
    """

    def __init__(self, path):
        self.path = Path(path)
        self.format, source = _locate(self.path)
        try:
            self._reader = AnyReader([source], default_typestore=get_typestore(Stores.ROS2_HUMBLE))
            self._reader.open()
        except (*_ROSBAGS_ERRORS, ValueError, KeyError, IndexError, struct.error) as error:
            hint = _repair_hint(self.path)
            raise ValueError(f"{self.path} is not a readable {self.format} recording ({error}).{hint}") from error
        if self._reader.message_count == 0:
            self.close()
            raise ValueError(f"{self.path} holds no messages: expected a recording with at least one")

    def close(self) -> None:
        """Close the recording's files."""
        self._reader.close()

    def __enter__(self) -> Recording:
        return self

    def __exit__(self, *exc_info) -> None:
        self.close()

    def topics(self) -> list[TopicInfo]:
        """Every topic, sorted by name."""
        return [
            TopicInfo(name, info.msgtype or " | ".join(sorted({c.msgtype for c in info.connections})), info.msgcount)
            for name, info in self._reader.topics.items()
        ]

    @property
    def start_ns(self) -> int:
        """Log time of the first message, ns."""
        return self._reader.start_time

    @property
    def end_ns(self) -> int:
        """Log time of the last message, ns."""
        return self._reader.end_time - 1  # rosbags' end time is one past the last message

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
        raw_messages = self._raw_messages(connections)
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
        """The camera of the first sensor_msgs/CameraInfo on ``topic`` (conventions in the module docstring)."""
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
        connections = [c for c in self._reader.connections if c.topic == topic]
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

    def _raw_messages(self, connections=()) -> Iterator[tuple[object, int, bytes]]:
        """(connection, log time ns, serialised message) in bag order; all topics when ``connections`` is empty."""
        try:
            yield from self._reader.messages(connections)
        except _ROSBAGS_ERRORS as error:
            raise ValueError(f"{self.path} is damaged: {error}") from error

    def _messages(self, connections) -> Iterator[object]:
        """The deserialised messages of ``connections`` in bag order."""
        for connection, _, raw in self._raw_messages(connections):
            yield self._deserialize(connection, raw)

    def _deserialize(self, connection, raw: bytes):
        """One message; ValueError naming the bag and topic when its bytes cannot be read."""
        try:
            return self._reader.deserialize(raw, connection.msgtype)
        except (AnyReaderError, ValueError, IndexError, TypeError) as error:
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


class BagWriter:
    """A new bag, open for writing; a context manager that finishes it.

    ``format``: ``ros1`` (``path`` a file named ``*.bag``), ``ros2`` (a folder, sqlite3 storage) or
    ``ros2-mcap`` (a folder, mcap storage). Raises FileExistsError when ``path`` exists. Every
    message is logged at its header stamp, in any order (see the module docstring); leaving the
    ``with`` block by an exception deletes the unfinished bag.
    """

    def __init__(self, path, format: str = "ros1"):
        self.path = Path(path)
        if format not in WRITE_FORMATS:
            raise ValueError(f"unknown bag format {format!r}: expected one of {', '.join(WRITE_FORMATS)}")
        if (format == "ros1") != (self.path.suffix == ".bag"):
            raise ValueError(f"{self.path}: a ros1 bag is one file named *.bag, a ros2 bag a folder not named so")
        if self.path.exists():
            raise FileExistsError(f"{self.path} exists; a BagWriter only creates new bags")
        self.format = format
        if format == "ros1":
            self._typestore = get_typestore(Stores.ROS1_NOETIC)
            self._typestore.register(get_types_from_msg(_ROS1_TF_MESSAGE, TF_MESSAGE))
            self._writer = rosbag1.Writer(self.path)
        else:
            self._typestore = get_typestore(Stores.ROS2_JAZZY)
            self._writer = rosbag2.Writer(
                self.path, version=rosbag2.Writer.VERSION_LATEST, storage_plugin=_WRITER_STORAGE[format]
            )
        self._types = self._typestore.types
        self._connections: dict[str, object] = {}
        self._sequence: Counter[str] = Counter()
        self._static_transforms: dict[str, object] = {}
        self._writer.open()

    def close(self) -> None:
        """Finish the bag: write its index and metadata."""
        self._writer.close()

    def __enter__(self) -> BagWriter:
        return self

    def __exit__(self, exc_type, exc_value, traceback) -> None:
        if exc_type is None:
            self.close()
            return
        self._writer.abort()
        if self.path.is_dir():
            shutil.rmtree(self.path)
        else:
            self.path.unlink(missing_ok=True)

    def add_image(self, topic: str, stamp_ns: int, image, frame_id: str, encoding: str | None = None) -> None:
        """A sensor_msgs/Image. ``encoding`` (see ENCODINGS) defaults to what ``image`` looks like:
        uint8 (H, W) mono8, uint16 (H, W) mono16, uint8 (H, W, 3) rgb8, uint8 (H, W, 4) rgba8."""
        image = np.asarray(image)
        image = np.ascontiguousarray(image, dtype=image.dtype.newbyteorder("="))
        encoding = _check_encoding(image, encoding, f"{self.path}, topic {topic}")
        height, width = image.shape[:2]
        message = self._types[IMAGE](
            header=self._header(topic, stamp_ns, frame_id),
            height=height,
            width=width,
            encoding=encoding,
            is_bigendian=int(sys.byteorder == "big"),
            step=image.strides[0],
            data=image.reshape(-1).view(np.uint8),
        )
        self._write(topic, message, stamp_ns)

    def add_compressed_image(
        self,
        topic: str,
        stamp_ns: int,
        image,
        frame_id: str,
        format: str = "png",
        encoding: str | None = None,
        jpeg_quality: int = 95,
    ) -> None:
        """A sensor_msgs/CompressedImage, coded as image_transport does (colour as BGR).

        ``format``: ``png`` (lossless; every encoding) or ``jpeg`` (lossy, ``jpeg_quality`` 0-100;
        mono8, rgb8, bgr8). ``encoding`` as for ``add_image``.
        """
        context = f"{self.path}, topic {topic}"
        if format not in CODECS:
            raise ValueError(f"{context}: compressed image format {format!r} unknown; expected one of {CODECS}")
        image = np.asarray(image)
        encoding = _check_encoding(image, encoding, context)
        if format == "jpeg" and encoding not in ("mono8", "rgb8", "bgr8"):
            raise ValueError(f"{context}: jpeg holds mono8, rgb8 or bgr8 images, not {encoding}")
        coded, coded_encoding = image, encoding
        if encoding in _TO_BGR:
            conversion, coded_encoding = _TO_BGR[encoding]
            coded = cv2.cvtColor(image, conversion)
        parameters = [cv2.IMWRITE_JPEG_QUALITY, jpeg_quality] if format == "jpeg" else []
        encoded, data = cv2.imencode(f".{format}", coded, parameters)
        if not encoded:
            raise ValueError(f"{context}: OpenCV could not encode a {encoding} image as {format}")
        message = self._types[COMPRESSED_IMAGE](
            header=self._header(topic, stamp_ns, frame_id),
            format=f"{encoding}; {format} compressed {coded_encoding}",
            data=data.reshape(-1),
        )
        self._write(topic, message, stamp_ns)

    def add_camera_info(self, topic: str, stamp_ns: int, camera: Camera, frame_id: str) -> None:
        """A sensor_msgs/CameraInfo of ``camera``, its distortion as `gpo.cameras.files.camera_info_distortion` has
        it."""
        model, distortion = camera_info_distortion(camera)
        k = [camera.fx, 0.0, camera.cx, 0.0, camera.fy, camera.cy, 0.0, 0.0, 1.0]
        p = [camera.fx, 0.0, camera.cx, 0.0, 0.0, camera.fy, camera.cy, 0.0, 0.0, 0.0, 1.0, 0.0]
        info_type = self._types[CAMERA_INFO]
        # ROS1 spells the matrices D, K, R, P; ROS2 d, k, r, p
        spelled = {name.lower(): name for name in info_type.__dataclass_fields__}
        matrices = {"d": distortion, "k": k, "r": [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0], "p": p}
        message = info_type(
            header=self._header(topic, stamp_ns, frame_id),
            height=camera.height,
            width=camera.width,
            distortion_model=model,
            binning_x=0,
            binning_y=0,
            roi=self._types["sensor_msgs/msg/RegionOfInterest"](
                x_offset=0, y_offset=0, height=0, width=0, do_rectify=False
            ),
            **{spelled[name]: np.array(values, dtype=np.float64) for name, values in matrices.items()},
        )
        self._write(topic, message, stamp_ns)

    def add_odometry(
        self,
        topic: str,
        stamp_ns: int,
        position,
        quaternion,
        frame_id: str,
        child_frame_id: str,
        linear=None,
        angular=None,
    ) -> None:
        """A nav_msgs/Odometry: pose of ``child_frame_id`` in ``frame_id`` (metres; quaternion x, y, z, w),
        and the twist in the child frame (``linear`` m/s, ``angular`` rad/s; zero when None).
        Covariances are zero."""
        twist = self._types["geometry_msgs/msg/Twist"](
            linear=self._vector3(np.zeros(3) if linear is None else linear),
            angular=self._vector3(np.zeros(3) if angular is None else angular),
        )
        message = self._types[ODOMETRY](
            header=self._header(topic, stamp_ns, frame_id),
            child_frame_id=child_frame_id,
            pose=self._types["geometry_msgs/msg/PoseWithCovariance"](
                pose=self._pose(position, quaternion), covariance=np.zeros(36)
            ),
            twist=self._types["geometry_msgs/msg/TwistWithCovariance"](twist=twist, covariance=np.zeros(36)),
        )
        self._write(topic, message, stamp_ns)

    def add_pose(self, topic: str, stamp_ns: int, position, quaternion, frame_id: str) -> None:
        """A geometry_msgs/PoseStamped in ``frame_id``: position in metres, quaternion (x, y, z, w)."""
        message = self._types[POSE_STAMPED](
            header=self._header(topic, stamp_ns, frame_id), pose=self._pose(position, quaternion)
        )
        self._write(topic, message, stamp_ns)

    def add_trajectory(self, topic: str, trajectory: Trajectory, msgtype: str = "odometry") -> None:
        """Every pose of ``trajectory`` as nav_msgs/Odometry (``msgtype="odometry"``, zero twist) or
        geometry_msgs/PoseStamped (``"pose"``, which drops the child frame)."""
        if msgtype not in ("odometry", "pose"):
            raise ValueError(f"msgtype must be 'odometry' or 'pose', got {msgtype!r}")
        for stamp, position, quaternion in zip(
            trajectory.stamps_ns, trajectory.positions, trajectory.quaternions, strict=True
        ):
            if msgtype == "odometry":
                self.add_odometry(topic, stamp, position, quaternion, trajectory.frame_id, trajectory.child_frame_id)
            else:
                self.add_pose(topic, stamp, position, quaternion, trajectory.frame_id)

    def add_transform(
        self, parent: str, child: str, translation, quaternion, stamp_ns: int, topic: str = "/tf"
    ) -> None:
        """A tf2_msgs/TFMessage on ``topic`` holding the transform of ``child`` in ``parent``."""
        transform = self._transform(parent, child, translation, quaternion, stamp_ns, topic)
        self._write(topic, self._types[TF_MESSAGE](transforms=[transform]), stamp_ns)

    def add_static_transform(self, parent: str, child: str, translation, quaternion, stamp_ns: int) -> None:
        """A static transform on /tf_static (latched, transient-local in ROS2).

        As tf2_ros's static broadcaster, each message holds every static transform added so far,
        so the last message alone is the whole static tree.
        """
        self._static_transforms[child] = self._transform(parent, child, translation, quaternion, stamp_ns, "/tf_static")
        message = self._types[TF_MESSAGE](transforms=list(self._static_transforms.values()))
        self._write("/tf_static", message, stamp_ns, latched=True)

    def _write(self, topic: str, message, stamp_ns: int, latched: bool = False) -> None:
        """Serialise ``message`` and write it on ``topic`` at log time ``stamp_ns``."""
        msgtype = message.__msgtype__
        connection = self._connections.get(topic)
        if connection is None:
            connection = self._connections[topic] = self._add_connection(topic, msgtype, latched)
        elif connection.msgtype != msgtype:
            raise ValueError(f"{self.path}: topic {topic} carries {connection.msgtype}, not {msgtype}")
        if self.format == "ros1":
            raw = self._typestore.serialize_ros1(message, msgtype)
        else:
            raw = self._typestore.serialize_cdr(message, msgtype)
        self._writer.write(connection, _check_stamp(stamp_ns), raw)

    def _add_connection(self, topic: str, msgtype: str, latched: bool):
        if self.format == "ros1":
            return self._writer.add_connection(topic, msgtype, typestore=self._typestore, latching=int(latched))
        qos = [_STATIC_TF_QOS] if latched else []
        return self._writer.add_connection(topic, msgtype, typestore=self._typestore, offered_qos_profiles=qos)

    def _header(self, topic: str, stamp_ns: int, frame_id: str):
        seconds, nanoseconds = divmod(_check_stamp(stamp_ns), NS_PER_S)
        fields = {"stamp": self._types["builtin_interfaces/msg/Time"](sec=seconds, nanosec=nanoseconds)}
        if "seq" in self._types["std_msgs/msg/Header"].__dataclass_fields__:  # ROS1 numbers messages
            fields["seq"] = self._sequence[topic]
            self._sequence[topic] += 1
        return self._types["std_msgs/msg/Header"](frame_id=frame_id, **fields)

    def _vector3(self, values, name: str = "geometry_msgs/msg/Vector3"):
        x, y, z = (float(v) for v in values)
        return self._types[name](x=x, y=y, z=z)

    def _quaternion(self, values):
        x, y, z, w = (float(v) for v in values)
        return self._types["geometry_msgs/msg/Quaternion"](x=x, y=y, z=z, w=w)

    def _pose(self, position, quaternion):
        return self._types["geometry_msgs/msg/Pose"](
            position=self._vector3(position, "geometry_msgs/msg/Point"), orientation=self._quaternion(quaternion)
        )

    def _transform(self, parent, child, translation, quaternion, stamp_ns, topic):
        return self._types[TRANSFORM_STAMPED](
            header=self._header(topic, stamp_ns, parent),
            child_frame_id=child,
            transform=self._types["geometry_msgs/msg/Transform"](
                translation=self._vector3(translation), rotation=self._quaternion(quaternion)
            ),
        )


def copy_with_trajectory(source_bag, destination, trajectory: Trajectory, topic: str = "/gpo/odom") -> Path:
    """Copy every message of ``source_bag`` into a new bag of the same format at ``destination``, and
    add ``trajectory`` on ``topic`` as nav_msgs/Odometry (frames from the trajectory); return the new path.

    Messages are copied as recorded (same bytes, log times, topics, types, latching and QoS), the way
    rosbags' own converter does it.
    """
    with Recording(source_bag) as source:
        if any(t.name == topic for t in source.topics()):
            raise ValueError(f"{source.path} already has a topic {topic}; choose another topic for the trajectory")
        with BagWriter(destination, format=source.format) as writer:
            _copy_messages(source, writer)
            writer.add_trajectory(topic, trajectory)
    return writer.path


def _copy_messages(source: Recording, writer: BagWriter) -> None:
    """Every message of ``source`` into ``writer``, each connection recreated as it was.

    A connection's ``ext`` holds the writer's options of its format: callerid and latching in ROS1,
    serialization format and offered QoS in ROS2.
    """
    copies = {
        connection.id: writer._writer.add_connection(
            connection.topic, connection.msgtype, typestore=source._reader.typestore, **connection.ext._asdict()
        ) for connection in source._reader.connections
    }
    for connection, log_time, raw in source._raw_messages():
        writer._writer.write(copies[connection.id], log_time, raw)


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


def _check_stamp(stamp_ns) -> int:
    if not isinstance(stamp_ns, int | np.integer) or stamp_ns < 0:
        raise ValueError(f"stamps are non-negative integer nanoseconds, got {stamp_ns!r}")
    return int(stamp_ns)


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
            StampWarning, stacklevel=3,
        )
    keep = np.delete(order, repeated)
    frame_id, child_frame_id = frame_pairs[0]
    return Trajectory(
        stamps[keep],
        np.array(positions)[keep],
        np.array(quaternions)[keep],
        frame_id,
        "base_link" if child_frame_id is None else child_frame_id,
    )


def _camera_from_info(message, context: str) -> Camera:
    """The camera of a sensor_msgs/CameraInfo (ROS1 spells its matrices D, K; ROS2 d, k)."""
    k = getattr(message, "k", None)
    k, d = (message.K, message.D) if k is None else (k, message.d)
    return camera_from_camera_info(message.distortion_model, d, k, message.width, message.height, context)


def _check_encoding(image: np.ndarray, encoding: str | None, context: str, colour: str = "rgb") -> str:
    """``encoding`` checked against ``image``'s dtype and shape, or inferred from them when None.

    An inferred 3- or 4-channel image is taken to be in ``colour`` channel order ("rgb" or "bgr").
    """
    kind = (image.dtype.type, image.shape[2] if image.ndim == 3 else 1)
    if encoding is None:
        inferred = {
            (np.uint8, 1): "mono8",
            (np.uint16, 1): "mono16",
            (np.uint8, 3): f"{colour}8",
            (np.uint8, 4): f"{colour}a8",
        }
        encoding = inferred.get(kind)
    if image.ndim not in (2, 3) or ENCODINGS.get(encoding) != kind:
        supported = ", ".join(f"{name} ({np.dtype(t).name} x{c})" for name, (t, c) in ENCODINGS.items())
        raise ValueError(
            f"{context}: a {image.dtype} image of shape {image.shape} is not {encoding or 'any encoding'}; "
            f"supported: {supported}"
        )
    return encoding


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
    """Decode a jpeg or png CompressedImage (image_transport's ``format`` conventions, module docstring)."""
    original, _, coding = message.format.rpartition(";")
    codec = next(iter(coding.split()), "").replace("jpg", "jpeg")
    if codec not in CODECS:
        raise ValueError(
            f"{context}: compressed image format {message.format!r} is not supported; supported: {', '.join(CODECS)}"
        )
    image = cv2.imdecode(message.data, cv2.IMREAD_UNCHANGED)
    if image is None:
        raise ValueError(f"{context}: the {codec} data of a compressed image cannot be decoded")
    encoding = _check_encoding(image, None, context, colour="bgr")
    conversion = _FROM_BGR.get((encoding, original.strip()))
    if conversion is not None:
        return cv2.cvtColor(image, conversion), original.strip()
    return image, encoding


def _to_gray(image: np.ndarray, encoding: str) -> tuple[np.ndarray, str]:
    if encoding in ("mono8", "mono16"):
        return image, encoding
    return cv2.cvtColor(image, _TO_GRAY[encoding]), "mono8"
