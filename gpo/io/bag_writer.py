"""Write ROS1 and ROS2 bags: frames, cameras, trajectories and transforms (``BagWriter``), and a copy of a bag with
a trajectory added (``copy_with_trajectory``).

Formats
-------
``ros1`` (one ``.bag`` file), ``ros2`` and ``ros2-sqlite3`` (a rosbag2 folder, sqlite3 storage), ``ros2-mcap`` (a
rosbag2 folder, mcap storage), written with `rosbags <https://gitlab.com/ternaris/rosbags>`_; ``gpo.io.bag`` reads
them all back. The messages' types, image encodings and frame and camera conventions are in
``gpo.io.ros_messages``.

Time
----
Timestamps are integer nanoseconds since the Unix epoch at this boundary. ``BagWriter`` logs each message at its
header stamp. Messages may be added in any time order on any topic: all three storage formats index messages by
log time, so readers get them back sorted.
"""

from __future__ import annotations

import shutil
import sys
from collections import Counter
from pathlib import Path

import cv2
import numpy as np
from rosbags import rosbag1, rosbag2
from rosbags.interfaces import Qos, QosDurability, QosHistory, QosLiveliness, QosReliability, QosTime
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from gpo.cameras.files import Camera, camera_info_distortion
from gpo.io.bag import Recording
from gpo.io.ros_messages import (
    CAMERA_INFO,
    CODECS,
    COMPRESSED_IMAGE,
    IMAGE,
    ODOMETRY,
    POSE_STAMPED,
    TF_MESSAGE,
    TRANSFORM_STAMPED,
    check_encoding,
)
from gpo.io.trajectory import NS_PER_S, Trajectory

_TO_BGR = {"rgb8": (cv2.COLOR_RGB2BGR, "bgr8"), "rgba8": (cv2.COLOR_RGBA2BGRA, "bgra8")}

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


ROS2_FILE_SUFFIXES = (".db3", ".mcap")
"""The storage files inside a ROS2 bag's folder: a folder named so would read as one of them."""


def check_bag_name(path, format: str, option: str = "") -> Path:
    """``path`` checked to name a bag of ``format`` (``WRITE_FORMATS``): a ros1 bag is one file named *.bag, a ros2
    bag a folder named neither *.bag nor *.db3 or *.mcap; a ValueError naming ``path`` (after ``option``, e.g.
    "--out") otherwise."""
    path = Path(path)
    if format not in WRITE_FORMATS:
        raise ValueError(f"unknown bag format {format!r}: expected one of {', '.join(WRITE_FORMATS)}")
    if format == "ros1" and path.suffix != ".bag":
        raise ValueError(f"{option} {path}: a ros1 bag is one file named *.bag: name it {path.stem}.bag, say".lstrip())
    if format != "ros1" and path.suffix in (".bag", *ROS2_FILE_SUFFIXES):
        raise ValueError(
            f"{option} {path}: a {format} bag is a folder, named neither *.bag nor *.db3 or *.mcap (the storage file "
            f"inside it is): name it {path.stem}, say".lstrip()
        )
    return path


def check_new_bag(path, format: str, option: str) -> Path:
    """``path`` checked to name a new bag of ``format`` (``check_bag_name``) that is not there yet: a bag is never
    replaced; a ValueError naming ``option`` and ``path`` otherwise."""
    path = Path(path)
    if path.exists():
        raise ValueError(f"{option} {path} exists; name a new bag (a bag is never replaced)")
    return check_bag_name(path, format, option)


class BagWriter:
    """A new bag, open for writing; a context manager that finishes it.

    ``format``: ``ros1`` (``path`` a file named ``*.bag``), ``ros2`` (a folder, sqlite3 storage) or
    ``ros2-mcap`` (a folder, mcap storage). Raises FileExistsError when ``path`` exists. Every
    message is logged at its header stamp, in any order (see the module docstring); leaving the
    ``with`` block by an exception deletes the unfinished bag.
    """

    def __init__(self, path, format: str = "ros1"):
        self.path = Path(path)
        check_bag_name(self.path, format)
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
        encoding = check_encoding(image, encoding, f"{self.path}, topic {topic}")
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
        encoding = check_encoding(image, encoding, context)
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
            connection.topic, connection.msgtype, typestore=source.reader.typestore, **connection.ext._asdict()
        ) for connection in source.reader.connections
    }
    for connection, log_time, raw in source.raw_messages():
        writer._writer.write(copies[connection.id], log_time, raw)



def _check_stamp(stamp_ns) -> int:
    if not isinstance(stamp_ns, int | np.integer) or stamp_ns < 0:
        raise ValueError(f"stamps are non-negative integer nanoseconds, got {stamp_ns!r}")
    return int(stamp_ns)

