"""The odometry EKF against exact motions: velocity measurements, frames, consistency, bad input."""

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation
from scipy.stats import chi2

from gpo.fusion import FilterDiverged, FusionSettings, OdometryFusion, fuse, increment_covariance
from gpo.fusion.ekf import ProcessNoise, increment_jacobians
from gpo.io.trajectory import Trajectory, base_from_sensor_odometry
from gpo.odometry.kinematics import arc_increment, between, integrate
from gpo.sim.drift import T265_DRIFT, TrackingDrift, tracking_odometry
from gpo.sim.paths import named_plan
from gpo.sim.rigs import RIGS


@given(st.tuples(*[st.floats(-3.0, 3.0)] * 6))
def test_increment_jacobians_match_finite_differences(poses):
    clone, pose = np.array(poses[:3]), np.array(poses[3:])
    by_clone, by_pose = increment_jacobians(clone, pose)
    step = 1e-6
    for jacobian, moved in (
        (by_clone, lambda d: between(clone + d, pose)),
        (by_pose, lambda d: between(clone, pose + d)),
    ):
        numeric = np.column_stack([(moved(step * e) - moved(-step * e)) / (2 * step) for e in np.eye(3)])
        numeric[2] = np.angle(np.exp(1j * numeric[2] * 2 * step)) / (2 * step)  # the turn is wrapped
        np.testing.assert_allclose(jacobian, numeric, atol=1e-5)


def _noisy(increment, covariance, rng):
    """``increment`` (dx, dy, dtheta) with white noise of ``covariance`` (2, 2) on its measured part (dx, dtheta)."""
    noisy = np.array(increment, dtype=float)
    noisy[[0, 2]] += rng.multivariate_normal(np.zeros(2), covariance)
    return noisy


def _drive(seconds=6.0, rate_hz=30.0, v=0.4, omega=0.3, sigma=(0.02, 0.02), seed=0):
    """A constant arc measured by one source whose increments carry white noise of ``increment_covariance(*sigma)``;
    the filter and the true final pose."""
    rng = np.random.default_rng(seed)
    dt = 1.0 / rate_hz
    fusion = OdometryFusion(0.0, ProcessNoise(), sources=("floor",))
    covariance = increment_covariance(*sigma, dt)
    for k in range(1, round(seconds * rate_hz) + 1):
        fusion.add("floor", k * dt, _noisy(arc_increment(v, omega, dt), covariance, rng), dt, covariance)
    return fusion, arc_increment(v, omega, seconds)


def test_a_constant_arc_is_followed():
    fusion, truth = _drive()
    assert np.hypot(*(fusion.state[:2] - truth[:2])) < 0.02  # measured 17.8 mm: 1.2 of the filter's own sigmas
    assert abs(fusion.state[2] - truth[2]) < 0.01  # measured 0.0037 rad; the filter's own sigma is 0.0089 rad
    velocity_error = fusion.state[3:5] - [0.4, 0.3]
    assert (np.abs(velocity_error) < 3 * np.sqrt(np.diag(fusion.covariance[3:5, 3:5]))).all()


def test_the_filter_is_consistent_over_many_runs():
    """The pose error's NEES averaged over 40 runs lies within the 99 % band of chi-square with 3 x 40 dof."""
    nees = []
    for seed in range(40):
        fusion, truth = _drive(seed=seed)
        error = fusion.state[:3] - truth
        nees.append(error @ np.linalg.solve(fusion.covariance[:3, :3], error))
    low, high = chi2.ppf([0.005, 0.995], 3 * 40) / 40
    assert low < np.mean(nees) < high


def test_an_accelerating_robot_is_not_followed_late():
    """Exact increments of a robot speeding up at 0.5 m/s^2: the fused pose at every stamp is the true one (a
    filter fed the increments as mean velocities lags by half a step, 0.45 m/s x 1/60 s = 7.5 mm at the end)."""
    rate, seconds, acceleration = 30.0, 0.9, 0.5
    times = np.arange(round(seconds * rate) + 1) / rate
    truth = np.column_stack([0.5 * acceleration * times**2, np.zeros_like(times), np.zeros_like(times)])
    fusion = OdometryFusion(0.0, ProcessNoise(), sources=("floor",))
    for k in range(1, len(times)):
        fusion.add(
            "floor", times[k], between(truth[k - 1], truth[k]), 1 / rate, increment_covariance(0.002, 0.03, 1 / rate)
        )
        assert np.hypot(*(fusion.state[:2] - truth[k, :2])) < 1e-8  # measured 1.1e-9 m at most: exact but rounding
    assert abs(fusion.state[3] - acceleration * seconds) < 0.005  # measured 1.8 mm/s: the velocity lags a little


def test_sideways_steps_are_not_fused():
    """base_link does not slide sideways: a source's steps that do (a bicycle model's slip) move the fused path as
    their forward part and turn alone do."""
    covariance = increment_covariance(0.002, 0.03, 1 / 30)
    paths = []
    for slide in (0.0, 0.002):
        fusion = OdometryFusion(0.0, sources=("floor",))
        for k in range(1, 31):
            fusion.add(
                "floor", k / 30, arc_increment(0.4, 0.3, 1 / 30) + np.array([0.0, slide, 0.0]), 1 / 30, covariance
            )
        paths.append(fusion.state)
    np.testing.assert_allclose(paths[1], paths[0], rtol=0, atol=1e-12)


TWO_SOURCES = {"floor": (30.0, 0.03), "camera": (200.0, 0.08)}  # rate (Hz), speed and turn sigma of each source


def _two_sources(seed, v=0.3, omega=-0.2, seconds=5.0):
    """Final position error (m) and variance (m^2, the covariance's trace) of the filter fed the floor alone, the
    camera alone and both along a constant arc; each source's noisy increments are drawn once, so that the three
    filters read the same measurements."""
    measured = []
    for index, (name, (rate, sigma)) in enumerate(TWO_SOURCES.items()):
        rng = np.random.default_rng([seed, index])
        covariance = increment_covariance(sigma, sigma, 1 / rate)
        for k in range(1, round(seconds * rate) + 1):
            noisy = _noisy(arc_increment(v, omega, 1 / rate), covariance, rng)
            measured.append((k / rate, name, noisy, 1 / rate, covariance))
    measured.sort(key=lambda measurement: measurement[0])  # in time, as they arrive
    errors, variances = [], []
    for used in (("floor",), ("camera",), ("floor", "camera")):
        fusion = OdometryFusion(0.0, sources=used)
        for time_s, name, increment, dt, covariance in measured:
            if name in used:
                fusion.add(name, time_s, increment, dt, covariance)
        fusion.predict(seconds)
        errors.append(np.hypot(*(fusion.state[:2] - arc_increment(v, omega, seconds)[:2])))
        variances.append(np.trace(fusion.covariance[:2, :2]))
    return errors, variances


def test_two_sources_at_different_rates_beat_either():
    """Over 20 seeded drives the fused final position's RMS error lies below either source's alone, and the filter's
    own position variance is about halved (the two sources weigh about the same over the drive). One drive alone
    proves nothing: its fused end lies nearer the truth than both sources' ends in 9 of these 20 drives."""
    errors, variances = np.array([_two_sources(seed) for seed in range(20)]).transpose(1, 0, 2)
    rms = np.sqrt(np.mean(errors**2, axis=0))  # floor, camera, both
    assert rms[2] < 0.85 * rms[:2].min(), rms  # measured 0.73; the filter's variances predict sqrt(0.52) = 0.72
    assert (variances[:, 2] < 0.55 * variances[:, :2].min(axis=1)).all()  # measured 0.52 at most; equal sources: 0.5


def test_bad_measurements_are_refused():
    fusion, _ = _drive(seconds=1.0)
    covariance = increment_covariance(0.01, 0.01, 1 / 30)
    with pytest.raises(ValueError, match="back in time"):
        fusion.add("floor", 0.5, [0.01, 0.0, 0.0], 1 / 30, covariance)
    with pytest.raises(ValueError, match="finite"):
        fusion.add("floor", 1.1, [np.nan, 0.0, 0.0], 1 / 30, covariance)
    with pytest.raises(ValueError, match="unknown source 'wheels'"):
        fusion.add("wheels", 1.1, [0.01, 0.0, 0.0], 1 / 30, covariance)
    assert not fusion.add("floor", 1.0 + 1 / 30, [1.0, 0.0, 0.0], 1 / 30, covariance)  # 30 m/s: an outlier
    assert fusion.refused == 1


def test_a_step_that_does_not_start_at_the_last_one_is_not_fused():
    fusion, _ = _drive(seconds=1.0)
    before = fusion.state
    covariance = increment_covariance(0.01, 0.01, 1 / 30)
    assert not fusion.add(
        "floor", 1.1, [0.5, 0.0, 0.0], 1 / 30, covariance
    )  # starts at 1.0667 s, the last ended at 1 s
    assert fusion.refused == 0
    np.testing.assert_allclose(fusion.state[3:], before[3:])  # only predicted (velocities and biases kept)
    assert fusion.add("floor", 1.1 + 1 / 30, arc_increment(0.4, 0.3, 1 / 30), 1 / 30, covariance)  # from 1.1 s on


def test_a_broken_covariance_is_reported_not_carried_on():
    fusion = OdometryFusion(0.0)
    fusion._filter.P[3, 3] = np.nan
    with pytest.raises(FilterDiverged):
        fusion.predict(0.1)


# fuse(): a floor odometry and a tracking camera's path against an exact arc

ARC_V, ARC_OMEGA, ARC_SECONDS = 0.4, 0.3, 6.0


def _arc_path(rate_hz, sigma=(0.0, 0.0), scale=1.0, seed=0, wrong_step=None):
    """base_link's path along the constant arc sampled at ``rate_hz`` (stamps from 0 s): each step's (v, omega) with
    white noise ``sigma``, its length scaled by ``scale`` (a scale error), and step ``wrong_step`` (an index) replaced
    by a jump of 0.3 m sideways and 1 rad."""
    rng = np.random.default_rng(seed)
    steps = round(ARC_SECONDS * rate_hz)
    velocities = np.array([ARC_V, ARC_OMEGA]) + rng.standard_normal((steps, 2)) * sigma
    increments = arc_increment(velocities[:, 0], velocities[:, 1], 1 / rate_hz)
    increments[:, :2] *= scale
    if wrong_step is not None:
        increments[wrong_step] = [0.02, 0.3, 1.0]
    stamps = np.round(np.arange(steps + 1) / rate_hz * 1e9).astype(np.int64)
    return Trajectory.from_planar(stamps, *integrate(increments).T, frame_id="odom")


def _measured(floor):
    inliers = np.full(len(floor), 100)
    inliers[0] = 0  # the first pose has no step behind it
    return inliers


def _final_position_error(trajectory):
    return float(np.hypot(*(trajectory.positions[-1, :2] - arc_increment(ARC_V, ARC_OMEGA, ARC_SECONDS)[:2])))


def test_fused_path_beats_a_tracker_with_a_scale_error_and_its_covariance_grows():
    floor = _arc_path(30.0, sigma=(0.003, 0.01), seed=1)
    tracker = _arc_path(200.0, sigma=(0.02, 0.02), scale=1.03, seed=2)  # 3 % too long: 6 cm after 6 s
    fused = fuse(floor, _measured(floor), tracker, FusionSettings())
    assert fused.trajectory.stamps_ns.tolist() == floor.stamps_ns.tolist()
    assert fused.refused == 0
    assert _final_position_error(tracker) > 0.05
    # measured 5.1 mm against the tracker's 58.7 mm: the floor's own 5.1 mm, the tracker's scale error estimated away
    assert _final_position_error(fused.trajectory) < 0.1 * _final_position_error(tracker)
    pose = fused.covariances[:, :3, :3]
    assert fused.covariances.shape == (len(floor), 7, 7) and fused.biases.shape == (len(floor), 2)
    np.testing.assert_allclose(pose, np.transpose(pose, (0, 2, 1)), rtol=0, atol=1e-15)
    assert np.linalg.eigvalsh(pose[1:]).min() > 0  # positive definite after the first step
    assert (np.diff(np.trace(pose[:, :2, :2], axis1=1, axis2=2)) > 0).all()  # velocities only: the position drifts
    assert (np.diff(np.linalg.det(pose[1:])) > 0).all()


def test_floor_steps_without_inliers_are_not_fused():
    tracker = _arc_path(200.0, sigma=(0.02, 0.02), seed=2)
    good, wrong = _arc_path(30.0, seed=1), _arc_path(30.0, seed=1, wrong_step=90)  # pose 91 on: 0.3 m aside
    inliers = _measured(good)
    inliers[91] = 0  # the step into pose 91 was flagged
    left_out = fuse(good, inliers, tracker, FusionSettings())
    flagged = fuse(wrong, inliers, tracker, FusionSettings())
    np.testing.assert_allclose(flagged.trajectory.positions, left_out.trajectory.positions, rtol=0, atol=1e-12)
    np.testing.assert_allclose(flagged.covariances, left_out.covariances, rtol=0, atol=1e-15)
    assert flagged.refused == 0  # not offered to the filter at all, so not refused by its gate either
    assert _final_position_error(flagged.trajectory) < 1e-3  # measured 0.38 mm
    offered = fuse(wrong, _measured(wrong), tracker, FusionSettings())  # the same step fused: refused as an outlier
    assert offered.refused == 1


def test_a_floor_step_in_doubt_is_not_fused_and_the_camera_biases_are_forgotten():
    """A step whose spread is infinite (its tracks and the whole view disagreed) is left out like a flagged one, and
    the tracker's scale error learned from the floor before it goes back to the prior: zero, the prior's sigma."""
    floor = _arc_path(30.0, sigma=(0.003, 0.01), seed=1)
    tracker = _arc_path(200.0, sigma=(0.02, 0.02), scale=1.03, seed=2)
    spread = np.full(len(floor), np.nan)
    trusted = fuse(floor, _measured(floor), tracker, FusionSettings(), spread)
    assert abs(trusted.biases[-1, 0] - 0.03) < 0.01  # the 3 % scale error, learned from the floor
    spread[-1] = np.inf
    doubted = fuse(floor, _measured(floor), tracker, FusionSettings(), spread)
    inliers = _measured(floor)
    inliers[-1] = 0
    left_out = fuse(floor, inliers, tracker, FusionSettings(), np.full(len(floor), np.nan))
    np.testing.assert_allclose(doubted.biases[:-1], trusted.biases[:-1], rtol=0, atol=1e-15)
    # forgotten: back to the prior but for the camera's last step, fused after the floor's (scale 0.0024), while the
    # step merely left out keeps what was learned
    assert abs(doubted.biases[-1, 0]) < 0.2 * trusted.biases[-1, 0] < left_out.biases[-1, 0]
    sigma = np.sqrt(np.diag(doubted.covariances[-1])[5:])
    prior = [FusionSettings().tracking_scale_sigma, FusionSettings().tracking_yaw_bias_sigma_radps]
    np.testing.assert_allclose(sigma, prior, rtol=0.2)  # measured 0.043 and 0.00495
    assert (np.sqrt(np.diag(trusted.covariances[-1])[5:]) < 0.5 * np.array(prior)).all()
    assert doubted.dropped == {"floor: step in doubt (tracks and whole view disagree), not fused": 1}


def test_repeated_and_out_of_order_tracker_stamps_are_skipped():
    floor = _arc_path(30.0, sigma=(0.003, 0.01), seed=1)
    tracker = _arc_path(200.0, sigma=(0.02, 0.02), seed=2)
    clean = fuse(floor, _measured(floor), tracker, FusionSettings())

    repeat = np.sort(np.r_[np.arange(len(tracker)), [100, 100, 500]])  # three messages sent again
    repeated = Trajectory(tracker.stamps_ns[repeat], tracker.positions[repeat], tracker.quaternions[repeat])
    again = fuse(floor, _measured(floor), repeated, FusionSettings())
    np.testing.assert_allclose(again.trajectory.positions, clean.trajectory.positions, rtol=0, atol=1e-12)

    shuffled = np.r_[np.arange(300), 301, 300, np.arange(302, len(tracker))]  # two messages swapped
    with pytest.raises(ValueError, match="backwards"):
        Trajectory(tracker.stamps_ns[shuffled], tracker.positions[shuffled], tracker.quaternions[shuffled])
    swapped = _Path(tracker.times[shuffled], tracker.positions[shuffled], tracker.yaw[shuffled])
    unordered = fuse(floor, _measured(floor), swapped, FusionSettings())
    assert np.isfinite(unordered.trajectory.positions).all()
    np.testing.assert_allclose(unordered.trajectory.positions, clean.trajectory.positions, rtol=0, atol=1e-12)


class _Path:
    """A path as a reader might hand it over before any checks: ``times``, ``positions`` and ``yaw`` as they came."""

    def __init__(self, times, positions, yaw):
        self.times, self.positions, self.yaw = times, positions, yaw

    def __len__(self):
        return len(self.times)


def test_inliers_must_match_the_floor_poses():
    floor = _arc_path(30.0)
    tracker = _arc_path(200.0)
    with pytest.raises(ValueError, match=rf"one count per floor pose \({len(floor)}\)"):
        fuse(floor, np.ones(len(floor) - 1), tracker, FusionSettings())
    with pytest.raises(ValueError, match="inliers"):
        fuse(floor, np.ones((len(floor), 1)), tracker, FusionSettings())


# biases as states: a floor odometry and the simulator's drifting tracking camera on a named path


FLOOR_SIGMA = (FusionSettings().floor_speed_sigma_mps, FusionSettings().floor_turn_sigma_radps)


def _simulated(path, seed, drift=None, floor_sigma=FLOOR_SIGMA, outage_s=None):
    """(floor odometry at 30 Hz: the truth's steps with white noise of ``increment_covariance(*floor_sigma)``, its
    inliers (0 inside ``outage_s`` = (start, end) seconds), the tracking camera of ``gpo.sim.drift`` with ``drift``
    (default: the T265's) seeded by ``seed`` turned into base_link, the truth at the floor's stamps as planar poses
    seen from its first)."""
    plan, mount = named_plan(path), RIGS["t265"]().mount
    truth = plan.ground_truth(30.0)
    true = np.column_stack([truth.positions[:, :2], truth.yaw])
    rng = np.random.default_rng([seed, 1])
    steps = between(true[:-1], true[1:])
    dt = np.diff(truth.times)
    steps[:, [0, 2]] += rng.standard_normal((len(steps), 2)) * np.array(floor_sigma) * dt[:, None]
    floor = Trajectory.from_planar(truth.stamps_ns, *integrate(steps).T, frame_id="odom")
    inliers = np.full(len(floor), 100)
    inliers[0] = 0
    if outage_s is not None:
        inliers[(truth.times >= outage_s[0]) & (truth.times < outage_s[1])] = 0
    odometry = tracking_odometry(plan, mount, 200.0, drift or T265_DRIFT, seed)
    start = (Rotation.identity(), np.zeros(3))
    tracking = base_from_sensor_odometry(odometry, (mount.body_rotation, mount.position), start)
    return floor, inliers, tracking, between(np.broadcast_to(true[0], true.shape), true)


def test_the_camera_biases_are_estimated_as_the_simulator_drifts():
    """On the 45 s loop long1 the filter finds the tracking camera's 2 % scale error and its 1 mrad/s yaw bias (the
    simulator's ``T265_DRIFT``) within three of its own standard deviations, and those are tight enough to tell."""
    for seed, drift in ((1, T265_DRIFT), (2, TrackingDrift(scale_error=-0.03, yaw_bias_radps=-2e-3))):
        floor, inliers, tracking, _ = _simulated("long1", seed, drift)
        fused = fuse(floor, inliers, tracking, FusionSettings())
        estimate, sigma = fused.biases[-1], np.sqrt(np.diagonal(fused.covariances[-1])[5:7])
        truth = np.array([drift.scale_error, drift.yaw_bias_radps])
        assert (np.abs(estimate - truth) < 3 * sigma).all(), (estimate, truth, sigma)
        assert (3 * sigma < np.abs(truth)).all(), sigma  # tight enough to tell: sigmas measured 0.0021 and 1.6e-4
        assert fused.refused == 0 and fused.dropped == {}


def test_an_outage_is_bridged_by_the_calibrated_camera():
    """The floor flagged for 8 s of long1's loop (3.1 m through its second corner): the camera, calibrated on the
    first 20 s, carries the pose through to within 0.6 % of that distance, and less than half as far off as the same
    filter without bias states (their priors zero), which is the camera's own error over the gap."""
    without = FusionSettings(tracking_scale_sigma=0.0, tracking_yaw_bias_sigma_radps=0.0,
                             tracking_scale_walk_per_sqrt_s=0.0, tracking_yaw_bias_walk_radps_per_sqrt_s=0.0)
    for seed in (3, 5, 6):
        floor, inliers, tracking, truth = _simulated("long1", seed, outage_s=(20.0, 28.0))
        start, end = np.searchsorted(floor.times, 20.0) - 1, np.searchsorted(floor.times, 28.0)  # the gap's ends
        distance = np.linalg.norm(np.diff(truth[start : end + 1, :2], axis=0), axis=1).sum()
        errors = {}
        for name, settings in (("biases", FusionSettings()), ("none", without)):
            fused = fuse(floor, inliers, tracking, settings)
            poses = np.column_stack([fused.trajectory.positions[:, :2], fused.trajectory.yaw])
            error = between(poses[start], poses[end]) - between(truth[start], truth[end])
            errors[name] = np.hypot(*error[:2])
        assert errors["biases"] < 0.006 * distance, (seed, errors)  # measured 0.52, 0.21 and 0.41 %
        assert errors["none"] > 2 * errors["biases"], (seed, errors)  # measured 3.0, 10.4 and 3.0 times


def test_the_filter_with_bias_states_is_consistent_over_40_drift_seeds():
    """The final NEES of pose and biases (5 dof) over 40 seeded runs of the T265's drift on the sample's path: its
    average inside the 95 % band of chi-square with 5 x 40 dof over 40; the NIS gate refuses nothing."""
    nees = []
    for seed in range(40):
        floor, inliers, tracking, truth = _simulated("sample", seed)
        fused = fuse(floor, inliers, tracking, FusionSettings())
        final = np.r_[fused.trajectory.positions[-1, :2], fused.trajectory.yaw[-1], fused.biases[-1]]
        error = final - np.r_[truth[-1], T265_DRIFT.scale_error, T265_DRIFT.yaw_bias_radps]
        error[2] = np.angle(np.exp(1j * error[2]))
        chosen = [0, 1, 2, 5, 6]
        nees.append(error @ np.linalg.solve(fused.covariances[-1][np.ix_(chosen, chosen)], error))
        assert fused.refused == 0
    low, high = chi2.ppf([0.025, 0.975], 5 * 40) / 40
    assert low < np.mean(nees) < high, np.mean(nees)


def test_bad_tracking_messages_are_dropped_and_counted():
    """NaN poses, a repeated stamp, a relocalisation jump and a 1 s gap in the tracking stream: each left out and
    counted, the fused path finite and still close to the truth."""
    floor, inliers, tracking, truth = _simulated("sample", 4)
    positions = tracking.positions.copy()
    positions[500:503] = np.nan  # three NaN poses
    positions[1200:] += [0.5, -0.3, 0.0]  # a relocalisation: every pose from 6 s on jumps 0.58 m
    keep = np.r_[np.arange(1500), np.arange(1700, len(tracking))]  # 1 s without messages
    keep = np.sort(np.r_[keep, 800])  # message 800 sent twice
    broken = _Path(tracking.times[keep], positions[keep], tracking.yaw[keep])
    fused = fuse(floor, inliers, broken, FusionSettings())
    assert fused.dropped == {"tracking: pose not finite": 3, "tracking: stamp repeated": 1,
                             "tracking: step over a gap": 1}
    assert fused.refused == 1  # the jump
    assert np.isfinite(fused.trajectory.positions).all()
    # measured 0.29 mm, the clean stream's 0.31 mm
    assert np.hypot(*(fused.trajectory.positions[-1, :2] - truth[-1, :2])) < 1e-3
