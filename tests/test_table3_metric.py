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
    """Two vectors by three statistics by three tests; each printed average within a ten-thousandth of its tests'
    mean."""
    from gpo.experiments.table3 import PAPER_TABLE3, TABLE3_VECTORS

    for (vector, statistic), values in PAPER_TABLE3.values.items():
        assert vector in TABLE3_VECTORS and statistic in ("min", "max", "avg") and len(values) == 4
        assert abs(np.mean(values[:3]) - values[3]) <= 1e-4 + 1e-12
    assert PAPER_TABLE3.average("median") / PAPER_TABLE3.average("mean") == pytest.approx(0.0329 / 0.0732)


def _made_up_table3(route="ortho-gpi"):
    """A ``Table3`` of made-up errors: test k's relative errors with the median (k + 1) mm and 3 (k + 1) mm, with
    the mean twice those; final errors 10 mm and 20 mm on 4 m."""
    from gpo.experiments.table3 import Table3
    from gpo.metrics import FinalError

    class Run:  # what Table3.format reads of a floor run: no step coasted
        inliers = np.array([0, 30, 30])

    tests = {"Test1": "short1", "Test2": "short2", "Test3": "short3"}
    relative, errors, results = {}, {}, {}
    for k, test in enumerate(tests):
        for vector, factor in (("median", 1.0), ("mean", 2.0)):
            relative[test, vector] = factor * 1e-3 * (k + 1) * np.array([1.0, 2.0, 3.0])
            errors[test, vector] = FinalError(0.01 * factor, 0.0, 4.0, 100)
            results[test, vector] = Run()
    return Table3(tests, results, {}, errors, relative, "gpo", route)


def test_table3_prints_each_cell_beside_the_papers_and_names_its_floor_image():
    from gpo.experiments.table3 import PAPER_TABLE3

    table = _made_up_table3()
    values = table.values()
    assert values["median", "min"] == pytest.approx((0.001, 0.002, 0.003, 0.002))
    assert values["mean", "avg"] == pytest.approx((0.004, 0.008, 0.012, 0.008))
    text = table.format()
    lines = text.splitlines()
    assert lines[0].startswith("Table 3 on the ortho-GPI")
    assert "Test1 (3.88 | 4.00 m)" in lines[1]
    median_min = next(line for line in lines if line.startswith("GPO (median)"))
    paper = PAPER_TABLE3.values["median", "min"]
    assert f"{paper[0]:.4f} | 0.0010" in median_min and f"{paper[3]:.4f} | 0.0020" in median_min
    assert "(0.50 x)" in text  # here the median's average is half the mean's
    assert "Table 3 on the analytic" in _made_up_table3("analytic").format()


def test_table3_names_each_cell_where_the_median_is_not_below_the_mean():
    """The paper's Test1 minimum is the one cell of its table where the median (0.0019 m) is not below the mean
    (0.0018 m); the made-up table's median is below the mean everywhere."""
    lines = _made_up_table3().orderings()
    assert len(lines) == 3
    assert lines[0] == "median < mean, min: the paper 3 of 4 (not: Test1 0.0019 against 0.0018), here 4 of 4"
    assert lines[1] == "median < mean, max: the paper 4 of 4, here 4 of 4"
