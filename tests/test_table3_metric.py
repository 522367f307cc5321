"""The first paper's Table 3 measure (``relative_translation_errors``) on analytic paths."""

import numpy as np
import pytest

from gpo.io.trajectory import Trajectory
from gpo.metrics import relative_translation_errors


def straight(scale=1.0, seconds=5.0, rate=20.0):
    t = np.arange(0.0, seconds, 1.0 / rate)
    positions = np.column_stack([scale * t, np.zeros_like(t), np.zeros_like(t)])
    stamps = np.round(t * 1e9).astype(np.int64)
    return Trajectory(stamps, positions, np.tile([0.0, 0.0, 0.0, 1.0], (len(t), 1)))


def test_a_two_percent_scale_error_is_two_centimetres_a_metre():
    errors = relative_translation_errors(straight(1.02), straight(1.0))
    assert len(errors) > 10
    np.testing.assert_allclose(errors, 0.02, atol=2e-3)  # pairs are at least 1 m apart, within evo's 10 % tolerance


def test_the_truth_against_itself_is_zero():
    assert relative_translation_errors(straight(), straight()).max() == pytest.approx(0.0, abs=1e-12)


def test_a_path_shorter_than_a_segment_is_an_error():
    with pytest.raises(ValueError, match=r"1\.0 m"):
        relative_translation_errors(straight(seconds=0.5), straight(seconds=0.5))


def test_the_papers_table3_is_every_row_and_test_it_prints():
    """Two vectors by three statistics by three tests; each printed average within a ten-thousandth of its tests' mean;
    the layout of the suite's table."""
    from gpo.experiments.table3 import PAPER_TABLE3, TABLE3_VECTORS

    for (vector, statistic), values in PAPER_TABLE3.values.items():
        assert vector in TABLE3_VECTORS and statistic in ("min", "max", "avg") and len(values) == 4
        assert abs(np.mean(values[:3]) - values[3]) <= 1e-4 + 1e-12
    assert PAPER_TABLE3.average("median") / PAPER_TABLE3.average("mean") == pytest.approx(0.0329 / 0.0732)
    lines = PAPER_TABLE3.format().splitlines()
    assert "Test1 (3.88)" in lines[1] and len(lines) == 2 + 6
