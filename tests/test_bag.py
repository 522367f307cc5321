"""Bags: round trips in ROS1, ROS2-sqlite3 and ROS2-mcap, topic discovery, tf, cameras, bad recordings.

Recordings that ``BagWriter`` would not make (unsupported encodings, header stamps apart from log
times, other drivers' camera models) are written with rosbags alone, so the reader is checked
against an independent writer too.
"""

import errno
import logging
import re
from contextlib import contextmanager
from pathlib import Path

import cv2
import numpy as np
import pytest
import yaml
from rosbags import rosbag1, rosbag2
from rosbags.highlevel import AnyReader
from rosbags.interfaces import QosDurability
from rosbags.typesys import Stores, get_typestore
from scipy.spatial.transform import Rotation

from gpo.cameras import KB4, T265_LIKE, DoubleSphere, Pinhole
from gpo.io.bag import Recording, StampWarning, describe
from gpo.io.bag_writer import BagWriter, copy_with_trajectory
from gpo.io.trajectory import Trajectory

FORMATS = ("ros1", "ros2", "ros2-mcap")
T0 = 1_700_000_000_123_456_789  # ns, a stamp whose every digit counts
PERIOD = 33_333_333  # ns, 30 Hz
CAMERA_FRAME = "t265_fisheye1_optical_frame"


def bag_path(folder: Path, bag_format: str, name: str = "recording") -> Path:
    return folder / (f"{name}.bag" if bag_format == "ros1" else name)


def storage_file(path: Path) -> Path:
    """The file holding the messages: the .bag itself, or the .db3/.mcap in a ROS2 folder."""
    return path if path.is_file() else next(p for p in path.iterdir() if p.suffix in (".db3", ".mcap"))


def random_image(rng, encoding: str, height: int = 24, width: int = 32) -> np.ndarray:
    dtype, channels = {
        "mono8": (np.uint8, 1),
        "mono16": (np.uint16, 1),
        "rgb8": (np.uint8, 3),
        "bgr8": (np.uint8, 3),
        "rgba8": (np.uint8, 4),
        "bgra8": (np.uint8, 4),
    }[encoding]
    shape = (height, width) if channels == 1 else (height, width, channels)
    return rng.integers(0, np.iinfo(dtype).max, shape, dtype=dtype, endpoint=True)


def smooth_rgb(height: int = 48, width: int = 64) -> np.ndarray:
    """A smooth colour image, which jpeg keeps close."""
    v, u = np.mgrid[0:height, 0:width]
    return np.stack([255 * u / width, 255 * v / height, 128 + 60 * np.sin(u / 9.0)], axis=-1).astype(np.uint8)


def raw_messages(path: Path) -> list[tuple[str, str, int, bytes]]:
    """(topic, type, log time, bytes) of every message, read with rosbags alone."""
    with AnyReader([path]) as reader:
        return [(c.topic, c.msgtype, t, bytes(raw)) for c, t, raw in reader.messages()]


@contextmanager
def rosbags_writer(path: Path, bag_format: str):
    """A bag written with rosbags alone (ROS1 Noetic, or ROS2 Humble types at metadata version 8).

    Yields the message types and ``write(topic, message, log_time_ns)``.
    """
    if bag_format == "ros1":
        typestore = get_typestore(Stores.ROS1_NOETIC)
        writer, serialize = rosbag1.Writer(path), typestore.serialize_ros1
    else:
        typestore = get_typestore(Stores.ROS2_HUMBLE)
        plugin = rosbag2.StoragePlugin.MCAP if bag_format == "ros2-mcap" else rosbag2.StoragePlugin.SQLITE3
        writer, serialize = rosbag2.Writer(path, version=8, storage_plugin=plugin), typestore.serialize_cdr
    connections = {}

    def write(topic, message, log_time_ns):
        if topic not in connections:
            connections[topic] = writer.add_connection(topic, message.__msgtype__, typestore=typestore)
        writer.write(connections[topic], log_time_ns, serialize(message, message.__msgtype__))

    with writer:
        yield typestore.types, write


def header(types, stamp_ns: int, frame_id: str):
    stamp = types["builtin_interfaces/msg/Time"](sec=stamp_ns // 10**9, nanosec=stamp_ns % 10**9)
    fields = {"seq": 0} if "seq" in types["std_msgs/msg/Header"].__dataclass_fields__ else {}
    return types["std_msgs/msg/Header"](stamp=stamp, frame_id=frame_id, **fields)


def raw_image_message(types, stamp_ns: int, encoding: str, data: np.ndarray, height: int, width: int):
    return types["sensor_msgs/msg/Image"](
        header=header(types, stamp_ns, CAMERA_FRAME),
        height=height,
        width=width,
        encoding=encoding,
        is_bigendian=0,
        step=data.size // height,
        data=data,
    )


# --- images ---------------------------------------------------------------------------------------


@pytest.mark.parametrize("bag_format", FORMATS)
@pytest.mark.parametrize("encoding", ["mono8", "mono16", "rgb8", "bgr8", "rgba8", "bgra8"])
def test_raw_images_round_trip_bit_exact(tmp_path, bag_format, encoding):
    rng = np.random.default_rng(0)
    images = [random_image(rng, encoding) for _ in range(3)]
    stamps = [T0 + i * PERIOD for i in range(3)]
    path = bag_path(tmp_path, bag_format)
    with BagWriter(path, bag_format) as writer:
        for stamp, image in zip(stamps, images, strict=True):
            writer.add_image("/camera/image_raw", stamp, image, CAMERA_FRAME, encoding=encoding)

    with Recording(path) as recording:
        frames = list(recording.frames("/camera/image_raw", progress=False))
    assert [f.stamp_ns for f in frames] == stamps
    assert {(f.frame_id, f.encoding) for f in frames} == {(CAMERA_FRAME, encoding)}
    for frame, image in zip(frames, images, strict=True):
        assert frame.image.dtype == image.dtype
        np.testing.assert_array_equal(frame.image, image)


def test_encoding_is_inferred_from_dtype_and_shape(tmp_path):
    rng = np.random.default_rng(0)
    images = {name: random_image(rng, name) for name in ("mono8", "mono16", "rgb8", "rgba8")}
    path = bag_path(tmp_path, "ros1")
    with BagWriter(path) as writer:
        for name, image in images.items():
            writer.add_image(f"/{name}", T0, image, CAMERA_FRAME)
    with Recording(path) as recording:
        for name, image in images.items():
            (frame,) = recording.frames(f"/{name}", progress=False)
            assert frame.encoding == name
            np.testing.assert_array_equal(frame.image, image)


@pytest.mark.parametrize("encoding", ["rgb8", "bgr8", "rgba8", "bgra8"])
def test_gray_frames_weigh_the_channels_as_luma(tmp_path, encoding):
    image = random_image(np.random.default_rng(0), encoding)
    red, green, blue = (image[..., encoding.index(c)].astype(float) for c in "rgb")
    luma = 0.299 * red + 0.587 * green + 0.114 * blue
    path = bag_path(tmp_path, "ros1")
    with BagWriter(path) as writer:
        writer.add_image("/camera", T0, image, CAMERA_FRAME, encoding=encoding)
    with Recording(path) as recording:
        (frame,) = recording.frames(gray=True, progress=False)
    assert frame.encoding == "mono8"
    assert frame.image.dtype == np.uint8
    # rounded to whole grey levels (0.5), OpenCV's weights in fixed point (measured 0.503 at most)
    np.testing.assert_allclose(frame.image, luma, atol=0.51)


def test_gray_keeps_mono16(tmp_path):
    image = random_image(np.random.default_rng(0), "mono16")
    path = bag_path(tmp_path, "ros1")
    with BagWriter(path) as writer:
        writer.add_image("/camera", T0, image, CAMERA_FRAME)
    with Recording(path) as recording:
        (frame,) = recording.frames(gray=True, progress=False)
    assert frame.encoding == "mono16"
    np.testing.assert_array_equal(frame.image, image)


@pytest.mark.parametrize("bag_format", FORMATS)
@pytest.mark.parametrize("encoding", ["mono8", "mono16", "rgb8", "bgr8", "bgra8"])
def test_png_round_trip_is_exact(tmp_path, bag_format, encoding):
    image = random_image(np.random.default_rng(0), encoding)
    path = bag_path(tmp_path, bag_format)
    with BagWriter(path, bag_format) as writer:
        writer.add_compressed_image("/camera/compressed", T0, image, CAMERA_FRAME, format="png", encoding=encoding)
    with Recording(path) as recording:
        (frame,) = recording.frames(progress=False)
    assert (frame.stamp_ns, frame.frame_id, frame.encoding) == (T0, CAMERA_FRAME, encoding)
    assert frame.image.dtype == image.dtype
    np.testing.assert_array_equal(frame.image, image)


@pytest.mark.parametrize("bag_format", FORMATS)
def test_jpeg_round_trip_is_close_and_keeps_the_channel_order(tmp_path, bag_format):
    image = smooth_rgb()
    path = bag_path(tmp_path, bag_format)
    with BagWriter(path, bag_format) as writer:
        writer.add_compressed_image("/rgb", T0, image, CAMERA_FRAME, format="jpeg", jpeg_quality=95)
        writer.add_compressed_image("/mono", T0, image[..., 1], CAMERA_FRAME, format="jpeg")
    with Recording(path) as recording:
        (colour,) = recording.frames("/rgb", progress=False)
        (mono,) = recording.frames("/mono", progress=False)
    assert (colour.encoding, mono.encoding) == ("rgb8", "mono8")
    for frame, original in ((colour, image), (mono, image[..., 1])):
        # what OpenCV's own codec gives at quality 95, pixel for pixel (its colour images are blue-green-red)
        coded = cv2.imencode(
            ".jpg", original[..., ::-1] if original.ndim == 3 else original, [cv2.IMWRITE_JPEG_QUALITY, 95]
        )[1]
        decoded = cv2.imdecode(coded, cv2.IMREAD_UNCHANGED)
        np.testing.assert_array_equal(frame.image, decoded[..., ::-1] if decoded.ndim == 3 else decoded)
        error = np.abs(frame.image.astype(int) - original)
        assert error.mean() < 1.5 and error.max() <= 10  # measured 0.71 and 5 (colour), 0.04 and 1 (mono)


def test_compressed_image_of_an_older_driver_comes_back_as_bgr(tmp_path):
    """A CompressedImage whose format is just "jpeg": coded by OpenCV, so blue-green-red."""
    bgr = smooth_rgb()[..., ::-1]
    path = bag_path(tmp_path, "ros1")
    with rosbags_writer(path, "ros1") as (types, write):
        data = cv2.imencode(".jpg", bgr, [cv2.IMWRITE_JPEG_QUALITY, 95])[1].reshape(-1)
        message = types["sensor_msgs/msg/CompressedImage"](
            header=header(types, T0, CAMERA_FRAME), format="jpeg", data=data
        )
        write("/camera/compressed", message, T0)
    with Recording(path) as recording:
        (frame,) = recording.frames(progress=False)
    assert frame.encoding == "bgr8"
    np.testing.assert_array_equal(frame.image, cv2.imdecode(data, cv2.IMREAD_COLOR))  # as written, channel for channel
    assert np.abs(frame.image.astype(int) - bgr).mean() < 1.5  # measured 0.71


def test_padded_rows_are_read_by_their_step(tmp_path):
    """Some cameras pad each row; ``step`` says how many bytes a row takes."""
    image = random_image(np.random.default_rng(0), "mono8", height=5, width=6)
    padded = np.zeros((5, 8), np.uint8)
    padded[:, :6] = image
    path = bag_path(tmp_path, "ros2")
    with rosbags_writer(path, "ros2") as (types, write):
        write("/camera", raw_image_message(types, T0, "mono8", padded.reshape(-1), 5, 6), T0)
    with Recording(path) as recording:
        (frame,) = recording.frames(progress=False)
    np.testing.assert_array_equal(frame.image, image)


def test_time_range_selects_by_header_stamp(tmp_path):
    """Log times lag the header stamps by a second here: the range must use the stamps."""
    stamps = [T0 + i * PERIOD for i in range(8)]
    path = bag_path(tmp_path, "ros1")
    with rosbags_writer(path, "ros1") as (types, write):
        for i, stamp in enumerate(stamps):
            data = np.full(6, i, np.uint8)
            write("/camera", raw_image_message(types, stamp, "mono8", data, 2, 3), stamp + 10**9)
    with Recording(path) as recording:
        frames = list(recording.frames(start_ns=stamps[2], end_ns=stamps[5], progress=False))
    assert [f.stamp_ns for f in frames] == stamps[2:5]  # start inclusive, end exclusive
    assert [int(f.image[0, 0]) for f in frames] == [2, 3, 4]


def test_frames_stream_one_message_at_a_time(tmp_path):
    path = bag_path(tmp_path, "ros1")
    with BagWriter(path) as writer:
        for i in range(5):
            writer.add_image("/camera", T0 + i * PERIOD, np.full((4, 4), i, np.uint8), CAMERA_FRAME)
    with Recording(path) as recording:
        frames = recording.frames(progress=False)
        assert next(frames).stamp_ns == T0
        assert next(frames).stamp_ns == T0 + PERIOD


def test_progress_bar_counts_the_topic_messages(tmp_path, capsys):
    path = bag_path(tmp_path, "ros1")
    with BagWriter(path) as writer:
        for i in range(3):
            writer.add_image("/camera", T0 + i * PERIOD, np.zeros((2, 2), np.uint8), CAMERA_FRAME)
    with Recording(path) as recording:
        assert len(list(recording.frames())) == 3
        progress = capsys.readouterr().err
        assert "/camera" in progress
        assert "3/3" in progress
        assert len(list(recording.frames(progress=False))) == 3
        assert capsys.readouterr().err == ""


@pytest.mark.parametrize("bag_format", FORMATS)
def test_messages_may_be_added_in_any_time_order(tmp_path, bag_format):
    path = bag_path(tmp_path, bag_format)
    with BagWriter(path, bag_format) as writer:
        for stamp, value in ((T0 + 3, 3), (T0 + 1, 1), (T0 + 2, 2)):
            writer.add_image("/camera", stamp, np.full((2, 2), value, np.uint8), CAMERA_FRAME)
        writer.add_odometry("/odom", T0, [0, 0, 0], [0, 0, 0, 1], "odom", "base_link")
    assert [t for _, _, t, _ in raw_messages(path)] == [T0, T0 + 1, T0 + 2, T0 + 3]
    with Recording(path) as recording:
        assert [int(f.image[0, 0]) for f in recording.frames(progress=False)] == [1, 2, 3]


# --- trajectories, tf, cameras --------------------------------------------------------------------


def random_trajectory(n: int = 20, child_frame_id: str = "base_link") -> Trajectory:
    rng = np.random.default_rng(0)
    stamps = T0 + np.cumsum(rng.integers(1, 10**8, n))
    return Trajectory(stamps, rng.normal(size=(n, 3)), Rotation.random(n, rng=1).as_quat(), "odom", child_frame_id)


@pytest.mark.parametrize("bag_format", FORMATS)
@pytest.mark.parametrize("msgtype", ["odometry", "pose"])
def test_trajectory_round_trip(tmp_path, bag_format, msgtype):
    trajectory = random_trajectory()
    path = bag_path(tmp_path, bag_format)
    with BagWriter(path, bag_format) as writer:
        writer.add_trajectory("/odom", trajectory, msgtype=msgtype)
    with Recording(path) as recording:
        again = recording.trajectory("/odom")
        frames = recording.pose_frames("/odom")
    assert frames == (again.frame_id, again.child_frame_id)
    np.testing.assert_array_equal(again.stamps_ns, trajectory.stamps_ns)
    np.testing.assert_array_equal(again.positions, trajectory.positions)
    np.testing.assert_array_equal(again.quaternions, trajectory.quaternions)
    assert (again.frame_id, again.child_frame_id) == ("odom", "base_link")


def test_pose_stamped_names_no_child_frame(tmp_path):
    path = bag_path(tmp_path, "ros1")
    with BagWriter(path) as writer:
        writer.add_trajectory("/pose", random_trajectory(child_frame_id="camera"), msgtype="pose")
    with Recording(path) as recording:
        assert recording.trajectory("/pose").child_frame_id == "base_link"
        assert recording.pose_frames("/pose") == ("odom", "base_link")


def test_odometry_twist_is_written_in_the_child_frame(tmp_path):
    path = bag_path(tmp_path, "ros2")
    with BagWriter(path, "ros2") as writer:
        writer.add_odometry("/odom", T0, [1, 2, 3], [0, 0, 0, 1], "odom", "base_link", [0.5, 0, 0], [0, 0, 0.25])
    with AnyReader([path]) as reader:
        ((connection, _, raw),) = reader.messages()
        message = reader.deserialize(raw, connection.msgtype)
    assert message.child_frame_id == "base_link"
    assert (message.twist.twist.linear.x, message.twist.twist.angular.z) == (0.5, 0.25)


@pytest.mark.parametrize("bag_format", FORMATS)
def test_transform_stamped_topic_reads_as_a_trajectory(tmp_path, bag_format):
    path = bag_path(tmp_path, bag_format)
    with rosbags_writer(path, bag_format) as (types, write):
        for i in range(3):
            transform = types["geometry_msgs/msg/Transform"](
                translation=types["geometry_msgs/msg/Vector3"](x=float(i), y=0.0, z=0.0),
                rotation=types["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0),
            )
            message = types["geometry_msgs/msg/TransformStamped"](
                header=header(types, T0 + i, "world"), child_frame_id="vicon/robot", transform=transform
            )
            write("/vicon/robot", message, T0 + i)
    with Recording(path) as recording:
        trajectory = recording.trajectory("/vicon/robot")
        assert recording.pose_frames("/vicon/robot") == ("world", "vicon/robot")
    assert (trajectory.frame_id, trajectory.child_frame_id) == ("world", "vicon/robot")
    np.testing.assert_array_equal(trajectory.positions[:, 0], [0.0, 1.0, 2.0])


@pytest.mark.parametrize("bag_format", FORMATS)
def test_tf_and_tf_static(tmp_path, bag_format):
    path = bag_path(tmp_path, bag_format)
    with BagWriter(path, bag_format) as writer:
        for i in range(4):
            writer.add_transform("odom", "base_link", [i, 0, 0], [0, 0, 0, 1], T0 + i * PERIOD)
            writer.add_transform("map", "odom", [0, i, 0], [0, 0, 0, 1], T0 + i * PERIOD)
        writer.add_static_transform("base_link", "camera", [9, 9, 9], [0, 0, 0, 1], T0)
        writer.add_static_transform("base_link", "imu", [0.1, 0, 0.05], [0, 0, 0, 1], T0)
        writer.add_static_transform("base_link", "camera", [0.3, 0, 0.12], [0, 0.7071, 0, 0.7071], T0)

    with Recording(path) as recording:
        odom = recording.transform("odom", "/base_link")  # a leading "/" as ROS1 allowed
        translation, quaternion = recording.static_transform("base_link", "camera")
        tree = recording.static_transforms()
        with pytest.raises(ValueError, match="no transform base_link -> odom; it has map -> odom, odom -> base_link"):
            recording.transform("base_link", "odom")
        with pytest.raises(ValueError, match="base_link -> camera, base_link -> imu"):
            recording.static_transform("base_link", "lidar")
    np.testing.assert_array_equal(odom.stamps_ns, [T0 + i * PERIOD for i in range(4)])
    np.testing.assert_array_equal(odom.positions[:, 0], [0, 1, 2, 3])
    assert (odom.frame_id, odom.child_frame_id) == ("odom", "base_link")
    np.testing.assert_array_equal(translation, [0.3, 0, 0.12])  # the last one recorded
    assert {child: parent for child, (parent, _, _) in tree.items()} == {"camera": "base_link", "imu": "base_link"}
    np.testing.assert_array_equal(tree["imu"][1], [0.1, 0, 0.05])
    np.testing.assert_array_equal(tree["camera"][1], translation)  # the last one recorded, as static_transform's
    np.testing.assert_array_equal(tree["camera"][2], [0, 0.7071, 0, 0.7071])
    np.testing.assert_array_equal(quaternion, [0, 0.7071, 0, 0.7071])


@pytest.mark.parametrize("bag_format", FORMATS)
def test_tf_static_is_latched(tmp_path, bag_format):
    path = bag_path(tmp_path, bag_format)
    with BagWriter(path, bag_format) as writer:
        writer.add_static_transform("base_link", "camera", [0, 0, 0], [0, 0, 0, 1], T0)
        writer.add_transform("odom", "base_link", [0, 0, 0], [0, 0, 0, 1], T0)
    with AnyReader([path]) as reader:
        ext = {c.topic: c.ext for c in reader.connections}
    if bag_format == "ros1":
        assert (ext["/tf_static"].latching, ext["/tf"].latching) == (1, 0)
    else:
        assert [q.durability for q in ext["/tf_static"].offered_qos_profiles] == [QosDurability.TRANSIENT_LOCAL]
        assert ext["/tf"].offered_qos_profiles == []


@pytest.mark.parametrize("bag_format", FORMATS)
@pytest.mark.parametrize(
    "camera",
    [
        T265_LIKE,
        Pinhole(fx=600.0, fy=601.0, cx=376.0, cy=240.0, dist=(-0.28, 0.09, 1e-3, -8e-4), width=752, height=480),
        Pinhole(fx=600.0, fy=601.0, cx=376.5, cy=240.5, dist=(-0.28, 0.09, 1e-3, -8e-4, 0.01), width=752, height=480),
        KB4(286.6, 286.5, 422.3, 395.2, k1=-0.0068, k2=0.045, k3=-0.0435, k4=0.0084, width=848, height=800),
        DoubleSphere(158.3, 158.27, 254.96, 256.89, xi=-0.172, alpha=0.593, width=512, height=512),
    ],
    ids=["eucm", "pinhole4", "pinhole5", "kb4", "ds"],
)
def test_camera_info_round_trip(tmp_path, bag_format, camera):
    path = bag_path(tmp_path, bag_format)
    with BagWriter(path, bag_format) as writer:
        writer.add_camera_info("/camera/camera_info", T0, camera, CAMERA_FRAME)
    with Recording(path) as recording:
        assert recording.camera_info("/camera/camera_info") == camera


def write_camera_info(path: Path, model: str, d: list[float]) -> None:
    with rosbags_writer(path, "ros1") as (types, write):
        message = types["sensor_msgs/msg/CameraInfo"](
            header=header(types, T0, CAMERA_FRAME),
            height=480,
            width=640,
            distortion_model=model,
            D=np.array(d),
            K=np.array([500.0, 0, 320, 0, 501, 240, 0, 0, 1]),
            R=np.eye(3).reshape(-1),
            P=np.array([500.0, 0, 320, 0, 0, 501, 240, 0, 0, 0, 1, 0]),
            binning_x=0,
            binning_y=0,
            roi=types["sensor_msgs/msg/RegionOfInterest"](x_offset=0, y_offset=0, height=0, width=0, do_rectify=False),
        )
        write("/camera_info", message, T0)


def test_camera_info_of_other_drivers(tmp_path):
    write_camera_info(tmp_path / "rational.bag", "rational_polynomial", [0.1, 0.01, 0.001, 0.002, 0.0001, 0, 0, 0])
    write_camera_info(tmp_path / "rectified.bag", "plumb_bob", [])
    with Recording(tmp_path / "rational.bag") as recording:
        assert recording.camera_info("/camera_info") == Pinhole(
            500.0, 501.0, 320.0, 240.0, (0.1, 0.01, 0.001, 0.002, 0.0001), 640, 480
        )
    with Recording(tmp_path / "rectified.bag") as recording:
        assert recording.camera_info("/camera_info").dist == (0.0,) * 5


def test_camera_info_of_realsense_ros_t265_is_kannala_brandt(tmp_path):
    # realsense-ros writes a T265 fisheye's factory calibration as "equidistant" with a fifth, zero coefficient
    write_camera_info(tmp_path / "t265.bag", "equidistant", [-0.0068, 0.045, -0.0435, 0.0084, 0.0])
    with Recording(tmp_path / "t265.bag") as recording:
        assert recording.camera_info("/camera_info") == KB4(
            500.0, 501.0, 320.0, 240.0, -0.0068, 0.045, -0.0435, 0.0084, 640, 480
        )


@pytest.mark.parametrize(
    ("model", "d"),
    [("equidistant", [0.1, 0.01, 0.001]), ("fov", [0.9]), ("rational_polynomial", [0.1, 0.01, 0, 0, 0, 0.2, 0, 0])],
)
def test_camera_info_of_unsupported_models_is_refused(tmp_path, model, d):
    write_camera_info(tmp_path / "camera.bag", model, d)
    with Recording(tmp_path / "camera.bag") as recording, pytest.raises(ValueError, match=f"{model}.*plumb_bob"):
        recording.camera_info("/camera_info")


# --- topics ---------------------------------------------------------------------------------------


def write_topics(path: Path, image_topics: list[str]) -> None:
    with BagWriter(path) as writer:
        for topic in image_topics:
            writer.add_image(topic, T0, np.zeros((2, 2), np.uint8), CAMERA_FRAME)
        writer.add_odometry("/odom", T0, [0, 0, 0], [0, 0, 0, 1], "odom", "base_link")


def test_the_only_image_topic_is_picked_and_logged(tmp_path, caplog):
    path = tmp_path / "one.bag"
    write_topics(path, ["/camera/fisheye1/image_raw"])
    with Recording(path) as recording, caplog.at_level(logging.INFO, logger="gpo.io.bag"):
        assert recording.image_topic() == "/camera/fisheye1/image_raw"
        assert len(list(recording.frames(progress=False))) == 1
    assert "/camera/fisheye1/image_raw" in caplog.text
    assert {record.name for record in caplog.records} == {"gpo.io.bag"}


def test_two_image_topics_must_be_told_apart(tmp_path):
    path = tmp_path / "two.bag"
    write_topics(path, ["/camera/fisheye1/image_raw", "/camera/fisheye2/image_raw"])
    with Recording(path) as recording:
        with pytest.raises(ValueError, match="2 image topics") as error:
            recording.image_topic()
        assert recording.image_topic("/camera/fisheye2/image_raw") == "/camera/fisheye2/image_raw"
    message = str(error.value)
    assert "/camera/fisheye1/image_raw" in message
    assert "/camera/fisheye2/image_raw" in message
    assert "(--topic)" in message


def test_a_misspelled_topic_names_the_close_match_and_every_topic(tmp_path):
    path = tmp_path / "one.bag"
    write_topics(path, ["/camera/fisheye1/image_raw"])
    with Recording(path) as recording, pytest.raises(ValueError) as error:
        recording.frames("/camera/fisheye1/image_rwa")  # checked at the call, before any reading
    message = str(error.value)
    assert str(path) in message
    assert "/camera/fisheye1/image_rwa" in message
    assert "did you mean /camera/fisheye1/image_raw?" in message
    assert "/odom (nav_msgs/msg/Odometry)" in message
    assert "/camera/fisheye1/image_raw (sensor_msgs/msg/Image)" in message


def test_a_topic_of_the_wrong_type_names_the_types_expected(tmp_path):
    path = tmp_path / "one.bag"
    write_topics(path, ["/camera/image_raw"])
    with Recording(path) as recording:
        with pytest.raises(ValueError, match="carries sensor_msgs/msg/Image; expected one of: nav_msgs/msg/Odometry"):
            recording.trajectory("/camera/image_raw")
        with pytest.raises(ValueError, match="expected one of: sensor_msgs/msg/Image"):
            recording.frames("/odom")


def test_no_image_topic(tmp_path):
    path = tmp_path / "none.bag"
    write_topics(path, [])
    with Recording(path) as recording, pytest.raises(ValueError, match=r"no image topic.*/odom"):
        recording.image_topic()


def test_topics_and_times(tmp_path):
    path = tmp_path / "two.bag"
    with BagWriter(path) as writer:
        for i in range(3):
            writer.add_image("/camera", T0 + i * PERIOD, np.zeros((2, 2), np.uint8), CAMERA_FRAME)
        writer.add_odometry("/odom", T0 + PERIOD, [0, 0, 0], [0, 0, 0, 1], "odom", "base_link")
    with Recording(path) as recording:
        assert [(t.name, t.msgtype, t.count) for t in recording.topics()] == [
            ("/camera", "sensor_msgs/msg/Image", 3),
            ("/odom", "nav_msgs/msg/Odometry", 1),
        ]
        assert (recording.start_ns, recording.end_ns) == (T0, T0 + 2 * PERIOD)
        assert recording.duration_s == pytest.approx(2 * PERIOD / 1e9)
        assert recording.format == "ros1"


@pytest.mark.parametrize(("bag_format", "suffix"), [("ros2", ".db3"), ("ros2-mcap", ".mcap")])
def test_a_ros2_storage_file_opens_its_folder(tmp_path, bag_format, suffix):
    path = bag_path(tmp_path, bag_format)
    with BagWriter(path, bag_format) as writer:
        writer.add_image("/camera", T0, np.zeros((2, 2), np.uint8), CAMERA_FRAME)
    with Recording(path / f"{path.name}{suffix}") as recording:
        assert recording.format == {"ros2": "ros2-sqlite3"}.get(bag_format, bag_format)
        assert [t.name for t in recording.topics()] == ["/camera"]


def test_describe(tmp_path):
    path = bag_path(tmp_path, "ros2-mcap")
    with BagWriter(path, "ros2-mcap") as writer:
        for i in range(11):
            writer.add_image("/camera/image_raw", T0 + i * 10**8, np.zeros((24, 32), np.uint8), CAMERA_FRAME)
        writer.add_compressed_image("/camera/compressed", T0, np.zeros((24, 32, 3), np.uint8), CAMERA_FRAME)
    lines = describe(path).splitlines()
    assert lines[:4] == [
        f"path:     {path}",
        "format:   ros2-mcap",
        "duration: 1.000 s",
        "start:    2023-11-14 22:13:20.123456789 UTC (1700000000123456789 ns)",
    ]
    rows = {line.split()[0]: line.split() for line in lines[5:]}
    assert rows["/camera/image_raw"] == ["/camera/image_raw", "sensor_msgs/msg/Image", "11", "10.0", "32x24", "mono8"]
    assert rows["/camera/compressed"][1:5] == ["sensor_msgs/msg/CompressedImage", "1", "-", "32x24"]
    assert "rgb8; png compressed bgr8" in lines[5 + list(rows).index("/camera/compressed")]


# --- bad recordings -------------------------------------------------------------------------------


@pytest.mark.parametrize("bag_format", FORMATS)
def test_a_truncated_recording_is_refused_with_its_path(tmp_path, bag_format):
    path = bag_path(tmp_path, bag_format)
    with BagWriter(path, bag_format) as writer:
        for i in range(20):
            writer.add_image("/camera", T0 + i * PERIOD, np.full((64, 64), i, np.uint8), CAMERA_FRAME)
    storage = storage_file(path)
    storage.write_bytes(storage.read_bytes()[: storage.stat().st_size // 2])
    with pytest.raises(ValueError, match="is not a readable") as error:
        Recording(path)
    assert str(path) in str(error.value)
    assert isinstance(error.value.__cause__, Exception)


@pytest.mark.parametrize("bag_format", FORMATS)
def test_an_os_error_of_reading_the_messages_names_the_bag(tmp_path, monkeypatch, bag_format):
    """A damaged offset can send the reader's seek past what the file system allows (the fuzzing campaign: an MCAP
    chunk index's offset, OSError EINVAL): the bag is named, as for any other damage, after the frames before it."""
    path = bag_path(tmp_path, bag_format)
    with BagWriter(path, bag_format) as writer:
        for i in range(3):
            writer.add_image("/camera", T0 + i * PERIOD, np.full((64, 64), i, np.uint8), CAMERA_FRAME)
    with Recording(path) as bag:
        messages = bag.reader.messages

        def seek_refused(*args, **kwargs):
            yield next(iter(messages(*args, **kwargs)))
            raise OSError(errno.EINVAL, "Invalid argument")

        monkeypatch.setattr(bag.reader, "messages", seek_refused)
        frames = bag.frames("/camera", progress=False)
        assert next(frames).image[0, 0] == 0
        with pytest.raises(
            ValueError, match=rf"^{re.escape(str(path))} is damaged or cannot be read: Invalid argument"
        ):
            next(frames)


@pytest.mark.parametrize("count", ["many", [1, 2], None])
def test_a_ros2_bag_whose_metadata_counts_its_messages_in_words_is_named(tmp_path, count):
    """A damaged metadata.yaml whose message_count is no number (the campaign, seeds 48101-48303)."""
    path = bag_path(tmp_path, "ros2")
    with BagWriter(path, "ros2") as writer:
        writer.add_image("/camera", T0, np.zeros((64, 64), np.uint8), CAMERA_FRAME)
    metadata = yaml.safe_load((path / "metadata.yaml").read_text())
    metadata["rosbag2_bagfile_information"]["message_count"] = count
    (path / "metadata.yaml").write_text(yaml.safe_dump(metadata))
    with pytest.raises(ValueError, match=rf"^{re.escape(str(path))} is damaged: it counts {re.escape(repr(count))} "):
        Recording(path)


@pytest.mark.parametrize(("whole", "each"), [(-3, None), (2, -1)])
def test_a_ros2_bag_whose_metadata_counts_fewer_than_no_messages_is_named(tmp_path, whole, each):
    """A damaged metadata.yaml whose message_count, or a topic's, is below zero: a count is a whole number from 0
    (``gpo info`` listed the topics with -1 messages at -5.5 Hz)."""
    path = bag_path(tmp_path, "ros2")
    with BagWriter(path, "ros2") as writer:
        writer.add_image("/camera", T0, np.zeros((64, 64), np.uint8), CAMERA_FRAME)
        writer.add_image("/camera", T0 + 10**8, np.zeros((64, 64), np.uint8), CAMERA_FRAME)
    metadata = yaml.safe_load((path / "metadata.yaml").read_text())
    information = metadata["rosbag2_bagfile_information"]
    information["message_count"] = whole
    for topic in information["topics_with_message_count"] if each is not None else ():
        topic["message_count"] = each
    (path / "metadata.yaml").write_text(yaml.safe_dump(metadata))
    said = (
        f"it counts {whole} messages"
        if each is None
        else f"a topic '/camera' of type 'sensor_msgs/msg/Image' with {each}"
    )
    with pytest.raises(ValueError, match=rf"^{re.escape(str(path))} is damaged: {re.escape(said)}.*from 0"):
        Recording(path)


@pytest.mark.parametrize("bag_format", ["ros2", "ros2-mcap"])
def test_a_bag_whose_metadata_names_its_files_in_a_word_is_read_and_closed(tmp_path, bag_format):
    """A damaged metadata.yaml whose ``files`` is text (the campaign, seeds 48101-48303): rosbags reads the bag by its
    storage files and then fails to close it; what was read stands, and the bag is closed."""
    path = bag_path(tmp_path, bag_format)
    with BagWriter(path, bag_format) as writer:
        writer.add_image("/camera", T0, np.full((64, 64), 7, np.uint8), CAMERA_FRAME)
    metadata = yaml.safe_load((path / "metadata.yaml").read_text())
    metadata["rosbag2_bagfile_information"]["files"] = "many"
    (path / "metadata.yaml").write_text(yaml.safe_dump(metadata))
    with Recording(path) as bag:
        [frame] = bag.frames("/camera", progress=False)
    assert frame.image[0, 0] == 7


def test_an_os_error_of_opening_a_bag_names_it(tmp_path, monkeypatch):
    """A ROS 1 bag's chunk position damaged, sought past what the file system allows (the campaign, seed 48101)."""
    path = bag_path(tmp_path, "ros1")
    with BagWriter(path, "ros1") as writer:
        writer.add_image("/camera", T0, np.zeros((64, 64), np.uint8), CAMERA_FRAME)

    def seek_refused(self):
        raise OSError(errno.EINVAL, "Invalid argument")

    monkeypatch.setattr(AnyReader, "open", seek_refused)
    with pytest.raises(ValueError, match=rf"^{re.escape(str(path))} is not a readable ros1 recording \(Invalid arg"):
        Recording(path)


@pytest.mark.parametrize("bag_format", FORMATS)
def test_an_empty_recording_is_refused(tmp_path, bag_format):
    path = bag_path(tmp_path, bag_format)
    with BagWriter(path, bag_format):
        pass
    with pytest.raises(ValueError, match=re.escape(f"{path} holds no messages")):
        Recording(path)


def test_missing_and_unreadable_paths(tmp_path):
    with pytest.raises(FileNotFoundError, match=r"no recording at .*missing\.bag"):
        Recording(tmp_path / "missing.bag")
    (tmp_path / "folder").mkdir()
    with pytest.raises(FileNotFoundError, match=r"without metadata\.yaml"):
        Recording(tmp_path / "folder")
    (tmp_path / "notes.txt").write_text("not a bag")
    with pytest.raises(ValueError, match=r"notes\.txt is not a recording"):
        Recording(tmp_path / "notes.txt")
    (tmp_path / "text.bag").write_text("not a bag either")
    with pytest.raises(ValueError, match=r"text\.bag is not a readable ros1 recording"):
        Recording(tmp_path / "text.bag")


@pytest.mark.parametrize("bag_format", FORMATS)
def test_an_unsupported_encoding_names_topic_encoding_and_the_supported_ones(tmp_path, bag_format):
    path = bag_path(tmp_path, bag_format)
    with rosbags_writer(path, bag_format) as (types, write):
        depth = np.ones((2, 3), np.float32).view(np.uint8).reshape(-1)
        write("/camera/depth", raw_image_message(types, T0, "32FC1", depth, 2, 3), T0)
    with Recording(path) as recording, pytest.raises(ValueError) as error:
        next(recording.frames(progress=False))
    message = str(error.value)
    for part in (str(path), "/camera/depth", "'32FC1'", "mono8, mono16, rgb8, bgr8"):
        assert part in message


def test_compressed_depth_is_refused(tmp_path):
    path = bag_path(tmp_path, "ros1")
    with rosbags_writer(path, "ros1") as (types, write):
        message = types["sensor_msgs/msg/CompressedImage"](
            header=header(types, T0, CAMERA_FRAME), format="16UC1; compressedDepth png", data=np.zeros(20, np.uint8)
        )
        write("/camera/depth/compressedDepth", message, T0)
    with Recording(path) as recording, pytest.raises(ValueError, match=r"compressedDepth.*supported: jpeg, png"):
        next(recording.frames(progress=False))


def write_disordered_stamps(path: Path) -> list[int]:
    """Header stamps 0, 20, 10, 10, 30 ms after T0, logged in that order; message i holds the value i."""
    stamps = [T0 + ms * 10**6 for ms in (0, 20, 10, 10, 30)]
    with rosbags_writer(path, "ros1") as (types, write):
        for i, stamp in enumerate(stamps):
            write("/camera", raw_image_message(types, stamp, "mono8", np.full(4, i, np.uint8), 2, 2), T0 + i)
            pose = types["geometry_msgs/msg/Pose"](
                position=types["geometry_msgs/msg/Point"](x=float(i), y=0.0, z=0.0),
                orientation=types["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0),
            )
            write(
                "/pose", types["geometry_msgs/msg/PoseStamped"](header=header(types, stamp, "odom"), pose=pose), T0 + i
            )
    return stamps


def test_frames_with_disordered_stamps_warn_and_keep_bag_order(tmp_path):
    path = tmp_path / "disordered.bag"
    stamps = write_disordered_stamps(path)
    with Recording(path) as recording, pytest.warns(StampWarning) as caught:
        frames = list(recording.frames(progress=False))
    assert [f.stamp_ns for f in frames] == stamps
    assert [int(f.image[0, 0]) for f in frames] == [0, 1, 2, 3, 4]
    messages = [str(w.message) for w in caught]
    assert len(messages) == 2
    assert "/camera: header stamp goes backwards at message 2" in messages[0]
    assert "/camera: header stamp repeats at message 3" in messages[1]


def test_trajectory_with_disordered_stamps_is_sorted_and_keeps_the_first_of_a_stamp(tmp_path):
    path = tmp_path / "disordered.bag"
    stamps = write_disordered_stamps(path)
    with Recording(path) as recording, pytest.warns(StampWarning) as caught:
        trajectory = recording.trajectory("/pose")
    np.testing.assert_array_equal(trajectory.stamps_ns, sorted(set(stamps)))
    np.testing.assert_array_equal(trajectory.positions[:, 0], [0, 2, 1, 4])
    messages = [str(w.message) for w in caught]
    assert len(messages) == 2
    assert "/pose: header stamps go backwards 1 times, first at message 2" in messages[0]
    assert "/pose: 1 poses repeat an earlier header stamp, first at message 3" in messages[1]


# --- writing --------------------------------------------------------------------------------------


@pytest.mark.parametrize("bag_format", FORMATS)
def test_copy_with_trajectory_keeps_every_message_and_adds_the_trajectory(tmp_path, bag_format):
    rng = np.random.default_rng(0)
    source = bag_path(tmp_path, bag_format, "source")
    with BagWriter(source, bag_format) as writer:
        for i in range(5):
            writer.add_image("/camera", T0 + i * PERIOD, random_image(rng, "mono8"), CAMERA_FRAME)
            writer.add_transform("odom", "base_link", rng.normal(size=3), [0, 0, 0, 1], T0 + i * PERIOD)
        writer.add_camera_info("/camera_info", T0, T265_LIKE, CAMERA_FRAME)
        writer.add_static_transform("base_link", "camera", [0.3, 0, 0.1], [0, 0, 0, 1], T0)
    trajectory = random_trajectory()

    copy = copy_with_trajectory(source, bag_path(tmp_path, bag_format, "copy"), trajectory)

    copied = raw_messages(copy)
    assert [m for m in copied if m[0] != "/gpo/odom"] == raw_messages(source)
    assert sum(m[0] == "/gpo/odom" for m in copied) == len(trajectory)
    with Recording(copy) as recording:
        assert recording.format == {"ros2": "ros2-sqlite3"}.get(bag_format, bag_format)
        again = recording.trajectory("/gpo/odom")
        np.testing.assert_array_equal(recording.static_transform("base_link", "camera")[0], [0.3, 0, 0.1])
    np.testing.assert_array_equal(again.stamps_ns, trajectory.stamps_ns)
    np.testing.assert_array_equal(again.positions, trajectory.positions)
    assert (again.frame_id, again.child_frame_id) == (trajectory.frame_id, trajectory.child_frame_id)
    with AnyReader([copy]) as reader:
        (static,) = [c for c in reader.connections if c.topic == "/tf_static"]
    if bag_format == "ros1":
        assert static.ext.latching == 1
    else:
        assert static.ext.offered_qos_profiles[0].durability == QosDurability.TRANSIENT_LOCAL


def test_copy_with_trajectory_refuses_a_topic_in_use(tmp_path):
    source = tmp_path / "source.bag"
    write_topics(source, ["/camera"])
    with pytest.raises(ValueError, match="already has a topic /odom"):
        copy_with_trajectory(source, tmp_path / "copy.bag", random_trajectory(), topic="/odom")
    assert not (tmp_path / "copy.bag").exists()


def test_writer_refuses_what_it_cannot_write(tmp_path):
    (tmp_path / "old.bag").write_text("")
    with pytest.raises(FileExistsError, match=r"old\.bag exists"):
        BagWriter(tmp_path / "old.bag")
    with pytest.raises(ValueError, match="a ros1 bag is one file named"):
        BagWriter(tmp_path / "recording")
    with pytest.raises(ValueError, match="a ros2 bag is a folder, named neither"):
        BagWriter(tmp_path / "recording.bag", "ros2")
    with pytest.raises(ValueError, match=r"recording\.mcap: a ros2-mcap bag is a folder, .*name it recording, say"):
        BagWriter(tmp_path / "recording.mcap", "ros2-mcap")  # the storage file inside the folder is named so
    with pytest.raises(ValueError, match="unknown bag format 'ros3'"):
        BagWriter(tmp_path / "recording", "ros3")

    path = tmp_path / "recording.bag"
    with BagWriter(path) as writer:
        writer.add_image("/camera", T0, np.zeros((2, 2), np.uint8), CAMERA_FRAME)
        with pytest.raises(ValueError, match="/camera carries sensor_msgs/msg/Image, not nav_msgs/msg/Odometry"):
            writer.add_odometry("/camera", T0, [0, 0, 0], [0, 0, 0, 1], "odom", "base_link")
        with pytest.raises(ValueError, match="float32 image of shape \\(2, 2\\) is not any encoding"):
            writer.add_image("/depth", T0, np.zeros((2, 2), np.float32), CAMERA_FRAME)
        with pytest.raises(ValueError, match="is not bgr8"):
            writer.add_image("/mono", T0, np.zeros((2, 2), np.uint8), CAMERA_FRAME, encoding="bgr8")
        with pytest.raises(ValueError, match="jpeg holds mono8, rgb8 or bgr8 images, not mono16"):
            writer.add_compressed_image("/c", T0, np.zeros((2, 2), np.uint16), CAMERA_FRAME, format="jpeg")
        with pytest.raises(ValueError, match=r"integer nanoseconds, got 1\.5"):
            writer.add_image("/camera", 1.5, np.zeros((2, 2), np.uint8), CAMERA_FRAME)
    with Recording(path) as recording:
        assert [(t.name, t.count) for t in recording.topics()] == [("/camera", 1)]


@pytest.mark.parametrize("bag_format", FORMATS)
def test_an_error_while_writing_leaves_no_half_written_bag(tmp_path, bag_format):
    path = bag_path(tmp_path, bag_format)
    with pytest.raises(RuntimeError), BagWriter(path, bag_format) as writer:
        writer.add_image("/camera", T0, np.zeros((2, 2), np.uint8), CAMERA_FRAME)
        raise RuntimeError("the camera fell off")
    assert not path.exists()
