"""Chapter 09's population comparison: each fisheye draw's error on its drawn floor beside the same floor matte."""

import matplotlib.pyplot as plt

from gpo.book.ch09_evaluation import draw_population, population_errors, population_text


def result(errors: dict, p90: dict) -> dict:
    """A ``benchmarks/population.py`` result holding ``errors`` {(draw, method): %} and each method's ``p90``."""
    return {
        "methods": {method: {"p90": value, "p90_target": {"gpo-exact": 0.3, "gpo-rigid": 0.5}[method]}
                    for method, value in p90.items()},
        "draw_parameters": {"draw000-fisheye": {"floor": "wood"}, "draw002-fisheye": {"floor": "industrial"},
                            "draw001-downward": {"floor": "raised"}},
        "runs": [{"draw": d, "method": m, "final_error_percent": e} for (d, m), e in errors.items()]
        + [{"draw": "draw001-downward", "method": "features", "final_error_percent": 0.05}],
    }


DRAWN = result({("draw000-fisheye", "gpo-exact"): 0.04, ("draw002-fisheye", "gpo-exact"): 2.7,
                ("draw000-fisheye", "gpo-rigid"): 0.11, ("draw002-fisheye", "gpo-rigid"): 2.1},
               {"gpo-exact": 2.4, "gpo-rigid": 1.9})
MATTE = result({("draw000-fisheye", "gpo-exact"): 0.04, ("draw002-fisheye", "gpo-exact"): 0.013,
                ("draw000-fisheye", "gpo-rigid"): 0.11, ("draw002-fisheye", "gpo-rigid"): 0.27},
               {"gpo-exact": 0.04, "gpo-rigid": 0.25})


def test_each_fisheye_draw_pairs_its_drawn_and_matte_errors():
    rows = population_errors(DRAWN, MATTE)
    assert list(rows) == ["draw000-fisheye", "draw002-fisheye"]  # the downward draw has no fisheye method
    assert rows["draw002-fisheye"] == {"floor": "industrial", "gpo-exact": (2.7, 0.013), "gpo-rigid": (2.1, 0.27)}


def test_the_text_gives_every_draw_and_each_methods_p90_and_target():
    lines = population_text(DRAWN, MATTE).splitlines()
    assert lines[2].split() == ["draw002-fisheye", "industrial", "2.700", "0.013", "2.100", "0.270"]
    assert lines[3].split() == ["p90", "2.400", "0.040", "1.900", "0.250"]
    assert lines[4].endswith("gpo-exact 0.3 %, gpo-rigid 0.5 %")


def test_the_figure_has_a_log_panel_per_method_with_its_target():
    figure = draw_population(DRAWN, MATTE)
    assert [ax.get_title() for ax in figure.axes] == ["gpo-exact", "gpo-rigid"]
    assert all(ax.get_yscale() == "log" for ax in figure.axes)
    assert [ax.lines[-1].get_ydata()[0] for ax in figure.axes] == [0.3, 0.5]
    plt.close(figure)
