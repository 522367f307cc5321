"""The odometry frame by frame as a robot's node runs it (``gpo.pipeline.live``), against the recorded run of the same
bag: the same floor records, the same fused path whatever order the two sources' messages arrive in; and the run on
two threads against the run on one (``gpo.io.ahead``)."""

import dataclasses
import math
import threading
from pathlib import Path

import numpy as np
import pytest

from gpo.fusion import FusionSettings, StreamingFusion, fuse
from gpo.io.ahead import read_ahead
from gpo.io.bag import Recording
from gpo.pipeline.config import load_config
from gpo.pipeline.live import LiveOdometer, RefusedMessage
from gpo.pipeline.odometer import FloorOdometer
from gpo.pipeline.run import odometry, run, tracking_mount
from gpo.sim.record import recording

STEP_NS = 5_000_000  # the tracking camera's 200 Hz
DOWNWARD = Path(__file__).resolve().parents[1] / "gpo" / "configs" / "sim_downward.yaml"


@pytest.fixture(scope="module")
def bag():
    return recording("test", progress=False)


@pytest.fixture(scope="module")
def messages(bag):
    """The bag's camera frames and tracking odometry, each (stamp_ns, ...), and the tracking camera's mount."""
    settings = FusionSettings()
    with Recording(bag) as recorded:
        frames = [(frame.stamp_ns, frame.image) for frame in recorded.frames(gray=True, progress=False)]
        odometry = recorded.trajectory(settings.tracking_topic)
        mount, _ = tracking_mount(recorded, settings)
    tracking = list(zip(odometry.stamps_ns.tolist(), odometry.positions, odometry.quaternions, strict=True))
    return frames, tracking, mount


def _live(config, mount, frames, tracking, delay_ns: int):
    """Feed a LiveOdometer the frames and the tracking messages in arrival order, each tracking message arriving
    ``delay_ns`` after its stamp (a camera frame at its stamp); the floor records and every fused pose it settled."""
    fused = []
    odometer = LiveOdometer(config, mount, on_fused=fused.append)
    arrivals = [(stamp, 1, ("frame", stamp, image)) for stamp, image in frames]
    arrivals += [(stamp + delay_ns, 0, ("tracking", stamp, p, q)) for stamp, p, q in tracking]
    records = []
    for _, _, message in sorted(arrivals, key=lambda arrival: arrival[:2]):
        if message[0] == "frame":
            records.append(odometer.step(*message[1:]))
        else:
            odometer.track(*message[1:])
    odometer.finish()
    assert odometer.latest is fused[-1]
    return records, fused


@pytest.mark.parametrize("delay_ns", [0, 12 * STEP_NS, -4 * STEP_NS])  # on time, 60 ms late, 20 ms ahead
def test_the_live_fused_path_is_the_recorded_runs_whatever_the_arrival_order(bag, messages, delay_ns):
    frames, tracking, mount = messages
    config = load_config().replace(method="fused")
    recorded = run(bag, config, progress=False)
    records, fused = _live(config, mount, frames, tracking, delay_ns)
    assert [r.pose for r in records] == [r.pose for r in recorded.records]
    times = np.array([pose.time_s for pose in fused])
    assert len(fused) == len(recorded.trajectory)  # every frame settled once, none twice
    np.testing.assert_array_equal(times, recorded.trajectory.stamps_ns * 1e-9)
    poses = np.array([pose.pose for pose in fused])
    np.testing.assert_allclose(poses[:, :2], recorded.trajectory.positions[:, :2], rtol=0, atol=1e-12)
    np.testing.assert_allclose(poses[:, 2], recorded.trajectory.yaw, rtol=0, atol=1e-12)


def test_a_fused_pose_waits_for_the_first_tracking_message_after_its_frame():
    fusion = StreamingFusion()
    assert fusion.add_tracking(0.0, (0.0, 0.0, 0.0)) == []
    assert fusion.add_floor(0.001, (0.0, 0.0, 0.0), 0) == []  # no tracking message after it yet
    [first] = fusion.add_tracking(0.005, (0.002, 0.0, 0.0))
    assert first.time_s == 0.001
    assert fusion.add_floor(0.034, (0.013, 0.0, 0.0), 80, 0.3) == []
    assert fusion.add_tracking(0.034, (0.0136, 0.0, 0.0)) == []  # at the frame's stamp: still at or before it
    [second] = fusion.add_tracking(0.039, (0.0156, 0.0, 0.0))
    assert second.time_s == 0.034 and 0.0125 < second.pose[0] < 0.0140


def test_the_streaming_filter_refuses_floor_poses_back_in_time_and_counts_bad_tracking_messages():
    fusion = StreamingFusion()
    fusion.add_floor(1.0, (0.0, 0.0, 0.0), 0)
    with pytest.raises(ValueError, match="time order"):
        fusion.add_floor(1.0, (0.0, 0.0, 0.0), 0)
    fusion.add_floor(1.2, (np.nan, 0.0, 0.0), 0)  # dropped, but its time still counts
    with pytest.raises(ValueError, match="time order"):
        fusion.add_floor(1.1, (0.0, 0.0, 0.0), 0)
    fusion.add_tracking(1.0, (0.0, 0.0, 0.0))
    fusion.add_tracking(0.9, (0.0, 0.0, 0.0))
    fusion.add_tracking(1.0, (0.0, 0.0, 0.0))
    fusion.add_tracking(1.1, (np.nan, 0.0, 0.0))
    assert fusion.dropped == {
        "tracking: stamp out of order (dropped)": 1,
        "tracking: stamp repeated": 1,
        "tracking: pose not finite": 1,
        "floor: pose not finite": 1,
    }


def test_fuse_is_the_streaming_filter_fed_a_recording(bag):
    config = load_config().replace(method="fused")
    result = run(bag, config.replace(method=config.fusion.floor_method), progress=False)
    floor = result.floor_run
    with Recording(bag) as recorded:
        from gpo.pipeline.run import tracking_path

        tracking = tracking_path(recorded, config.fusion)
    fused = fuse(floor.trajectory, floor.inliers, tracking, config.fusion, floor.spread_px)
    streaming = StreamingFusion(config.fusion)
    for stamp_ns, pose in zip(
        tracking.stamps_ns, np.column_stack([tracking.positions[:, :2], tracking.yaw]), strict=True
    ):
        streaming.add_tracking(stamp_ns * 1e-9, pose)
    settled = []
    for k, stamp_ns in enumerate(floor.trajectory.stamps_ns):
        pose = (*floor.trajectory.positions[k, :2], floor.trajectory.yaw[k])
        settled += streaming.add_floor(stamp_ns * 1e-9, pose, floor.inliers[k], floor.spread_px[k])
    settled += streaming.finish()
    np.testing.assert_array_equal(np.array([p.pose for p in settled])[:, :2], fused.trajectory.positions[:, :2])
    np.testing.assert_array_equal(np.array([p.covariance for p in settled]), fused.covariances)


def test_a_live_floor_odometer_gives_the_recorded_runs_records(bag, messages):
    frames, _, _ = messages
    config = load_config()
    odometer = LiveOdometer(config)
    assert [odometer.step(stamp, image) for stamp, image in frames] == run(bag, config, progress=False).records
    odometer.finish()
    assert odometer.latest is None
    with pytest.raises(ValueError, match="fuses tracking messages"):
        odometer.track(0, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0))


@pytest.fixture(scope="module")
def downward_frames():
    """The first 150 frames of the downward camera's wood floor, and the downward config following keypoints by
    Lucas-Kanade between keyframes (``features.follow: lk``)."""
    config = load_config(DOWNWARD)
    config = config.replace(features=dataclasses.replace(config.features, follow="lk"))
    with Recording(recording("downward-wood", progress=False)) as recorded:
        frames = [(frame.stamp_ns, frame.image) for frame, _ in zip(
            recorded.frames(config.rig.image_topic, gray=True, progress=False), range(150), strict=False)]
    return frames, config


def test_a_live_keypoint_follower_gives_the_recorded_runs_records_on_one_thread_or_two(downward_frames):
    frames, config = downward_frames
    odometer = LiveOdometer(config)
    records = [odometer.step(stamp, image) for stamp, image in frames]
    assert sum(record.status.value == "measured" for record in records) == len(frames) - 1
    assert records == odometry(frames, config).records
    two = odometry(frames, config, threads=2).records
    assert [(r.stamp_ns, r.pose, r.status, r.flag, r.inliers) for r in two] == [
        (r.stamp_ns, r.pose, r.status, r.flag, r.inliers) for r in records
    ]


def test_the_fused_method_needs_the_tracking_cameras_mount():
    with pytest.raises(ValueError, match="tracking camera's mount"):
        LiveOdometer(load_config().replace(method="fused"))


@pytest.mark.parametrize("method", ["gpo-exact", "features"])
def test_two_threads_give_the_one_threads_records(bag, method):
    config = load_config().replace(method=method)
    one = run(bag, config, progress=False, threads=1).records
    two = run(bag, config, progress=False, threads=2).records
    assert len(one) > 50
    assert [(r.stamp_ns, r.pose, r.status, r.flag, r.inliers) for r in two] == [
        (r.stamp_ns, r.pose, r.status, r.flag, r.inliers) for r in one
    ]


def test_read_ahead_keeps_the_order_raises_in_place_and_stops_its_thread():
    assert list(read_ahead(range(100), depth=3)) == list(range(100))

    def failing():
        yield from range(5)
        raise OSError("disk gone")

    seen = []
    with pytest.raises(OSError, match="disk gone"):
        for item in read_ahead(failing()):
            seen.append(item)
    assert seen == list(range(5))
    before = threading.active_count()
    items = read_ahead(iter(range(10**9)), depth=2)
    assert next(items) == 0
    items.close()  # a consumer that stops early stops the thread
    assert threading.active_count() == before
    with pytest.raises(ValueError, match="depth"):
        next(read_ahead([1], depth=0))


# ------------------------------------------------------------------------------------- what the live face refuses

DAY_NS = 86_400 * 10**9


def _stream(config, mount, frames, tracking, refused=(), before: int = 11) -> tuple[list, list]:
    """A LiveOdometer of ``config`` fed the frames and tracking messages in stamp order (a tracking message before a
    frame of its stamp), each call of ``refused`` (the odometer's method, its arguments, the words of its error) made
    before message number ``before`` (counted from 0: by default after the eleventh message; 0, before the first); the
    floor records, and the x, y, theta of every fused pose settled."""
    fused = []
    odometer = LiveOdometer(config, mount, on_fused=fused.append)
    messages = sorted(
        [(stamp, 1, ("step", stamp, image)) for stamp, image in frames]
        + [(stamp, 0, ("track", stamp, p, q)) for stamp, p, q in tracking],
        key=lambda m: m[:2],
    )
    records = []
    for number, (_, _, (kind, *arguments)) in enumerate(messages):
        if number == before:
            for method, bad, words in refused:
                with pytest.raises(RefusedMessage) as raised:
                    getattr(odometer, method)(*bad)
                    pytest.fail(f"{method} took {bad!r:.200}")
                for word in words:
                    assert word in str(raised.value), f"{word!r} not in {raised.value}"
        if kind == "step":
            records.append(odometer.step(*arguments))
        else:
            odometer.track(*arguments)
    odometer.finish()
    return records, [tuple(pose.pose) for pose in fused]


def _bad_steps(config, frames) -> list:
    """Calls of ``step`` with an argument that is no stamp or no frame, and the words of their refusals."""
    stamp, image = frames[6]
    height, width = image.shape
    other = load_config().replace(method="features" if config.floor_method != "features" else "gpo-exact")
    prepared = FloorOdometer(other).prepare(image)  # what the other kind of method makes of a frame
    calls = [
        ((math.nan, image), ["stamp_ns", "a whole number of nanoseconds", "nan"]),
        ((None, image), ["stamp_ns", "None"]),
        ((12.5, image), ["stamp_ns", "a whole number", "12.5"]),
        ((True, image), ["stamp_ns", "True"]),
        ((1e30, image), ["stamp_ns", "from 0 to"]),
        ((10**30, image), ["stamp_ns", "from 0 to"]),
        ((-1, image), ["stamp_ns", "from 0 to"]),
        ((stamp + 2 * DAY_NS, image), ["stamp_ns", "more than a day", "after the last message"]),
        ((stamp, None), ["image", "NoneType"]),
        ((stamp, image.tolist()), ["image", "list"]),
        ((stamp, np.zeros((), np.uint8)), ["image", "2-D", "shape ()"]),
        ((stamp, np.zeros((0, 0), np.uint8)), ["image", f"{width} x {height}", "0 x 0"]),
        ((stamp, image > 128), ["image", "uint8", "bool"]),
        ((stamp, image.astype(np.float32)), ["image", "uint8", "float32"]),
        ((stamp, np.dstack([image] * 3)), ["image", "2-D", f"shape ({height}, {width}, 3)"]),
        ((stamp, image[:-2]), ["image", f"{width} x {height}", f"{width} x {height - 2}"]),
        ((stamp, prepared), ["image", type(prepared).__name__]),
    ]
    return [("step", arguments, words) for arguments, words in calls]


@pytest.mark.parametrize("method", ["gpo-exact", "features"])
def test_a_refused_frame_leaves_the_odometer_as_it_was(messages, method):
    """Each bad call raises RefusedMessage naming its argument and what was expected; the run around them gives the
    records of the same frames given without them."""
    frames, _, _ = messages
    frames = frames[:16]
    config = load_config().replace(method=method)
    expected, _ = _stream(config, None, frames, [])
    records, _ = _stream(config, None, frames, [], _bad_steps(config, frames))
    assert records == expected and len(records) == 16
    assert sum(r.status == "measured" for r in records) >= 12


def _bad_tracks(tracking) -> list:
    """Calls of ``track`` with an argument that is no stamp, no position or no orientation, and the words of their
    refusals."""
    stamp, position, orientation = tracking[40]
    bad_tracks = [
        ((stamp, position[:2], orientation), ["position", "3 numbers", "x, y, z"]),
        ((stamp, [*position, 0.0], orientation), ["position", "3 numbers"]),
        ((stamp, None, orientation), ["position", "None"]),
        ((stamp, ["0.1", "0", "0"], orientation), ["position", "3 numbers"]),
        ((stamp, [True, 0.0, 0.0], orientation), ["position", "3 numbers"]),
        ((stamp, position, orientation[:3]), ["orientation", "4 numbers", "x, y, z, w"]),
        ((stamp, position, [0.0, 0.0, 0.0, 0.0]), ["orientation", "length"]),
        ((math.nan, position, orientation), ["stamp_ns", "nan"]),
        ((stamp + 2 * DAY_NS, position, orientation), ["stamp_ns", "more than a day"]),
    ]
    return [("track", arguments, words) for arguments, words in bad_tracks]


def _fused_sources(messages) -> tuple[list, list, tuple]:
    """The first 16 frames and the tracking messages up to one after the last of them, and the mount."""
    frames, tracking, mount = messages
    frames = frames[:16]
    return frames, [message for message in tracking if message[0] <= frames[-1][0] + STEP_NS], mount


def test_a_refused_tracking_message_leaves_the_fused_odometer_as_it_was(messages):
    frames, tracking, mount = _fused_sources(messages)
    config = load_config().replace(method="fused")
    refused = _bad_tracks(tracking) + _bad_steps(config, frames)
    expected_records, expected = _stream(config, mount, frames, tracking)
    records, fused = _stream(config, mount, frames, tracking, refused)
    assert records == expected_records and fused == expected and len(fused) == 16


@pytest.mark.parametrize("method", ["gpo-exact", "features", "fused"])
def test_a_refused_first_message_leaves_the_odometer_as_it_was(messages, method):
    """The bad calls before any message is taken, when the odometer has no frame to compare with yet (a None first
    frame was taken by the features method, whose next frame then raised an AttributeError, and a NaN first stamp
    made every pose NaN): the run after them gives the records and fused poses of the same messages without them. A
    stamp more than a day after the last message is no refusal here: there is no last message yet."""
    frames, tracking, mount = _fused_sources(messages)
    config = load_config().replace(method=method)
    tracking = tracking if method == "fused" else []
    refused = [
        call
        for call in (_bad_tracks(tracking) if tracking else []) + _bad_steps(config, frames)
        if "more than a day" not in call[2]
    ]
    expected_records, expected = _stream(config, mount, frames, tracking)
    records, fused = _stream(config, mount, frames, tracking, refused, before=0)
    assert records == expected_records and fused == expected and len(records) == 16
    assert sum(record.status == "measured" for record in records) >= 12


def test_a_tracking_pose_that_is_not_finite_is_dropped_and_counted(messages):
    _, tracking, mount = messages
    odometer = LiveOdometer(load_config().replace(method="fused"), mount)
    stamp, position, orientation = tracking[0]
    odometer.track(stamp, [math.nan, 0.0, 0.0], orientation)
    odometer.track(stamp + STEP_NS, position, [math.inf, 0.0, 0.0, 1.0])
    assert odometer.fusion.dropped == {"tracking: pose not finite": 2}


def test_the_live_odometer_refuses_what_is_no_config_mount_or_callback(messages):
    _, _, mount = messages
    config = load_config().replace(method="fused")
    with pytest.raises(RefusedMessage, match="config: expected an OdometryConfig"):
        LiveOdometer("robot.yaml")
    with pytest.raises(RefusedMessage, match="tracking_mount: expected 3 numbers, the translation"):
        LiveOdometer(config, (mount[0], [0.0, 0.0]))
    with pytest.raises(RefusedMessage, match="on_fused: expected a callable"):
        LiveOdometer(config, mount, on_fused="print")
    with pytest.raises(RefusedMessage, match="fuses tracking messages"):
        LiveOdometer(load_config()).track(0, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0))
