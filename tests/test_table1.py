"""The first paper's Table 1 under its definitions (``gpo.experiments.table1.paper_table1``)."""

import matplotlib.pyplot as plt
import numpy as np
import pytest

from gpo.book.ch04_ortho_gpi import table1_errors_panel
from gpo.cameras import T265_LIKE
from gpo.experiments.table1 import (
    CALIBRATION_ERRORS,
    PAPER_TABLE1,
    PAPER_TABLE1_ERRORS,
    PAPER_TABLE1_PRINTED,
    format_paper_table1,
    format_table1,
    miscalibrated,
    paper_table1,
    reproduce_table1,
)


def test_the_papers_truth_is_its_measured_squares():
    long, short, area = PAPER_TABLE1["truth"]
    assert long == pytest.approx(4 * 20.007) and short == pytest.approx(2 * 20.050)
    assert area == pytest.approx(long * short, abs=0.02)  # 3209.139 printed, 3209.123 from the two sides
    for image in ("GPI", "ortho-GPI"):  # the paper's (a + c) / 2 is the long side: near 80 mm, not 40
        assert PAPER_TABLE1[image][0] > 75 and PAPER_TABLE1[image][1] < 45


def test_the_papers_printed_table_is_its_numbers():
    for image in ("GPI", "ortho-GPI"):
        values = tuple(float(value) for value, _ in PAPER_TABLE1_PRINTED[image])
        assert values == PAPER_TABLE1[image]
        computed = abs(PAPER_TABLE1[image][0] - PAPER_TABLE1["truth"][0])
        assert PAPER_TABLE1_ERRORS[image][0] == pytest.approx(computed, abs=1.5e-3)  # its own rounding: 0.058


def test_the_suites_table_is_rounded_to_what_the_measurement_supports():
    rows = reproduce_table1(placements=[(0.0, 0.0, 0.0), (0.005, -0.005, 2.0)])
    lines = format_table1(rows).splitlines()
    assert len(lines) == 4 and lines[0].startswith("image")
    gpi = lines[1].split()
    assert gpi[0] == "GPI" and len(gpi[1].split(".")[1]) == 2 and "." not in gpi[5]  # sides in 0.01 mm, area in mm^2


def test_miscalibrated_applies_relative_focal_and_absolute_other_errors():
    camera = miscalibrated(T265_LIKE)
    assert camera.fx == pytest.approx(T265_LIKE.fx * (1 + CALIBRATION_ERRORS["fx"]))
    assert camera.cx == pytest.approx(T265_LIKE.cx + CALIBRATION_ERRORS["cx"])
    assert camera.alpha == pytest.approx(T265_LIKE.alpha + CALIBRATION_ERRORS["alpha"])
    assert miscalibrated(T265_LIKE, {}) == T265_LIKE


@pytest.fixture(scope="module")
def table():
    return paper_table1(mean_over=2)


def test_the_ortho_gpi_corrects_the_gpi_on_a_placement_it_never_saw(table):
    truth, rows = table
    assert truth == pytest.approx((80.0, 40.0, 3200.0))
    second = {row.image: row for row in rows if row.where == "second"}
    gpi_area, ortho_area = (abs(second[name].area_mm2 - truth[2]) for name in ("GPI", "ortho-GPI"))
    assert gpi_area > 10.0  # tens of mm^2: the miscalibrated, hand-picked GPI (measured 73 mm^2)
    assert ortho_area < gpi_area / 10  # measured 4.5 mm^2, a sixteenth
    assert abs(second["ortho-GPI"].long_mm - truth[0]) < 0.15  # measured 0.071 mm


def test_the_format_prints_the_papers_rows_first(table):
    text = format_paper_table1(*table)
    assert text.splitlines()[0].startswith("the paper")
    assert "84.664 (4.636)" in text and "3207.881 (1.258)" in text
    assert "80.085 (0.058)" in text and "36.660 (3.44)" in text  # the paper's errors as it prints them
    assert text.count("(a+c)/2 mm") == 4 and np.isfinite([row.area_mm2 for row in table[1]]).all()


def test_without_a_mean_only_the_two_placements_are_measured_and_printed():
    truth, rows = paper_table1(mean_over=0)
    assert sorted({row.where for row in rows}) == ["fitted", "second"] and len(rows) == 4
    text = format_paper_table1(truth, rows)
    assert "mean over placements" not in text and text.count("(a+c)/2 mm") == 3


def test_the_errors_panel_follows_the_picked_corners(capsys):
    def gpi_second_long_error() -> float:
        lines = [line for line in capsys.readouterr().out.splitlines() if line.strip().startswith("GPI, second")]
        return float(lines[-1].split("sides off")[1].split()[0])  # the last redraw's

    panel = table1_errors_panel()
    controls = {control.description: control for control in panel.children[0].children}
    at_two_px = gpi_second_long_error()
    controls["corner pick sigma [px]"].value = 0.0
    controls["calibration errors x"].value = 0.0
    exact = gpi_second_long_error()
    plt.close("all")
    # hand-picked corners 2 px off move the GPI's long sides by about a millimetre; picked exactly, a few tenths
    assert at_two_px > 0.5 and exact < at_two_px / 2
