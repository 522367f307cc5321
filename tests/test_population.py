"""The drawn population: deterministic for a seed, inside the issue's ranges, and a drawn world's recording holds
the truth of what was drawn."""

import dataclasses
import math

import numpy as np
import pytest

from gpo.cameras import EUCM, Pinhole
from gpo.io import cache
from gpo.io.bag import Recording
from gpo.sim.drift import tracking_odometry
from gpo.sim.floors import FLOOR_KINDS, FloorDesign, make_floor
from gpo.sim.plans import MotionPlan
from gpo.sim.population import (
    CEILING,
    DOWNWARD,
    FISHEYE,
    MIN_FOOTPRINT_M,
    PATH_LENGTH_M,
    ROOM_M,
    SPIN_DEG,
    draw,
    matte,
)
from gpo.sim.record import GROUND_TRUTH_TOPIC, ODOMETRY_TOPIC, START_NS, recording, setup_of
from gpo.sim.segments import Slide, Spin, Straight

SEEDS = range(40)


@pytest.fixture(scope="module")
def draws():
    return [draw(seed) for seed in SEEDS]


def within(value, bounds, slack=1e-9) -> bool:
    return bounds[0] - slack <= value <= bounds[1] + slack


def test_a_seed_draws_the_same_world_and_another_seed_another(draws):
    again = draw(6)
    assert again.setup.description() == draws[6].setup.description()
    assert again.parameters == draws[6].parameters
    descriptions = [d.setup.description() for d in draws]
    assert all(descriptions[i] != descriptions[j] for i in range(10) for j in range(i))
    with pytest.raises(ValueError, match="seed"):
        draw(-1)


def test_fisheye_rigs_lie_in_the_issues_ranges(draws):
    fisheyes = [d for d in draws if d.kind == "fisheye"]
    assert len(fisheyes) == len(draws) // 2
    for chosen in fisheyes:
        rig = chosen.setup.rig
        roll, pitch, yaw = rig.mount.body_rpy  # read back from the mount's rotation, not from the drawn numbers
        assert within(rig.mount.height, (0.08, 0.30)) and within(rig.mount.position[0], (0.3, 0.9))
        assert within(math.degrees(pitch), (0.0, 15.0)) and within(math.degrees(roll), (-2.0, 2.0))
        assert abs(yaw) < 1e-9
        camera = rig.camera
        assert isinstance(camera, EUCM) and (camera.width, camera.height) == (848, 800)
        assert within(camera.fx, FISHEYE["f_px"]) and abs(camera.fy / camera.fx - 1) <= 0.003
        assert within(camera.alpha, FISHEYE["alpha"]) and within(camera.beta, FISHEYE["beta"])
        assert chosen.setup.drift is not None  # the T265's own tracking camera
        assert not any(isinstance(s, Slide) for s in chosen.setup.plan.segments)  # a car-like robot: no slides


def test_downward_cameras_look_down_from_other_heights_with_other_lenses(draws):
    downward = [d for d in draws if d.kind == "downward"]
    for chosen in downward:
        rig = chosen.setup.rig
        axis = rig.mount.rotation.apply([0.0, 0.0, 1.0])  # the optical axis in base_link
        tilt = math.degrees(math.acos(-axis[2]))
        assert tilt <= math.hypot(3.0, 3.0) + 1e-9
        camera = rig.camera
        assert isinstance(camera, Pinhole) and (camera.width, camera.height) == (752, 480)
        assert within(camera.fx, DOWNWARD["f_px"]) and within(rig.mount.height, DOWNWARD["height_m"])
        assert rig.mount.height >= MIN_FOOTPRINT_M * camera.fx - 1e-12
        assert chosen.setup.drift is None
        k1, k2 = camera.dist[:2]
        assert within(k1, DOWNWARD["k1"]) and within(k2, DOWNWARD["k2"]) and k2 >= 0.6 * k1**2 - 1e-12
        assert camera.max_radius == math.inf  # the radial map never stops growing: every pixel sees one ray
        corners = [[0.0, 0.0], [751.0, 0.0], [0.0, 479.0], [751.0, 479.0]]
        assert camera.unproject(corners)[1].all()
    focal = [d.setup.rig.camera.fx for d in downward]
    assert max(focal) - min(focal) > 200  # lenses differ, not one tuned camera
    # strong barrel distortion among them, where a keypoint offset the same in every frame turns the path
    assert min(d.setup.rig.camera.dist[0] for d in downward) < -0.3
    assert any(isinstance(s, Slide) for d in downward for s in d.setup.plan.segments)


def test_paths_floors_and_drifts_cover_the_population(draws):
    for chosen in draws:
        plan = chosen.setup.plan
        shortest, longest = PATH_LENGTH_M[chosen.kind]
        assert shortest <= plan.distance_m  # and it ends with the segment that reached the drawn length:
        assert plan.distance_m - plan.segments[-1].path_length_m < longest
        state = plan.sample(np.linspace(0.0, plan.duration_s, 2000))
        half = ROOM_M[chosen.kind] / 2 + 1e-9
        assert np.abs(state.x).max() <= half and np.abs(state.y).max() <= half
        spins = [abs(math.degrees(s.angle_rad)) for s in plan.segments if isinstance(s, Spin)]
        assert all(within(angle, SPIN_DEG[chosen.kind]) for angle in spins)  # quarter turns on the downward rig
    segments = [s for d in draws for s in d.setup.plan.segments]
    assert any(isinstance(s, Spin) for s in segments)
    assert any(isinstance(s, Straight) and s.distance_m < 0 for s in segments)  # reverse
    floors = [d.setup.floor for d in draws]
    assert {kind for f in floors for kind in f.kinds} == set(FLOOR_KINDS)
    assert any(len(f.kinds) == 2 for f in floors) and any(f.photos != ("gravel", "grass") for f in floors)
    scales = [d.setup.drift.scale_error for d in draws if d.setup.drift is not None]
    assert min(scales) < 0 < max(scales)
    for kind in ("fisheye", "downward"):  # glossy and matte floors, the screed among the glossy, for both rigs
        glossy = [d.setup.floor for d in draws if d.kind == kind and d.setup.floor.sheen]
        assert any(f.kinds == ("industrial",) for f in glossy)
        assert any(not d.setup.floor.sheen for d in draws if d.kind == kind)
    lengths = [d.setup.plan.distance_m for d in draws]
    assert min(lengths) < 8.0 and max(lengths) > 14.0  # the papers' short and long paths both


def test_ceilings_lie_in_the_issues_ranges(draws):
    ceilings = [d.setup.ceiling for d in draws]
    for ceiling in ceilings:
        assert within(ceiling.height_m, CEILING["height_m"]) and within(ceiling.reflection, CEILING["reflection"])
        assert all(within(pitch, CEILING["pitch_m"]) for pitch in ceiling.pitch_m)
        assert ceiling.lamp_m[0] <= 0.8 * ceiling.pitch_m[0] and ceiling.lamp_m[1] <= 0.8 * ceiling.pitch_m[1]
    heights = [c.height_m for c in ceilings]
    assert min(heights) < 4.0 and max(heights) > 10.0  # low rooms and high halls


def test_a_mixed_floor_is_made_of_its_kinds():
    extent, texel = (0.0, 3.0, 0.0, 3.0), 4e-3
    mixed = FloorDesign(("wood", "industrial"), patch_m=0.6).texture(extent, texel, 5)
    wood = make_floor("wood", extent, texel, [5, 0]).levels[0].astype(float)
    industrial = make_floor("industrial", extent, texel, [5, 1]).levels[0].astype(float)
    image = mixed.levels[0].astype(float)
    is_wood, is_industrial = np.abs(image - wood) <= 1, np.abs(image - industrial) <= 1
    distinct = np.abs(wood - industrial) > 10
    assert (is_wood | is_industrial)[distinct].mean() > 0.95  # away from the edges a texel is one kind's
    assert 0.15 < is_wood[distinct].mean() < 0.85  # and both kinds show
    assert mixed.sheen and mixed.kind == "wood+industrial"


def test_a_floors_sheen_can_be_taken_off_or_put_on():
    extent, texel = (0.0, 1.0, 0.0, 1.0), 4e-3
    glossy = FloorDesign(("industrial",)).texture(extent, texel, 3)
    matte_screed = FloorDesign(("industrial",), sheen=False).texture(extent, texel, 3)
    assert glossy.sheen and not matte_screed.sheen
    assert all(np.array_equal(a, b) for a, b in zip(glossy.levels, matte_screed.levels, strict=True))
    assert FloorDesign(("wood",), sheen=True).texture(extent, texel, 3).sheen
    assert not FloorDesign(("wood", "industrial"), sheen=False).texture(extent, texel, 3).sheen
    with pytest.raises(ValueError, match="sheen"):
        FloorDesign(("wood",), sheen="yes")


def test_a_matte_draw_is_the_same_world_without_the_sheen():
    chosen = draw(9)
    plain = matte(chosen)
    assert chosen.setup.floor.kinds == ("industrial",) and chosen.setup.floor.sheen
    assert plain.setup.floor.sheen is False
    assert plain.setup.floor == dataclasses.replace(chosen.setup.floor, sheen=False)
    for part in ("rig", "plan", "drift", "seed", "ceiling"):
        assert getattr(plain.setup, part) == getattr(chosen.setup, part)
    assert chosen.parameters["sheen"] == "on" and plain.parameters == {**chosen.parameters, "sheen": "off"}
    assert plain.label == chosen.label
    assert plain.setup.description() != chosen.setup.description()  # a recording of its own


def short(chosen, segments: int, rate_hz: float):
    """``chosen``'s setup with its first ``segments`` segments only and its camera at ``rate_hz``: few frames."""
    setup = chosen.setup
    rig = dataclasses.replace(setup.rig, rate_hz=rate_hz)
    return dataclasses.replace(setup, rig=rig, plan=MotionPlan(setup.plan.segments[:segments]))


@pytest.mark.parametrize("seed, segments, rate_hz", [(0, 1, 3.0), (1, 2, 10.0)])
def test_a_drawn_recording_holds_what_was_drawn(tmp_path, monkeypatch, seed, segments, rate_hz):
    monkeypatch.setenv(cache.ENVIRONMENT_VARIABLE, str(tmp_path))
    setup = short(draw(seed), segments, rate_hz)
    bag = recording(setup, progress=False, label=f"draw{seed}")
    assert bag.name.startswith(f"draw{seed}-") and recording(setup, progress=False, label=f"draw{seed}") == bag
    rig, plan = setup.rig, setup.plan
    with Recording(bag) as recorded:
        frames = list(recorded.frames(rig.image_topic, progress=False))
        truth = recorded.trajectory(GROUND_TRUTH_TOPIC)
        assert recorded.camera_info(rig.info_topic) == rig.camera
        translation, quaternion = recorded.static_transform("base_link", rig.frame_id)
        topics = {t.name for t in recorded.topics()}
        odometry = recorded.trajectory(ODOMETRY_TOPIC) if setup.drift is not None else None
    assert len(frames) == math.ceil(plan.duration_s * rate_hz)
    assert frames[0].image.shape == (rig.camera.height, rig.camera.width) and frames[0].image.std() > 3
    np.testing.assert_allclose(translation, rig.mount.position, atol=1e-12)
    assert abs(np.dot(quaternion, rig.mount.rotation.as_quat())) == pytest.approx(1.0, abs=1e-12)
    state = plan.sample((truth.stamps_ns - START_NS) / 1e9)
    np.testing.assert_allclose(truth.positions[:, :2], np.column_stack([state.x, state.y]), atol=1e-9)
    assert plan.duration_s - 1 / 120 < (truth.stamps_ns[-1] - START_NS) / 1e9 <= plan.duration_s  # all of the plan
    if setup.drift is None:
        assert ODOMETRY_TOPIC not in topics
    else:
        expected = tracking_odometry(plan, rig.mount, 200.0, setup.drift, setup.seed, START_NS)
        np.testing.assert_allclose(odometry.positions, expected.positions, atol=1e-9)


def test_a_setup_takes_no_seed():
    with pytest.raises(ValueError, match="seed"):
        setup_of(draw(0).setup, seed=3)
