"""``gpo-rigid``: no kinematic model; the rigid 2-D motion of the kept tracks (RANSAC, then least squares) is the
increment since the frame they start in: the keyframe (``KEYFRAMES``), so that the small error of each fit's rotation
is made once per keyframe, not once per frame. A frame measured by the whole-view check (``gpo.motion.overview``: a
translation from the previous frame, no rotation) takes the exact arc of a robot that does not slide at its rear
axle instead, as ``gpo-exact`` does."""

from __future__ import annotations

import numpy as np

from gpo.odometry.estimators.base import FloorEstimator, agreeing, vector_motion
from gpo.odometry.kinematics import increment_from_point_motion, increment_from_point_pairs

RANSAC_THRESHOLD_PX = 1.0  # a track fits the rigid motion when it lands this close to where the motion puts it


class RigidFit(FloorEstimator):
    """The rigid motion of the kept tracks, fitted on those RANSAC finds agreeing."""

    NAME = "gpo-rigid"
    KEYFRAMES = True
    OVERVIEW = True

    def increment(self, measurement, dt: float) -> tuple[np.ndarray | None, str | None]:
        if measurement.quality.overview:
            where, moved = vector_motion(measurement, self.geometry, "median")
            return increment_from_point_motion(where, where + moved), None
        start, end = self.geometry.metres(measurement.start), self.geometry.metres(measurement.end)
        threshold = RANSAC_THRESHOLD_PX * self.geometry.pixel_m
        chosen = agreeing(start, end, threshold)
        if chosen is None or chosen.sum() < self.config.klt.min_tracks:
            return None, "rigid fit: too few tracks agree"
        return increment_from_point_pairs(start[chosen], end[chosen]), None
