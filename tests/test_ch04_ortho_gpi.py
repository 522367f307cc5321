"""Chapter 04's Table 1 read from a figure: every way of measuring the block is a group of bars, every image a bar; how
much floor one fisheye pixel covers."""

import matplotlib.pyplot as plt
import pytest

from gpo.book.ch04_ortho_gpi import TABLE1_FLOOR, draw_table1, fisheye_pixel_on_floor
from gpo.experiments.table1 import PaperTable1Row, Table1Row
from gpo.sim.rigs import t265_rig


def test_table1_draws_the_papers_rows_the_suites_rows_and_its_own_measure():
    truth = (80.0, 40.0, 3200.0)
    paper_rows = [
        PaperTable1Row(image, where, 80.0 + error, 40.0 - error, 3200.0 - 10 * error)
        for where in ("fitted", "second", "mean")
        for image, error in (("GPI", 1.0), ("ortho-GPI", 0.0))
    ]
    suite_rows = [
        Table1Row(image, 40.0, 80.0 - error, 3199.0, 0.0, -error, -1.0, 0.03, 2.4)
        for image, error in (("GPI", 0.16), ("ortho-GPI", 0.03), ("analytic", 0.03))
    ]
    fig = draw_table1(truth, paper_rows, suite_rows)
    axes = fig.axes
    assert len(axes) == 3
    widths = [bar.get_width() for bar in axes[0].patches]
    assert len(widths) == 2 + 3 * 2 + 3 + 3  # the paper, three of its placements, the suite's mean and one placement
    assert widths[0] == pytest.approx(4.636) and widths[1] == pytest.approx(0.058)  # the paper's (a+c)/2 errors
    assert min(widths) == TABLE1_FLOOR  # an error of zero is drawn at the floor of the log scale
    assert len(axes[0].get_yticklabels()) == 6
    plt.close(fig)


def test_a_fisheye_pixel_covers_more_floor_further_ahead_and_more_along_than_across():
    rig = t265_rig()
    near_across, near_along = fisheye_pixel_on_floor(rig.camera, rig.mount, (0.75, 0.0))
    far_across, far_along = fisheye_pixel_on_floor(rig.camera, rig.mount, (0.90, 0.0))
    assert 0.5 < near_across < far_across < 1.5  # millimetres: about one across at the floor board
    assert near_along > near_across and far_along > far_across  # the floor is seen at a slant: longer along
    assert far_along > near_along
