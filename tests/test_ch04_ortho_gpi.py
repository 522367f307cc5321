"""Chapter 04's Table 1 read from a figure: every way of measuring the block is a group of bars, every image a bar."""

import matplotlib.pyplot as plt
import pytest

from gpo.book.ch04_ortho_gpi import TABLE1_FLOOR, draw_table1
from gpo.experiments.table1 import PaperTable1Row, Table1Row


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
