"""Bad input never costs data: every command, given what users give it by mistake, exits with the documented code and
a message that names the problem, shows no traceback, and leaves every input and earlier output as it was.

Each case runs ``python -m gpo`` in-process (``main(argv)``) on small files made here: a 12-frame bag of a camera
with a quarter of the T265's resolution and its config (``tiny_config``), and variants of both. Every file of the
case's folders is hashed before and after. The signal cases run a real process.

The file is longer than the project's modules: it is the reliability catalogue of DESIGN.md, case beside case,
each a few lines on the small bags and configs made at its top, and reads best whole.
"""

from __future__ import annotations

import hashlib
import os
import re
import signal
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

import cv2
import numpy as np
import pytest
import yaml
from fuzzing.bags import mcap_records, ros1_chunks

import gpo.cli.calibrate
import gpo.cli.run
import gpo.pipeline.odometer
import gpo.pipeline.run
from gpo.cameras import T265_LIKE
from gpo.cli import main
from gpo.io.bag import Recording
from gpo.io.bag_writer import BagWriter
from gpo.io.ros_messages import COMPRESSED_IMAGE, IMAGE
from gpo.io.trajectory import Trajectory
from gpo.pipeline.config import load_config

IMAGE_TOPIC = "/camera/fisheye1/image_raw"
ODOMETRY_TOPIC = "/camera/odom/sample"
START_NS = 1_700_000_000 * 10**9
FRAME_NS = 33_333_333
SIZE = (200, 212)  # height, width: the tiny camera's
CONFIG = Path(__file__).parents[1] / "gpo" / "configs" / "sim_t265.yaml"


# ------------------------------------------------------------------------------------------------ the files


def tiny_config(path: Path, **changes) -> Path:
    """The shipped T265 config with the camera at a quarter of its resolution and a 4 mm floor image, so that a run
    takes a fraction of a second; ``changes`` replace top-level sections."""
    document = yaml.safe_load(CONFIG.read_text())
    document["camera"]["intrinsics"] = [0.6, 1.1, 71.5, 71.5, 106.0, 100.0]
    document["camera"]["resolution"] = [SIZE[1], SIZE[0]]
    document["floor_image"]["metres_per_pixel"] = 0.004
    document["klt"].update(
        max_corners=40, min_distance_px=3.0, block_size=3, window_px=7, pyramid_levels=1, redetect_below=15,
        min_tracks=4, flat_field_px=0,
    )
    document.update(changes)
    path.write_text(yaml.safe_dump(document, sort_keys=False))
    return path


def texture(size=SIZE, seed=0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    noise = (rng.random((size[0] + 40, size[1] + 80)) * 255).astype(np.uint8)
    return cv2.GaussianBlur(noise, (0, 0), 1.5)


def frame(index: int, size=SIZE) -> np.ndarray:
    """The floor moved one pixel a frame."""
    return np.ascontiguousarray(texture(size)[20 : 20 + size[0], 20 + index : 20 + index + size[1]])


def write_bag(
    path: Path, frames: int = 12, image=frame, stamps=None, odometry=True, static_tf=True, poses=None, fmt="ros1"
):
    """A bag of format ``fmt``: ``frames`` images (``image(i)``: an array, or a callable writing the message
    itself), the tracking camera's odometry (``poses(i)``: position) and its mount on /tf_static, a mocap truth."""
    stamps = stamps or [START_NS + i * FRAME_NS for i in range(frames)]
    poses = poses or (lambda i: [0.01 * i, 0.0, 0.0])
    with BagWriter(path, fmt) as bag:
        if static_tf:
            bag.add_static_transform("base_link", "camera_pose_frame", [0.6, 0, 0.12], [0, 0, 0, 1], START_NS)
        for i, stamp in enumerate(stamps):
            picture = image(i)
            if callable(picture):
                picture(bag, stamp)
            else:
                bag.add_image(IMAGE_TOPIC, stamp, picture, "cam")
            if odometry:
                bag.add_odometry(ODOMETRY_TOPIC, stamp, poses(i), [0, 0, 0, 1], "odom", "camera_pose_frame")
            bag.add_pose("/mocap/base_link", stamp, [0.01 * i, 0.0, 0.0], [0, 0, 0, 1], "world")
    return path


def raw_image(encoding="mono8", data=None, size=SIZE):
    """A sensor_msgs/Image written as given (another encoding, a short buffer)."""

    def write(bag: BagWriter, stamp: int):
        pixels = frame(0, size)
        message = bag._types[IMAGE](
            header=bag._header(IMAGE_TOPIC, stamp, "cam"), height=size[0], width=size[1], encoding=encoding,
            is_bigendian=0, step=size[1], data=pixels.reshape(-1) if data is None else data,
        )
        bag._write(IMAGE_TOPIC, message, stamp)

    return write


def stamped(index: int, header_ns: int):
    """Frame ``index`` whose header stamp is ``header_ns``, whatever its log time."""

    def write(bag: BagWriter, stamp: int):
        pixels = frame(index)
        message = bag._types[IMAGE](
            header=bag._header(IMAGE_TOPIC, header_ns, "cam"), height=SIZE[0], width=SIZE[1], encoding="mono8",
            is_bigendian=0, step=SIZE[1], data=pixels.reshape(-1),
        )
        bag._write(IMAGE_TOPIC, message, stamp)

    return write


def jpeg(index: int, corrupt: bool = False):
    def write(bag: BagWriter, stamp: int):
        if not corrupt:
            bag.add_compressed_image(IMAGE_TOPIC, stamp, frame(index), "cam", format="jpeg")
            return
        data = np.frombuffer(b"\xff\xd8\xff\xe0 not a jpeg at all", np.uint8)
        message = bag._types[COMPRESSED_IMAGE](
            header=bag._header(IMAGE_TOPIC, stamp, "cam"), format="mono8; jpeg compressed mono8", data=data
        )
        bag._write(IMAGE_TOPIC, message, stamp)

    return write


def stamps(*offsets_frames) -> list[int]:
    return [START_NS + round(k * FRAME_NS) for k in offsets_frames]


BAGS = {
    "good": {},
    "other_size": {"image": lambda i: frame(i, (100, 106))},
    "other_encoding": {"image": lambda i: raw_image("32FC1")},
    "corrupt_jpeg": {"image": lambda i: jpeg(i, corrupt=i == 5)},
    "corrupt_first_jpeg": {"image": lambda i: jpeg(i, corrupt=i == 0)},
    "short_buffer": {"image": lambda i: raw_image(data=np.zeros(100, np.uint8)) if i == 4 else frame(i)},
    "mixed_size": {"image": lambda i: frame(i, (100, 106)) if i == 6 else frame(i)},
    "duplicated": {"stamps": stamps(0, 1, 2, 3, 3, 4, 5, 6, 7, 8, 9, 10)},
    "out_of_order": {"image": lambda i: stamped(i, START_NS + round(3.5 * FRAME_NS)) if i == 5 else frame(i)},
    "gappy": {"stamps": stamps(0, 1, 2, 3, 4, 5, 60, 61, 62, 63, 64, 65)},
    "textureless": {"image": lambda i: np.full(SIZE, 128, np.uint8)},
    "black": {"image": lambda i: np.zeros(SIZE, np.uint8)},
    "no_odometry": {"odometry": False},
    "no_tf_static": {"static_tf": False},
    "nan_odometry": {"poses": lambda i: [np.nan if i == 3 else 0.01 * i, 0.0, 0.0]},
    "jumping_odometry": {"poses": lambda i: [5.0 if i == 6 else 0.0, 0.0, 0.0]},  # standing, but for frame 6
}


def board_image(size=(240, 320), corners=(7, 5), square=24, shift=(0, 0), seed=0) -> np.ndarray:
    """A chessboard of ``corners`` inner corners, slightly turned, on white."""
    rows, columns = corners[1] + 1, corners[0] + 1
    board = np.kron((np.indices((rows, columns)).sum(axis=0) % 2) * 255, np.ones((square, square))).astype(np.uint8)
    board = cv2.copyMakeBorder(board, square, square, square, square, cv2.BORDER_CONSTANT, value=255)
    turn = cv2.getRotationMatrix2D((board.shape[1] / 2, board.shape[0] / 2), 5 + 4 * seed, 0.9)
    turn[:, 2] += np.array(shift) + (np.array(size[::-1]) - board.shape[1::-1]) / 2
    return cv2.warpAffine(board, turn, size[::-1], borderValue=255)


class World:
    """The shared inputs of the cases, made on first use."""

    def __init__(self, root: Path):
        self.root = root
        self.config = tiny_config(root / "rig.yaml")
        self._bags: dict[str, Path] = {}

    def bag(self, name: str = "good") -> Path:
        if name not in self._bags:
            self._bags[name] = write_bag(self.root / f"{name}.bag", **BAGS[name])
        return self._bags[name]

    def tum(self, name: str, lines: list[str]) -> Path:
        path = self.root / name
        path.write_text("".join(f"{line}\n" for line in lines))
        return path

    def truth(self) -> Path:
        return self.tum("truth.tum", [f"{1 + 0.1 * i:.1f} {0.1 * i:.3f} 0 0 0 0 0 1" for i in range(30)])


@pytest.fixture(scope="module")
def world(tmp_path_factory) -> World:
    return World(tmp_path_factory.mktemp("world"))


def _hashes(*folders: Path) -> dict[Path, str]:
    return {
        path: hashlib.sha256(path.read_bytes()).hexdigest()
        for folder in folders
        for path in folder.rglob("*")
        if path.is_file()
    }


def check(capsys, folders, argv, code: int, *words: str, changed=()) -> tuple[str, str]:
    """Run ``argv``; assert the exit ``code``, every word in the output, no traceback, no temporary file left, and
    that every file that was in ``folders`` is as it was (but ``changed``); return (stdout, stderr)."""
    before = _hashes(*folders)
    got = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    after = _hashes(*folders)
    assert got == code, f"exit {got}, expected {code}\n{out}\n{err}"
    for word in words:
        assert word in out + err, f"{word!r} not in:\n{out}{err}"
    assert "Traceback" not in err
    assert not [path for path in after if ".partial" in str(path)]
    for path, digest in before.items():
        if path not in changed:
            assert after.get(path) == digest, f"{path} changed or vanished"
    return out, err


def summary(path: Path) -> dict:
    return yaml.safe_load(path.with_suffix(".summary.yaml").read_text())


# --------------------------------------------------------------------------------------------------------- info


@pytest.mark.parametrize(
    ("content", "name", "words"),
    [
        (None, "missing.bag", ["no recording at"]),
        (b"", "empty.bag", ["not a readable ros1 recording", "empty", "does not start as a bag"]),
        (b"hello, I am text\n", "text.bag", ["not a readable ros1 recording", "does not start as a bag"]),
        (b"hello", "notes.txt", ["is not a recording", "expected a ROS1 .bag"]),
        (bytes(range(256)) * 64, "noise.bag", ["not a readable ros1 recording"]),
        ("folder", "folder", ["without metadata.yaml"]),
    ],
)
def test_info_refuses_what_is_not_a_bag(world, tmp_path, capsys, content, name, words):
    path = tmp_path / name
    if content == "folder":
        path.mkdir()
    elif content is not None:
        path.write_bytes(content)
    check(capsys, [tmp_path], ["info", path], 1, *words)


def test_info_names_a_bag_cut_short_and_how_it_may_be_repaired(world, tmp_path, capsys):
    cut = tmp_path / "cut.bag"
    cut.write_bytes(world.bag().read_bytes()[:5000])
    check(capsys, [tmp_path], ["info", cut], 1, "not a readable ros1 recording", "rosbag reindex")


def _damage_the_second_half(path: Path, fmt: str) -> Path:
    """The bag at ``path`` damaged past its first half, as a bad sector or a bad copy leaves it: an 8 KiB stretch of
    the sqlite3 database's pages overwritten, the messages of the second chunk made another kind of record (ROS1),
    or the length of the second chunk's first record 2**64 - 1 (MCAP)."""
    storage = path if path.is_file() else next(p for p in path.iterdir() if p.suffix in (".db3", ".mcap"))
    data = bytearray(storage.read_bytes())
    if fmt == "ros2":
        start = int(0.6 * len(data))
        data[start : start + 8192] = b"\xa5" * 8192
    elif fmt == "ros1":
        _, chunk_data, end = ros1_chunks(bytes(data))[1]
        data[chunk_data:end] = data[chunk_data:end].replace(b"op=\x02", b"op=\x09")
    else:
        second = [start for start, _ in mcap_records(bytes(data)) if data[start] == 0x06][1]
        data[second + 50 : second + 58] = b"\xff" * 8  # past the chunk's own fields: its first record's length
    storage.write_bytes(bytes(data))
    return path


@pytest.mark.parametrize("fmt", ["ros1", "ros2", "ros2-mcap"])
def test_a_bag_damaged_midway_names_the_bag_and_keeps_the_frames_before(world, tmp_path, capsys, fmt):
    """A ROS 2 bag's sqlite3 database damaged (apsw's CorruptError) as a ROS 1 or MCAP bag's records: the same
    words, naming the bag, and the frames read before the damage written, flagged."""
    path = tmp_path / ("damaged.bag" if fmt == "ros1" else "damaged")
    good = load_config(world.config)
    whole = gpo.pipeline.run.run(write_bag(path, frames=40, fmt=fmt), good, progress=False).trajectory
    _damage_the_second_half(path, fmt)
    out = tmp_path / "t.tum"
    check(capsys, [world.root], ["run", path, "--config", world.config, "--out", out], 1, "stopped early after",
          f"{path} is damaged", "the frames before were kept")
    kept = Trajectory.read_tum(out)
    assert 0 < len(kept) < 40 and summary(out)["stopped_early"].startswith(f"after {len(kept)} frames")
    np.testing.assert_array_equal(kept.positions, whole.positions[: len(kept)])


@pytest.mark.parametrize("nesting", ["[" * 600 + "]" * 600, "{a: " * 600 + "1" + "}" * 600])
def test_a_ros2_bag_whose_metadata_nests_hundreds_deep_is_named(world, tmp_path, capsys, nesting):
    path = write_bag(tmp_path / "deep", frames=3, fmt="ros2")
    metadata = path / "metadata.yaml"
    metadata.write_text(metadata.read_text() + f"\nextra: {nesting}\n")
    check(capsys, [tmp_path], ["info", path], 1, f"{path} is not a readable ros2-sqlite3 recording")


def test_info_of_a_bag_whose_first_image_is_unreadable(world, capsys):
    check(capsys, [world.root], ["info", world.bag("corrupt_first_jpeg")], 0, IMAGE_TOPIC, "unreadable")


def test_info_describes_a_good_bag(world, capsys):
    check(capsys, [world.root], ["info", world.bag()], 0, IMAGE_TOPIC, "212x200 mono8", ODOMETRY_TOPIC)


# --------------------------------------------------------------------------------------------------------- run


@pytest.mark.parametrize(
    ("content", "words"),
    [(None, ["no recording at"]), (b"plain text\n", ["not a readable ros1 recording", "does not start as a bag"])],
)
def test_run_refuses_what_is_not_a_bag_before_anything(world, tmp_path, capsys, content, words):
    bag = tmp_path / "input.bag"
    if content is not None:
        bag.write_bytes(content)
    check(capsys, [world.root, tmp_path], ["run", bag, "--config", world.config, "--out", tmp_path / "t.tum"], 1,
          *words)
    assert not (tmp_path / "t.tum").exists()


@pytest.mark.parametrize("method", ["gpo", "gpo-exact", "gpo-rigid", "features", "fused"])
def test_every_method_runs_on_the_tiny_bag(world, tmp_path, capsys, method):
    """The keypoint method finds too few keypoints on the tiny bag's noise floor to measure most of its frames: its
    run is written (no file was there) and flagged, exit 1."""
    out = tmp_path / "traj.tum"
    words = ["flagged: measured", "of 11 steps"] if method == "features" else []
    check(capsys, [world.root, tmp_path], ["run", world.bag(), "--config", world.config, "--out", out,
                                            "--method", method], 1 if method == "features" else 0, f"wrote {out}",
          *words)
    assert len(Trajectory.read_tum(out)) == 12 and summary(out)["method"] == method


@pytest.mark.parametrize("onto", ["bag", "config"])
def test_run_never_writes_onto_its_input(world, capsys, onto):
    target = world.bag() if onto == "bag" else world.config
    check(capsys, [world.root], ["run", world.bag(), "--config", world.config, "--out", target], 1,
          "is an input of this command", "would be overwritten")


def test_run_refuses_an_input_under_another_name(world, tmp_path, capsys):
    link = tmp_path / "link.tum"
    os.link(world.config, link)
    check(capsys, [world.root, tmp_path], ["run", world.bag(), "--config", world.config, "--out", link], 1,
          "is an input of this command")


def test_run_refuses_a_folder_for_out_before_working(world, tmp_path, capsys):
    folder = tmp_path / "results"
    folder.mkdir()
    check(capsys, [world.root, tmp_path], ["run", world.bag(), "--config", world.config, "--out", folder], 1,
          "is a folder")
    assert list(tmp_path.rglob("*.yaml")) == []  # no stray summary


def test_run_refuses_a_read_only_folder_before_working(world, tmp_path, capsys, monkeypatch):
    """The suite may run as root, whom no permission stops: the folder's access is what the check asks."""
    folder = tmp_path / "locked"
    folder.mkdir()
    real = os.access
    monkeypatch.setattr(os, "access", lambda path, mode: Path(path) != folder and real(path, mode))
    check(capsys, [world.root, tmp_path], ["run", world.bag(), "--config", world.config, "--out", folder / "t.tum"], 1,
          "cannot be written (read-only)")


@pytest.mark.parametrize("stops", ["trajectory", "summary", "bag copy"])
def test_a_full_disk_keeps_the_earlier_result_whole(world, tmp_path, capsys, monkeypatch, stops):
    """The disk fills while the trajectory, its summary or the bag's copy is written: the earlier trajectory and its
    summary stay, both (a new summary beside the old trajectory would no longer describe it)."""
    out = tmp_path / "traj.tum"
    out.write_text("# a good trajectory\n")
    out.with_suffix(".summary.yaml").write_text("method: gpo-exact\n")

    write_text = Path.write_text

    def full(path):
        write_text(Path(path), "half a file")
        raise OSError(28, "No space left on device", str(path))

    if stops == "trajectory":
        monkeypatch.setattr(Trajectory, "write_tum", lambda self, path: full(path))
    elif stops == "summary":
        monkeypatch.setattr(Path, "write_text", lambda self, text, *args, **kwargs: full(self)
                            if self.name.endswith(".summary.yaml") else write_text(self, text, *args, **kwargs))
    else:
        monkeypatch.setattr(gpo.cli.run, "copy_with_trajectory", lambda bag, path, trajectory: full(path))
    named = {"trajectory": out, "summary": out.with_suffix(".summary.yaml"), "bag copy": tmp_path / "copy.bag"}
    _, err = check(capsys, [world.root, tmp_path], ["run", world.bag(), "--config", world.config, "--out", out,
                                                    "--write-bag", tmp_path / "copy.bag"], 1,
                   f"{named[stops]}: the disk is full", "the files already there are kept as they were")
    assert ".partial" not in err and "Errno" not in err  # the user's path, not the hidden temporary one
    assert not (tmp_path / "copy.bag").exists()


KILLED_RUN = """
import os, pathlib, signal, sys
stop, name = sys.argv[1], sys.argv[2]
rename, write_text = os.replace, pathlib.Path.write_text
staged = lambda path: pathlib.Path(path).name == name and pathlib.Path(path).parent.name.endswith(".partial")

def replace(source, target):  # killed at once, as kill -9 does, before the rename of a staged file onto name
    if stop == "rename" and staged(source) and pathlib.Path(target).name == name:
        os.kill(os.getpid(), signal.SIGKILL)
    rename(source, target)

def written(self, text, *args, **kwargs):  # killed half way through writing name
    if stop == "write" and staged(self):
        write_text(self, text[:10])
        os.kill(os.getpid(), signal.SIGKILL)
    return write_text(self, text, *args, **kwargs)

os.replace, pathlib.Path.write_text = replace, written
from gpo.cli import main
sys.exit(main(sys.argv[3:]))
"""


@pytest.mark.parametrize(
    ("stop", "name", "after"),
    [
        ("write", "t.summary.yaml", "gpo-exact"),  # killed while the new summary is written: the old set stays
        ("rename", "t.tum", "gpo-rigid"),  # killed before the first rename: the new set is finished
        ("rename", "t.summary.yaml", "gpo-rigid"),  # killed between the two renames: the new set is finished
    ],
)
def test_a_run_killed_while_it_writes_leaves_one_set_the_next_time_its_folder_is_used(world, tmp_path, capsys, stop,
                                                                                       name, after):
    """``gpo run --out t.tum`` over the files of an earlier run (gpo-exact) is killed (kill -9) as it writes a new
    run's (gpo-rigid): once the folder is used again (here by another run), the trajectory and its summary are one
    run's, the old or the new, each checked against that method's path computed through the library."""
    out = tmp_path / "t.tum"
    check(capsys, [world.root], ["run", world.bag(), "--config", world.config, "--out", out], 0, f"wrote {out}")
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).parents[1])}
    arguments = ["run", world.bag(), "--config", world.config, "--out", out, "--method", "gpo-rigid"]
    killed = subprocess.run([sys.executable, "-c", KILLED_RUN, stop, name, *map(str, arguments)], env=env,
                            capture_output=True, text=True, timeout=300, check=False)
    assert killed.returncode == -signal.SIGKILL, killed.stderr
    assert any(path.name.endswith(".partial") for path in tmp_path.iterdir())  # what the killed write left
    check(capsys, [world.root], ["run", world.bag(), "--config", world.config, "--out", tmp_path / "other.tum"], 0)
    assert not any(path.name.endswith(".partial") for path in tmp_path.iterdir())
    assert summary(out)["method"] == after
    np.testing.assert_array_equal(Trajectory.read_tum(out).positions, _path(world, method=after).positions)
    assert np.abs(_path(world, method="gpo-rigid").positions - _path(world).positions).max() > 0.01  # two paths


def test_a_full_cache_is_named_and_the_run_goes_on(world, tmp_path, capsys, monkeypatch):
    """The floor image's remap table, built, cannot be kept in the cache: the run uses it, says which folder is full,
    and writes its trajectory, the same as with room."""
    cache_folder = tmp_path / "cache"
    monkeypatch.setenv("GPO_CACHE_DIR", str(cache_folder))

    def full(path, **arrays):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(np, "savez", full)
    out = tmp_path / "t.tum"
    check(capsys, [world.root], ["run", world.bag(), "--config", world.config, "--out", out], 0,
          f"the cache folder {cache_folder} is full", "was not kept", f"wrote {out}")
    np.testing.assert_array_equal(Trajectory.read_tum(out).positions, _path(world).positions)


def test_write_bag_needs_room_for_the_copy(world, tmp_path, capsys, monkeypatch):
    monkeypatch.setattr("shutil.disk_usage", lambda path: SimpleNamespace(total=10**9, used=10**9, free=1000))
    check(capsys, [world.root, tmp_path], ["run", world.bag(), "--config", world.config, "--out", tmp_path / "t.tum",
                                           "--write-bag", tmp_path / "copy.bag"], 1, "MB free", "needed")
    assert not (tmp_path / "t.tum").exists()


@pytest.mark.parametrize("existing", ["bag", "other"])
def test_write_bag_never_replaces_a_bag(world, tmp_path, capsys, existing):
    target = world.bag() if existing == "bag" else world.bag("black")
    check(capsys, [world.root, tmp_path], ["run", world.bag(), "--config", world.config, "--out", tmp_path / "t.tum",
                                           "--write-bag", target], 1, "exists", "never replaced")


@pytest.mark.parametrize(("name", "words"), [("out.db3", ["a ros1 bag is one file named *.bag: name it out.bag"]),
                                             ("missing/out.txt", ["a ros1 bag is one file named *.bag"])])
def test_write_bag_is_checked_before_the_run_and_named_as_given(world, tmp_path, capsys, monkeypatch, name, words):
    monkeypatch.setattr(gpo.pipeline.run, "odometry", lambda *a, **k: pytest.fail("frames were read"))
    target = tmp_path / name
    _, err = check(capsys, [world.root, tmp_path], ["run", world.bag(), "--config", world.config, "--out",
                                                    tmp_path / "t.tum", "--write-bag", target], 1,
                   f"--write-bag (a copy of {world.bag()}) {target}", *words)
    assert ".partial" not in err and not (tmp_path / "t.tum").exists()


@pytest.mark.parametrize("fmt", ["ros1", "ros2"])
def test_write_bag_copies_the_bag_with_the_estimate(world, tmp_path, capsys, fmt):
    bag = world.bag() if fmt == "ros1" else write_bag(tmp_path / "input", fmt="ros2")
    copy = tmp_path / ("copy.bag" if fmt == "ros1" else "copy")
    check(capsys, [world.root, tmp_path], ["run", bag, "--config", world.config, "--out", tmp_path / "t.tum",
                                           "--write-bag", copy], 0, "/gpo/odom")
    with Recording(copy) as recorded:
        carried, written = recorded.trajectory("/gpo/odom"), Trajectory.read_tum(tmp_path / "t.tum")
    np.testing.assert_array_equal(carried.stamps_ns, written.stamps_ns)  # the estimate, pose for pose
    np.testing.assert_array_equal(carried.positions, written.positions)
    assert len(carried) == 12


@pytest.mark.parametrize(
    ("arguments", "words"),
    [
        (["--topic", "/camera/fisheye1/image"], ["has no topic /camera/fisheye1/image", "did you mean"]),
        (["--topic", ODOMETRY_TOPIC], ["carries nav_msgs/msg/Odometry", "expected one of"]),
        (["--method", "fast"], ["invalid choice: 'fast'"]),
        (["--vector", "mode"], ["invalid choice: 'mode'"]),
    ],
)
def test_run_names_a_bad_option(world, tmp_path, capsys, arguments, words):
    code = 2 if "invalid choice" in words[0] else 1
    check(capsys, [world.root, tmp_path], ["run", world.bag(), "--config", world.config, "--out", tmp_path / "t.tum",
                                           *arguments], code, *words)


def test_run_asks_for_the_topic_of_a_bag_with_two(world, tmp_path, capsys):
    bag = tmp_path / "two.bag"
    with BagWriter(bag) as writer:
        for i in range(3):
            writer.add_image("/left/image_raw", START_NS + i * FRAME_NS, frame(i), "left")
            writer.add_image("/right/image_raw", START_NS + i * FRAME_NS, frame(i), "right")
    check(capsys, [world.root, tmp_path], ["run", bag, "--config", world.config, "--out", tmp_path / "t.tum"], 1,
          "has 2 image topics", "(--topic)")


def test_run_names_bag_topic_and_config_when_the_image_size_is_wrong(world, tmp_path, capsys):
    bag = world.bag("other_size")
    check(capsys, [world.root, tmp_path], ["run", bag, "--config", world.config, "--out", tmp_path / "t.tum"], 1,
          str(bag), IMAGE_TOPIC, "106 x 100 pixels", "212 x 200", str(world.config), "--topic")


def test_run_refuses_a_bag_whose_every_frame_is_unreadable(world, tmp_path, capsys):
    check(capsys, [world.root, tmp_path], ["run", world.bag("other_encoding"), "--config", world.config, "--out",
                                           tmp_path / "t.tum"], 1, "none of the 12 frames could be read", "32FC1")
    assert not (tmp_path / "t.tum").exists()


@pytest.mark.parametrize(
    ("name", "flag", "skipped"),
    [
        ("corrupt_jpeg", "cannot be decoded", 1),
        ("short_buffer", "short buffer", 1),
        ("mixed_size", "106 x 100 pixels, not the calibration's", 1),
    ],
)
def test_an_unreadable_frame_is_skipped_and_flagged_and_the_run_goes_on(world, tmp_path, capsys, name, flag, skipped):
    out = tmp_path / "t.tum"
    check(capsys, [world.root, tmp_path], ["run", world.bag(name), "--config", world.config, "--out", out], 0,
          "flagged 1: unreadable frame")
    assert summary(out)["frames_skipped"] == skipped and flag in summary(out)["unreadable"][0]
    path = Trajectory.read_tum(out)
    assert len(path) == 11  # every readable frame, the ones after it too
    # and the step over the skipped frame is measured whole: the path turns as the good bag's does (measured within
    # 0.4 %; a step lost would leave it 9 % short)
    assert abs(path.yaw[-1] / _path(world).yaw[-1] - 1) < 0.01


@pytest.mark.parametrize(
    ("name", "flag"),
    [
        ("duplicated", "stamp out of order"),
        ("out_of_order", "stamp out of order"),
        ("gappy", "frame gap"),
        ("textureless", "no texture"),
        ("black", "no texture"),
    ],
)
def test_frames_that_cannot_be_measured_are_flagged(world, tmp_path, capsys, name, flag):
    """Each such frame is flagged with its reason; a run that measured none of its steps is a flagged result."""
    out = tmp_path / "t.tum"
    nothing = name in ("textureless", "black")
    words = ["flagged: measured 0 of 11 steps"] if nothing else []
    check(capsys, [world.root, tmp_path], ["run", world.bag(name), "--config", world.config, "--out", out],
          1 if nothing else 0, f": {flag}", *words)
    assert flag in summary(out)["flags"]
    assert ("flagged" in summary(out)) == nothing


def test_a_run_that_measured_nothing_never_replaces_a_good_trajectory(world, tmp_path, capsys):
    out = tmp_path / "good.tum"
    out.write_text("# a good trajectory\n")
    check(capsys, [world.root, tmp_path], ["run", world.bag("black"), "--config", world.config, "--out", out], 1,
          "measured 0 of 11 steps", f"{out} is kept", "--force")
    assert out.read_text() == "# a good trajectory\n"
    assert summary(tmp_path / "good.flagged.tum")["flagged"] == "measured 0 of 11 steps between frames"


@pytest.mark.parametrize(
    ("name", "words"),
    [
        ("no_odometry", [f"no topic {ODOMETRY_TOPIC} for the tracking camera's odometry"]),
        ("no_tf_static", ["has no topic /tf_static"]),
        ("nan_odometry", ["finite"]),
    ],
)
def test_fused_checks_its_second_source_before_the_first_frame(world, tmp_path, capsys, monkeypatch, name, words):
    monkeypatch.setattr(gpo.pipeline.run, "odometry", lambda *a, **k: pytest.fail("frames were read"))
    check(capsys, [world.root, tmp_path], ["run", world.bag(name), "--config", world.config, "--method", "fused",
                                           "--out", tmp_path / "t.tum"], 1, *words)
    assert not (tmp_path / "t.tum").exists()


def test_fused_with_jumping_poses_still_gives_a_path(world, tmp_path, capsys):
    """The tracking camera stands still but for a 5 m jump at frame 6: the filter refuses the steps into and out of
    the jump, and the path is the one the camera standing still throughout gives (within 0.1 micrometre and 0.4
    millidegrees measured: the still camera's two steps there are fused)."""
    still = write_bag(tmp_path / "still.bag", poses=lambda i: [0.0, 0.0, 0.0])
    expected = gpo.pipeline.run.run(still, load_config(world.config).replace(method="fused"), progress=False)
    out = tmp_path / "t.tum"
    check(capsys, [world.root, tmp_path], ["run", world.bag("jumping_odometry"), "--config", world.config, "--method",
                                           "fused", "--out", out], 0, f"wrote {out}")
    refused = summary(out)["fusion"]["refused_by_nis_gate"]
    assert refused == expected.summary()["fusion"]["refused_by_nis_gate"] + 2
    path = Trajectory.read_tum(out)
    np.testing.assert_allclose(path.positions, expected.trajectory.positions, rtol=0, atol=1e-6)
    np.testing.assert_allclose(np.degrees(path.yaw), np.degrees(expected.trajectory.yaw), rtol=0, atol=1e-3)


def test_a_fusion_that_fails_late_still_writes_the_floor_odometry(world, tmp_path, capsys, monkeypatch):
    def failing(*args, **kwargs):
        raise ValueError("the filter diverged")

    floor = _path(world)  # the config's fusion.floor_method, gpo-exact
    monkeypatch.setattr(gpo.pipeline.run, "fuse", failing)
    out = tmp_path / "t.tum"
    check(capsys, [world.root, tmp_path], ["run", world.bag(), "--config", world.config, "--method", "fused", "--out",
                                           out], 1, "the floor odometry is the result: the filter diverged")
    kept = "fusion failed, the floor odometry is the result"
    assert kept in summary(out)["stopped_early"]
    np.testing.assert_array_equal(Trajectory.read_tum(out).positions, floor.positions)  # every one of its 12 poses


def _path(world: World, name: str = "good", method: str = "gpo-exact") -> Trajectory:
    """The path of a run of bag ``name`` by ``method``, through the library: what a whole run writes."""
    config = load_config(world.config).replace(method=method)
    return gpo.pipeline.run.run(world.bag(name), config, progress=False).trajectory


def _stop_after(count: int, exception: BaseException):
    real = Recording.frames

    def frames(self, *args, **kwargs):
        for index, item in enumerate(real(self, *args, **kwargs)):
            if index == count:
                raise exception
            yield item

    return frames


def test_a_flagged_run_never_replaces_a_good_trajectory(world, tmp_path, capsys, monkeypatch):
    whole = _path(world)
    out = tmp_path / "t.tum"
    out.write_text("# a good trajectory\n")
    monkeypatch.setattr(Recording, "frames", _stop_after(6, ValueError("message 6 is damaged")))
    check(capsys, [world.root, tmp_path], ["run", world.bag(), "--config", world.config, "--out", out], 1,
          "stopped early after 6 frames: message 6 is damaged", "is kept", "--force")
    assert out.read_text() == "# a good trajectory\n"
    np.testing.assert_array_equal(Trajectory.read_tum(tmp_path / "t.flagged.tum").positions, whole.positions[:6])


def test_force_lets_a_flagged_run_replace_the_file(world, tmp_path, capsys, monkeypatch):
    out = tmp_path / "t.tum"
    out.write_text("# a good trajectory\n")
    whole = _path(world)
    monkeypatch.setattr(Recording, "frames", _stop_after(6, ValueError("message 6 is damaged")))
    check(capsys, [world.root, tmp_path], ["run", world.bag(), "--config", world.config, "--out", out, "--force"], 1,
          f"wrote {out}", changed=[out])
    np.testing.assert_array_equal(Trajectory.read_tum(out).positions, whole.positions[:6])


@pytest.mark.parametrize("done", [0, 5])
def test_ctrl_c_keeps_the_frames_done(world, tmp_path, capsys, monkeypatch, done):
    whole = _path(world)
    out = tmp_path / "t.tum"
    monkeypatch.setattr(Recording, "frames", _stop_after(done, KeyboardInterrupt()))
    check(capsys, [world.root, tmp_path], ["run", world.bag(), "--config", world.config, "--out", out], 130,
          f"interrupted after {done} frames")
    assert summary(out)["interrupted"] is True
    np.testing.assert_array_equal(Trajectory.read_tum(out).positions.reshape(-1, 3), whole.positions[:done])


SLOW_MAIN = """
import sys, time
import gpo.pipeline.odometer
import gpo.pipeline.run
step = gpo.pipeline.odometer.FloorOdometer.step
gpo.pipeline.odometer.FloorOdometer.step = lambda self, *args: (time.sleep(0.25), step(self, *args))[1]
from gpo.cli import main
sys.exit(main(sys.argv[1:]))
"""


def _as_from_a_terminal():
    """In the child, before it starts: Ctrl-C's default disposition, as a command typed in a terminal has it (a test
    process may run with SIGINT ignored, which its children inherit, and Python then installs no handler for it)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_to_the_process_keeps_the_frames_done(world, tmp_path, signum):
    """A real process, its frames slowed to 4 a second, is sent the signal while it reads them."""
    out = tmp_path / "t.tum"
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).parents[1])}
    arguments = ["run", world.bag(), "--config", world.config, "--out", out]
    command = [sys.executable, "-c", SLOW_MAIN, *map(str, arguments)]
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env, text=True,
                               preexec_fn=_as_from_a_terminal)
    seen = ""  # the progress bar counts frames read, and from two threads on they are read a few ahead
    while not re.search(r"\| *([2-9]|1[01])/12", seen) and process.poll() is None:
        seen += process.stderr.read(1)
    process.send_signal(signum)
    _, err = process.communicate(timeout=60)
    assert process.returncode == 130, seen + err
    assert "Traceback" not in err and "interrupted after" in err
    done = summary(out)
    assert done["interrupted"] is True and 0 < done["frames"] < 12
    assert len(Trajectory.read_tum(out)) == done["frames"]


def _signal_after(count: int, signum: int):
    """Frames as the bag holds them, the process sent ``signum`` as frame ``count`` is read."""
    real = Recording.frames

    def frames(self, *args, **kwargs):
        for index, item in enumerate(real(self, *args, **kwargs)):
            if index == count:
                os.kill(os.getpid(), signum)
            yield item

    return frames


@pytest.mark.parametrize("first", [signal.SIGINT, signal.SIGTERM])
@pytest.mark.parametrize("when", ["before the files", "while they are written"])
def test_a_second_signal_never_costs_the_frames_done(world, tmp_path, capsys, monkeypatch, first, when):
    """Two Ctrl-C (or SIGTERM) in quick succession: the second, before the partial result is written or while it
    is, is waited out; the frames done are written whole and the run exits 130."""
    whole = _path(world)
    second = signal.SIGTERM if first == signal.SIGINT else signal.SIGINT
    monkeypatch.setattr(Recording, "frames", _signal_after(5, first))
    if when == "before the files":
        shown = gpo.cli.run.print_run
        monkeypatch.setattr(gpo.cli.run, "print_run", lambda result: (os.kill(os.getpid(), second), shown(result)))
    else:
        write_tum = Trajectory.write_tum
        monkeypatch.setattr(Trajectory, "write_tum",
                            lambda self, path: (os.kill(os.getpid(), second), write_tum(self, path))[1])
    out = tmp_path / "t.tum"
    check(capsys, [world.root, tmp_path], ["run", world.bag(), "--config", world.config, "--out", out, "--threads",
                                           "1"], 130, "interrupted after 5 frames", f"wrote {out}")
    assert summary(out)["interrupted"] is True
    np.testing.assert_array_equal(Trajectory.read_tum(out).positions, whole.positions[:5])


def test_an_interrupted_fused_run_says_it_was_not_fused(world, tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(Recording, "frames", _stop_after(5, KeyboardInterrupt()))
    out = tmp_path / "t.tum"
    check(capsys, [world.root, tmp_path], ["run", world.bag(), "--config", world.config, "--method", "fused", "--out",
                                           out], 130, "interrupted after 5 frames", "not fused: interrupted before "
          "the fusion: the trajectory is the floor odometry of gpo-exact alone")
    assert summary(out)["method"] == "fused" and "not_fused" in summary(out)["fusion"]
    np.testing.assert_array_equal(Trajectory.read_tum(out).positions, _path(world).positions[:5])


WHILE_IMPORTING = """
import builtins, os, runpy, signal, sys
signum, imported = int(sys.argv[1]), builtins.__import__

def importing(name, *args, **kwargs):  # the signal as the command's modules import numpy, at its first instant
    if name == "numpy" and "numpy" not in sys.modules:
        os.kill(os.getpid(), signum)
    return imported(name, *args, **kwargs)

builtins.__import__ = importing
sys.argv = ["gpo", *sys.argv[2:]]
runpy.run_module("gpo", run_name="__main__", alter_sys=True)
"""


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_while_the_command_starts_exits_130_without_a_traceback(world, signum):
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).parents[1])}
    done = subprocess.run([sys.executable, "-c", WHILE_IMPORTING, str(int(signum)), "info", str(world.bag())],
                          capture_output=True, text=True, env=env, preexec_fn=_as_from_a_terminal, timeout=120)
    assert done.returncode == 130 and done.stderr == "interrupted\n", (done.returncode, done.stderr)


# ------------------------------------------------------------------------------------------------------ configs


def _config(world: World, folder: Path, edit) -> Path:
    document = yaml.safe_load(world.config.read_text())
    edit(document)
    path = folder / "bad.yaml"
    path.write_text(yaml.safe_dump(document, sort_keys=False))
    return path


def _set(path: str, value):
    def edit(document):
        *sections, key = path.split(".")
        for section in sections:
            document = document[section]
        document[key] = value

    return edit


def _rename(path: str, new: str):
    def edit(document):
        *sections, key = path.split(".")
        for section in sections:
            document = document[section]
        document[new] = document.pop(key)

    return edit


def _delete(path: str):
    def edit(document):
        *sections, key = path.split(".")
        for section in sections:
            document = document[section]
        del document[key]

    return edit


@pytest.mark.parametrize(
    ("edit", "words"),
    [
        (_rename("odometry", "odometery"), ["odometery: unknown key; did you mean odometry?"]),
        (_rename("klt.max_corners", "max_corner"), ["klt.max_corner: unknown key; did you mean max_corners?"]),
        (_rename("kinematics.wheelbase_m", "wheelbase"), ["kinematics.wheelbase: unknown key", "wheelbase_m?"]),
        (_rename("mount.position_m", "position"), ["mount.position_m: missing", "mount.position: unknown key"]),
        (_rename("fusion.tracking_topic", "tracking_topik"), ["did you mean tracking_topic?"]),
        (_rename("floor_image.metres_per_pixel", "metre_per_pixel"), ["did you mean metres_per_pixel?"]),
        (_set("klt.max_corners", "many"), ["klt.max_corners: expected a whole number (got 'many')"]),
        (_set("floor_image", [1, 2]), ["floor_image: expected a mapping of its keys (got [1, 2])"]),
        (_set("rate_hz", float("nan")), ["rate_hz must be a number over 0 to 1000 Hz, got nan"]),
        (_set("fusion.accel_mps2", float("inf")), ["fusion.accel_mps2", "finite number"]),
        (_set("rate_hz", -30.0), ["rate_hz must be a number over 0 to 1000 Hz, got -30.0"]),
        (_set("klt.window_px", 4), ["klt.window_px must be an odd whole number from 5 to 101 px, got 4"]),
        (_set("klt.max_corners", 10**8), ["klt.max_corners must be a whole number from 1 to 10000 corners"]),
        (_set("klt.min_distance_px", 1e30), ["klt.min_distance_px must be a number from 0 to 1000 px, got 1e+30"]),
        (_set("floor_image.metres_per_pixel", 0), ["floor_image.metres_per_pixel must be a number from 1e-05"]),
        (_set("camera.intrinsics", [0.6, 1.1, "thirty", 71.5, 106.0, 100.0]), ["camera.intrinsics.2", "'thirty'"]),
        (_set("camera.resolution", [212, 200, 3]), ["camera.resolution", "at most 2 items"]),
        (_set("camera.camera_model", "fisheye-9000"), ["camera", "unsupported camera model 'fisheye-9000'"]),
        (_set("mount.quaternion_xyzw", [0, 0, 0, 0]), ["mount.quaternion_xyzw", "all zeros"]),
        (_set("mount.rpy_deg", [0, 6]), ["mount.rpy_deg.2: missing"]),
        (_delete("mount"), ["mount: missing"]),
        (_delete("camera"), ["give either 'camera'", "or 'camchain'"]),
        (_set("odometry.method", "fastest"), ["unknown method 'fastest'"]),
        (_set("fusion.floor_method", "magic"), ["fusion.floor_method must be one of"]),
        (_set("floor_image.route", "scenic"), ["unknown route 'scenic'"]),
        (_set("features.detector", "surf"), ["features", "detector must be one of"]),
        (_set("topics", "camera"), ["topics: expected a mapping of its keys (got 'camera')"]),
        (_set("camchain", "."), ["give either 'camera'"]),
    ],
)
def test_config_errors_name_the_file_and_the_key(world, tmp_path, capsys, edit, words):
    config = _config(world, tmp_path, edit)
    check(capsys, [world.root, tmp_path], ["run", world.bag(), "--config", config, "--out", tmp_path / "t.tum"], 1,
          str(config), *words)
    assert not (tmp_path / "t.tum").exists()


@pytest.mark.parametrize(
    ("edit", "words"),
    [  # each key, its value, its range and unit: what no real rig has
        (_set("rate_hz", 1e6), ["rate_hz must be a number over 0 to 1000 Hz, got 1000000.0"]),
        (_set("camera.resolution", [10**6, 200]), ["camera.resolution.0 must be a whole number from 1 to 20000 px"]),
        (_set("mount.position_m", [0.6, 0.0, 12.0]), ["mount.position_m.2 must be a number over 0 to 5 m above the "
                                                      "floor, got 12.0"]),
        (_set("mount.position_m", [1e4, 0.0, 0.12]), ["mount.position_m.0 must be a number from -50 to 50 m"]),
        (_set("mount.rpy_deg", [1.5, 6e3, 0.0]), ["mount.rpy_deg.1 must be a number from -360 to 360 deg, got 6000.0"]),
        (_set("floor_image.x_range_m", [0.7, 1e6]), ["floor_image.x_range_m.1 must be a number from -50 to 50 m"]),
        (_set("floor_image.metres_per_pixel", 5.0), ["floor_image.metres_per_pixel", "to 0.1 m, got 5.0"]),
        (_set("kinematics.wheelbase_m", 1e3), ["kinematics.wheelbase_m must be a number over 0 to 20 m, got 1000.0"]),
        (_set("odometry.max_gap_s", 1e9), ["odometry.max_gap_s must be a number over 0 to 60 s"]),
        (_set("fusion.tracking_position_walk_m_per_sqrt_s", 1e3),
         ["fusion.tracking_position_walk_m_per_sqrt_s must be a number from 0 to 10 m/sqrt(s), got 1000.0"]),
        (_set("fusion.floor_reference_inliers", 0), ["fusion.floor_reference_inliers must be a whole number from 1"]),
        (_set("fusion.tracking_mount", {"position_m": [0.6, 0, 1e5], "rpy_deg": [0, 0, 0]}),
         ["fusion.tracking_mount.position_m must be 3 numbers from -50 to 50 m"]),
        (_set("features.cardinality", 10**9), ["features.cardinality must be None or a whole number from 3 to 10000"]),
    ],
)
def test_a_number_no_real_rig_has_is_refused_with_its_range_and_unit(world, tmp_path, capsys, monkeypatch, edit,
                                                                     words):
    monkeypatch.setattr(gpo.pipeline.run, "odometry", lambda *a, **k: pytest.fail("frames were read"))
    config = _config(world, tmp_path, edit)
    check(capsys, [world.root, tmp_path], ["run", world.bag(), "--config", config, "--out", tmp_path / "t.tum"], 1,
          str(config), *words)


def test_a_floor_image_of_terabytes_is_refused_before_it_is_made(world, tmp_path, capsys, monkeypatch):
    """An extent each of whose numbers is in range, at a pixel in range, still makes too many pixels: named with
    its keys before a table is built (the remap table's build would ask for terabytes)."""
    monkeypatch.setattr(gpo.pipeline.run, "odometry", lambda *a, **k: pytest.fail("frames were read"))
    config = _config(world, tmp_path, _set("floor_image", {"x_range_m": [-40, 40], "y_range_m": [-40, 40],
                                                           "metres_per_pixel": 1e-5}))
    check(capsys, [world.root, tmp_path], ["run", world.bag(), "--config", config, "--out", tmp_path / "t.tum"], 1,
          str(config), "floor_image: x_range [-40.0, 40.0] m", "8000000 x 8000000 pixels, over the 16000000 allowed")


def test_a_missing_camchain_names_the_config_and_its_key(world, tmp_path, capsys):
    def edit(document):
        del document["camera"]
        document["camchain"] = "calib/camchain.yaml"

    config = _config(world, tmp_path, edit)
    _, err = check(capsys, [world.root, tmp_path], ["run", world.bag(), "--config", config, "--out",
                                                    tmp_path / "t.tum"], 1,
                   f"{config}: camchain calib/camchain.yaml: no file {tmp_path / 'calib' / 'camchain.yaml'}")
    assert "Errno" not in err


@pytest.mark.parametrize(
    ("text", "words"),
    [
        ("name: [t265\ncamera: }\n", ["line 2", "not valid YAML"]),
        ("name: t265\n  mount: 1\n", ["line 2", "not valid YAML"]),
        ("", ["a config is a YAML mapping", "NoneType"]),
        ("- a list\n- of things\n", ["a config is a YAML mapping", "list"]),
        (b"\x89PNG\r\n\x1a\n\x00\x00\xff\xfe", ["not a text file"]),
        ("!!float", ["not valid YAML", "a value tagged !!int, !!float, !!bool or !!timestamp is empty"]),
    ],
)
def test_config_files_that_are_not_configs(world, tmp_path, capsys, text, words):
    config = tmp_path / "bad.yaml"
    config.write_bytes(text if isinstance(text, bytes) else text.encode())
    check(capsys, [world.root, tmp_path], ["run", world.bag(), "--config", config, "--out", tmp_path / "t.tum"], 1,
          str(config), *words)


def test_an_alias_bomb_is_refused_at_once(world, tmp_path, capsys):
    lines = ['a: &a ["lol","lol","lol","lol","lol","lol","lol","lol","lol"]']
    lines += [f"{chr(98 + i)}: &{chr(98 + i)} [{', '.join([f'*{chr(97 + i)}'] * 9)}]" for i in range(9)]
    config = tmp_path / "bomb.yaml"
    config.write_text("\n".join(lines) + "\n")
    check(capsys, [world.root, tmp_path], ["run", world.bag(), "--config", config, "--out", tmp_path / "t.tum"], 1,
          "aliases expand to more than")  # counted on the YAML's nodes, before a billion strings are built


def test_a_camchain_that_is_a_folder(world, tmp_path, capsys):
    def edit(document):
        del document["camera"]
        document["camchain"] = "."

    config = _config(world, tmp_path, edit)
    check(capsys, [world.root, tmp_path], ["run", world.bag(), "--config", config, "--out", tmp_path / "t.tum"], 1,
          str(config), "camchain . is a folder; expected a Kalibr camchain YAML file")


@pytest.mark.parametrize("kind", ["folder", "missing"])
def test_a_config_that_is_no_file(world, tmp_path, capsys, kind):
    config = tmp_path / "rig.yaml"
    if kind == "folder":
        config.mkdir()
    words = ["is a folder; expected a YAML file"] if kind == "folder" else ["no file", "expected a YAML file"]
    check(capsys, [world.root, tmp_path], ["run", world.bag(), "--config", config, "--out", tmp_path / "t.tum"], 1,
          *words)


# ------------------------------------------------------------------------------------------------------ evaluate


@pytest.mark.parametrize(
    ("lines", "words"),
    [
        ([f"{100 + i} {i} 0 0 0 0 0 1" for i in range(20)], ["do not overlap"]),
        (["1.0 0 0 0 0 0 0 1", "what is this", "1.2 0 0 0 0 0 0 1"], [":2: a TUM line has 8 numbers"]),
        (["1.0 0 0 0 0 0 0 1", "1.1 zero 0 0 0 0 0 1"], [":2: not a number"]),
        (["1.0 0 0 0 0 0 0 1", "1.1000000000.99 0 0 0 0 0 0 1"], [":2: the stamp '1.1000000000.99' is not a time"]),
        ([f"{1 + 0.1 * i:.1f} nan 0 0 0 0 0 1" for i in range(5)], ["must be finite numbers"]),
        ([], ["holds no poses"]),
        (["1.0 0 0 0 0 0 0 1", "1.2 0 0 0 0 0 0 1", "1.1 0 0 0 0 0 0 1"], [":3: '1.1 0 0 0 0 0 0 1': the stamps go "
                                                                             "backwards"]),
        (["1.0 0 0 0 0 0 0 1", "1.1 0 0 0 0 0 0 0"], [":2: '1.1 0 0 0 0 0 0 0': the quaternion", "zero length"]),
    ],
)
def test_evaluate_names_what_is_wrong_with_the_estimate(world, tmp_path, capsys, lines, words):
    """Lines are counted from 1, as editors count them."""
    estimate = world.tum("estimate.tum", lines)
    check(capsys, [world.root, tmp_path], ["evaluate", estimate, world.truth()], 1, str(estimate), *words)


def test_evaluate_refuses_a_repeated_stamp_with_another_pose(world, tmp_path, capsys):
    lines = [f"{1 + 0.1 * i:.1f} {0.1 * i:.3f} 0 0 0 0 0 1" for i in range(30)]
    estimate = world.tum("repeated.tum", [*lines[:10], "1.9 5.9 0 0 0 0 0 1", *lines[10:]])
    check(capsys, [world.root, tmp_path], ["evaluate", estimate, world.truth()], 1,
          "stamp 1.900000000 s repeats with another pose (5.000 m away)")


def test_evaluate_reads_a_pose_repeated_as_it_was_once(world, tmp_path, capsys):
    lines = [f"{1 + 0.1 * i:.1f} {0.1 * i:.3f} 0 0 0 0 0 1" for i in range(30)]
    estimate = world.tum("same.tum", lines[:10] + lines[9:])
    check(capsys, [world.root, tmp_path], ["evaluate", estimate, world.truth()], 0, "poses associated        30")


@pytest.mark.parametrize("given", ["bag", "bag_named_tum"])
def test_evaluate_names_a_bag_given_as_the_estimate(world, tmp_path, capsys, given):
    estimate = world.bag()
    if given == "bag_named_tum":
        estimate = tmp_path / "estimate.tum"
        estimate.write_bytes(world.bag().read_bytes())
    _, err = check(capsys, [world.root, tmp_path], ["evaluate", estimate, world.truth()], 1,
                   f"{estimate} is a ROS bag, not a TUM text file", "gpo run --out")
    assert "codec" not in err and "utf-8" not in err


def test_evaluate_against_a_truth_that_stands_still(world, tmp_path, capsys):
    """No distance travelled: the final error in per cent of it is undefined (it was a ZeroDivisionError)."""
    still = world.tum("still.tum", [f"{1 + 0.1 * i:.1f} 0 0 0 0 0 0 1" for i in range(30)])
    check(capsys, [world.root, tmp_path], ["evaluate", world.truth(), still], 0, "distance (truth)        0.000 m",
          "final position error    2900.0 mm = nan % of the distance")  # the estimate ends 2.9 m from the start


def test_evaluate_names_bag_and_topic_of_a_truth_with_nan(world, tmp_path, capsys):
    bag = tmp_path / "nan_truth.bag"
    with BagWriter(bag) as writer:
        for i in range(6):
            writer.add_pose("/mocap/base_link", START_NS + i * FRAME_NS, [np.nan if i == 3 else 0.01 * i, 0.0, 0.0],
                            [0, 0, 0, 1], "world")
    check(capsys, [world.root, tmp_path], ["evaluate", world.truth(), bag, "--gt-topic", "/mocap/base_link"], 1,
          f"{bag}, topic /mocap/base_link: 1 of 6 poses hold NaN or infinite numbers, the first at message 4, stamp "
          "1700000000.099999999 s")


def test_evaluate_names_bag_and_topic_of_a_truth_with_a_quaternion_of_zero_length(world, tmp_path, capsys):
    """Found by the campaign (seeds 49111-49333): the Trajectory's refusal named neither the bag nor the topic."""
    bag = tmp_path / "zero_quaternion.bag"
    with BagWriter(bag) as writer:
        for i in range(6):
            writer.add_pose("/mocap/base_link", START_NS + i * FRAME_NS, [0.01 * i, 0.0, 0.0],
                            [0, 0, 0, 0.0 if i == 3 else 1], "world")
    check(capsys, [world.root, tmp_path], ["evaluate", world.truth(), bag, "--gt-topic", "/mocap/base_link"], 1,
          f"{bag}, topic /mocap/base_link: quaternion 3 has zero length")


@pytest.mark.parametrize("delta", ["0", "-1", "nan", "inf", "one"])
def test_evaluate_refuses_a_bad_delta_as_usage(world, tmp_path, capsys, delta):
    check(capsys, [world.root, tmp_path], ["evaluate", world.truth(), world.truth(), "--delta", delta], 2,
          "--delta", repr(delta))


@pytest.mark.parametrize("onto", ["estimate", "truth", "folder", "format"])
def test_evaluate_checks_the_plot_before_working(world, tmp_path, capsys, onto):
    estimate = world.tum("estimate_ok.tum", [f"{1 + 0.1 * i:.1f} {0.1 * i:.3f} 0 0 0 0 0 1" for i in range(30)])
    truth = world.truth()
    plot = {"estimate": estimate, "truth": truth, "folder": tmp_path, "format": tmp_path / "plot.xyz"}[onto]
    words = {"folder": "is a folder", "format": "name a file ending in one of"}.get(onto, "is an input")
    out, _ = check(capsys, [world.root, tmp_path], ["evaluate", estimate, truth, "--plot", plot], 1, "--plot", words)
    assert "alignment" not in out  # nothing evaluated


def test_evaluate_plot_on_a_full_disk_leaves_nothing_half_written(world, tmp_path, capsys, monkeypatch):
    import matplotlib.figure

    def full(self, path, **kwargs):
        Path(path).write_bytes(b"\x89PNG half")
        raise OSError(28, "No space left on device", str(path))

    monkeypatch.setattr(matplotlib.figure.Figure, "savefig", full)
    plot = tmp_path / "plot.png"
    plot.write_bytes(b"\x89PNG an earlier plot")
    check(capsys, [world.root, tmp_path], ["evaluate", world.truth(), world.truth(), "--plot", plot], 1,
          f"{plot}: the disk is full", "the file already there is kept")


@pytest.mark.parametrize(
    ("arguments", "words"),
    [
        (["missing.tum", "truth"], ["missing.tum"]),
        (["folder", "truth"], ["is a folder; expected a TUM file"]),
        (["truth", "bag"], ["is a recording: name its ground-truth topic with --gt-topic"]),
        (["truth", "bag", "--gt-topic", "/mocap/base"], ["has no topic /mocap/base", "did you mean /mocap/base_link"]),
        (["truth", "truth", "--gt-topic", "/mocap"], ["--gt-topic /mocap names a bag's topic"]),
    ],
)
def test_evaluate_names_a_missing_or_wrong_file(world, tmp_path, capsys, arguments, words):
    (tmp_path / "folder").mkdir()
    named = {"truth": world.truth(), "bag": world.bag(), "folder": tmp_path / "folder"}
    argv = [named.get(a, tmp_path / a if a.endswith(".tum") else a) for a in arguments]
    check(capsys, [world.root, tmp_path], ["evaluate", *argv], 1, *words)


# ----------------------------------------------------------------------------------------------------- calibrate


def _images(folder: Path, images: list[np.ndarray]) -> list[Path]:
    paths = []
    for index, image in enumerate(images):
        paths.append(folder / f"view{index}.png")
        cv2.imwrite(str(paths[-1]), image)
    return paths


@pytest.mark.parametrize(
    ("views", "board", "words"),
    [
        ("two", "7x5", ["only 2 usable view(s)", "at least 3"]),
        ("blank", "7x5", ["no chessboard of 7x5 inner corners", "found in any of the 3 images"]),
        ("two", "9x7", ["no chessboard of 9x7 inner corners"]),
        ("two", "8x6", ["shows a board of 7x5 inner corners", "--board 7x5", "partly hidden"]),
        ("nine", "7x5", ["view1.png shows a board of 9x6 inner corners, more than the 7x5 given: give --board 9x6"]),
        ("nine", "6x4", ["view0.png shows a board of 9x6 inner corners, more than the 6x4 given: give --board 9x6"]),
        ("nine", "10x7", ["view0.png shows a board of 9x6 inner corners", "if 10x7 counted the board's squares, give "
                                                                           "--board 9x6"]),
        ("mixed", "7x5", ["calibrate images of one camera at one resolution"]),
        ("text", "7x5", ["not an image that OpenCV can read"]),
        ("missing", "7x5", ["no such image file"]),
        ("two", "7by5", ["expected inner corners per row x per column"]),
    ],
)
def test_calibrate_names_what_is_wrong_with_the_views(tmp_path, capsys, views, board, words):
    if views == "text":
        (tmp_path / "view0.png").write_text("not a picture")
        paths = [tmp_path / "view0.png"]
    elif views == "missing":
        paths = [tmp_path / "nowhere.png"]
    else:
        images = {
            "two": [board_image(seed=0), board_image(seed=1, shift=(10, 5))],
            "blank": [np.full((240, 320), 255, np.uint8) for _ in range(3)],
            "mixed": [board_image(seed=0), board_image(size=(200, 300), seed=1)],
            "nine": [board_image(corners=(9, 6), seed=i, shift=(10 * i, 5 * i)) for i in range(3)],
        }[views]
        paths = _images(tmp_path, images)
    out = tmp_path / "calib.yaml"
    printed, err = check(capsys, [tmp_path], ["calibrate", *paths, "--board", board, "--square", "0.03", "--out", out],
                         1, *words)
    assert not out.exists()
    if views == "nine":  # the board's part that a smaller pattern finds is never offered: it gives a garbage fit
        assert "--board 6x4" not in printed + err.replace("the 6x4 given", "")


@pytest.mark.parametrize(
    ("arguments", "code", "words"),
    [
        (["--square", "0"], 2, ["--square", "expected a finite number > 0"]),
        (["--square", "-0.03"], 2, ["--square"]),
        (["--model", "kb9"], 2, ["invalid choice: 'kb9'"]),
        (["--out", "view0.png"], 1, ["is an input of this command"]),
        (["--out", "."], 1, ["is a folder"]),
    ],
)
def test_calibrate_checks_its_options_before_working(tmp_path, capsys, monkeypatch, arguments, code, words):
    paths = _images(tmp_path, [board_image(seed=0)])
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(gpo.cli.calibrate, "calibrate_images", lambda *a, **k: pytest.fail("calibrated"))
    options = {"--board": "7x5", "--square": "0.03", **dict(zip(arguments[::2], arguments[1::2], strict=True))}
    argv = ["calibrate", *paths, *[item for pair in options.items() for item in pair]]
    check(capsys, [tmp_path], argv, code, *words)


def _fit(ok: bool):
    def calibrate_images(*args, **kwargs):
        verdict = "good" if ok else "NOT A GOOD CALIBRATION"
        warnings = [] if ok else ["RMS reprojection error 4.44 px > 1 px"]
        return SimpleNamespace(ok=ok, camera=T265_LIKE, summary=lambda: f"eucm calibration ({verdict})",
                               warnings=warnings)

    return calibrate_images


def test_a_bad_fit_never_replaces_a_good_calibration(tmp_path, capsys, monkeypatch):
    paths = _images(tmp_path, [board_image(seed=0)])
    good = tmp_path / "calib.yaml"
    good.write_text("cam0: {camera_model: eucm}  # the good one\n")
    monkeypatch.setattr(gpo.cli.calibrate, "calibrate_images", _fit(ok=False))
    check(capsys, [tmp_path], ["calibrate", *paths, "--board", "7x5", "--square", "0.03", "--out", good], 1,
          "NOT A GOOD CALIBRATION", f"{good} is kept", "calib.flagged.yaml")
    flagged = (tmp_path / "calib.flagged.yaml").read_text()
    assert "camera_model: eucm" in flagged  # the file carries its flag, each warning, as comments before the camera
    assert flagged.startswith("# flagged by gpo calibrate: NOT A GOOD CALIBRATION (eucm calibration (NOT A GOOD")
    assert "# WARNING: RMS reprojection error 4.44 px > 1 px\n" in flagged


def test_force_and_a_good_fit_replace_the_calibration(tmp_path, capsys, monkeypatch):
    paths = _images(tmp_path, [board_image(seed=0)])
    old = tmp_path / "calib.yaml"
    for ok, extra in ((False, ["--force"]), (True, [])):
        old.write_text("cam0: {}\n")
        monkeypatch.setattr(gpo.cli.calibrate, "calibrate_images", _fit(ok=ok))
        check(capsys, [tmp_path], ["calibrate", *paths, "--board", "7x5", "--square", "0.03", "--out", old, *extra],
              0 if ok else 1, f"wrote {old}", changed=[old])
        assert "intrinsics" in old.read_text()


# ------------------------------------------------------------------------------------------------------ simulate


@pytest.mark.parametrize(
    ("out", "arguments", "code", "words"),
    [
        ("existing.bag", [], 1, ["exists; name a new bag"]),
        ("folder", ["--format", "ros2"], 1, ["exists; name a new bag"]),
        ("sim.txt", [], 1, ["a ros1 bag is one file named *.bag"]),
        ("sim.bag", ["--format", "ros2"], 1, ["a ros2 bag is a folder", "name it sim, say"]),
        ("sim.db3", ["--format", "ros2"], 1, ["a ros2 bag is a folder", "named neither *.bag nor *.db3 or *.mcap"]),
        ("sim.bag", ["--format", "ros3"], 2, ["invalid choice: 'ros3'"]),
    ],
)
def test_simulate_checks_its_output_before_rendering(tmp_path, capsys, monkeypatch, out, arguments, code, words):
    (tmp_path / "existing.bag").write_bytes(b"an earlier bag")
    (tmp_path / "folder").mkdir()
    monkeypatch.setattr("gpo.sim.record.simulate", lambda *a, **k: pytest.fail("rendered"))  # imported when run
    check(capsys, [tmp_path], ["simulate", "--preset", "test", "--out", tmp_path / out, *arguments], code, *words)


def test_simulate_refuses_an_unknown_preset_as_usage(tmp_path, capsys):
    check(capsys, [tmp_path], ["simulate", "--preset", "marathon", "--out", tmp_path / "x.bag"], 2,
          "invalid choice: 'marathon'")


# ------------------------------------------------------------------------------------------------ the exit codes


def test_the_help_documents_the_exit_codes(capsys):
    assert main(["--help"]) == 0
    text = capsys.readouterr().out
    for line in ("0    done", "1    bad input", "2    usage", "130  interrupted", "--debug"):
        assert line in text


def test_debug_shows_the_traceback(world, tmp_path):
    config = tmp_path / "rig.yaml"
    config.mkdir()
    with pytest.raises(ValueError, match="is a folder"):
        main(["--debug", "run", str(world.bag()), "--config", str(config), "--out", str(tmp_path / "t.tum")])


def test_an_unexpected_error_is_one_line_and_points_to_debug(world, tmp_path, capsys, monkeypatch):
    def broken(*args, **kwargs):
        raise MemoryError("out of memory")

    monkeypatch.setattr(gpo.pipeline.run, "odometry", broken)
    check(capsys, [world.root, tmp_path], ["run", world.bag(), "--config", world.config, "--out", tmp_path / "t.tum"],
          1, "error: MemoryError: out of memory", "--debug")
