"""Bags to fuzz the recording reader with (``gpo.io.bag.Recording``): ROS1, ROS2 sqlite3 and ROS2 mcap.

The seeds are small bags made from ``data/``: three 64x48 crops of the floor board's image as mono8 frames, two
compressed (PNG, JPEG), the T265-like camera's camera_info, the first poses of the sample recording's ground truth
(PoseStamped) and tracking odometry (Odometry), and two static transforms; each in three forms: as written
(``good``), with messages whose bytes are of another type than their topic declares (``lies``), and with the topics'
names swapped between types (``swapped``). Mutations: bytes (``harness.byte_mutation``, aimed at records' headers
half the time), whole records shuffled, dropped or doubled (ROS1, mcap), rows and types changed in the sqlite3
database, and the ROS2 ``metadata.yaml`` mutated as a document or as text.
"""

from __future__ import annotations

import contextlib
import functools
import sqlite3
import struct
import tempfile
from pathlib import Path

import cv2
import numpy as np
from hypothesis import strategies as st

from fuzzing.documents import yaml_mutated
from fuzzing.harness import Mutant, Target, bytes_mutated, parts
from fuzzing.readers import check_cameras
from gpo.cameras import T265_LIKE, CameraModel
from gpo.io.bag import Frame, Recording, describe
from gpo.io.bag_writer import BagWriter
from gpo.io.ros_messages import CAMERA_INFO, IMAGE, ODOMETRY, POSE_STAMPED
from gpo.io.trajectory import Trajectory

DATA = Path(__file__).resolve().parents[2] / "data"
IMAGE_TOPIC = "/camera/fisheye1/image_raw"
COMPRESSED_TOPIC = "/camera/fisheye1/image_raw/compressed"
INFO_TOPIC = "/camera/fisheye1/camera_info"
TRUTH_TOPIC = "/mocap/base_link"
ODOMETRY_TOPIC = "/camera/odom/sample"
POSES = 12  # of each trajectory
FRAME_NS = 33_333_333
FORMS = ("good", "swapped", "lies")  # lies after good: made from it
_WRITER_FORMAT = {"ros1": "ros1", "ros2-sqlite3": "ros2", "ros2-mcap": "ros2-mcap"}
FORMATS = {"ros1": "bag.bag", "ros2-sqlite3": "bag", "ros2-mcap": "bag"}
ROS1_MAGIC = b"#ROSBAG V2.0\n"
MCAP_MAGIC = b"\x89MCAP0\r\n"


@functools.cache
def pictures() -> tuple[np.ndarray, ...]:
    """Three 48x64 mono8 crops of the floor board's image, a pixel apart."""
    board = cv2.imread(str(DATA / "floor_board_t265.png"), cv2.IMREAD_GRAYSCALE)
    return tuple(np.ascontiguousarray(board[400:448, 300 + k : 364 + k]) for k in range(3))


@functools.cache
def trajectories() -> dict[str, Trajectory]:
    """The first ``POSES`` poses of the sample's truth and tracking odometry."""
    read = {topic: Trajectory.read_tum(DATA / name) for topic, name in
            ((TRUTH_TOPIC, "sample_groundtruth.tum"), (ODOMETRY_TOPIC, "sample_tracking_odometry.tum"))}
    return {topic: Trajectory(t.stamps_ns[:POSES], t.positions[:POSES], t.quaternions[:POSES]) for topic, t in
            read.items()}


def _write(path: Path, fmt: str, form: str) -> None:
    """A seed bag at ``path``: ``good``, or ``swapped`` (the topics' names swapped between types)."""
    names = {IMAGE_TOPIC: IMAGE_TOPIC, TRUTH_TOPIC: TRUTH_TOPIC, INFO_TOPIC: INFO_TOPIC, ODOMETRY_TOPIC: ODOMETRY_TOPIC}
    if form == "swapped":
        names = {IMAGE_TOPIC: TRUTH_TOPIC, TRUTH_TOPIC: IMAGE_TOPIC, INFO_TOPIC: ODOMETRY_TOPIC,
                 ODOMETRY_TOPIC: INFO_TOPIC}
    truth, odometry = trajectories()[TRUTH_TOPIC], trajectories()[ODOMETRY_TOPIC]
    start = int(truth.stamps_ns[0])
    with BagWriter(path, _WRITER_FORMAT[fmt]) as bag:
        if fmt == "ros1":
            bag._writer.chunk_threshold = 4096  # several chunks: records to shuffle
        bag.add_static_transform("base_link", "camera_pose_frame", [0.6, 0.0, 0.12], [0, 0, 0, 1], start)
        bag.add_static_transform("base_link", "optical", [0.6, 0.0, 0.12], [-0.5, 0.5, -0.5, 0.5], start)
        bag.add_camera_info(names[INFO_TOPIC], start, T265_LIKE, "optical")
        for k, picture in enumerate(pictures()):
            bag.add_image(names[IMAGE_TOPIC], start + k * FRAME_NS, picture, "optical")
        for k, extension in enumerate(("png", "jpeg")):
            bag.add_compressed_image(COMPRESSED_TOPIC, start + k * FRAME_NS, pictures()[k], "optical", extension)
        for k in range(POSES):
            bag.add_pose(names[TRUTH_TOPIC], int(truth.stamps_ns[k]), truth.positions[k], truth.quaternions[k], "world")
            bag.add_odometry(names[ODOMETRY_TOPIC], int(odometry.stamps_ns[k]), odometry.positions[k],
                             odometry.quaternions[k], "odom", "camera_pose_frame")


def _write_lies(good: Path, path: Path, fmt: str) -> None:
    """The bag at ``good`` again, and on four topics a message whose bytes are of another type than they declare."""
    with Recording(good) as source, BagWriter(path, _WRITER_FORMAT[fmt]) as bag:
        raw_of_type = {}
        for connection, stamp, raw in source.raw_messages():
            topic = connection.topic
            if topic not in bag._connections:
                bag._connections[topic] = bag._add_connection(topic, connection.msgtype, topic == "/tf_static")
            bag._writer.write(bag._connections[topic], stamp, raw)
            raw_of_type.setdefault(connection.msgtype, raw)
        for topic, other in ((IMAGE_TOPIC, ODOMETRY), (TRUTH_TOPIC, IMAGE), (INFO_TOPIC, POSE_STAMPED),
                             ("/tf_static", CAMERA_INFO)):
            bag._writer.write(bag._connections[topic], source.start_ns + FRAME_NS // 2, raw_of_type[other])


@functools.cache
def seeds() -> dict[str, Mutant]:
    """Every seed bag, by ``FORMAT/FORM``: its files (a ROS2 bag's folder, ``bag/``, holds two) as a Mutant."""
    made = {}
    with tempfile.TemporaryDirectory() as name:
        folder = Path(name)
        for fmt, entry in FORMATS.items():
            for form in FORMS:
                path = folder / fmt / form / entry
                path.parent.mkdir(parents=True)
                if form == "lies":
                    _write_lies(folder / fmt / "good" / entry, path, fmt)
                else:
                    _write(path, fmt, form)
                files = sorted(p for p in path.parent.rglob("*") if p.is_file())
                made[f"{fmt}/{form}"] = Mutant(
                    f"{fmt}/{form}", tuple((str(p.relative_to(path.parent)), p.read_bytes()) for p in files), entry
                )
    return made


# ------------------------------------------------------------------------------------------------ records


def ros1_records(content: bytes, start: int = len(ROS1_MAGIC)) -> list[tuple[int, int]]:
    """(start, end) of each record of ROS1 bag bytes from ``start``: header length, header, data length, data."""
    spans, at = [], start
    while at + 8 <= len(content):
        header = struct.unpack_from("<I", content, at)[0]
        if at + 4 + header + 4 > len(content):
            break
        data = struct.unpack_from("<I", content, at + 4 + header)[0]
        spans.append((at, min(len(content), at + 8 + header + data)))
        at = spans[-1][1]
    return spans


def mcap_records(content: bytes) -> list[tuple[int, int]]:
    """(start, end) of each record of MCAP bytes between the magic at both ends: opcode, length (u64), content."""
    spans, at = [], len(MCAP_MAGIC)
    while at + 9 <= len(content) - len(MCAP_MAGIC):
        length = struct.unpack_from("<Q", content, at + 1)[0]
        spans.append((at, min(len(content), at + 9 + length)))
        at = spans[-1][1]
    return spans


def ros1_chunks(content: bytes) -> list[tuple[int, int, int]]:
    """ROS1 chunk records (op 5): (record start, data start, end)."""
    found = []
    for start, end in ros1_records(content):
        header = struct.unpack_from("<I", content, start)[0]
        if b"op=\x05" in content[start + 4 : start + 4 + header]:
            found.append((start, start + 8 + header, end))
    return found


def record_starts(name: str, content: bytes) -> tuple[int, ...]:
    """Where the records of a bag file start (and a ROS1 chunk's inner records): the offsets worth hitting."""
    if name.endswith(".bag"):
        inner = [s for _, data, _ in ros1_chunks(content) for s, _ in ros1_records(content, data)]
        return tuple(sorted({s for s, _ in ros1_records(content)} | set(inner) | {0}))
    if name.endswith(".mcap"):
        return (0, *(s for s, _ in mcap_records(content)))
    return ()


@st.composite
def records_mutated(draw, mutant: Mutant) -> Mutant:
    """``mutant``'s bag file with its records (or, ROS1, a chunk's inner records) shuffled, dropped or doubled."""
    name, content = next((n, c) for n, c in mutant.files if n.endswith((".bag", ".mcap")))
    region = (0, len(content))
    if name.endswith(".bag"):
        chunks = ros1_chunks(content)
        if chunks and draw(st.booleans()):
            _, data, end = draw(st.sampled_from(chunks))
            region, spans = (data, end), ros1_records(content, data)
            spans = [(s, e) for s, e in spans if e <= end]
        else:
            spans = ros1_records(content)
    else:
        spans = mcap_records(content)
    if len(spans) < 2:
        return mutant
    pieces = [content[s:e] for s, e in spans]
    kind = draw(st.sampled_from(("shuffle", "drop", "double", "swap")))
    if kind == "shuffle":
        order = draw(st.permutations(range(len(pieces))))
    else:
        i, j = draw(st.integers(0, len(pieces) - 1)), draw(st.integers(0, len(pieces) - 1))
        order = list(range(len(pieces)))
        if kind == "drop":
            del order[i]
        elif kind == "double":
            order.insert(j, i)
        else:
            order[i], order[j] = order[j], order[i]
    changed = content[: spans[0][0]] + b"".join(pieces[k] for k in order) + content[spans[-1][1] :]
    if region != (0, len(content)):  # a chunk's data: its length field follows its new size
        start = next(s for s, d, _ in ros1_chunks(content) if d == region[0])
        changed = bytearray(changed)
        struct.pack_into("<I", changed, region[0] - 4, region[1] - region[0] + len(changed) - len(content))
        changed = bytes(changed)
        where = f"the chunk at {start}"
    else:
        where = "the file"
    return mutant.replaced(name, changed, f"{name}: records of {where} {kind}: order {list(order)}")


SQL_TYPES = (IMAGE, ODOMETRY, POSE_STAMPED, CAMERA_INFO, "tf2_msgs/msg/TFMessage", "std_msgs/msg/String", "", "x/y")


@st.composite
def sql_mutated(draw, mutant: Mutant) -> Mutant:
    """``mutant``'s sqlite3 database with a message moved to another topic, a topic's type or serialisation changed,
    a message dropped, cut, replaced or restamped, or a table dropped."""
    name = next(n for n, _ in mutant.files if n.endswith(".db3"))
    message, topic = draw(st.integers(1, 40)), draw(st.integers(1, 7))
    statement, values = draw(st.sampled_from((
        ("UPDATE messages SET topic_id = ? WHERE id = ?", (topic, message)),
        ("UPDATE topics SET type = ? WHERE id = ?", (draw(st.sampled_from(SQL_TYPES)), topic)),
        ("UPDATE topics SET serialization_format = ? WHERE id = ?", (draw(st.sampled_from(("ros1", "", "json"))),
                                                                     topic)),
        ("DELETE FROM messages WHERE id = ?", (message,)),
        ("UPDATE messages SET timestamp = ? WHERE id = ?", (draw(st.integers(-2**63, 2**63 - 1)), message)),
        ("UPDATE messages SET data = substr(data, 1, ?) WHERE id = ?", (draw(st.integers(0, 300)), message)),
        ("UPDATE messages SET data = ? WHERE id = ?", (draw(st.binary(max_size=64)), message)),
        ("UPDATE messages SET data = NULL WHERE id = ?", (message,)),
        (f"DROP TABLE {draw(st.sampled_from(('messages', 'topics', 'schema', 'metadata')))}", ()),
    )))
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "bag.db3"
        path.write_bytes(mutant.content(name))
        with contextlib.closing(sqlite3.connect(path)) as database, contextlib.suppress(sqlite3.Error, ValueError):
            database.execute(statement, values)  # an error: a table it lacks, a database already damaged
            database.commit()
        changed = path.read_bytes()
    shown = [v if not isinstance(v, bytes) else f"<{len(v)} bytes>" for v in values]
    return mutant.replaced(name, changed, f"{name}: {statement} {shown}")


@st.composite
def bag_mutants(draw, fmt: str) -> Mutant:
    """A seed bag of format ``fmt`` with up to three mutations (none: the seed as it is)."""
    mutant = draw(st.sampled_from([seeds()[f"{fmt}/{form}"] for form in FORMS]))
    for _ in range(draw(st.integers(0, 3))):
        choices = [bytes_mutated(mutant, record_starts)]
        if fmt == "ros2-sqlite3":
            choices.append(sql_mutated(mutant))
        else:
            choices.append(records_mutated(mutant))
        if fmt != "ros1":
            choices.append(yaml_mutated(mutant, "bag/metadata.yaml"))
        mutant = draw(st.one_of(choices))
    return mutant


# ------------------------------------------------------------------------------------------------ reading


def read_bag(path: Path) -> dict[str, object]:
    """Everything the reader gives of the bag: each read on its own, each of which may refuse."""
    with Recording(path) as bag:
        return parts({
            "describe": lambda: describe(path),
            "topics": bag.topics,
            "image topic": lambda: bag.image_topic(IMAGE_TOPIC),
            "frames": lambda: list(bag.frames(IMAGE_TOPIC, progress=False)),
            "frames flagged": lambda: list(bag.frames(IMAGE_TOPIC, progress=False, flag_unreadable=True, gray=True)),
            "compressed": lambda: list(bag.frames(COMPRESSED_TOPIC, progress=False, flag_unreadable=True)),
            "truth": lambda: bag.trajectory(TRUTH_TOPIC),
            "odometry": lambda: bag.trajectory(ODOMETRY_TOPIC),
            "pose frames": lambda: bag.pose_frames(ODOMETRY_TOPIC),
            "camera": lambda: bag.camera_info(INFO_TOPIC),
            "static": bag.static_transforms,
            "static one": lambda: bag.static_transform("base_link", "camera_pose_frame"),
            "messages": lambda: sum(1 for _ in bag.raw_messages()),
        })


def check_bag(result: dict[str, object], mutant: Mutant) -> None:
    """Frames, trajectories and the camera well formed; the seed as written read as it was written."""
    for name in ("frames", "frames flagged", "compressed"):
        for frame in result[name] if isinstance(result[name], list) else ():
            assert isinstance(frame, Frame), f"{name}: {frame!r} is no Frame"
            if frame.image is None:
                assert frame.problem, f"{name}: a frame without image or problem"
            else:
                assert frame.image.dtype in (np.uint8, np.uint16) and frame.image.ndim in (2, 3), (
                    f"{name}: an image {frame.image.dtype} {frame.image.shape}")
    for name in ("truth", "odometry"):
        assert isinstance(result[name], Trajectory | ValueError | OSError), f"{name}: {result[name]!r}"
    camera = result["camera"]
    assert isinstance(camera, CameraModel | ValueError | OSError), f"camera: {camera!r}"
    if isinstance(camera, CameraModel):
        check_cameras([camera])
    if mutant.how or not mutant.seed.endswith("/good"):
        return
    frames = [frame.image for frame in result["frames"]]
    assert len(frames) == 3 and all(np.array_equal(a, b) for a, b in zip(frames, pictures(), strict=True))
    for topic, name in ((TRUTH_TOPIC, "truth"), (ODOMETRY_TOPIC, "odometry")):
        expected = trajectories()[topic]
        assert np.array_equal(result[name].stamps_ns, expected.stamps_ns)
        assert np.array_equal(result[name].positions, expected.positions)
    assert result["camera"] == T265_LIKE


BAG_TARGETS = [Target(fmt, bag_mutants(fmt), read_bag, check_bag) for fmt in FORMATS]
"""The recording reader on each format: every refusal names the bag (poses that are not finite with the bag and the
topic, ``gpo.io.bag``)."""
