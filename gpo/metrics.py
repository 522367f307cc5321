"""How far an estimated trajectory is from the truth, with evo doing the association and the alignment.

Trajectories are ``gpo.trajectory.Trajectory`` objects (base_link in some frame, integer-nanosecond stamps);
``to_evo`` turns one into evo's ``PoseTrajectory3D``. ``final_error`` is the figure the issues and the papers
quote: after associating the two by time and placing the estimate's first pose on the truth's (evo's
``align_origin``), the distance between the last positions in the floor plane, in metres and in per cent of the
distance the truth travelled, and the difference of the last headings.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from evo.core import sync
from evo.core.trajectory import PoseTrajectory3D

from gpo.trajectory import Trajectory

MAX_STAMP_DIFFERENCE_S = 0.005  # poses further apart in time than this are not associated


def to_evo(trajectory: Trajectory) -> PoseTrajectory3D:
    """evo's trajectory of the same poses (quaternions reordered to w, x, y, z; stamps in float seconds)."""
    quaternions = trajectory.quaternions[:, [3, 0, 1, 2]]
    return PoseTrajectory3D(trajectory.positions.copy(), quaternions, trajectory.times)


@dataclass(frozen=True)
class FinalError:
    """The end of an estimated path against the truth: ``position_m`` in the floor plane, ``heading_rad`` (estimate
    minus truth, wrapped to (-pi, pi]), over ``distance_m`` travelled by the truth, with ``poses`` associated."""

    position_m: float
    heading_rad: float
    distance_m: float
    poses: int

    @property
    def percent(self) -> float:
        """The final position error in per cent of the distance travelled."""
        return 100.0 * self.position_m / self.distance_m

    def __str__(self) -> str:
        return (
            f"{self.position_m * 1e3:.1f} mm ({self.percent:.3f} % of {self.distance_m:.2f} m), "
            f"heading {np.degrees(self.heading_rad):+.2f} deg"
        )


def final_error(estimate: Trajectory, truth: Trajectory, max_difference_s: float = MAX_STAMP_DIFFERENCE_S):
    """``FinalError`` of ``estimate`` against ``truth``: associated by time, the estimate's first pose placed on the
    truth's. Raises ValueError when fewer than two poses match in time."""
    try:
        reference, estimated = sync.associate_trajectories(
            to_evo(truth), to_evo(estimate), max_diff=max_difference_s
        )
    except sync.SyncException as error:
        raise ValueError(f"the trajectories do not match in time: {error}") from None
    if reference.num_poses < 2:
        raise ValueError(f"only {reference.num_poses} pose(s) match in time within {max_difference_s} s")
    estimated.align_origin(reference)
    last_true, last_estimated = reference.poses_se3[-1], estimated.poses_se3[-1]
    position = float(np.hypot(*(last_estimated[:2, 3] - last_true[:2, 3])))
    turn = last_true[:2, :2].T @ last_estimated[:2, :2]
    heading = float(np.arctan2(turn[1, 0], turn[0, 0]))
    return FinalError(position, heading, float(reference.path_length), reference.num_poses)
