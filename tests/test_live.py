"""The odometry frame by frame as a robot's node runs it (``gpo.pipeline.live``), against the recorded run of the same
bag: the same floor records, the same fused path whatever order the two sources' messages arrive in; and the run on
two threads against the run on one (``gpo.io.ahead``)."""

import threading

import numpy as np
import pytest

from gpo.fusion import FusionSettings, StreamingFusion, fuse
from gpo.io.ahead import read_ahead
from gpo.io.bag import Recording
from gpo.pipeline.config import load_config
from gpo.pipeline.live import LiveOdometer
from gpo.pipeline.run import run, tracking_mount
from gpo.sim.record import recording

STEP_NS = 5_000_000  # the tracking camera's 200 Hz


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
    assert fusion.dropped == {"tracking: stamp out of order (dropped)": 1, "tracking: stamp repeated": 1,
                              "tracking: pose not finite": 1, "floor: pose not finite": 1}


def test_fuse_is_the_streaming_filter_fed_a_recording(bag):
    config = load_config().replace(method="fused")
    result = run(bag, config.replace(method=config.fusion.floor_method), progress=False)
    floor = result.floor_run
    with Recording(bag) as recorded:
        from gpo.pipeline.run import tracking_path

        tracking = tracking_path(recorded, config.fusion)
    fused = fuse(floor.trajectory, floor.inliers, tracking, config.fusion, floor.spread_px)
    streaming = StreamingFusion(config.fusion)
    for stamp_ns, pose in zip(tracking.stamps_ns, np.column_stack([tracking.positions[:, :2], tracking.yaw]),
                              strict=True):
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


def test_the_fused_method_needs_the_tracking_cameras_mount():
    with pytest.raises(ValueError, match="tracking camera's mount"):
        LiveOdometer(load_config().replace(method="fused"))


@pytest.mark.parametrize("method", ["gpo-exact", "features"])
def test_two_threads_give_the_one_threads_records(bag, method):
    config = load_config().replace(method=method)
    one = run(bag, config, progress=False, threads=1).records
    two = run(bag, config, progress=False, threads=2).records
    assert len(one) > 50
    assert [(r.stamp_ns, r.pose, r.status, r.flag, r.inliers) for r in two] == \
        [(r.stamp_ns, r.pose, r.status, r.flag, r.inliers) for r in one]


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
