"""``gpo-exact``: the motion vector of the floor's own tracks, turned into the exact circular arc of a rigid robot that
does not slide at its rear axle (reverse driving and turning on the spot included).

On a glossy floor the tracks of the ceiling lights' reflections move slower than the floor's; only the floor's own
layer counts (``gpo.motion.layers.floor_layer``), looked for where the tracks may move in two layers
(``gpo.motion.klt.FlowQuality.layers``).

The tracks start in a keyframe (``KEYFRAMES``): the arc spans the frames since it. Where the robot's curvature changes
within those frames, the one arc through the measured point's motion is an approximation; at the keyframe policy's
few frames it reads a path's end closer than arcs of single frames, whose small errors add up.
"""

from __future__ import annotations

import numpy as np

from gpo.motion.layers import floor_layer
from gpo.odometry.estimators.base import FloorEstimator, vector_motion
from gpo.odometry.kinematics import increment_from_point_motion


class ExactArc(FloorEstimator):
    """The exact arc that moves the measured floor point by the vector of the floor's own tracks."""

    NAME = "gpo-exact"
    KEYFRAMES = True
    OVERVIEW = True

    def increment(self, measurement, dt: float) -> tuple[np.ndarray | None, str | None]:
        floor = None  # every track: one layer
        if measurement.quality.layers:
            floor = floor_layer(measurement.start, measurement.end, self.geometry.nadir_px)
        where, moved = vector_motion(measurement, self.geometry, self.config.vector, floor)
        return increment_from_point_motion(where, where + moved), None
