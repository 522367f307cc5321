"""Lab E's pieces: what .ci/fp-path switches, a frame changed by one grey level, a sum's digits."""

import math

import numpy as np
import pytest

from gpo.book.lab_e_precision import (
    FP_PATH,
    PATHS,
    agreeing_digits,
    changed,
    fp_path_settings,
    machine,
    running_errors,
    sums,
)


def test_the_paths_are_read_from_the_script():
    settings = fp_path_settings()
    assert sorted(settings) == sorted(PATHS)
    assert settings["avx2"]["OPENBLAS_CORETYPE"] == "Haswell" and settings["sse4"]["OPENBLAS_CORETYPE"] == "Nehalem"
    for variables in settings.values():
        assert sorted(variables) == ["NPY_DISABLE_CPU_FEATURES", "OPENBLAS_CORETYPE", "OPENCV_CPU_DISABLE"]
    assert "AVX2" in settings["sse4"]["OPENCV_CPU_DISABLE"].split(",")
    assert FP_PATH.is_file()


def test_a_frame_changes_in_so_many_pixels_by_one_grey_level():
    image = np.random.default_rng(3).integers(0, 256, (80, 90), dtype=np.uint8)
    image[0, :] = 0
    image[1, :] = 255
    out = changed(image, 500, np.random.default_rng(0))
    difference = out.astype(int) - image.astype(int)
    assert np.count_nonzero(difference) == 500 and np.abs(difference).max() == 1
    assert out.dtype == np.uint8 and np.array_equal(changed(image, 500, np.random.default_rng(0)), out)
    assert np.array_equal(image[0] <= out[0], np.ones(90, bool)) and np.all(out[1] <= 255)


def test_digits_agree_up_to_the_first_that_differs():
    assert agreeing_digits(1.2345, 1.2346) == 4
    assert agreeing_digits(500159.25, 500159.25646368443) == 8
    assert agreeing_digits(0.1, 0.1) == 17
    assert agreeing_digits(9.99, 10.0) == 0  # another power of ten


def test_six_sums_one_exact():
    values = np.random.default_rng(0).random(10_000)
    answers = sums(values)
    assert len(answers) == 6 and answers["exact (math.fsum)"] == math.fsum(values)
    for way, total in answers.items():
        assert total == pytest.approx(math.fsum(values), rel=1e-5), way
    errors = running_errors(values, np.array([10, 100, 10_000]))
    assert errors["float32"][-1] > errors["float64"][-1]


def test_the_machine_names_its_path():
    found = machine()
    assert sorted(found) == ["NumPy's widest loops", "OpenBLAS kernels", "OpenCV's widest loops"]
    assert all(found.values())
