"""The floor feature odometer's stages against known motions: keypoints, matching, the histogram filter, the
geometric invariance check (the second paper's Algorithm 1) and what a frame that cannot be measured gives."""

import dataclasses

import cv2
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gpo.features import (
    ORB_PATCH_PX,
    FeatureError,
    FeatureParameters,
    FeatureTracker,
    choose_cardinality,
    degenerate,
    detect,
    histogram_filter,
    invariance_check,
    refit,
)
from gpo.kinematics import increment_from_point_pairs, seen_after

SIZE = (320, 240)  # width, height


def _texture(seed=0, size=SIZE) -> np.ndarray:
    """A seeded random texture with blobs at several scales, 8-bit grey."""
    rng = np.random.default_rng(seed)
    width, height = size
    image = np.zeros((height, width))
    for sigma in (1.0, 2.5, 6.0):
        image += cv2.GaussianBlur(rng.uniform(-1, 1, (height, width)), (0, 0), sigma) * sigma
    image = (image - image.min()) / np.ptp(image) * 235 + 10
    return image.astype(np.uint8)


def _moved(image: np.ndarray, angle_deg: float, shift) -> tuple[np.ndarray, np.ndarray]:
    """``image`` turned by ``angle_deg`` about its centre and shifted by ``shift`` (px); the 2 x 3 map."""
    height, width = image.shape
    matrix = cv2.getRotationMatrix2D((width / 2, height / 2), angle_deg, 1.0)
    matrix[:, 2] += shift
    return cv2.warpAffine(image, matrix, (width, height), flags=cv2.INTER_CUBIC, borderMode=cv2.BORDER_REFLECT), matrix


def _turn_and_shift(detector, refitted=False):
    """The error (degrees, px) of the rigid fit of a frame turned by 3 degrees and shifted by (12, -7) px."""
    image = _texture(1)
    moved, matrix = _moved(image, 3.0, (12.0, -7.0))
    parameters = FeatureParameters(detector=detector, scale=1.0, max_features=400)
    tracker = FeatureTracker(parameters)
    assert tracker.track(image) is None  # the first frame has nothing to match
    matches = tracker.track(moved)
    assert matches.flag is None and matches.kept.sum() >= 30
    # end = T^-1 start in the increment's terms: the increment of the frame that sees the points move so
    increment = increment_from_point_pairs(matches.start, matches.end)
    if refitted:
        increment = refit(*matches.matched, increment, 1.5, parameters.min_matches)
    moved_points = seen_after(matches.start, increment)
    true_points = matches.start @ matrix[:, :2].T + matrix[:, 2]
    true_angle = np.arctan2(matrix[1, 0], matrix[0, 0])
    return np.degrees(-increment[2] - true_angle), np.abs(moved_points - true_points).max()


def test_sift_recovers_a_known_rigid_motion():
    angle_deg, worst_px = _turn_and_shift("sift")
    assert abs(angle_deg) < 0.1 and worst_px < 0.5


def test_orb_reads_a_turn_short_until_the_fit_readmits_every_match_it_explains():
    """ORB's keypoints sit on the grid of their pyramid level; the histogram filter then keeps the vectors whose
    errors bring them near the mean, which in a turn makes the turn look smaller (section 4 of chapter 08)."""
    angle_deg, _ = _turn_and_shift("orb")
    assert angle_deg > 0.2  # the 3 degree turn read short by more than 0.2 degrees (about 10 %)
    refitted_deg, worst_px = _turn_and_shift("orb", refitted=True)
    assert abs(refitted_deg) < 0.1 and worst_px < 1.0


def test_keypoints_keep_their_descriptor_support_inside_the_image_and_off_the_mask():
    image = _texture(2)
    orb = FeatureParameters(detector="orb", scale=1.0)
    points = detect(image, orb).points
    margin = ORB_PATCH_PX / 2
    assert len(points) > 50
    assert (points >= margin).all() and (points[:, 0] <= SIZE[0] - 1 - margin).all()
    assert (points[:, 1] <= SIZE[1] - 1 - margin).all()
    mask = np.full(image.shape, 255, np.uint8)
    cv2.circle(mask, (160, 120), 60, 0, -1)  # a light spot
    sift = detect(image, FeatureParameters(scale=1.0), mask)
    distance = np.hypot(sift.points[:, 0] - 160, sift.points[:, 1] - 120)
    assert len(sift) > 20 and (distance > 60 + sift.sizes / 2 - 1).all()


def test_scale_and_roi_give_full_image_pixels():
    image = _texture(3, (480, 360))
    moved, matrix = _moved(image, 0.0, (9.0, 4.0))
    for chosen in (FeatureParameters(scale=0.5), FeatureParameters(scale=1.0, roi=(100, 80, 240, 180))):
        tracker = FeatureTracker(chosen)
        tracker.track(image)
        matches = tracker.track(moved)
        np.testing.assert_allclose(np.median(matches.end - matches.start, axis=0), matrix[:, 2], atol=0.3)
        if chosen.roi is not None:
            u, v, width, height = chosen.roi
            assert (matches.start >= [u, v]).all() and (matches.start <= [u + width, v + height]).all()


def _with_outliers(count=120, share=0.3, seed=0):
    """Points moved by a rigid motion (2 degrees, (15, 4) px) plus ``share`` wrong pairs; which are right."""
    rng = np.random.default_rng(seed)
    start = rng.uniform([0, 0], SIZE, (count, 2))
    angle = np.radians(2.0)
    rotation = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
    end = start @ rotation.T + [15.0, 4.0] + rng.normal(0, 0.3, (count, 2))
    wrong = rng.random(count) < share
    end[wrong] = rng.uniform([0, 0], SIZE, (wrong.sum(), 2))
    return start, end, ~wrong


def test_both_filters_remove_wrong_matches():
    start, end, right = _with_outliers()
    histogram, _, _ = histogram_filter(start, end)
    loops = invariance_check(start, end, rng=np.random.default_rng(0)).kept
    both = histogram.copy()
    both[histogram] = invariance_check(start[histogram], end[histogram], rng=np.random.default_rng(0)).kept

    def precision(kept):
        return right[kept].mean()

    assert precision(both) > 0.97 and both.sum() >= 30
    assert precision(histogram) > 0.9 and precision(loops) > 0.9
    assert precision(both) >= max(precision(histogram), precision(loops))
    assert right.mean() < 0.75  # what they started from


def test_the_histogram_filter_keeps_mu_plus_minus_sigma_of_each_histogram():
    start, end, _ = _with_outliers(share=0.0)
    kept, orientation, length = histogram_filter(start, end)
    assert orientation.counts.sum() == len(start) and length.counts.sum() == orientation.kept.sum()
    inside = np.abs(length.values - length.mean) <= max(length.sigma, 0.5 * np.diff(length.edges)[0])
    np.testing.assert_array_equal(kept, orientation.kept & inside)
    assert 0.3 < kept.mean() < 0.8  # mu +- sigma twice over: about 0.47 of normal values, fewer of flatter ones


@settings(max_examples=30, deadline=None)
@given(st.floats(-180.0, 180.0))
def test_the_orientation_histogram_works_in_every_direction(direction_deg):
    rng = np.random.default_rng(0)
    start = rng.uniform(0, 300, (80, 2))
    angle = np.radians(direction_deg + rng.normal(0, 3.0, 80))
    end = start + 20 * np.column_stack([np.cos(angle), np.sin(angle)])
    _, orientation, _ = histogram_filter(start, end)
    difference = np.angle(np.exp(1j * np.radians(orientation.mean - direction_deg)))
    assert abs(np.degrees(difference)) < 2.0
    assert 0.4 < orientation.kept.mean() < 0.9  # the directions around +-180 degrees are not split


def test_a_still_frame_keeps_its_matches():
    start = np.random.default_rng(0).uniform(0, 300, (40, 2))
    kept, _, length = histogram_filter(start, start.copy())
    assert kept.all() and length.sigma == 0.0


def test_algorithm_1_keeps_rigid_loops_and_rejects_a_stretched_side():
    rng = np.random.default_rng(1)
    start = rng.uniform(0, 300, (60, 2))
    end = start[:, ::-1] * [1, -1] + [400.0, 50.0]  # turned by 90 degrees: distances kept exactly
    assert invariance_check(start, end, rng=rng).kept.all()
    triangle = np.array([[0.0, 0.0], [100.0, 0.0], [0.0, 100.0]])
    stretched = triangle * [1.2, 1.0]  # one side 20 % longer, one 10 % longer
    assert not invariance_check(triangle, stretched, 0.85, cardinality=3, rounds=1).kept.any()
    assert invariance_check(triangle, stretched, 0.75, cardinality=3, rounds=1).kept.all()


def test_cardinality_grows_with_the_matches_and_every_match_is_tested():
    assert [choose_cardinality(n) for n in (5, 11, 12, 39, 40, 400)] == [3, 3, 4, 4, 5, 5]
    start = np.random.default_rng(0).uniform(0, 300, (23, 2))
    check = invariance_check(start, start + 5.0, rounds=2, rng=np.random.default_rng(0))
    assert check.cardinality == 4 and len(check.loops) == 2 * 6
    assert set(np.concatenate(check.loops[:6]).tolist()) == set(range(23))


def test_too_few_matches_for_a_loop_keep_nothing():
    start = np.zeros((2, 2))
    assert not invariance_check(start, start, cardinality=3).kept.any()


def test_degenerate_point_sets():
    line = np.column_stack([np.linspace(0, 100, 20), np.linspace(0, 50, 20)])
    assert degenerate(line) and degenerate(line[:2]) and degenerate(np.ones((10, 2)))
    assert not degenerate(np.random.default_rng(0).uniform(0, 100, (20, 2)))


def test_a_blank_frame_is_flagged_not_measured():
    tracker = FeatureTracker(FeatureParameters(scale=1.0))
    tracker.track(np.full((240, 320), 128, np.uint8))
    matches = tracker.track(np.full((240, 320), 128, np.uint8))
    assert matches.flag.startswith("too few keypoints") and not matches.kept.any()


def test_the_same_seed_gives_the_same_matches():
    image, moved = _texture(4), _moved(_texture(4), 1.0, (5.0, 3.0))[0]
    kept = []
    for _ in range(2):
        tracker = FeatureTracker(FeatureParameters(scale=1.0, seed=7))
        tracker.track(image)
        kept.append(tracker.track(moved).kept)
    np.testing.assert_array_equal(*kept)


def test_bad_input_is_refused():
    with pytest.raises(FeatureError, match="grey 8-bit"):
        detect(np.zeros((10, 10), np.float32), FeatureParameters())
    with pytest.raises(FeatureError, match="grey 8-bit"):
        detect(np.zeros((10, 10, 3), np.uint8), FeatureParameters())
    with pytest.raises(FeatureError, match="mask"):
        detect(_texture(), FeatureParameters(), np.ones((5, 5)))
    with pytest.raises(FeatureError, match="reaches outside"):
        detect(_texture(), FeatureParameters(roi=(300, 0, 100, 100)))
    for field, value in (("detector", "surf"), ("ratio", 1.5), ("scale", 0.0), ("cardinality", 2), ("refit_px", -1)):
        with pytest.raises(FeatureError, match=field):
            dataclasses.replace(FeatureParameters(), **{field: value})
