"""The feature odometer's figures and panel: what is drawn is what the matches hold, and each control reaches the
odometer without the keypoints being detected again."""

import re

import cv2
import matplotlib.pyplot as plt
import numpy as np
import pytest
from matplotlib.collections import LineCollection, PatchCollection, PolyCollection
from matplotlib.colors import to_rgba
from matplotlib.patches import StepPatch
from textures import blurred_noise

import gpo.book.ch08_floor_features
from gpo.book.ch08_floor_features import (
    draw_band_selection,
    draw_feature_matches,
    draw_invariance_loops,
    draw_keypoints,
    draw_match_histogram,
    feature_panel,
    paper_value,
)
from gpo.motion.keypoints import FeatureParameters, FeatureTracker, detect, histogram_filter

SIZE = (320, 240)  # width, height
NOISY = {"detector": "orb", "ratio": 1.0, "invariance_threshold": 0.95}  # wrong matches for both filters to reject


pytestmark = pytest.mark.usefixtures("close_figures")  # conftest.py


def _floor(seed=0) -> np.ndarray:
    """A seeded floor-like texture, 8-bit grey: uniform noise blurred at three scales."""
    return blurred_noise(np.random.default_rng(seed), SIZE).astype(np.uint8)


@pytest.fixture(scope="module")
def frames() -> tuple[np.ndarray, np.ndarray]:
    """A floor frame and the next one, turned 2 degrees about its centre and shifted (9, -6) px."""
    previous = _floor(1)
    matrix = cv2.getRotationMatrix2D((SIZE[0] / 2, SIZE[1] / 2), 2.0, 1.0)
    matrix[:, 2] += (9.0, -6.0)
    current = cv2.warpAffine(previous, matrix, SIZE, flags=cv2.INTER_CUBIC, borderMode=cv2.BORDER_REFLECT)
    return previous, current


def _matches(frames, **fields):
    parameters = FeatureParameters(**fields)
    return FeatureTracker(parameters).matches(*(detect(image, parameters) for image in frames))


def _lines_by_colour(ax) -> dict[str, np.ndarray]:
    """The segments (K, 2, 2) of each ``LineCollection`` on ``ax`` by colour name."""
    names = {to_rgba(name): name for name in ("tab:red", "tab:orange", "tab:green", "tab:gray")}
    drawn = {}
    for collection in ax.collections:
        if isinstance(collection, LineCollection) and not isinstance(collection, PolyCollection):
            colour = names[tuple(collection.get_colors()[0])] if len(collection.get_colors()) else None
            drawn[colour] = np.array(collection.get_segments()).reshape(-1, 2, 2)
    return drawn


def _polygons_by_colour(ax) -> dict[str, list[np.ndarray]]:
    """The vertices of each polygon of each ``PolyCollection`` on ``ax`` by edge colour name."""
    names = {to_rgba("tab:green"): "green", to_rgba("tab:red"): "red"}
    return {
        names[tuple(collection.get_edgecolor()[0])]: [path.vertices for path in collection.get_paths()]
        for collection in ax.collections
        if isinstance(collection, PolyCollection)
    }


def test_keypoints_are_circles_of_their_diameter(frames):
    keypoints = detect(frames[0], FeatureParameters(detector="sift"))
    ax = draw_keypoints(frames[0], keypoints)
    (circles,) = [collection for collection in ax.collections if isinstance(collection, PatchCollection)]
    extents = np.array([path.get_extents().bounds for path in circles.get_paths()])  # u, v, width, height
    assert len(extents) == len(keypoints) > 50
    np.testing.assert_allclose(extents[:, :2] + extents[:, 2:] / 2, keypoints.points, atol=1e-6)
    np.testing.assert_allclose(extents[:, 2], keypoints.sizes, rtol=1e-6)
    assert ax.get_title() == f"{len(keypoints)} keypoints"


def test_matches_are_coloured_by_their_fate(frames):
    matches = _matches(frames, **NOISY)
    through_histogram = matches.histogram[1].kept
    ax = draw_feature_matches(frames[1], matches)
    drawn = _lines_by_colour(ax)
    counts = {colour: len(segments) for colour, segments in drawn.items()}
    rejected_late = through_histogram & ~matches.kept
    assert counts == {
        "tab:red": (~through_histogram).sum(),
        "tab:orange": rejected_late.sum(),
        "tab:green": matches.kept.sum(),
    }
    assert min(counts.values()) > 0
    np.testing.assert_allclose(drawn["tab:green"], np.stack([matches.start, matches.end], axis=1))
    start, end = matches.matched
    np.testing.assert_allclose(drawn["tab:orange"], np.stack([start[rejected_late], end[rejected_late]], axis=1))
    legend = {text.get_text() for text in ax.get_legend().get_texts()}
    assert legend == {
        f"{counts['tab:red']} rejected by the histogram filter",
        f"{counts['tab:orange']} rejected by the invariance check",
        f"{counts['tab:green']} kept",
    }
    assert ax.get_title() == f"{counts['tab:green']} of {len(matches.pairs)} matches kept"


def test_a_frame_flagged_before_filtering_keeps_no_match(frames):
    matches = _matches(frames, detector="orb", min_matches=10_000)
    assert matches.flag.startswith("too few keypoints") and matches.kept.all()
    ax = draw_feature_matches(frames[1], matches)
    counts = {colour: len(segments) for colour, segments in _lines_by_colour(ax).items()}
    assert counts == {"tab:red": 0, "tab:orange": 0, "tab:green": 0, "tab:gray": len(matches.pairs)}
    assert ax.get_title() == f"0 of {len(matches.pairs)} matches kept"


@pytest.mark.parametrize("stage", [0, 1])
def test_histogram_bars_and_lines_sit_where_the_stage_says(frames, stage):
    histogram = _matches(frames, **NOISY).histogram[stage]
    ax = draw_match_histogram(histogram, label="x")
    (bars,) = [patch for patch in ax.patches if isinstance(patch, StepPatch)]
    counts, edges, _ = bars.get_data()
    np.testing.assert_array_equal(counts, histogram.counts)
    np.testing.assert_array_equal(edges, histogram.edges)
    lines = sorted(line.get_xdata()[0] for line in ax.lines)
    mean, sigma = histogram.mean, histogram.sigma
    np.testing.assert_allclose(lines, [mean - sigma, mean, mean + sigma])
    assert sigma > 1.0
    assert ax.get_title() == f"{histogram.kept.sum()} of {len(histogram.values)} kept"
    assert ax.get_xlabel() == "x"


def test_an_empty_histogram_draws_without_lines():
    _, orientation, _ = histogram_filter(np.zeros((4, 2)), np.full((4, 2), 0.2))  # all too short to bin
    assert np.isnan(orientation.mean)
    ax = draw_match_histogram(orientation)
    assert len(ax.lines) == 0 and ax.get_title() == "4 of 4 kept"


@pytest.mark.parametrize("max_loops", [1000, 5])
def test_loops_are_drawn_through_their_matches_start_points(frames, max_loops):
    matches = _matches(frames, **NOISY)
    check = matches.invariance
    assert not matches.histogram_kept.all()  # the loops count among the histogram filter's survivors only
    ax = draw_invariance_loops(frames[0], matches, max_loops=max_loops)
    polygons = _polygons_by_colour(ax)
    kept, tried = check.kept_loops.sum(), len(check.loops)
    assert min(kept, tried - kept) > 5
    assert len(polygons["green"]) == min(kept, max_loops)
    assert len(polygons["red"]) == min(tried - kept, max_loops)
    start = matches.matched[0][matches.histogram_kept]
    for colour, passed in (("green", True), ("red", False)):
        loops = [loop for loop, kept_loop in zip(check.loops, check.kept_loops, strict=True) if kept_loop == passed]
        for vertices, loop in zip(polygons[colour], loops, strict=False):
            np.testing.assert_allclose(vertices[: check.cardinality], start[loop])
    assert ax.get_title() == f"{kept} of {tried} loops kept, C = {check.cardinality}"
    widths = {
        tuple(collection.get_edgecolor()[0]): collection.get_linewidth()[0]
        for collection in ax.collections
        if isinstance(collection, PolyCollection)
    }
    assert widths[to_rgba("tab:red")] > widths[to_rgba("tab:green")]  # the few rejected loops stand out


def test_loops_without_the_check(frames):
    ax = draw_invariance_loops(frames[0], _matches(frames, detector="orb", invariance_check=False))
    assert _polygons_by_colour(ax) == {} and ax.get_title() == "the invariance check did not run"


def _controls(panel) -> dict:
    return {control.description: control for control in panel.children[0].children}


def _counts(printed: str) -> tuple[int, ...]:
    """The matches left after each stage, read from the last line ``printed``."""
    last = printed.splitlines()[-1]
    found = re.search(r"(\d+) matches, (\d+) after the histogram filter, (\d+) after the invariance check", last)
    return tuple(int(count) for count in found.groups())


def test_panel_controls_start_from_the_parameters(frames):
    parameters = FeatureParameters(detector="orb", invariance_threshold=0.9, cardinality=4, ratio=0.7)
    controls = _controls(feature_panel(*frames, parameters))
    assert set(controls) == {"detector", "t", "C", "orientation bins", "length bins", "ratio test"}
    assert controls["detector"].options == ("orb", "sift")
    assert [label for label, _ in controls["C"].options] == ["auto", "3", "4", "5", "6"]
    assert dict(controls["C"].options)["auto"] == 0  # a Dropdown's None would show no choice
    values = {name: control.value for name, control in controls.items()}
    assert values == {
        "detector": "orb",
        "t": 0.9,
        "C": 4,
        "orientation bins": 180,
        "length bins": 160,
        "ratio test": 0.7,
    }
    sliders = ("t", "orientation bins", "length bins", "ratio test")
    assert all(not controls[name].continuous_update for name in sliders)
    assert (controls["t"].min, controls["t"].max, controls["t"].step) == (0.5, 1.0, 0.01)
    assert (controls["orientation bins"].min, controls["orientation bins"].max) == (10, 360)
    assert (controls["length bins"].min, controls["length bins"].max) == (10, 320)
    assert (controls["ratio test"].min, controls["ratio test"].max) == (0.5, 1.0)


def test_automatic_cardinality_shows_as_auto_and_runs_as_none(frames):
    controls = _controls(feature_panel(*frames))
    automatic = _matches(frames, detector="sift").invariance.cardinality
    assert controls["C"].label == "auto" and automatic != 3
    assert plt.gcf().axes[3].get_title().endswith(f"C = {automatic}")
    controls["C"].value = 3
    assert plt.gcf().axes[3].get_title().endswith("C = 3")
    controls["C"].value = 0
    assert plt.gcf().axes[3].get_title().endswith(f"C = {automatic}")


def test_panel_reads_out_each_stage_and_follows_the_controls(frames, capsys):
    panel = feature_panel(*frames)
    expected = _matches(frames, detector="sift")
    printed = capsys.readouterr().out
    assert _counts(printed) == (len(expected.pairs), expected.histogram_kept.sum(), expected.kept.sum())
    assert re.search(r"\(detect [0-9.]+ ms, match [0-9.]+ ms, histogram [0-9.]+ ms, invariance [0-9.]+ ms\)", printed)
    green = len(_lines_by_colour(plt.gcf().axes[0])["tab:green"])
    assert green == expected.kept.sum() > 50

    controls = _controls(panel)
    controls["t"].value = 1.0  # no side keeps its length exactly
    printed = capsys.readouterr().out
    assert _counts(printed)[2] == 0 and "flagged: all matches rejected by the invariance check" in printed
    assert len(_lines_by_colour(plt.gcf().axes[0])["tab:green"]) == 0

    controls["C"].value = 3
    assert plt.gcf().axes[3].get_title().endswith("C = 3")
    controls["orientation bins"].value = 10
    assert len(next(p for p in plt.gcf().axes[1].patches if isinstance(p, StepPatch)).get_data()[0]) == 10
    controls["ratio test"].value = 1.0
    assert _counts(capsys.readouterr().out)[0] == len(_matches(frames, detector="sift", ratio=1.0).pairs)


def test_panel_without_filtering_says_so(frames, capsys):
    feature_panel(*frames, FeatureParameters(detector="orb", min_matches=10_000))
    assert "; flagged: too few keypoints" in capsys.readouterr().out
    titles = [ax.get_title() for ax in plt.gcf().axes]
    assert titles[1:] == ["no orientation histogram", "no length histogram", "the invariance check did not run"]


def test_panel_detects_once_per_detector(frames, monkeypatch):
    detected = []

    def counting(image, parameters, mask=None):
        detected.append(parameters.detector)
        return detect(image, parameters, mask)

    monkeypatch.setattr(gpo.book.ch08_floor_features, "detect", counting)
    controls = _controls(feature_panel(*frames))
    assert detected == ["sift", "sift"]
    for name, value in (("t", 0.7), ("C", 5), ("orientation bins", 90), ("length bins", 40), ("ratio test", 0.9)):
        controls[name].value = value
    assert detected == ["sift", "sift"]
    controls["detector"].value = "orb"
    controls["detector"].value = "sift"
    controls["detector"].value = "orb"
    assert detected == ["sift", "sift", "orb", "orb"]


def test_the_histogram_decisions_are_drawn_by_band_and_scaled(frames):
    from gpo.book.lab_c_second_paper import draw_histogram_decisions

    matches = _matches(frames, **NOISY)
    orientation, length = matches.histogram
    ax = draw_histogram_decisions(frames[1], matches, scale=4.0, centre_px=(160.0, 120.0))
    drawn = _lines_by_colour(ax)
    start, end = matches.matched
    for colour, chosen in (
        ("tab:red", ~orientation.kept),
        ("tab:orange", orientation.kept & ~length.kept),
        ("tab:green", length.kept),
    ):
        tips = start[chosen] + 4 * (end - start)[chosen]
        np.testing.assert_allclose(drawn[colour], np.stack([start[chosen], tips], axis=1))
    assert "centre of rotation" in {text.get_text() for text in ax.get_legend().get_texts()}
    far = draw_histogram_decisions(frames[1], matches, centre_px=(900.0, 120.0))
    assert "towards the centre of rotation, 740 px away" in {text.get_text() for text in far.get_legend().get_texts()}


def test_the_band_selection_plots_each_match_where_it_starts_and_fits_both_slopes():
    """Matches moving down the image, longer the further right they start (a turn's slope of 0.02): each group drawn
    at (its start's u, its length), the band shaded, and the two least-squares lines labelled with their slopes."""
    rng = np.random.default_rng(3)
    start = np.column_stack([rng.uniform(150, 600, 80), rng.uniform(100, 380, 80)])
    length = 15.0 + 0.02 * start[:, 0] + rng.normal(0, 0.2, 80)
    end = start + np.column_stack([np.zeros(80), length])
    end[:3] += [8.0, -9.0]  # three wrong matches
    right = np.arange(80) >= 3
    band = (20.0, 24.0)
    kept = right & (length > band[0]) & (length < band[1])
    ax = draw_band_selection(start, end, kept, right, band)
    points = {line.get_label(): line for line in ax.lines if line.get_linestyle() == "None"}
    kept_line = points[f"{kept.sum()} right, kept"]
    np.testing.assert_allclose(kept_line.get_xdata(), start[kept, 0])  # across a motion down the image: u
    np.testing.assert_allclose(kept_line.get_ydata(), length[kept])
    assert f"{(right & ~kept).sum()} right, dropped" in points and "3 wrong" in points
    fits = [line.get_label() for line in ax.lines if line.get_linestyle() == "-"]
    slope = np.polyfit(start[right, 0], length[right], 1)[0]
    assert fits[0] == f"least squares, the right ones: slope {slope:.4f}"
    assert fits[1].startswith("least squares, the kept: slope ")
    assert ax.patches[0].get_label() == "the length band"


def test_the_papers_final_percent_is_drawn_from_its_own_columns():
    from gpo.experiments.table2 import experiment

    first = experiment("I").paper
    assert paper_value(first, "final_error_percent") == pytest.approx(100 * 0.1098 / 17.83)
    assert paper_value(first, "heading_rmse_deg") == first.heading_rmse_deg
