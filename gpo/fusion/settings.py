"""What ``--method fused`` fuses and how much it trusts each source: a run config's ``fusion`` section."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from gpo.fusion.ekf import BiasModel, ProcessNoise
from gpo.motion.ranges import REACH_M, check_rules, in_range


@dataclass(frozen=True)
class TrackingMount:
    """The pose of the tracking camera's pose frame (REP-103: x forward, y left, z up) in base_link:
    ``position_m`` (x, y, z metres) and ``rpy_deg`` (roll, pitch, yaw degrees, extrinsic x-y-z)."""

    position_m: tuple[float, float, float]
    rpy_deg: tuple[float, float, float]

    def __post_init__(self):
        ranges = {"position_m": (-REACH_M, REACH_M, " m"), "rpy_deg": (-360, 360, " deg")}
        for name, (low, high, unit) in ranges.items():
            values = getattr(self, name)
            if np.shape(values) != (3,) or not np.isfinite(np.asarray(values, dtype=float)).all():
                raise ValueError(f"fusion.tracking_mount.{name} must be 3 finite numbers, got {values!r}")
            object.__setattr__(self, name, tuple(float(v) for v in values))
            if not all(in_range(value, low, high)[0] for value in getattr(self, name)):
                raise ValueError(f"fusion.tracking_mount.{name} must be 3 numbers from {low} to {high}{unit}, "
                                 f"got {values!r}")

    @property
    def transform(self) -> tuple[Rotation, np.ndarray]:
        """The mount as a rigid transform: (rotation, translation in metres) of the pose frame in base_link."""
        return Rotation.from_euler("xyz", self.rpy_deg, degrees=True), np.array(self.position_m)


@dataclass(frozen=True)
class FusionSettings:
    """What ``--method fused`` fuses: the floor odometry of ``floor_method`` with a tracking camera's own odometry on
    ``tracking_topic`` (nav_msgs/Odometry of ``tracking_frame``), mounted where the bag's /tf_static says or, without
    it, where ``tracking_mount`` says (``TrackingMount``, or its dict).

    The floor: each step's mean velocity scatters by ``floor_speed_sigma_mps`` and ``floor_turn_sigma_radps`` when
    its flow kept ``floor_reference_inliers`` inlier vectors that spread by ``floor_reference_spread_px``: a median of
    n vectors spread by s scatters as q = s / sqrt(n), and the variance is the reference's times (1 + (q / q_ref)^2) / 2
    (``floor_variance_scale``; on the sample the steps' scatter against the truth grows with q so, as lab F prints:
    0.55 mm/s and 0.47 mrad/s at the best third of q, 2.53 mm/s and 2.28 mrad/s at the worst). A step without a
    spread (the features method) counts as the reference.
    The tracking camera, as its maker would specify it: random walks of position and heading
    (``tracking_position_walk_m_per_sqrt_s``, ``tracking_yaw_walk_rad_per_sqrt_s``), white jitter on each pose
    (``tracking_jitter_m``, ``tracking_jitter_rad``), and a scale error and yaw-rate bias that the filter estimates
    (``BiasModel``: their prior sigmas and random walks, the ``tracking_scale_*`` and ``tracking_yaw_bias_*``
    fields). A tracking increment over more than ``tracking_max_gap_s`` is not fused.
    The process noise is ``ProcessNoise(accel_mps2, angular_accel_radps2)``."""

    floor_method: str = "gpo-exact"
    tracking_topic: str = "/camera/odom/sample"
    tracking_frame: str = "camera_pose_frame"
    tracking_mount: TrackingMount | None = None
    floor_speed_sigma_mps: float = 0.0006
    floor_turn_sigma_radps: float = 0.0006
    floor_reference_inliers: int = 60
    floor_reference_spread_px: float = 0.3
    tracking_position_walk_m_per_sqrt_s: float = 5e-3
    tracking_yaw_walk_rad_per_sqrt_s: float = 1e-3
    tracking_jitter_m: float = 5e-4
    tracking_jitter_rad: float = 5e-4
    tracking_scale_sigma: float = BiasModel.scale_sigma
    tracking_yaw_bias_sigma_radps: float = BiasModel.yaw_bias_sigma_radps
    tracking_scale_walk_per_sqrt_s: float = BiasModel.scale_walk_per_sqrt_s
    tracking_yaw_bias_walk_radps_per_sqrt_s: float = BiasModel.yaw_bias_walk_radps_per_sqrt_s
    tracking_max_gap_s: float = 0.25
    accel_mps2: float = ProcessNoise.accel_mps2
    angular_accel_radps2: float = ProcessNoise.angular_accel_radps2

    def __post_init__(self):
        if isinstance(self.tracking_mount, dict):
            unknown = sorted(set(self.tracking_mount) - {"position_m", "rpy_deg"})
            missing = sorted({"position_m", "rpy_deg"} - set(self.tracking_mount))
            if unknown or missing:
                raise ValueError(
                    f"fusion.tracking_mount needs position_m and rpy_deg, got {', '.join(sorted(self.tracking_mount))}"
                )
            object.__setattr__(self, "tracking_mount", TrackingMount(**self.tracking_mount))
        check_rules(self._ranges(), self)

    def _ranges(self) -> dict[str, tuple[bool, str]]:
        """Each number: whether it lies in the range a real rig's sensors have, and that range with its unit. The
        tracking camera's walks reach 5 m/sqrt(s) and 1 rad/sqrt(s): lab F's camera that is not to be trusted."""
        sigma = {"floor_speed_sigma_mps": " m/s", "floor_turn_sigma_radps": " rad/s", "tracking_jitter_m": " m",
                 "tracking_jitter_rad": " rad", "tracking_scale_sigma": ", a share of the distance",
                 "tracking_yaw_bias_sigma_radps": " rad/s", "tracking_scale_walk_per_sqrt_s": " per sqrt(s)",
                 "tracking_yaw_bias_walk_radps_per_sqrt_s": " rad/s per sqrt(s)"}
        walks = {"tracking_position_walk_m_per_sqrt_s": " m/sqrt(s)",
                 "tracking_yaw_walk_rad_per_sqrt_s": " rad/sqrt(s)"}
        return {
            **{name: in_range(getattr(self, name), 0, 1, unit) for name, unit in sigma.items()},
            **{name: in_range(getattr(self, name), 0, 10, unit) for name, unit in walks.items()},
            "floor_reference_inliers": in_range(self.floor_reference_inliers, 1, 10_000, " vectors", whole=True),
            "floor_reference_spread_px": in_range(self.floor_reference_spread_px, 0, 100, " px", low_open=True),
            "tracking_max_gap_s": in_range(self.tracking_max_gap_s, 0, 60, " s", low_open=True),
            "accel_mps2": in_range(self.accel_mps2, 0, 100, " m/s^2 per sqrt(Hz)"),
            "angular_accel_radps2": in_range(self.angular_accel_radps2, 0, 100, " rad/s^2 per sqrt(Hz)"),
        }

    @property
    def bias_model(self) -> BiasModel:
        return BiasModel(
            self.tracking_scale_sigma,
            self.tracking_yaw_bias_sigma_radps,
            self.tracking_scale_walk_per_sqrt_s,
            self.tracking_yaw_bias_walk_radps_per_sqrt_s,
        )

    def to_dict(self) -> dict:
        """The settings as a config file's ``fusion`` section."""
        document = dict(vars(self))
        mount = self.tracking_mount
        document["tracking_mount"] = None if mount is None else {"position_m": [*mount.position_m],
                                                                 "rpy_deg": [*mount.rpy_deg]}
        return document


def floor_variance_scale(inliers: np.ndarray, spread_px: np.ndarray, settings: FusionSettings) -> np.ndarray:
    """How much each floor step's variance exceeds the reference's (``FusionSettings``): (1 + (q / q_ref)^2) / 2 with
    q = spread / sqrt(inliers) pixels; 1 where the spread is unknown (NaN)."""
    quality = spread_px / np.sqrt(np.maximum(inliers, 1.0))
    reference = settings.floor_reference_spread_px / math.sqrt(settings.floor_reference_inliers)
    return np.nan_to_num(0.5 * (1.0 + (quality / reference) ** 2), nan=1.0)
