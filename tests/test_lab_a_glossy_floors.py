"""Lab A's glossy floors: the check's three variants as configs, the runs' table, a frame's true shift, and the strip of
what measured each step."""

from types import SimpleNamespace

import numpy as np
import pytest

from gpo.book.lab_a_glossy_floors import (
    STEP_KINDS,
    VARIANTS,
    _true_shift,
    draw_steps,
    whole_view_text,
    with_check,
)
from gpo.metrics import FinalError
from gpo.pipeline.config import load_config
from gpo.pipeline.odometer import Status

pytestmark = pytest.mark.usefixtures("close_figures")  # conftest.py


def test_the_three_variants_turn_the_check_off_on_and_never_wary():
    shipped = load_config()
    off, on, never = (with_check(shipped, variant).klt for variant in VARIANTS)
    assert off.overview_scale == 0.0
    assert (on.overview_scale, on.overview_wary_share) == (shipped.klt.overview_scale, shipped.klt.overview_wary_share)
    assert on.overview_scale > 0 and on.overview_wary_share > 0
    assert (never.overview_scale, never.overview_wary_share) == (shipped.klt.overview_scale, 0.0)


def test_the_table_has_a_cell_per_method_and_variant_and_a_dash_where_none_ran():
    errors = {
        ("gpo-exact", "tracks alone"): FinalError(0.5, np.radians(-10.0), 5.0, 100),
        ("gpo-exact", "with the check"): FinalError(0.05, np.radians(2.0), 5.0, 100),
        ("gpo-exact", "never wary"): FinalError(0.06, np.radians(2.5), 5.0, 100),
        ("gpo", "tracks alone"): FinalError(1.0, np.radians(-30.0), 5.0, 100),
        ("gpo", "with the check"): FinalError(1.0, np.radians(-30.0), 5.0, 100),
    }
    lines = whole_view_text(errors).splitlines()
    assert lines[0].split() == ["method", "tracks", "alone", "with", "the", "check", "never", "wary"]
    assert lines[1].split() == ["gpo-exact", "10.00", "%", "-10.0", "deg", "1.00", "%", "+2.0", "deg", "1.20", "%",
                                "+2.5", "deg"]  # fmt: skip
    assert lines[2].split()[-1] == "-"


def test_a_step_forward_moves_the_floor_image_s_middle_down_by_the_step_in_pixels():
    config = load_config()
    step = 0.01  # m straight ahead
    shift = _true_shift(config, np.array([step, 0.0, 0.0]))
    np.testing.assert_allclose(shift, [0.0, step / config.floor.metres_per_pixel], atol=1e-9)


def test_the_strip_shows_what_measured_each_step():
    def record(status=Status.MEASURED, overview=False, disagreed=False, slower=0, kept=50):
        return SimpleNamespace(status=status, overview=overview, disagreed=disagreed, slower=slower, kept=kept)

    records = [
        record(Status.FIRST),
        record(),
        record(disagreed=True),
        record(overview=True, disagreed=True),
        record(Status.COASTED),
        record(slower=20),
    ]
    upper = draw_steps(records)
    strip = upper.images[0].get_array()
    kinds = list(STEP_KINDS)
    expected = ["the tracks", "the tracks, in doubt", "the whole view", "not measured", "the tracks"]
    assert strip[0].tolist() == [kinds.index(kind) for kind in expected]
    lower = upper.figure.axes[1].images[0].get_array()
    assert lower[0].tolist() == [False, False, False, False, True]
