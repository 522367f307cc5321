"""``gpo``: the first paper's Ground Plane Odometry, its bicycle model (eqs. 25-34, one Euler step) on the motion
vector.

The vector is read as the motion of a virtual front wheel a wheelbase L ahead of the rear axle. It is the motion of
the floor where the tracks are, and tracks drift towards the robot between re-detections, so the wheel is placed at
the tracks' median each frame (about L; l_r keeps its ratio to L). Left at the fixed L, every turn read 5 % short on
the ``long1`` path.
"""

from __future__ import annotations

import numpy as np

from gpo.odometry.estimators.base import FloorEstimator, vector_motion
from gpo.odometry.kinematics import PaperBicycle


class PaperGPO(FloorEstimator):
    """The paper's bicycle model on the median (or mean) vector, its virtual wheel at the measured point."""

    NAME = "gpo"

    def increment(self, measurement, dt: float) -> tuple[np.ndarray | None, str | None]:
        where, moved = vector_motion(measurement, self.geometry, self.config.vector)
        return self._virtual_wheel_at(where[0]).step(np.zeros(3), -moved, dt), None  # from the origin

    def _virtual_wheel_at(self, wheelbase_m: float) -> PaperBicycle:
        """The configured bicycle model with its virtual front wheel moved to ``wheelbase_m``, l_r in proportion."""
        model = self.config.model
        return PaperBicycle(wheelbase_m, min(wheelbase_m, wheelbase_m * model.rear_to_reference_m / model.wheelbase_m))
