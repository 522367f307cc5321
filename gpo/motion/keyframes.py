"""When a tracker measures a frame against an earlier keyframe instead of the frame before it (``KeyframePolicy``).

A floor estimator that fits the motion of each pair of frames adds one error per pair: a rotation read from a floor
patch 0.2 m wide is off by a little every frame, partly at random and partly with a sign (a floor image resampled
from the camera's pixels carries their grid, fixed to the robot, and the tracks cling to it a little, reading each
step short), and the heading walks away with the frame count. Measured against a keyframe that stays while enough of
it is still in view, the same error is made once per keyframe: the frames in between are each measured from the
keyframe, and their errors do not add up. A new keyframe is the frame whose measurement left too little of the
keyframe in view, or the last one the policy allows.

The trackers (``gpo.motion.klt.FloorFlow``, ``gpo.motion.keypoints.FeatureTracker``) apply the policy;
``gpo.pipeline.odometer.FloorOdometer`` composes each measured pose onto the keyframe's. ``max_frames: 1`` is
frame-to-frame tracking, the papers'.
"""

from __future__ import annotations

from dataclasses import dataclass

from gpo.motion.ranges import in_range


@dataclass(frozen=True)
class KeyframePolicy:
    """How long a keyframe is kept: the frames after it are measured against it while at least ``min_overlap`` of its
    corners are still followed into the frame (a share, 0-1: the floor it shares with the frame, less the tracks lost
    to noise; for keypoints, of the matches kept in the first frame after it), for at most ``max_frames`` frames (1:
    every frame against the one before, frame-to-frame)."""

    min_overlap: float = 0.6
    max_frames: int = 30

    def __post_init__(self):
        ranges = {
            "min_overlap": in_range(self.min_overlap, 0, 1, ", a share of the keyframe's corners"),
            "max_frames": in_range(self.max_frames, 1, 10_000, " frames (1: frame-to-frame)", whole=True),
        }
        bad = [f"{name}={getattr(self, name)!r} ({allowed})" for name, (ok, allowed) in ranges.items() if not ok]
        if bad:
            raise ValueError(f"bad keyframe policy: {'; '.join(bad)}")

    def keeps(self, followed: int, corners: int, frames: int) -> bool:
        """Whether the keyframe whose ``corners`` were followed into the latest frame ``followed`` times, that frame
        the ``frames``-th since the keyframe, stays the keyframe of the next frame."""
        return frames < self.max_frames and followed >= self.min_overlap * corners


FRAME_TO_FRAME = KeyframePolicy(max_frames=1)
"""Every frame measured against the one before it: the first paper's tracking."""
