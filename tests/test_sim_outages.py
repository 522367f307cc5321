"""Floor outages: each kind makes the floor odometry flag the frame instead of measuring a wrong motion."""

import itertools

import numpy as np
import pytest

from gpo.odometry.kinematics import between
from gpo.pipeline.config import load_config
from gpo.pipeline.odometer import FloorOdometer
from gpo.sim.floors import make_floor
from gpo.sim.outages import KINDS, Outage, apply_outage, outage_at, outage_fraction
from gpo.sim.paths import named_plan
from gpo.sim.record import FLOOR_OUTAGES, PRESETS
from gpo.sim.render import FloorRenderer
from gpo.sim.rigs import RIGS


@pytest.fixture(scope="module")
def frames():
    """Four frames of the fisheye rig driving 0.4 m/s straight over the raised floor, 30 Hz."""
    rig = RIGS["t265"]()
    renderer = FloorRenderer(rig, make_floor("raised", (-1.0, 2.0, -1.0, 1.0), 1e-3, 5))
    return [renderer.render(np.array([0.4 * k / 30, 0.0, 0.0]), frame_seed=k) for k in range(4)]


STEP_M = 0.4 / 30  # the truth's step between two frames, straight ahead
# a measured step's error, twice the worst measured (on the avx2 and sse4 paths too, .ci/fp-path): the clean frames'
# steps 15 micrometres and 5 microradians at most, the step after an outage 2.7 micrometres and 8.4 microradians
STEP_TOL_M, STEP_TOL_RAD = 3e-5, 2e-5


@pytest.mark.parametrize("kind", KINDS)
def test_every_outage_is_flagged_and_the_floor_is_measured_again_after_it(frames, kind):
    odometer = FloorOdometer(load_config())
    stamps = [round(k * 1e9 / 30) for k in range(4)]
    assert odometer.step(stamps[0], frames[0]).status == "first"
    hidden = odometer.step(stamps[1], apply_outage(kind, frames[1]))
    assert hidden.status == "coasted" and hidden.flag
    after = odometer.step(stamps[2], frames[2])
    assert after.status in ("coasted", "measured")  # the frame after may still be compared with the hidden one
    again = odometer.step(stamps[3], frames[3])
    assert again.status == "measured"  # and the next one is measured: its step is the truth's
    step = between(np.array(after.pose), np.array(again.pose))
    assert np.hypot(step[0] - STEP_M, step[1]) < STEP_TOL_M and abs(step[2]) < STEP_TOL_RAD


def test_the_clean_frames_are_measured(frames):
    odometer = FloorOdometer(load_config())
    records = [odometer.step(round(k * 1e9 / 30), frame) for k, frame in enumerate(frames)]
    assert [r.status for r in records] == ["first", "measured", "measured", "measured"]
    for start, end in itertools.pairwise(records):
        step = between(np.array(start.pose), np.array(end.pose))
        assert np.hypot(step[0] - STEP_M, step[1]) < STEP_TOL_M and abs(step[2]) < STEP_TOL_RAD


def test_outage_presets_hide_at_least_a_tenth_of_each_long_path():
    for k in (1, 2, 3):
        chosen = PRESETS[f"long{k}-outages"]
        assert chosen.outages == FLOOR_OUTAGES and chosen.path == f"long{k}" and chosen.seed == PRESETS[f"long{k}"].seed
        times = np.arange(0.0, named_plan(chosen.path).duration_s, 1 / 30)
        assert outage_fraction(chosen.outages, times) >= 0.10
    assert all(0.5 <= o.duration_s <= 3.0 for o in FLOOR_OUTAGES)
    assert {o.kind for o in FLOOR_OUTAGES} == set(KINDS)


def test_outage_lookup_and_bad_outages():
    outages = (Outage("glare", 1.0, 0.5),)
    assert outage_at(outages, 0.99) is None and outage_at(outages, 1.5) is None
    assert outage_at(outages, 1.0) == outages[0]
    with pytest.raises(ValueError, match="unknown outage kind 'fog'"):
        Outage("fog", 0.0, 1.0)
    with pytest.raises(ValueError, match="duration_s > 0"):
        Outage("glare", 0.0, 0.0)
