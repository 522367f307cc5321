"""Motion plans and the tracking camera's odometry, checked against geometry and kinematics computed here."""

from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import quad
from scipy.spatial.transform import Rotation

from gpo.sim.drift import NO_DRIFT, TrackingDrift, camera_truth, tracking_odometry
from gpo.sim.paths import CART_II_TURN_RATE_RADPS, PAPER_TURN_RATE_RADPS, PATH_LIMITS, PATHS, named_plan
from gpo.sim.plans import MotionPlan
from gpo.sim.segments import DEFAULT_LIMITS, Arc, Bend, MotionLimits, SCurve, Slide, Spin, Stop, Straight

START = (1.0, -2.0, 0.7)  # a start pose off the origin, so that frames are not confused
MOUNT_ROTATION = Rotation.from_euler("YX", [np.radians(6.0), np.radians(1.5)])  # pitched down, rolled
MOUNT = ((0.60, 0.02, 0.12), MOUNT_ROTATION)


def in_start_frame(start, local):
    """World pose of ``local`` = (x, y, yaw) given in the frame of the pose ``start``."""
    x0, y0, yaw0 = start
    x, y, yaw = local
    return (x0 + np.cos(yaw0) * x - np.sin(yaw0) * y, y0 + np.sin(yaw0) * x + np.cos(yaw0) * y, yaw0 + yaw)


def end_pose(plan):
    state = plan.sample(plan.duration_s)
    return state.x[0], state.y[0], state.yaw[0]


def segment_windows(plan, kind):
    """(start, end) times of the plan's segments of type ``kind``."""
    bounds = plan.boundaries_s
    return [(bounds[i], bounds[i + 1]) for i, seg in enumerate(plan.segments) if isinstance(seg, kind)]


# ------------------------------------------------------------------------------------------ geometry


@pytest.mark.parametrize("distance", [2.5, -0.8])
def test_straight_ends_distance_along_heading(distance):
    plan = MotionPlan([Straight(distance, 0.4)], START)
    np.testing.assert_allclose(end_pose(plan), in_start_frame(START, (distance, 0.0, 0.0)), atol=1e-9)
    assert plan.distance_m == pytest.approx(abs(distance))
    assert np.sign(plan.sample(plan.duration_s / 2).v[0]) == np.sign(distance)


def test_left_arc_ends_where_the_circle_says():
    radius, angle = 1.3, 2.0
    plan = MotionPlan([Arc(radius, angle, 0.3)], START)
    expected = (radius * np.sin(angle), radius * (1 - np.cos(angle)), angle)
    np.testing.assert_allclose(end_pose(plan), in_start_frame(START, expected), atol=1e-9)
    assert plan.distance_m == pytest.approx(radius * angle)


@pytest.mark.parametrize(("angle", "speed"), [(1.2, 0.3), (-2.5, 0.4), (0.9, -0.25), (-1.1, -0.3)])
def test_arc_stays_on_its_circle_and_turns_the_heading_by_its_angle(angle, speed):
    """The circle's centre lies 1/κ to the left; the robot turns about it by the heading change."""
    radius = 0.8
    plan = MotionPlan([Arc(radius, angle, speed)], START)
    state = plan.sample(np.linspace(0.0, plan.duration_s, 400))
    curvature = np.sign(angle) * np.sign(speed) / radius
    centre = in_start_frame(START, (0.0, 1.0 / curvature, 0.0))[:2]
    np.testing.assert_allclose(np.hypot(state.x - centre[0], state.y - centre[1]), radius, atol=1e-9)
    start_xy = np.subtract(START[:2], centre)
    end_xy = Rotation.from_euler("z", angle).apply([*start_xy, 0.0])[:2] + centre
    np.testing.assert_allclose(end_pose(plan), (*end_xy, START[2] + angle), atol=1e-9)
    assert np.all(np.sign(state.v[1:-1]) == np.sign(speed))


def test_bend_matches_an_independent_quadrature():
    angle, length = 1.3, 2.2

    def heading(u):
        return angle * (u - np.sin(2 * np.pi * u) / (2 * np.pi))

    plan = MotionPlan([Bend(angle, length, 0.4)], START)
    x = length * quad(lambda u: np.cos(heading(u)), 0, 1, epsabs=1e-13)[0]
    y = length * quad(lambda u: np.sin(heading(u)), 0, 1, epsabs=1e-13)[0]
    np.testing.assert_allclose(end_pose(plan), in_start_frame(START, (x, y, angle)), atol=1e-9)


@pytest.mark.parametrize("speed", [0.4, -0.3])
def test_scurve_shifts_sideways_and_keeps_the_heading(speed):
    plan = MotionPlan([SCurve(2.0, 0.5, speed)], START)
    local_end = np.array(end_pose(plan)) - [*START[:2], 0.0]
    along, across = Rotation.from_euler("z", -START[2]).apply([local_end[0], local_end[1], 0.0])[:2]
    assert across == pytest.approx(0.5, abs=1e-9)
    assert np.sign(along) == np.sign(speed)
    assert local_end[2] == pytest.approx(START[2], abs=1e-12)


def test_scurve_rejects_an_offset_it_cannot_reach():
    with pytest.raises(ValueError, match="offset_m"):
        SCurve(1.0, 0.9)


def test_spin_turns_on_the_spot_and_stop_keeps_the_pose():
    plan = MotionPlan([Straight(1.0), Stop(2.0), Spin(-np.pi / 2, 0.5), Straight(0.5)], START)
    (stop_from, stop_to), (spin_from, spin_to) = segment_windows(plan, Stop)[0], segment_windows(plan, Spin)[0]
    still = plan.sample(np.linspace(stop_from, stop_to, 50))
    assert np.ptp(still.x) == np.ptp(still.y) == np.ptp(still.yaw) == 0.0
    assert np.all(still.v == 0.0) and np.all(still.omega == 0.0)
    spin = plan.sample(np.linspace(spin_from, spin_to, 200))
    np.testing.assert_allclose([np.ptp(spin.x), np.ptp(spin.y)], 0.0, atol=1e-12)
    assert np.all(spin.v == 0.0)
    assert spin.yaw[-1] - spin.yaw[0] == pytest.approx(-np.pi / 2, abs=1e-12)
    assert np.all(spin.omega <= 0.0) and spin.omega.min() == pytest.approx(-0.5)


# ------------------------------------------------------------------------------- continuity, kinematics

KINEMATIC_PLANS = ["sample", "long2", "downward"]


@pytest.mark.parametrize("name", KINEMATIC_PLANS)
def test_pose_and_velocity_are_continuous_at_every_join(name):
    plan = named_plan(name, START)
    joins = plan.boundaries_s[1:-1]
    before, after = plan.sample(joins - 1e-7), plan.sample(joins + 1e-7)
    for field in ("x", "y", "yaw", "v", "omega", "accel", "angular_accel"):
        np.testing.assert_allclose(getattr(after, field), getattr(before, field), atol=2e-6, err_msg=field)


@pytest.mark.parametrize("name", KINEMATIC_PLANS)
def test_numerical_derivatives_of_the_pose_are_the_sampled_velocities(name):
    """ẋ = v cos θ, ẏ = v sin θ, θ̇ = ω, v̇ = a and the derivative of ω, by central differences of the sampled state."""
    plan = named_plan(name, START)
    step = 1e-4
    times = np.linspace(step, plan.duration_s - step, 4001)
    state, ahead, behind = plan.sample(times), plan.sample(times + step), plan.sample(times - step)

    def rate(field):
        return (getattr(ahead, field) - getattr(behind, field)) / (2 * step)

    np.testing.assert_allclose(rate("x"), state.v * np.cos(state.yaw), atol=1e-7)
    np.testing.assert_allclose(rate("y"), state.v * np.sin(state.yaw), atol=1e-7)
    np.testing.assert_allclose(rate("yaw"), state.omega, atol=1e-7)
    np.testing.assert_allclose(rate("v"), state.accel, atol=2e-4)
    np.testing.assert_allclose(rate("omega"), state.angular_accel, atol=2e-3)


def test_the_robot_keeps_rolling_only_where_curvature_and_direction_allow():
    plan = MotionPlan([Straight(1.0), Bend(1.0, 1.5), Straight(1.0), Arc(1.0, 1.0), Straight(-1.0)])
    joins = plan.sample(plan.boundaries_s)
    assert joins.v[1] > 0.25 and joins.v[2] > 0.25  # straight -> bend -> straight: curvature meets at zero
    np.testing.assert_allclose(joins.v[[0, 3, 4, 5]], 0.0, atol=1e-12)  # into the arc, reversing, the end


@pytest.mark.parametrize("name", list(PATHS))
def test_speeds_accelerations_and_jerks_stay_within_the_limits(name):
    limits = PATH_LIMITS.get(name, MotionLimits())
    plan = named_plan(name)
    step = 1e-3
    times = np.arange(0.0, plan.duration_s, step)
    state = plan.sample(times)
    along_path = np.hypot(state.accel, np.gradient(state.lateral, step))
    assert np.abs(state.accel).max() <= limits.accel_mps2 * (1 + 1e-9)
    assert along_path.max() <= limits.accel_mps2 * (1 + 1e-3)
    assert np.abs(np.diff(state.accel) / step).max() <= limits.jerk_mps3 * (1 + 1e-6)
    for index, segment in enumerate(plan.segments):
        inside = (times >= plan.boundaries_s[index]) & (times <= plan.boundaries_s[index + 1])
        if isinstance(segment, Spin):
            assert np.abs(state.omega[inside]).max() <= segment.rate_radps * (1 + 1e-9)
            assert np.abs(state.angular_accel[inside]).max() <= limits.angular_accel_radps2 * (1 + 1e-9)
        elif not isinstance(segment, Stop):
            speed = np.hypot(state.v[inside], state.lateral[inside])
            assert speed.max() <= abs(segment.speed_mps) * (1 + 1e-9)


def test_sampling_outside_the_plan_names_the_range():
    plan = named_plan("test")
    with pytest.raises(ValueError, match=r"\[0, 3\.\d+\] s"):
        plan.sample([0.5, plan.duration_s + 0.1])
    with pytest.raises(ValueError, match="within"):
        plan.sample(-0.01)


def test_bad_segments_are_named():
    with pytest.raises(ValueError, match=r"Arc\.radius_m"):
        Arc(0.0, 1.0)
    with pytest.raises(ValueError, match=r"Straight\.distance_m"):
        Straight(0.0)
    with pytest.raises(TypeError, match="segment 1 is a str"):
        MotionPlan([Straight(1.0), "left"])


# ----------------------------------------------------------------------------------------- ground truth


def test_ground_truth_is_the_sampled_plan_at_the_rate():
    plan = named_plan("test", START)
    truth = plan.ground_truth(rate_hz=120.0, start_ns=1_700_000_000_000_000_000)
    assert (truth.frame_id, truth.child_frame_id) == ("world", "base_link")
    assert truth.stamps_ns[0] == 1_700_000_000_000_000_000
    assert len(truth) == int(plan.duration_s * 120) + 1
    np.testing.assert_allclose(np.diff(truth.stamps_ns), 1e9 / 120, atol=1)
    state = plan.sample((truth.stamps_ns - truth.stamps_ns[0]) * 1e-9)
    np.testing.assert_allclose(truth.positions, np.column_stack([state.x, state.y, 0 * state.x]), atol=1e-12)
    np.testing.assert_allclose(np.unwrap(truth.yaw), state.yaw, atol=1e-12)


def test_ground_truth_noise_is_seeded_and_of_the_asked_size():
    plan = named_plan("long1")
    exact = plan.ground_truth()
    noisy = plan.ground_truth(noise_m=0.002, noise_rad=0.001, seed=3)
    np.testing.assert_array_equal(noisy.positions, plan.ground_truth(noise_m=0.002, noise_rad=0.001, seed=3).positions)
    assert np.std(noisy.positions[:, :2] - exact.positions[:, :2]) == pytest.approx(0.002, rel=0.05)
    yaw_error = np.angle(np.exp(1j * (noisy.yaw - exact.yaw)))
    assert np.std(yaw_error) == pytest.approx(0.001, rel=0.05)


# ------------------------------------------------------------------------------------ tracking camera


def independent_camera_odometry(plan, translation, rotation, rate_hz):
    """Camera body poses in the first camera pose: (world <- cam_0)⁻¹ (world <- base) (base <- cam)."""
    base = plan.ground_truth(rate_hz)
    world_camera = base.rotations * rotation
    camera_positions = base.positions + base.rotations.apply(translation)
    first = world_camera[0].inv()
    return first.apply(camera_positions - camera_positions[0]), first * world_camera


def position_errors(odometry, truth):
    return np.linalg.norm(odometry.positions - truth.positions, axis=1)


def test_odometry_without_drift_is_the_camera_truth():
    plan = named_plan("sample", START)
    quaternion_mount = (MOUNT[0], MOUNT_ROTATION.as_quat())
    odometry = tracking_odometry(plan, quaternion_mount, rate_hz=200.0, drift=NO_DRIFT, start_ns=5)
    positions, rotations = independent_camera_odometry(plan, MOUNT[0], MOUNT_ROTATION, 200.0)
    assert (odometry.frame_id, odometry.child_frame_id) == ("camera_odom_frame", "camera_pose_frame")
    assert odometry.stamps_ns[0] == 5
    np.testing.assert_allclose(odometry.positions, positions, atol=1e-9)
    assert np.max((odometry.rotations * rotations.inv()).magnitude()) < 1e-9
    truth = camera_truth(plan, MOUNT)
    np.testing.assert_allclose(truth.positions, positions, atol=1e-9)
    assert truth.positions[:, 2].std() > 1e-3  # the camera is pitched: its own frame is not level


def test_a_rig_camera_mount_is_read_in_its_body_frame():
    plan = named_plan("test")
    rig_mount = SimpleNamespace(position=np.array(MOUNT[0]), body_rotation=MOUNT_ROTATION)
    np.testing.assert_array_equal(camera_truth(plan, rig_mount).positions, camera_truth(plan, MOUNT).positions)


def test_drift_is_seeded_starts_at_the_identity_and_grows():
    plan = named_plan("long3")
    truth = camera_truth(plan, MOUNT)
    first, again, other = (tracking_odometry(plan, MOUNT, seed=seed) for seed in (0, 0, 1))
    np.testing.assert_array_equal(first.positions, again.positions)
    np.testing.assert_array_equal(first.quaternions, again.quaternions)
    assert not np.allclose(first.positions, other.positions)
    np.testing.assert_array_equal(first.positions[0], 0.0)
    np.testing.assert_allclose(first.quaternions[0], [0, 0, 0, 1], atol=1e-15)
    for odometry in (first, other):
        errors = position_errors(odometry, truth)
        tenth = len(errors) // 10
        assert errors[-tenth:].mean() > 3 * errors[:tenth].mean()


@pytest.mark.parametrize("name", ["long1", "long2", "long3"])
def test_default_drift_is_of_the_t265s_size_on_long_paths(name):
    """The first paper: about 0.17 m of T265 error on 12-17 m paths."""
    plan = named_plan(name)
    final = position_errors(tracking_odometry(plan, MOUNT, seed=0), camera_truth(plan, MOUNT))[-1]
    assert 0.05 < final < 0.3


def test_scale_error_lengthens_the_path_by_its_ratio():
    plan = named_plan("long2")
    odometry = tracking_odometry(plan, MOUNT, drift=TrackingDrift(0.025, 0, 0, 0, 0, 0))
    assert odometry.path_length / camera_truth(plan, MOUNT).path_length == pytest.approx(1.025, abs=1e-12)


def test_yaw_drift_turns_about_the_floor_normal_only():
    """A heading error must not tilt the track: the height above the floor stays the true one."""
    plan = named_plan("long1")
    truth = camera_truth(plan, MOUNT)
    odometry = tracking_odometry(plan, MOUNT, drift=TrackingDrift(0, 0.01, 0.005, 0, 0, 0), seed=2)
    up = MOUNT_ROTATION.inv().apply([0.0, 0.0, 1.0])
    np.testing.assert_allclose(odometry.positions @ up, truth.positions @ up, atol=1e-12)
    assert position_errors(odometry, truth)[-1] > 0.3
    tilt = (odometry.rotations * truth.rotations.inv()).as_rotvec()
    np.testing.assert_allclose(np.cross(tilt, up), 0.0, atol=1e-12)


# ----------------------------------------------------------------------------------------- named paths

LENGTHS_M = {"sample": (3, 5), "test": (0.5, 1.5), "downward": (9, 11), "downward-short": (4, 5)}
LENGTHS_M |= {"downward-long": (16, 17)}
LENGTHS_M |= {f"short{i}": (2, 5) for i in (1, 2, 3)} | {f"long{i}": (12, 17) for i in (1, 2, 3)}
LENGTHS_M |= {"cart-i": (17.8, 18.8), "cart-ii": (19.2, 20.2), "stage-iv": (0.5, 0.5 + 1e-9)}  # the second paper's
LENGTHS_M |= {"stage-v": (1.24, 1.24 + 1e-9), "stage-vi": (3.18, 3.18 + 1e-9), "agv-ix": (80, 81)}
LENGTHS_M |= {"corridor-iii": (14.48 - 1e-3, 14.48 + 1e-3)}  # the paper's III: 14.48 m
LENGTHS_M |= {"rotation-vii": (0.43, 0.44), "rotation-viii": (0.86, 0.88)}


@pytest.mark.parametrize("name", list(PATHS))
def test_named_paths_have_their_stated_length(name):
    low, high = LENGTHS_M[name]
    plan = named_plan(name)
    assert low <= plan.distance_m <= high
    assert PATHS[name].__doc__


def test_sample_and_test_paths_take_their_stated_time():
    assert 12 <= named_plan("sample").duration_s <= 15
    assert 2.5 <= named_plan("test").duration_s <= 3.5


def test_sample_path_reverses_and_spins():
    plan = named_plan("sample")
    state = plan.sample(np.arange(0.0, plan.duration_s, 0.01))
    assert state.v.min() < -0.1
    assert np.any((state.v == 0.0) & (np.abs(state.omega) > 0.1))


@pytest.mark.parametrize("name", ["short3", "long1", "long2", "long3"])
def test_car_like_paths_drive_forward_and_turn_no_tighter_than_a_metre(name):
    """A bicycle-model robot: never in reverse, never turning on the spot, |ω| <= v / 1 m everywhere."""
    plan = named_plan(name)
    state = plan.sample(np.arange(0.0, plan.duration_s, 1e-3))
    assert state.v.min() >= 0.0
    assert np.all(np.abs(state.omega) <= state.v / 1.0 + 1e-9)


def test_long_paths_are_like_the_papers_tests():
    """Test4 closes a loop; Test5 has S-curves (the heading swings both ways); Test6 stops on the way."""
    loop = named_plan("long1")
    np.testing.assert_allclose(end_pose(loop), (0.0, 0.0, 2 * np.pi), atol=1e-9)
    curves = named_plan("long2").sample(np.arange(0.0, named_plan("long2").duration_s, 0.01))
    assert curves.omega.min() < -0.1 and curves.omega.max() > 0.1
    stops = named_plan("long3")
    assert sum(end - start for start, end in segment_windows(stops, Stop)) >= 3.0


def test_unknown_path_lists_the_names():
    with pytest.raises(ValueError, match="long1"):
        named_plan("long9")


# ----------------------------------------------------------------------------------- random segment lists

speeds = st.floats(0.05, 0.6) | st.floats(-0.6, -0.05)
segments = st.one_of(
    st.builds(Straight, st.floats(-3, 3).filter(lambda d: abs(d) > 1e-3), st.floats(0.05, 0.6)),
    st.builds(Arc, st.floats(0.2, 3), st.floats(-3.5, 3.5).filter(lambda a: abs(a) > 1e-3), speeds),
    st.builds(Bend, st.floats(-2, 2).filter(lambda a: abs(a) > 1e-3), st.floats(0.05, 3), speeds),
    st.builds(
        lambda length, share, speed: SCurve(length, share * length, speed),
        st.floats(0.05, 3),
        st.floats(0.01, 0.45) | st.floats(-0.45, -0.01),
        speeds,
    ),
    st.builds(Spin, st.floats(-4, 4).filter(lambda a: abs(a) > 1e-3), st.floats(0.05, 1.0)),
    st.builds(Stop, st.floats(0.01, 2)),
)


@settings(max_examples=100)
@given(st.lists(segments, min_size=1, max_size=6))
def test_random_plans_are_continuous_finite_and_end_at_rest(plan_segments):
    plan = MotionPlan(plan_segments, START)
    assert np.isfinite(plan.duration_s) and plan.duration_s > 0
    state = plan.sample(np.linspace(0.0, plan.duration_s, 300))
    assert all(np.isfinite(getattr(state, f)).all() for f in ("x", "y", "yaw", "v", "omega", "accel"))
    assert np.abs(state.accel).max() <= MotionLimits().accel_mps2 * (1 + 1e-9)
    joins = plan.boundaries_s[1:-1]
    before, after = plan.sample(np.maximum(joins - 1e-7, 0)), plan.sample(joins + 1e-7)
    for field in ("x", "y", "yaw", "v", "omega"):
        np.testing.assert_allclose(getattr(after, field), getattr(before, field), atol=1e-5, err_msg=field)
    end = plan.sample(plan.duration_s)
    assert end.v[0] == pytest.approx(0.0, abs=1e-9) and end.omega[0] == pytest.approx(0.0, abs=1e-9)


# ------------------------------------------------------------------- the omnidirectional robot's slides


@pytest.mark.parametrize(("forward", "left"), [(0.0, 1.2), (0.8, -0.6), (-0.5, 0.0)])
def test_a_slide_moves_in_a_straight_line_across_the_heading_without_turning(forward, left):
    plan = MotionPlan([Slide(forward, left, 0.5)], START)
    np.testing.assert_allclose(end_pose(plan), in_start_frame(START, (forward, left, 0.0)), atol=1e-9)
    assert plan.distance_m == pytest.approx(np.hypot(forward, left))
    state = plan.sample(np.linspace(0.0, plan.duration_s, 50))
    np.testing.assert_allclose(state.yaw, START[2], atol=1e-12)
    # every sample on the segment's line: its offset from the start is parallel to (forward, left) turned by yaw
    direction = in_start_frame((0.0, 0.0, START[2]), (forward, left, 0.0))[:2]
    offsets = np.column_stack([state.x - START[0], state.y - START[1]])
    np.testing.assert_allclose(offsets[:, 0] * direction[1] - offsets[:, 1] * direction[0], 0.0, atol=1e-9)


def test_holonomic_kinematics_by_numerical_derivatives():
    """ẋ = v cos θ - v_y sin θ, ẏ = v sin θ + v_y cos θ along a plan that slides sideways and diagonally."""
    plan = MotionPlan([Straight(1.0), Slide(0.0, 0.7), Spin(1.0), Slide(0.4, -0.5), Bend(0.8, 1.2)], START)
    step = 1e-4
    times = np.linspace(step, plan.duration_s - step, 3001)
    state, ahead, behind = plan.sample(times), plan.sample(times + step), plan.sample(times - step)
    x_rate = (ahead.x - behind.x) / (2 * step)
    y_rate = (ahead.y - behind.y) / (2 * step)
    np.testing.assert_allclose(x_rate, state.v * np.cos(state.yaw) - state.lateral * np.sin(state.yaw), atol=1e-7)
    np.testing.assert_allclose(y_rate, state.v * np.sin(state.yaw) + state.lateral * np.cos(state.yaw), atol=1e-7)
    assert np.abs(state.lateral).max() > 0.3  # the slides do slide


def test_a_slide_of_nothing_is_named():
    with pytest.raises(ValueError, match=r"Slide\.forward_m and Slide\.left_m"):
        Slide(0.0, 0.0)


# --------------------------------------------------------------- the second paper's experiments I-IX


@pytest.mark.parametrize(
    ("name", "fastest_radps"),
    [("cart-i", PAPER_TURN_RATE_RADPS), ("cart-ii", CART_II_TURN_RATE_RADPS), ("rotation-viii", PAPER_TURN_RATE_RADPS),
     ("agv-ix", PAPER_TURN_RATE_RADPS)],
)
def test_the_experiments_turn_no_faster_than_their_stated_rate(name, fastest_radps):
    """The paper's fastest measured rotation, 20 deg/s, and II's cart twice that, the rate at which it can average
    the paper's 0.294 m/s (``gpo.sim.paths.path_cart_ii``)."""
    plan = named_plan(name)
    state = plan.sample(np.arange(0.0, plan.duration_s, 2e-3))
    assert np.abs(state.omega).max() <= fastest_radps * (1 + 1e-6)


def test_the_rotational_stage_turns_the_camera_on_its_arm():
    """VII: 90 degrees clockwise in 1 degree steps; VIII: 180 degrees: the camera stays on a circle about the axis."""
    for name, turned, travelled in (("rotation-vii", -np.pi / 2, 0.435), ("rotation-viii", np.pi, 0.870)):
        plan = named_plan(name)
        state = plan.sample(np.linspace(0.0, plan.duration_s, 400))
        centre = np.array([0.0, np.sign(turned) * 0.277])  # the axis, on base_link's left (counter-clockwise) or right
        np.testing.assert_allclose(np.hypot(state.x - centre[0], state.y - centre[1]), 0.277, atol=1e-9)
        assert state.yaw[-1] == pytest.approx(turned)
        assert plan.distance_m == pytest.approx(travelled, abs=1e-3)


def test_the_agv_slides_sideways_and_diagonally_and_returns_to_its_start():
    plan = named_plan("agv-ix")
    kinds = {type(segment) for segment in plan.segments}
    assert {Straight, Spin, Slide} <= kinds
    assert any(s.forward_m == 0 for s in plan.segments if isinstance(s, Slide))
    assert any(s.forward_m != 0 and s.left_m != 0 for s in plan.segments if isinstance(s, Slide))
    np.testing.assert_allclose(end_pose(plan), (0.0, 0.0, 0.0), atol=1e-9)


def test_the_random_cart_stays_in_its_room_and_repeats_with_its_seed():
    plan = named_plan("cart-i")
    state = plan.sample(np.linspace(0.0, plan.duration_s, 5000))
    assert np.abs(state.x).max() <= 2.0 + 1e-9 and np.abs(state.y).max() <= 1.75 + 1e-9
    assert named_plan("cart-i").segments == plan.segments
    assert named_plan("cart-ii").segments != plan.segments


def test_stage_paths_use_their_own_limits_and_others_the_default():
    assert named_plan("stage-iv").limits == PATH_LIMITS["stage-iv"]
    assert named_plan("long1").limits == DEFAULT_LIMITS
