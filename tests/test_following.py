"""Keypoints detected on keyframes and followed between them by Lucas-Kanade, against known image motions: where the
followed keypoints land, when a keyframe is renewed, and the matching that stands in when following fails."""

import cv2
import numpy as np
import pytest
from textures import blurred_noise, turned_and_shifted

from gpo.motion.following import FollowFrame, KeypointFollower
from gpo.motion.keyframes import KeyframePolicy
from gpo.motion.keypoints import FeatureParameters
from gpo.motion.klt import KLTParameters
from gpo.odometry.kinematics import rigid_fit

WIDTH, HEIGHT = 320, 240


def _floor(seed: int = 0, size=(WIDTH, HEIGHT)) -> np.ndarray:
    """A seeded floor-like texture, 8-bit grey: uniform noise blurred at three scales."""
    return blurred_noise(np.random.default_rng(seed), size, sigmas=(1.5, 3.0, 6.0)).astype(np.uint8)


def _follower(**keyframe) -> KeypointFollower:
    policy = KeyframePolicy(**({"min_overlap": 0.5, "max_frames": 30} | keyframe))
    return KeypointFollower(FeatureParameters(detector="orb", keyframe=policy, follow="lk"), KLTParameters())


def test_followed_keypoints_land_where_the_floor_took_them():
    """Eight frames, each turned 0.8 degrees and shifted (3, -2) px more than the one before, all measured against
    the first: the kept pairs move as the known motion moves the floor, and nothing is detected again. Each frame is
    searched from the keyframe, so its errors are its own: measured 0.03-0.06 px (median) in every frame, the pairs'
    rigid fit turned 0.1 % short of the 6.4 degrees."""
    image = _floor()
    follower = _follower()
    assert follower.track(image) is None
    keyframe = None
    for k in range(1, 9):
        frame, matrix = turned_and_shifted(image, 0.8 * k, (3.0 * k, -2.0 * k))
        measured = follower.track(frame)
        assert measured.flag is None and not follower.keyframe_is_latest
        keyframe = keyframe or measured.previous
        assert measured.previous is keyframe  # measured against the first frame's keypoints
        assert set(measured.seconds) == {"follow", "histogram", "invariance"}  # followed, not detected
        expected = measured.start @ matrix[:, :2].T + matrix[:, 2]
        error = np.hypot(*(measured.end - expected).T)
        assert np.median(error) < 0.1 and error.max() < 0.5 and measured.kept.sum() >= 50
    angle, _ = rigid_fit(measured.start, measured.end)
    assert angle == pytest.approx(-np.radians(6.4), rel=0.005)


def test_a_keyframe_half_out_of_view_gives_way_to_the_latest_frame():
    """A floor slid ever faster under a 320 px view, up to 40 px a frame: once fewer than half of the keyframe's
    keypoints are still in view and followed, the frame measured then becomes the keyframe, its keypoints detected
    then (and only then); every frame is measured from its keyframe."""
    offsets = [0, 4, 12, 24, 40, 60, 80, 100, 120, 140, 160, 180, 200, 220, 240]
    floor = _floor(1, (WIDTH + offsets[-1], HEIGHT))
    follower = _follower()
    assert follower.track(floor[:, :WIDTH]) is None
    measured = [follower.track(floor[:, offset : offset + WIDTH]) for offset in offsets[1:]]
    renewed = [k for k, m in enumerate(measured, start=1) if "detect" in m.seconds]
    assert renewed and renewed[0] < len(measured)
    keyframes = [max([0] + [r for r in renewed if r < k]) for k in range(1, len(offsets))]  # each frame's
    for k, (m, keyframe) in enumerate(zip(measured, keyframes, strict=True), start=1):
        assert m.flag is None
        if k > 1:
            assert (m.previous is measured[k - 2].previous) is (keyframe == keyframes[k - 2])
        np.testing.assert_allclose(np.median(m.end - m.start, axis=0), [offsets[keyframe] - offsets[k], 0.0],
                                   atol=0.1)


def test_a_frame_beyond_the_pyramids_reach_is_matched_with_the_keyframe_instead():
    """After three frames of 3 px, a jump of 160 px, twice the pyramid's reach: no search started from the predicted
    motion finds it, so the frame's keypoints, detected for the new keyframe, are matched with the keyframe's
    descriptors."""
    floor = _floor(2, (WIDTH + 200, HEIGHT))
    offsets = [0, 3, 6, 9, 169]
    follower = _follower()
    assert follower.track(floor[:, :WIDTH]) is None
    measured = [follower.track(floor[:, offset : offset + WIDTH]) for offset in offsets[1:]]
    assert not any("match" in m.seconds for m in measured[:-1])
    jump = measured[-1]
    assert "match" in jump.seconds and "detect" in jump.seconds and follower.keyframe_is_latest
    assert jump.flag is None
    np.testing.assert_allclose(np.median(jump.end - jump.start, axis=0), [-169.0, 0.0], atol=0.5)  # ORB's points


def test_a_prepared_frame_is_followed_as_its_image_and_restart_forgets_the_frames_before():
    image = _floor(3)
    frames = [turned_and_shifted(image, 0.5 * k, (2.0 * k, 1.0 * k))[0] for k in range(4)]
    by_image, by_prepared = _follower(), _follower()
    for frame in frames:
        prepared = by_prepared.prepare(frame)
        assert isinstance(prepared, FollowFrame) and prepared.levelled.dtype == np.uint8
        first, second = by_image.track(frame), by_prepared.track(prepared)
        if first is not None:
            np.testing.assert_array_equal(first.end, second.end)
            np.testing.assert_array_equal(first.kept, second.kept)  # the invariance check drew the same loops
    by_image.restart()
    assert by_image.track(frames[0]) is None


@pytest.mark.parametrize("levelled", [True, False])
def test_the_frames_are_followed_levelled_as_the_klt_section_says(levelled):
    """A frame 20 % brighter than the one before: levelled, it looks the same; not levelled, as it comes."""
    image = _floor(4)
    brighter = cv2.convertScaleAbs(image, alpha=1.2)
    follower = KeypointFollower(FeatureParameters(follow="lk"), KLTParameters(normalise_brightness=levelled))
    first, second = follower.prepare(image), follower.prepare(brighter)
    difference = np.abs(first.levelled.astype(int) - second.levelled.astype(int)).mean()
    assert (difference < 1.0) if levelled else (difference > 15.0)
