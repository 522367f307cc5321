"""Trajectories and TUM files: exact round trips, the real rpg_trajectory_evaluation files, bad input."""

import re
from decimal import Decimal

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from gpo.io.trajectory import Trajectory, base_from_sensor_odometry


def test_tum_round_trip_keeps_every_nanosecond_and_value(tmp_path):
    rng = np.random.default_rng(0)
    stamps = np.cumsum(rng.integers(1, 10**8, 500)) + 1_700_000_000 * 10**9
    trajectory = Trajectory(stamps, rng.normal(size=(500, 3)), Rotation.random(500, rng=1).as_quat(), "odom", "cam")
    again = Trajectory.read_tum(trajectory.write_tum(tmp_path / "t.tum"), "odom", "cam")
    np.testing.assert_array_equal(again.stamps_ns, trajectory.stamps_ns)
    np.testing.assert_array_equal(again.positions, trajectory.positions)
    np.testing.assert_array_equal(again.quaternions, trajectory.quaternions)


def test_planar_heading_and_length():
    yaw = np.array([0.0, 0.5, -3.0, np.pi])
    trajectory = Trajectory.from_planar(np.arange(4), [0, 3, 3, 0], [0, 4, 0, 0], yaw)
    np.testing.assert_allclose(trajectory.yaw, [0.0, 0.5, -3.0, np.pi], atol=1e-12)
    assert trajectory.path_length == pytest.approx(5 + 4 + 3)


def test_compose_changes_frames_like_homogeneous_matrices():
    rng = np.random.default_rng(2)
    trajectory = Trajectory(np.arange(20), rng.normal(size=(20, 3)), Rotation.random(20, rng=3).as_quat())
    left = (Rotation.random(rng=4), rng.normal(size=3))
    right = (Rotation.random(rng=5), rng.normal(size=3))

    def matrix(rotation, translation):
        m = np.eye(4)
        m[:3, :3], m[:3, 3] = rotation.as_matrix(), translation
        return m

    composed = trajectory.compose(left, right, "w", "c")
    for i in range(20):
        expected = matrix(*left) @ matrix(trajectory.rotations[i], trajectory.positions[i]) @ matrix(*right)
        np.testing.assert_allclose(matrix(composed.rotations[i], composed.positions[i]), expected, atol=1e-12)
    assert (composed.frame_id, composed.child_frame_id) == ("w", "c")


def test_sensor_odometry_of_a_rigid_mount_gives_back_the_base_path():
    """A sensor rigidly mounted on the robot, its odometry built independently from the base path, maps back."""
    rng = np.random.default_rng(6)
    base = Trajectory(np.arange(50), rng.normal(size=(50, 3)), Rotation.random(50, rng=7).as_quat(), "world")
    mount = (Rotation.random(rng=8), rng.normal(size=3))
    sensor_rotations = base.rotations * mount[0]
    sensor_positions = base.positions + base.rotations.apply(mount[1])
    first = sensor_rotations[0].inv()
    odometry = Trajectory(
        base.stamps_ns, first.apply(sensor_positions - sensor_positions[0]), (first * sensor_rotations).as_quat()
    )
    again = base_from_sensor_odometry(odometry, mount, (base.rotations[0], base.positions[0]))
    np.testing.assert_allclose(again.positions, base.positions, atol=1e-12)
    np.testing.assert_allclose(np.abs(np.sum(again.quaternions * base.quaternions, axis=1)), 1.0, atol=1e-12)


def test_reads_the_real_groundtruth_file(fetch_or_skip):
    run = "rpg_trajectory_evaluation/results/euroc_vislam_mono/laptop/vislam_ba/laptop_vislam_ba_V1_02"
    path = fetch_or_skip(f"{run}/stamped_groundtruth.txt")
    trajectory = Trajectory.read_tum(path)
    rows = [line.split() for line in path.read_text().splitlines() if line and not line.startswith("#")]
    assert len(trajectory) == len(rows)
    # the stamps are written to the nanosecond (1.403715524907143116e+09): the exact nanoseconds are the text's
    # decimal number times 1e9, which a float of seconds (53 bits, about 16 digits) cannot hold
    expected = [Decimal(row[0]).scaleb(9) for row in rows]
    assert all(stamp == stamp.to_integral_value() for stamp in expected)
    assert trajectory.stamps_ns.tolist() == [int(stamp) for stamp in expected]
    np.testing.assert_array_equal(trajectory.positions[0], [float(v) for v in rows[0][1:4]])


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ("1.0 2 3\n", ":1: a TUM line has 8 numbers"),
        ("1.0 0 0 0 0 0 0 one\n", ":1: not a number"),
        ("1.0 1_0 0 0 0 0 0 1\n", ":1: not a number"),
        ("# t x y z qx qy qz qw\n2 0 0 0 0 0 0 1\n1 0 0 0 0 0 0 1\n", ":3: '1 0 0 0 0 0 0 1': the stamps go backwards"),
        ("1 0 0 0 0 0 0 1\n\n2 0 0 0 0 0 0 0\n", ":3: '2 0 0 0 0 0 0 0': the quaternion .* has zero length"),
        ("1 0 0 0 0 0 0 1\n2 nan 0 0 0 0 0 1\n", ":2: '2 nan 0 0 0 0 0 1': positions and quaternions must be finite"),
        # found by the campaign (seeds 49111-49333): a length that overflows normalised every component to zero
        ("1 0 0 0 0 0 0 1\n2 0 0 0 0 -6e158 0 1\n", ":2: '2 0 0 0 0 -6e158 0 1': the quaternion .* too long"),
    ],
)
def test_bad_tum_files_name_the_line_counted_from_one(tmp_path, content, message):
    """The line numbers are the ones an editor shows: the first line is 1, comments and blank lines count."""
    path = tmp_path / "bad.tum"
    path.write_text(content)
    with pytest.raises(ValueError, match=f"^{re.escape(str(path))}{message}"):
        Trajectory.read_tum(path)


def test_a_file_that_is_not_text_is_named_not_decoded(tmp_path):
    bag = tmp_path / "estimate.tum"
    bag.write_bytes(b"#ROSBAG V2.0\n\xb3\x00\xff" * 10)  # a ROS1 bag's first bytes, whatever its name
    with pytest.raises(ValueError, match=r"estimate\.tum is a ROS bag, not a TUM text file") as raised:
        Trajectory.read_tum(bag)
    assert "codec" not in str(raised.value)
    noise = tmp_path / "noise.tum"
    noise.write_bytes(bytes(range(128, 256)))
    with pytest.raises(ValueError, match=r"noise\.tum is binary data, not a TUM text file"):
        Trajectory.read_tum(noise)


@pytest.mark.parametrize(
    ("stamp", "read_ns"),
    [
        ("9223372036.854775807", 2**63 - 1),  # the last nanosecond an int64 holds
        ("-9223372036.854775808", -(2**63)),
        ("9223372036.854775808", None),
        ("9" * 30, None),
        ("1e400", None),
        ("-1e19", None),
        ("1700000000.0100000000.99", None),  # two decimal points: no number
        ("1700000000.000000000abc", None),
        ("1_700_000_000.5", None),  # Python's literal, not a number of a TUM file
        ("\u0661\u0662", None),  # Arabic-Indic digits
        ("0x10", None),
        ("nan", None),
        ("-inf", None),
        ("1.5e+3", 1500 * 10**9),
        ("1700000000.1234567891234", 1_700_000_000_123_456_789),  # to the nearest nanosecond
        ("1700000000.1234567896", 1_700_000_000_123_456_790),
        (".5", 500_000_000),
        ("-0.000000001", -1),
    ],
)
def test_a_stamp_is_read_to_the_nanosecond_or_refused_with_its_line(tmp_path, stamp, read_ns):
    path = tmp_path / "far.tum"
    path.write_text(f"{stamp} 0 0 0 0 0 0 1\n")
    if read_ns is not None:
        assert Trajectory.read_tum(path).stamps_ns.tolist() == [read_ns]
        return
    with pytest.raises(ValueError, match=rf"far\.tum:1: the stamp '{stamp}' is not a time in seconds"):
        Trajectory.read_tum(path)
