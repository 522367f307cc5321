"""Lab F, the fused route in depth: the saved acceptance runs drawn, the noise settings' variants, the arc's own
Jacobian beside the filter's first-order one (and a way to run the filter with it), and the NEES of a fused path."""

from __future__ import annotations

import contextlib
import dataclasses
import math

import matplotlib.pyplot as plt
import numpy as np

import gpo.fusion.ekf
from gpo.fusion import FusionSettings
from gpo.metrics import truth_poses
from gpo.odometry.kinematics import between

SMALL_TURN = 1e-4  # below this turn per step (rad), the arc's functions of the turn are taken from their series


def arc_jacobian(state: np.ndarray, dt: float) -> np.ndarray:
    """The Jacobian (5, 5) of the exact arc the filter moves its pose along (``gpo.odometry.kinematics.arc_increment``
    turned by theta) with respect to (x, y, theta, v, omega). ``gpo.fusion.ekf.motion_jacobian`` is that of the
    first-order motion (the first paper's eq. 34): the two differ most in the omega column, where the arc moves the
    position sideways by v dt^2 / 2 per unit of omega and the first-order motion does not move it at all."""
    theta, v, omega = float(state[2]), float(state[3]), float(state[4])
    phi, length = omega * dt, v * dt
    if abs(phi) < SMALL_TURN:  # sin(phi)/phi, (1 - cos(phi))/phi and their derivatives, by their series
        sinc, cosc = 1 - phi**2 / 6, phi / 2 - phi**3 / 24
        sinc_prime, cosc_prime = -phi / 3 + phi**3 / 30, 0.5 - phi**2 / 8
    else:
        sinc, cosc = math.sin(phi) / phi, (1 - math.cos(phi)) / phi
        sinc_prime = (phi * math.cos(phi) - math.sin(phi)) / phi**2
        cosc_prime = (phi * math.sin(phi) - (1 - math.cos(phi))) / phi**2
    cos, sin = math.cos(theta), math.sin(theta)
    rotation = np.array([[cos, -sin], [sin, cos]])
    moved = rotation @ [length * sinc, length * cosc]
    jacobian = np.eye(5)
    jacobian[:2, 2] = [-moved[1], moved[0]]
    jacobian[:2, 3] = rotation @ [dt * sinc, dt * cosc]
    jacobian[:2, 4] = rotation @ [length * dt * sinc_prime, length * dt * cosc_prime]
    jacobian[2, 4] = dt
    return jacobian


@contextlib.contextmanager
def arc_jacobian_in_filter():
    """Within the block, ``gpo.fusion.OdometryFusion`` (and so ``fuse``) moves its covariance with ``arc_jacobian``
    instead of ``gpo.fusion.ekf.motion_jacobian``; the package's own comes back after the block, whatever happens."""
    original = gpo.fusion.ekf.motion_jacobian
    gpo.fusion.ekf.motion_jacobian = arc_jacobian
    try:
        yield
    finally:
        gpo.fusion.ekf.motion_jacobian = original


def noise_variants(settings: FusionSettings) -> dict[str, FusionSettings]:
    """``settings`` and six variants of its noise: the floor's sigmas three times larger, no bias states, the camera
    or the floor trusted alone (the other's sigmas a thousand times larger), the process noise densities ten times
    smaller and ten times larger (its covariance Q a hundred times)."""
    no_biases = dataclasses.replace(
        settings,
        tracking_scale_sigma=0.0,
        tracking_yaw_bias_sigma_radps=0.0,
        tracking_scale_walk_per_sqrt_s=0.0,
        tracking_yaw_bias_walk_radps_per_sqrt_s=0.0,
    )
    return {
        "default": settings,
        "floor sigmas x 3": dataclasses.replace(
            settings,
            floor_speed_sigma_mps=3 * settings.floor_speed_sigma_mps,
            floor_turn_sigma_radps=3 * settings.floor_turn_sigma_radps,
        ),
        "no bias states": no_biases,
        "trust the floor only": dataclasses.replace(
            settings,
            tracking_position_walk_m_per_sqrt_s=1000 * settings.tracking_position_walk_m_per_sqrt_s,
            tracking_yaw_walk_rad_per_sqrt_s=1000 * settings.tracking_yaw_walk_rad_per_sqrt_s,
            tracking_jitter_m=1000 * settings.tracking_jitter_m,
            tracking_jitter_rad=1000 * settings.tracking_jitter_rad,
        ),
        "trust the camera only": dataclasses.replace(
            no_biases,
            floor_speed_sigma_mps=1000 * settings.floor_speed_sigma_mps,
            floor_turn_sigma_radps=1000 * settings.floor_turn_sigma_radps,
        ),
        "process noise / 10": scaled_process_noise(settings, 0.1),
        "process noise x 10": scaled_process_noise(settings, 10.0),
    }


def scaled_process_noise(settings: FusionSettings, factor: float) -> FusionSettings:
    """``settings`` with both process noise densities multiplied by ``factor`` (the process covariance Q by its
    square)."""
    return dataclasses.replace(
        settings,
        accel_mps2=factor * settings.accel_mps2,
        angular_accel_radps2=factor * settings.angular_accel_radps2,
    )


def pose_nees(fused, truth, block=(0, 1, 2)) -> np.ndarray:
    """The NEES of every pose of a ``gpo.fusion.FusedPath`` after its first against ``truth`` (both seen from the
    truth's pose at the first stamp, the heading's error wrapped), over the state's entries ``block`` (default the
    pose: x, y, theta)."""
    estimate = fused.trajectory
    true = truth_poses(truth, estimate.times)
    true = between(np.broadcast_to(true[0], true.shape), true)
    errors = np.column_stack([estimate.positions[:, :2], estimate.yaw]) - true
    errors[:, 2] = np.angle(np.exp(1j * errors[:, 2]))
    chosen = list(block)
    errors = errors[1:][:, chosen]
    covariance = fused.covariances[1:][:, chosen][:, :, chosen]
    return np.einsum("ni,ni->n", errors, np.linalg.solve(covariance, errors[..., None])[..., 0])


PRESET_COLOURS = {"long1": "tab:blue", "long2": "tab:green", "long3": "tab:purple"}


def draw_acceptance(results: dict, axes=None, ratio: float = 1.1, outage_target_percent: float = 0.3) -> np.ndarray:
    """The saved runs of ``benchmarks/fusion_accuracy.py`` (``results``: its JSON) on two axes. Left, where both sources
    work: each run's fused final error against the better source's (% of the distance), with the lines fused = better
    and fused = ``ratio`` x better. Right, with floor outages: each run's floor, camera and fused final errors (log
    scale), runs side by side per path, and the ``outage_target_percent`` line."""
    if axes is None:
        _, axes = plt.subplots(1, 2, figsize=(14, 5))
    left, right = axes
    runs = results["runs"]
    both = [run for run in runs if not run["preset"].endswith("-outages")]
    for preset in dict.fromkeys(run["preset"] for run in both):
        chosen = [run for run in both if run["preset"] == preset]
        better = [min(run["floor_final_percent"], run["camera_final_percent"]) for run in chosen]
        left.plot(
            better, [run["fused_final_percent"] for run in chosen], "o", color=PRESET_COLOURS.get(preset), label=preset
        )
    reach = np.array([0.0, 1.1 * max(run["fused_final_percent"] for run in both)])
    left.plot(reach, reach, "k-", lw=1, label="fused = the better source")
    left.plot(reach, ratio * reach, "k--", lw=1, label=f"fused = {ratio:g} x the better")
    left.set(xlabel="the better source's final error [% of the distance]", ylabel="fused final error [%]")
    left.set_title("both sources working: 10 drifts of the camera per path")
    outages = [run for run in runs if run["preset"].endswith("-outages")]
    offset = {"floor": -0.25, "camera": 0.0, "fused": 0.25}
    colours = {"floor": "tab:blue", "camera": "tab:orange", "fused": "tab:red"}
    for source, shift in offset.items():
        positions = np.arange(len(outages)) + shift
        right.plot(
            positions,
            [run[f"{source}_final_percent"] for run in outages],
            "o",
            ms=4,
            color=colours[source],
            label=f"{source}",
        )
    right.axhline(outage_target_percent, color="k", ls="--", lw=1, label=f"{outage_target_percent:g} %")
    right.set_yscale("log")
    presets = list(dict.fromkeys(run["preset"] for run in outages))
    ticks = [np.mean([k for k, run in enumerate(outages) if run["preset"] == preset]) for preset in presets]
    right.set_xticks(ticks, presets)
    right.set_ylabel("final error [% of the distance]")
    right.set_title("the floor out 12-14 % of the frames: 10 drifts per path")
    for ax in axes:
        ax.grid(True, alpha=0.3, which="both")
        ax.legend(fontsize="small")
    return axes
