"""Files as the chapters show them: numbers rounded, structure kept."""

import pytest

from gpo.book.shown import rounded


def test_a_calibration_reads_at_six_significant_digits():
    text = "intrinsics: [0.5999394332078319, 286.21372062199777]\nposition_m: [4.327942524631062e-05, 0.12]\nrate: 30.0"
    shown = "intrinsics: [0.599939, 286.214]\nposition_m: [4.32794e-05, 0.12]\nrate: 30.0"
    assert rounded(text, significant=6) == shown


def test_whole_numbers_and_timestamps_are_kept():
    text = "resolution: [848, 800]\n1700000000.033333333 1.7170684351586196e-05 -8.61e-11 0.0 1.0"
    shown = "resolution: [848, 800]\n1700000000.033333333 0.000017 0.000000 0.000000 1.000000"
    assert rounded(text, decimals=6) == shown
    assert rounded("t 1700000000.033333333", significant=6) == "t 1700000000.033333333"


def test_names_with_digits_are_not_numbers():
    assert rounded("cam0 fisheye1 v1.2.3 x2.5", significant=2) == "cam0 fisheye1 v1.2.3 x2.5"


def test_one_precision_is_asked_for():
    with pytest.raises(ValueError):
        rounded("1.0", significant=3, decimals=2)
