"""Lab B's population results: each fisheye draw's error on its drawn floor beside the same floor matte."""

import matplotlib.pyplot as plt

from gpo.book.lab_b_population import (
    CAUSES,
    PEER,
    cause_of,
    distributions_text,
    draw_drawn,
    draw_listed,
    draw_peer_groups,
    draw_population,
    draw_population_distributions,
    draw_sources,
    drawn_text,
    failing_text,
    finish,
    population_errors,
    population_groups,
    population_text,
    run_errors,
    sources_by_finish,
    sources_text,
    targets_text,
)


def result(errors: dict, p90: dict) -> dict:
    """A ``benchmarks/population.py`` result holding ``errors`` {(draw, method): %} and each method's ``p90``."""
    return {
        "methods": {
            method: {"p90": value, "p90_target": {"gpo-exact": 0.3, "gpo-rigid": 0.5}[method]}
            for method, value in p90.items()
        },
        "draw_parameters": {
            "draw000-fisheye": {"floor": "wood"},
            "draw002-fisheye": {"floor": "industrial"},
            "draw001-downward": {"floor": "raised"},
        },
        "runs": [{"draw": d, "method": m, "final_error_percent": e} for (d, m), e in errors.items()]
        + [{"draw": "draw001-downward", "method": "features", "final_error_percent": 0.05}],
    }


DRAWN = result(
    {
        ("draw000-fisheye", "gpo-exact"): 0.04,
        ("draw002-fisheye", "gpo-exact"): 2.7,
        ("draw000-fisheye", "gpo-rigid"): 0.11,
        ("draw002-fisheye", "gpo-rigid"): 2.1,
    },
    {"gpo-exact": 2.4, "gpo-rigid": 1.9},
)
MATTE = result(
    {
        ("draw000-fisheye", "gpo-exact"): 0.04,
        ("draw002-fisheye", "gpo-exact"): 0.013,
        ("draw000-fisheye", "gpo-rigid"): 0.11,
        ("draw002-fisheye", "gpo-rigid"): 0.27,
    },
    {"gpo-exact": 0.04, "gpo-rigid": 0.25},
)


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


def test_a_draws_finish_comes_from_its_sheen_or_for_the_first_population_its_screed():
    assert finish({"floor": "wood", "sheen": "on"}) == "glossy"
    assert finish({"floor": "industrial", "sheen": "off"}) == "matte"
    assert finish({"floor": "wood+industrial"}) == "glossy" and finish({"floor": "raised"}) == "matte"


def test_groups_count_a_mixed_floor_under_both_kinds_and_a_failed_run_as_infinitely_far():
    result = dict(DRAWN, draw_parameters={**DRAWN["draw_parameters"], "draw000-fisheye": {"floor": "wood+raised"}})
    result["runs"] = [*result["runs"], {"draw": "draw002-fisheye", "method": "gpo-exact", "final_error_percent": None}]
    groups = population_groups(result)["gpo-exact"]
    assert groups["wood"] == groups["raised"] == [0.04] and groups["matte"] == [0.04]
    assert groups["industrial"] == groups["glossy"] == [2.7, float("inf")] and len(groups["all"]) == 3


def test_the_distributions_give_each_population_of_each_method_a_line_with_its_p90s():
    lines = distributions_text({"short": DRAWN, "matte": MATTE}).splitlines()
    exact = [line.split() for line in lines if line.startswith("gpo-exact")]
    # the p90 of (0.04, 2.7) by linear interpolation: 0.04 + 0.9 * 2.66
    assert exact[0][:7] == ["gpo-exact", "(0.3)", "short", "2", "1.370", "2.434", "2.70"]
    assert exact[0][-5:] == ["0.040", "-", "2.700", "0.040", "2.700"]  # wood, raised, industrial, matte, glossy
    assert [line.split()[0] for line in lines[1:-1]] == ["gpo-exact"] * 2 + ["gpo-rigid"] * 2 + ["features"] * 2


def test_the_distributions_figure_has_a_panel_per_method_with_both_populations():
    figure = draw_population_distributions({"short": DRAWN, "matte": MATTE}, ("gpo-exact", "gpo-rigid"), columns=3)
    assert [ax.get_title() for ax in figure.axes if ax.get_visible()] == ["gpo-exact", "gpo-rigid"]
    assert len(figure.axes) == 3  # one row of three panels, the third hidden
    points = sum(len(c.get_offsets()) for c in figure.axes[0].collections if len(c.get_offsets()))
    assert points >= 4 and figure.axes[0].get_yscale() == "log"
    plt.close(figure)


def test_the_correlation_peers_runs_count_as_a_method_of_their_own():
    result = dict(
        DRAWN,
        peer={
            "runs": {
                "draw000-fisheye": {"final_error_percent": 0.5, "final_heading_deg": 1.0},
                "draw002-fisheye": {"final_error_percent": 3.0, "final_heading_deg": 2.0},
            }
        },
    )
    peer = [row for row in run_errors(result) if row[0] == PEER]
    assert peer == [(PEER, ("wood",), "matte", 0.5), (PEER, ("industrial",), "glossy", 3.0)]
    lines = distributions_text({"paper": result}).splitlines()
    assert [line.split()[:4] for line in lines if line.startswith(PEER)] == [[PEER, "paper", "2", "1.750"]]


def test_the_failing_runs_are_counted_with_those_no_cause_names():
    result = {
        "methods": {
            "gpo-exact": {"runs": 4, "p90_target": 0.3},
            "fused": {"runs": 4, "p90_target": None},
            "gpo-rigid": {"runs": 4, "p90_target": 0.5},
        },
        "failing": [
            {"method": "gpo-exact", "over": 0.3, "explained": True},
            {"method": "gpo-exact", "over": 0.3, "explained": False},
            {"method": "fused", "over": 0.3, "explained": True},
        ],
    }
    lines = failing_text(result).splitlines()
    assert lines[0].split() == [
        "gpo-exact",
        "2",
        "of",
        "4",
        "runs",
        "over",
        "0.3",
        "%",
        "or",
        "not",
        "finished,",
        "1",
        "of",
        "them",
        "without",
        "a",
        "named",
        "cause",
    ]
    assert lines[1].split()[:8] == ["fused", "1", "of", "4", "runs", "over", "0.3", "%"]
    assert lines[2].split()[:8] == ["gpo-rigid", "0", "of", "4", "runs", "over", "0.5", "%"]


def test_a_run_no_cause_names_says_how_its_heading_error_grew_against_the_truth():
    walk = {"steps": 14, "mean_deg": 0.199, "sd_deg": 0.478, "t": 1.56, "steady": False}
    result = {
        "methods": {"features": {"runs": 30, "p90_target": 0.3}},
        "failing": [
            {
                "method": "features",
                "over": 0.3,
                "explained": False,
                "draw": "draw029-downward",
                "final_error_percent": 0.4034,
                "heading_steps": walk,
            },
            {
                "method": "features",
                "over": 0.3,
                "explained": True,
                "draw": "draw045-downward",
                "final_error_percent": 3.149,
                "heading_steps": dict(walk, steady=True),
            },
        ],
    }
    lines = failing_text(result).splitlines()
    assert len(lines) == 2 and "1 of them without a named cause" in lines[0]
    assert lines[1].split()[:3] == ["draw029-downward", "0.403", "%,"] and "a random walk" in lines[1]
    assert "+0.199 +- 0.478 deg a metre over 14 metres (t +1.6)" in lines[1]


def test_the_fused_route_is_listed_where_it_ends_further_off_than_its_better_source():
    runs = {
        "draw000-fisheye": {"fused": 0.011, "gpo-exact": 0.007, "camera": 0.2, "over_better": 0.004, "ratio": 1.57},
        "draw048-fisheye": {"fused": 1.19, "gpo-exact": 10.18, "camera": 0.166, "over_better": 1.024, "ratio": 7.17},
        "draw020-fisheye": {"fused": 0.006, "gpo-exact": 0.93, "camera": 0.3, "over_better": -0.924, "ratio": 0.01},
    }
    lines = sources_text({"sources": {"floor_method": "gpo-exact", "draws": 3, "worse": 2, "runs": runs}}).splitlines()
    assert lines[0] == (
        "fused worse than the better of gpo-exact and the camera alone on 2 of 3 draws; by more than 0.01 points on 1:"
    )
    assert lines[1:] == ["  draw048-fisheye: fused 1.190 %, gpo-exact 10.180 %, camera 0.166 % (x7.17 the better)"]


def listed(method: str, draw: str, error: float, **named) -> dict:
    """A run a report lists: nothing named unless ``named`` says so."""
    return {
        "method": method,
        "draw": draw,
        "final_error_percent": error,
        "status": "ok",
        "flags": {},
        "frames_not_measured": {},
        "cautions": [],
        "outside_paper_model": False,
        "explained": bool(named),
    } | named


def test_a_listed_run_is_counted_under_the_first_cause_it_names():
    assert cause_of(listed("gpo", "d", 40.0, outside_paper_model=True, flags={"too few tracks kept": 3})) == CAUSES[0]
    assert cause_of(listed("gpo-exact", "d", 2.0, frames_not_measured={"coasted": 2})) == CAUSES[1]
    whole = "1339 of 1590 steps measured on the whole view, the tracks disagreeing with it"
    assert (
        cause_of(listed("fused", "d", 1.2, cautions=[whole, "5 steps held a second, slower layer of motion"]))
        == CAUSES[2]
    )
    assert (
        cause_of(listed("fused", "d", 0.4, cautions=["5 of 9 steps held a second, slower layer of motion"]))
        == CAUSES[3]
    )
    assert cause_of(listed("features", "d", 0.4)) == CAUSES[4]


PAPER = {
    "draw_parameters": {
        "draw000-fisheye": {"floor": "industrial", "sheen": "on", "path_m": 10.0, "height_m": 0.2},
        "draw002-fisheye": {"floor": "wood", "sheen": "off", "path_m": 6.0, "height_m": 0.1},
        "draw001-downward": {"floor": "raised", "sheen": "on", "path_m": 12.0, "height_m": 0.3},
    },
    "methods": {
        "gpo-exact": {
            "runs": 2,
            "p90": 2.0,
            "worst": 8.0,
            "p90_target": 0.3,
            "by_finish": {"matte": {"p90": 0.05}, "glossy": {"p90": 3.0}},
        },
        "features": {
            "runs": 1,
            "p90": 0.2,
            "worst": 0.2,
            "p90_target": 0.3,
            "by_finish": {"matte": {"p90": 0.1}, "glossy": {"p90": 0.2}},
        },
    },
    "failing": [listed("gpo-exact", "draw000-fisheye", 8.0, frames_not_measured={"coasted": 4})],
    "peer": {
        "ahead_everywhere": {"gpo-exact": False},
        "groups": {
            "industrial, glossy": {"draws": 1, "peer": 3.0, "gpo-exact": 8.0, "gpo-rigid": 2.0},
            "wood, matte": {"draws": 1, "peer": 0.5, "gpo-exact": 0.05, "gpo-rigid": 0.1},
        },
    },
    "sources": {
        "floor_method": "gpo-exact",
        "draws": 2,
        "worse": 1,
        "worst_draw": "draw000-fisheye",
        "runs": {
            "draw000-fisheye": {"fused": 1.2, "gpo-exact": 8.0, "camera": 0.2, "over_better": 1.0, "ratio": 6.0},
            "draw002-fisheye": {"fused": 0.04, "gpo-exact": 0.05, "camera": 0.9, "over_better": -0.01, "ratio": 0.8},
        },
    },
}


def test_what_was_drawn_is_told_per_rig():
    lines = drawn_text(PAPER).splitlines()
    assert lines[0].split()[:7] == ["fisheye", "2", "draws,", "1", "glossy", "(1", "on"]
    assert "paths  6.0-10.0 m, camera 10.0-20.0 cm" in lines[0] and lines[1].startswith("downward")
    figure = draw_drawn(PAPER)
    assert [ax.get_title() for ax in figure.axes] == ["floors drawn", "paths", "heights"]
    plt.close(figure)


def test_every_target_is_said_met_or_missed():
    lines = targets_text(PAPER).splitlines()
    assert lines[1].split()[-1] == "missed" and lines[2].split()[-1] == "met"  # p90 2.0 > 0.3; 0.2 <= 0.3
    assert lines[3].split()[-3:] == ["4.00", "x", "missed"] and lines[4].split()[-3:] == ["1.00", "x", "met"]
    assert "missed: industrial, glossy" in lines[5]
    assert lines[-1].endswith("missed on 1 of 2")


def test_the_fused_route_is_set_beside_its_sources_by_finish_and_drawn_per_draw():
    lines = sources_by_finish(PAPER).splitlines()
    assert lines[0].startswith("matte   fused worse on  0 of  1 draws")
    assert lines[1].startswith("glossy  fused worse on  1 of  1 draws, by at most 1.000 points")
    assert lines[1].endswith("gpo-exact 0, camera 1")
    ax = draw_sources(PAPER)
    assert [t.get_text() for t in ax.get_xticklabels()] == ["002", "000"]  # in order of fused / better source
    plt.close(ax.figure)


def test_the_listed_runs_and_the_peer_are_drawn():
    figure = draw_listed({**PAPER, "failing": [dict(PAPER["failing"][0], heading_steps={"t": 1.2})]})
    assert figure.axes[1].get_yscale() == "log"
    plt.close(figure)
    ax = draw_peer_groups(PAPER)
    assert len(ax.patches) == 6  # two groups, each with the peer's bar and the two fisheye methods'
    plt.close(ax.figure)
