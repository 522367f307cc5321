"""How far an estimated trajectory is from the truth, with evo doing the association, the alignment and the errors.

Trajectories are ``gpo.io.trajectory.Trajectory`` objects (base_link in some world frame, integer-nanosecond stamps) or
evo ``PoseTrajectory3D`` objects (float-second stamps); ``to_evo`` turns the first into the second and ``from_evo``
back. Each function first associates the two by time (``associate``: evo's ``sync``, nearest stamps within
``MAX_STAMP_DIFFERENCE_S``), then moves the estimate onto the truth (``Alignment``) and expresses every error in the
truth's frame.

Alignments
----------
``none``    the estimate as it is, in the truth's frame.
``origin``  the estimate's first pose placed on the truth's (evo's ``align_origin``): what the papers do.
``se3``     evo's Umeyama alignment of all associated positions (rotation and translation, no scale).
``se2``     rotation about z and translation in x-y that best fit all associated positions (least squares): evo's
            Umeyama on the x-y coordinates alone. For a robot on the floor; a straight path is enough, where ``se3``
            cannot tell the rotation about the path's own line.
``posyaw``  rpg_trajectory_evaluation's ``posyaw`` over all frames (``align_num_frames: -1``, its
            ``alignPositionYaw``): the rotation about z and the 3-D translation minimising the summed squared
            position differences, with Rz maximising trace(Rz C), C = sum of (p_est - mean_est)(p_gt - mean_gt)^T
            (its ``get_best_yaw``), and t = mean_gt - Rz mean_est. Orientations do not enter. The best Rz is the
            proper 2-D Umeyama rotation of the x-y coordinates, so ``posyaw`` is ``se2`` plus the shift of the mean
            height; the two agree for a path on the floor.

Errors (``evaluate``)
---------------------
APE         evo's absolute position error (``PoseRelation.translation_part``): the 3-D distance between associated
            positions after the alignment, metres; RMSE, mean, median, max.
RPE         evo's relative position error over consecutive segments of at least ``rpe_delta_m`` metres (default
            ``RPE_DELTA_M`` = 1 m) travelled by the truth (``delta_unit=Unit.meters``, pairs from the reference):
            metres of error per segment. Its mean over the segment length, in %, is the suite's drift measure
            (``Evaluation.drift_percent_per_m``). It does not depend on the alignment.
final       ``final_error``'s definition after the chosen alignment: the distance between the last positions in the
            floor plane, metres and % of the distance the truth travelled, and the last heading difference.
heading     the yaw (heading of base_link's x axis in the floor plane, ``atan2(R[1, 0], R[0, 0])``) of the estimate
            minus the truth's, wrapped to (-pi, pi]. evo's ``rotation_angle_deg`` is the full 3-D angle, which also
            counts tilt; heading here is the yaw alone. RMSE and final, degrees.

Each measure, its one definition and its name
---------------------------------------------
The papers' measures carry the papers' names; the suite's own are named for what they are.

==============================  ======================================================================================
first paper, Table 3,           ``relative_translation_errors``: evo's RPE, translation part, over every pair of
"relative translation error"    poses ``TABLE3_DELTA_M`` = 1 m of the truth's travel apart; the table lists its
                                minimum, maximum and average per test
first paper, Table 4,           read here as ``final_error``'s ``position_m``, the first pose placed on the truth's
"translation error"             (the paper says only that a trajectory evaluation toolbox computed the odometry's
                                translation error against the ground truth, one number per test); its "mean
                                localization error" of 0.058 m is that number averaged over its three tests (Table
                                4's 0.0579 m), not a mean along a path
second paper, Table 2           ``paper_table2`` (``PaperTable2``): positioning RMSE, heading RMSE, final error (mm,
                                %), final heading and relative positioning error, at the samples its ground truth
                                gives
the suite's drift               ``Evaluation.drift_percent_per_m``: mean RPE over 1 m segments per metre, %
the suite's position error      ``Evaluation.ape_m``: evo's APE after the chosen alignment (RMSE, mean, median, max)
along the path
==============================  ======================================================================================
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import StrEnum

import numpy as np
from evo.core import filters, geometry, lie_algebra, metrics, sync
from evo.core.trajectory import PoseTrajectory3D

from gpo.io.trajectory import Trajectory

MAX_STAMP_DIFFERENCE_S = 0.005  # poses further apart in time than this are not associated
MIN_POSES = 2  # associated poses needed for any error
RPE_DELTA_M = 1.0  # the RPE's segment length: distance travelled by the truth, metres


class Alignment(StrEnum):
    """How the estimate is moved onto the truth before the errors (see the module docstring)."""

    NONE = "none"
    ORIGIN = "origin"
    SE2 = "se2"
    SE3 = "se3"
    POSYAW = "posyaw"


def to_evo(trajectory: Trajectory) -> PoseTrajectory3D:
    """evo's trajectory of the same poses (quaternions reordered to w, x, y, z; stamps in float seconds)."""
    quaternions = trajectory.quaternions[:, [3, 0, 1, 2]]
    return PoseTrajectory3D(trajectory.positions.copy(), quaternions, trajectory.times)


def from_evo(trajectory: PoseTrajectory3D, frame_id: str = "world", child_frame_id: str = "base_link") -> Trajectory:
    """Our trajectory of evo's poses (quaternions reordered to x, y, z, w; float-second stamps rounded to whole
    nanoseconds, so as exact as the floats: within 0.2 us at today's Unix times)."""
    stamps = np.round(trajectory.timestamps * 1e9).astype(np.int64)
    quaternions = trajectory.orientations_quat_wxyz[:, [1, 2, 3, 0]]
    return Trajectory(stamps, trajectory.positions_xyz, quaternions, frame_id, child_frame_id)


def associate(
    estimate: Trajectory | PoseTrajectory3D,
    truth: Trajectory | PoseTrajectory3D,
    max_difference_s: float = MAX_STAMP_DIFFERENCE_S,
    min_poses: int = MIN_POSES,
) -> tuple[PoseTrajectory3D, PoseTrajectory3D]:
    """(estimate, truth) as evo trajectories reduced to the poses matched by time (evo's nearest-stamp ``sync``,
    at most ``max_difference_s`` seconds apart); copies, the inputs are not changed.

    Raises ValueError naming the problem: a non-finite number in either, no overlap in time (both time ranges
    given), or fewer than ``min_poses`` matching stamps (how many did).
    """
    estimated, reference = _checked(estimate, "estimate"), _checked(truth, "truth")
    (e0, e1), (t0, t1) = estimated.timestamps[[0, -1]], reference.timestamps[[0, -1]]
    if e0 > t1 + max_difference_s or t0 > e1 + max_difference_s:
        raise ValueError(
            f"the trajectories do not match in time, they do not overlap: the estimate spans {e0:.3f} .. {e1:.3f} s, "
            f"the truth {t0:.3f} .. {t1:.3f} s"
        )
    try:
        reference, estimated = sync.associate_trajectories(reference, estimated, max_diff=max_difference_s)
    except sync.SyncException:
        matched = 0
    else:
        matched = estimated.num_poses
    if matched < min_poses:
        raise ValueError(
            f"only {matched} pose(s) of the estimate match the truth in time within {max_difference_s} s; "
            f"at least {min_poses} needed"
        )
    return estimated, reference


def _checked(trajectory: Trajectory | PoseTrajectory3D, name: str) -> PoseTrajectory3D:
    """``trajectory`` as evo's, refused with a ValueError naming it when empty or not finite."""
    if isinstance(trajectory, Trajectory):
        if len(trajectory) == 0:
            raise ValueError(f"the {name} has no poses")
        trajectory = to_evo(trajectory)
    values = np.column_stack([trajectory.timestamps, trajectory.positions_xyz, trajectory.orientations_quat_wxyz])
    bad = np.flatnonzero(~np.isfinite(values).all(axis=1))
    if bad.size:
        raise ValueError(f"the {name} has NaN or infinite numbers in {bad.size} pose(s), first at pose {bad[0]}")
    return trajectory


def apply_alignment(estimate: PoseTrajectory3D, truth: PoseTrajectory3D, mode: Alignment | str) -> np.ndarray:
    """Move the associated ``estimate`` onto ``truth`` in place by ``mode``; return the 4x4 rigid transform applied
    (truth's frame from the estimate's). Raises ValueError for an unknown mode or positions it cannot align."""
    try:
        mode = Alignment(mode)
    except ValueError:
        raise ValueError(f"unknown alignment {mode!r}: expected one of {', '.join(Alignment)}") from None
    try:
        return _ALIGNERS[mode](estimate, truth)
    except geometry.GeometryException as error:
        raise ValueError(
            f"cannot align by {mode}: {error} (positions along one line need se2, posyaw or origin; "
            "a robot that does not move, origin)"
        ) from None


def _align_se3(estimate: PoseTrajectory3D, truth: PoseTrajectory3D) -> np.ndarray:
    """evo's Umeyama alignment of all positions, without scale."""
    rotation, translation, _ = estimate.align(truth)
    return lie_algebra.se3(rotation, translation)


def _align_yaw(estimate: PoseTrajectory3D, truth: PoseTrajectory3D, height: bool) -> np.ndarray:
    """Rotation about z and translation in x-y by evo's Umeyama on the x-y positions; with ``height``, also the
    shift of the mean z (``posyaw``)."""
    rotation, translation, _ = geometry.umeyama_alignment(estimate.positions_xyz[:, :2].T, truth.positions_xyz[:, :2].T)
    transform = np.eye(4)
    transform[:2, :2], transform[:2, 3] = rotation, translation
    if height:
        transform[2, 3] = truth.positions_xyz[:, 2].mean() - estimate.positions_xyz[:, 2].mean()
    estimate.transform(transform)
    return transform


_ALIGNERS = {
    Alignment.NONE: lambda estimate, truth: np.eye(4),
    Alignment.ORIGIN: lambda estimate, truth: estimate.align_origin(truth),
    Alignment.SE3: _align_se3,
    Alignment.SE2: lambda estimate, truth: _align_yaw(estimate, truth, height=False),
    Alignment.POSYAW: lambda estimate, truth: _align_yaw(estimate, truth, height=True),
}


def heading_errors(estimate: PoseTrajectory3D, truth: PoseTrajectory3D) -> np.ndarray:
    """Yaw of each associated estimate pose minus the truth's, radians wrapped to (-pi, pi], shape (N,)."""
    difference = _yaw(estimate) - _yaw(truth)
    return np.angle(np.exp(1j * difference))


def _yaw(trajectory: PoseTrajectory3D) -> np.ndarray:
    """Heading of each pose's x axis in the floor plane, radians: atan2(R[1, 0], R[0, 0])."""
    rotations = np.asarray(trajectory.poses_se3)[:, :3, :3]
    return np.arctan2(rotations[:, 1, 0], rotations[:, 0, 0])


@dataclass(frozen=True)
class FinalError:
    """The end of an estimated path against the truth: ``position_m`` in the floor plane, ``heading_rad`` (estimate
    minus truth, wrapped to (-pi, pi]), over ``distance_m`` travelled by the truth, with ``poses`` associated.

    After ``final_error`` (first pose placed on the truth's), ``position_m`` is the first paper's Table 4 "translation
    error" and, with ``percent``, the second paper's Table 2 "final error": the one number both papers print."""

    position_m: float
    heading_rad: float
    distance_m: float
    poses: int

    @property
    def percent(self) -> float:
        """The final position error in per cent of the distance travelled; NaN for a truth that did not move."""
        return 100.0 * self.position_m / self.distance_m if self.distance_m > 0 else float("nan")

    def __str__(self) -> str:
        return (
            f"{self.position_m * 1e3:.1f} mm ({self.percent:.3f} % of {self.distance_m:.2f} m), "
            f"heading {np.degrees(self.heading_rad):+.2f} deg"
        )


def _final(estimate: PoseTrajectory3D, truth: PoseTrajectory3D) -> FinalError:
    """``FinalError`` of an associated, aligned pair."""
    position = float(np.hypot(*(estimate.positions_xyz[-1, :2] - truth.positions_xyz[-1, :2])))
    heading = float(heading_errors(estimate, truth)[-1])
    return FinalError(position, heading, float(truth.path_length), truth.num_poses)


def final_error(
    estimate: Trajectory | PoseTrajectory3D,
    truth: Trajectory | PoseTrajectory3D,
    max_difference_s: float = MAX_STAMP_DIFFERENCE_S,
) -> FinalError:
    """``FinalError`` of ``estimate`` against ``truth``: associated by time, the estimate's first pose placed on the
    truth's. Raises ValueError as ``associate`` does (fewer than two poses matching in time, among others)."""
    return _final(*_placed_on_truth(estimate, truth, max_difference_s))


def _placed_on_truth(
    estimate: Trajectory | PoseTrajectory3D, truth: Trajectory | PoseTrajectory3D, max_difference_s: float
) -> tuple[PoseTrajectory3D, PoseTrajectory3D]:
    estimated, reference = associate(estimate, truth, max_difference_s)
    apply_alignment(estimated, reference, Alignment.ORIGIN)
    return estimated, reference


def place_on_truth(
    estimate: Trajectory | PoseTrajectory3D,
    truth: Trajectory | PoseTrajectory3D,
    max_difference_s: float = MAX_STAMP_DIFFERENCE_S,
) -> tuple[Trajectory, Trajectory]:
    """(estimate, truth) associated by time, the estimate's first pose placed on the truth's: the papers' alignment
    (``Alignment.ORIGIN``), the one ``final_error`` and ``evaluate`` use. Raises ValueError as ``associate`` does."""
    estimated, reference = _placed_on_truth(estimate, truth, max_difference_s)
    return from_evo(estimated), from_evo(reference)


def truth_poses(truth: Trajectory, times) -> np.ndarray:
    """(N, 3) planar poses (x, y, unwrapped yaw) of ``truth`` at ``times`` (seconds), linearly interpolated between
    its poses (held at its ends)."""
    yaw = np.unwrap(truth.yaw)
    return np.column_stack([np.interp(times, truth.times, values) for values in (*truth.positions[:, :2].T, yaw)])


@dataclass(frozen=True)
class Statistics:
    """Summary of a metric's errors, in the metric's unit."""

    rmse: float
    mean: float
    median: float
    max: float

    @classmethod
    def of(cls, metric: metrics.PE) -> Statistics:
        """The statistics evo computed for ``metric``."""
        values = metric.get_all_statistics()
        return cls(*(float(values[name]) for name in ("rmse", "mean", "median", "max")))


@dataclass(frozen=True)
class Evaluation:
    """An estimate against the truth after an ``alignment`` (see the module docstring for each number).

    ``ape_m``: position errors, metres. ``rpe_m``: position error per segment of ``rpe_delta_m`` travelled by the
    truth, metres; None when the truth travels less than that. ``final``: the last pose's error.
    ``heading_rmse_deg``: RMSE of the yaw differences, degrees. The per-pose arrays and the associated
    trajectories (``estimate`` aligned, both in the truth's frame) are kept for plots.
    """

    alignment: Alignment
    ape_m: Statistics
    rpe_m: Statistics | None
    rpe_delta_m: float
    final: FinalError
    heading_rmse_deg: float
    distances_m: np.ndarray = field(compare=False, repr=False)  # along the truth from its first associated pose
    position_errors_m: np.ndarray = field(compare=False, repr=False)  # evo's APE of each pose
    heading_errors_rad: np.ndarray = field(compare=False, repr=False)
    estimate: Trajectory = field(compare=False, repr=False)
    truth: Trajectory = field(compare=False, repr=False)

    @property
    def drift_percent_per_m(self) -> float | None:
        """The suite's drift: the mean RPE over its segments of ``rpe_delta_m`` travelled, per metre of them, in %
        (metres of error per 100 m driven); None without an RPE. Neither paper's measure: the first paper's Table 3
        lists the same segments' errors in metres (``relative_translation_errors``), the second paper's relative
        positioning error is read at its ground-truth samples (``PaperTable2.relative_error_percent``)."""
        return None if self.rpe_m is None else 100.0 * self.rpe_m.mean / self.rpe_delta_m

    def measures(self) -> dict[str, float | None]:
        """The suite's measures by name, for tables: ``ape_rmse_m``, ``heading_rmse_deg``, ``final_error_mm``,
        ``final_error_percent`` and ``drift_percent_per_m``. With the ``origin`` alignment and a ground truth at every
        pose, the first four are the second paper's positioning RMSE, heading RMSE and final error as
        ``paper_table2`` computes them; its relative positioning error is not among them."""
        return {
            "ape_rmse_m": self.ape_m.rmse,
            "heading_rmse_deg": self.heading_rmse_deg,
            "final_error_mm": self.final.position_m * 1e3,
            "final_error_percent": self.final.percent,
            "drift_percent_per_m": self.drift_percent_per_m,
        }

    def table(self) -> str:
        """A readable multi-line table of every number: lengths in mm, angles in degrees."""
        final, drift = self.final, self.drift_percent_per_m
        rpe = f"none: the truth travels less than {self.rpe_delta_m:g} m"
        rows = {
            "alignment": str(self.alignment),
            "poses associated": str(final.poses),
            "distance (truth)": f"{final.distance_m:.3f} m",
            "": "".join(f"{name:>9}" for name in ("rmse", "mean", "median", "max")),
            "APE position [mm]": _millimetres(self.ape_m),
            f"RPE per {self.rpe_delta_m:g} m [mm]": rpe if self.rpe_m is None else _millimetres(self.rpe_m),
            "drift per metre": "none" if drift is None else f"{drift:.3f} % (RPE mean / {self.rpe_delta_m:g} m)",
            "final position error": f"{final.position_m * 1e3:.1f} mm = {final.percent:.3f} % of the distance",
            "heading (yaw) error": (
                f"rmse {self.heading_rmse_deg:.3f} deg, final {np.degrees(final.heading_rad):+.3f} deg"
            ),
        }
        return "\n".join(f"{label:<24}{value}" for label, value in rows.items())

    def __str__(self) -> str:
        return self.table()


def _rpe(estimate: PoseTrajectory3D, truth: PoseTrajectory3D, delta_m: float) -> Statistics | None:
    """evo's RPE (translation, consecutive segments of at least ``delta_m`` travelled by the truth), or None when
    the truth travels less than ``delta_m``."""
    rpe = metrics.RPE(metrics.PoseRelation.translation_part, delta_m, metrics.Unit.meters, pairs_from_reference=True)
    try:
        rpe.process_data((truth, estimate))
    except filters.FilterException:
        return None
    return Statistics.of(rpe)


def _millimetres(statistics: Statistics) -> str:
    """RMSE, mean, median and max of metres, in millimetres, in columns of 9."""
    values = (statistics.rmse, statistics.mean, statistics.median, statistics.max)
    return "".join(f"{value * 1e3:9.2f}" for value in values)


def evaluate(
    estimate: Trajectory | PoseTrajectory3D,
    truth: Trajectory | PoseTrajectory3D,
    align: Alignment | str = Alignment.ORIGIN,
    rpe_delta_m: float = RPE_DELTA_M,
    max_difference_s: float = MAX_STAMP_DIFFERENCE_S,
) -> Evaluation:
    """``Evaluation`` of ``estimate`` against ``truth``: associated by time, aligned by ``align``, then evo's APE and
    RPE, the final error and the heading errors. Raises ValueError as ``associate`` and ``align`` do, and for an
    RPE segment length ``rpe_delta_m`` that is not a finite number of metres > 0."""
    if not (np.isfinite(rpe_delta_m) and rpe_delta_m > 0):
        raise ValueError(f"the RPE segment length must be a finite number of metres > 0, got {rpe_delta_m!r}")
    estimated, reference = associate(estimate, truth, max_difference_s)
    apply_alignment(estimated, reference, align)
    ape = metrics.APE(metrics.PoseRelation.translation_part)
    ape.process_data((reference, estimated))
    headings = heading_errors(estimated, reference)
    return Evaluation(
        alignment=Alignment(align),
        ape_m=Statistics.of(ape),
        rpe_m=_rpe(estimated, reference, rpe_delta_m),
        rpe_delta_m=rpe_delta_m,
        final=_final(estimated, reference),
        heading_rmse_deg=float(np.degrees(np.sqrt(np.mean(headings**2)))),
        distances_m=reference.distances,
        position_errors_m=ape.error,
        heading_errors_rad=headings,
        estimate=from_evo(estimated),
        truth=from_evo(reference),
    )


TABLE3_DELTA_M = 1.0  # the segment length of the first paper's Table 3 as read here: metres travelled by the truth


def relative_translation_errors(
    estimate: Trajectory | PoseTrajectory3D,
    truth: Trajectory | PoseTrajectory3D,
    delta_m: float = TABLE3_DELTA_M,
    max_difference_s: float = MAX_STAMP_DIFFERENCE_S,
) -> np.ndarray:
    """The first paper's "relative translation error", metres, one per pair of poses: evo's RPE, translation part,
    over every pair ``delta_m`` of the truth's travel apart. (The paper compares GPO with the median and the mean
    vector by this error's minimum, maximum and average on each short test, its Table 3; it names the measure and its
    evaluation toolbox but no segment length, and 1 m is this suite's reading.) Raises ValueError as ``associate``
    does, and when the truth travels less than ``delta_m``."""
    estimated, reference = associate(estimate, truth, max_difference_s)
    rpe = metrics.RPE(
        metrics.PoseRelation.translation_part, delta_m, metrics.Unit.meters, all_pairs=True, pairs_from_reference=True
    )
    try:
        rpe.process_data((reference, estimated))
    except filters.FilterException as error:
        raise ValueError(f"no pair of poses {delta_m} m of travel apart: {error}") from error
    return np.asarray(rpe.error, dtype=float)


@dataclass(frozen=True)
class PaperTable2:
    """One row of the second paper's Table 2 under its own definitions (its §4.3), every column it prints.

    With p_k, θ_k the truth and p̂_k, θ̂_k the estimate (first pose placed on the truth's) at the N samples the
    ground truth gives (``samples``), D the distance the truth travels, and S the segments (j, k) between
    consecutive samples, d_jk the distance the truth travels over one::

        positioning RMSE  = sqrt( 1/N Σ_k ||p̂_k - p_k||² )                          mm
        heading RMSE      = sqrt( 1/N Σ_k wrap(θ̂_k - θ_k)² )                        deg
        final error       = ||p̂_N - p_N||   (mm)   and   100 ||p̂_N - p_N|| / D      (%)
        final heading     = |wrap(θ̂_N - θ_N)|                                       deg
        relative error    = 100/|S| Σ_(j,k) ||(p̂_k - p̂_j) - (p_k - p_j)|| / d_jk   %

    The paper gives no formula for its relative positioning error; this is the reading its table bears out:
    where the ground truth was the run's end alone (its VI, VIII, IX) it prints the relative error equal to the
    final error in %, which this gives (one segment, d = D), and where it was each stage step (IV, V, VII) the
    error per step is a few per cent of a step of 5-12 mm. It depends on the segments, hence ``samples``; the
    suite's own drift measure (RPE per metre travelled, ``Evaluation.drift_percent_per_m``) is another number.
    Segments over which base_link does not move (a turn on the spot) are left out."""

    distance_m: float
    positioning_rmse_mm: float
    heading_rmse_deg: float
    final_error_mm: float
    final_error_percent: float
    final_heading_deg: float
    relative_error_percent: float
    samples: int


def paper_table2(
    estimate: Trajectory | PoseTrajectory3D,
    truth: Trajectory | PoseTrajectory3D,
    samples_ns=None,
    max_difference_s: float = MAX_STAMP_DIFFERENCE_S,
) -> PaperTable2:
    """``PaperTable2`` of ``estimate`` against ``truth`` at the ground-truth samples nearest to ``samples_ns`` (stamps,
    ns; None: every pose the two share, i.e. a continuous ground truth, segment by segment). The first and last
    associated poses are always samples: the paper's final error is the run's end. With those two alone the RMSEs
    are NaN, as the paper prints a dash there. Raises ValueError as ``evaluate`` does, or when the samples give no
    segment that moves."""
    evaluation = evaluate(estimate, truth, Alignment.ORIGIN, RPE_DELTA_M, max_difference_s)
    stamps = evaluation.truth.stamps_ns
    chosen = np.arange(len(stamps))
    if samples_ns is not None:
        nearest = np.clip(np.searchsorted(stamps, np.asarray(samples_ns, dtype=np.int64)), 0, len(stamps) - 1)
        earlier = np.clip(nearest - 1, 0, len(stamps) - 1)
        closer = np.abs(stamps[earlier] - samples_ns) < np.abs(stamps[nearest] - samples_ns)
        chosen = np.unique(np.concatenate([[0, len(stamps) - 1], np.where(closer, earlier, nearest)]))
    true_xy = evaluation.truth.positions[chosen, :2]
    estimated_xy = evaluation.estimate.positions[chosen, :2]
    errors = np.hypot(*(estimated_xy - true_xy).T)
    headings = evaluation.heading_errors_rad[chosen]
    true_steps, estimated_steps = np.diff(true_xy, axis=0), np.diff(estimated_xy, axis=0)
    travelled = np.diff(evaluation.distances_m[chosen])
    moving = travelled > 1e-6  # a turn on the spot moves base_link by nothing: no relative error to take
    if not moving.any():
        raise ValueError("the ground truth never moves between its samples: no relative positioning error")
    step_errors = np.hypot(*(estimated_steps - true_steps)[moving].T) / travelled[moving]
    final = evaluation.final
    between_ends = len(chosen) > 2  # the start lies on the truth by construction: its end alone makes no RMSE
    return PaperTable2(
        distance_m=final.distance_m,
        positioning_rmse_mm=float(1e3 * np.sqrt(np.mean(errors**2))) if between_ends else float("nan"),
        heading_rmse_deg=float(np.degrees(np.sqrt(np.mean(headings**2)))) if between_ends else float("nan"),
        final_error_mm=1e3 * final.position_m,
        final_error_percent=final.percent,
        final_heading_deg=float(np.degrees(abs(final.heading_rad))),
        relative_error_percent=float(100.0 * step_errors.mean()),
        samples=len(chosen),
    )
