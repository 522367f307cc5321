"""Chapter 07, the EKF of the floor and the tracking camera: noisy steps along an arc and the filter fed them,
paths placed on the truth, their errors along the way, the NEES between its bounds, and the filter's panel."""

from __future__ import annotations

import dataclasses
import math

import ipywidgets as widgets
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.ticker import FuncFormatter

from gpo.book.figures import draw_placed_paths
from gpo.book.panels import slider
from gpo.fusion import FilterDiverged, FusionSettings, OdometryFusion, fuse, increment_covariance
from gpo.metrics import final_error, place_on_truth
from gpo.odometry.kinematics import arc_increment


def draw_paths_on_truth(paths: dict, truth, ax=None, styles: dict | None = None) -> plt.Axes:
    """Top view of trajectories (label -> ``Trajectory``) against ``truth``, each placed on the truth at its first
    pose (``gpo.metrics.place_on_truth``); the truth a wide grey line, the start and each path's end marked."""
    placed = {label: place_on_truth(trajectory, truth)[0].positions[:, :2] for label, trajectory in paths.items()}
    return draw_placed_paths(placed, truth, ax, styles)


def draw_position_errors(paths: dict, truth, ax=None, styles: dict | None = None) -> plt.Axes:
    """How far each trajectory (label -> ``Trajectory``), placed on the truth as ``draw_paths_on_truth`` does, is from
    the truth along the way: millimetres against seconds since the truth's first stamp."""
    if ax is None:
        _, ax = plt.subplots(figsize=(7, 4))
    styles = styles or {}
    for label, trajectory in paths.items():
        placed, associated = place_on_truth(trajectory, truth)
        apart = np.hypot(*(placed.positions[:, :2] - associated.positions[:, :2]).T)
        ax.plot(placed.times - truth.times[0], 1e3 * apart, label=label, **{"lw": 1.2, **styles.get(label, {})})
    ax.set_xlabel("time [s]")
    ax.set_ylabel("position error [mm]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize="small")
    return ax


def draw_nees(
    times, nees, dof: int = 3, confidence: float = 0.95, ax=None, label: str = "NEES", runs: int = 1
) -> plt.Axes:
    """The normalised estimation error squared against time (seconds), on a log scale, between the two-sided
    ``confidence`` bounds of chi-square with ``dof`` degrees of freedom (shaded), with its mean and the share of
    values inside the bounds in the legend. With ``runs`` > 1, ``nees`` is the average over that many independent
    runs, and the bounds are those of chi-square with ``dof * runs`` degrees of freedom divided by ``runs``."""
    from scipy.stats import chi2

    if ax is None:
        _, ax = plt.subplots(figsize=(9, 3.5))
    nees = np.asarray(nees, dtype=float)
    low, high = chi2.ppf([(1 - confidence) / 2, (1 + confidence) / 2], dof * runs) / runs
    inside = np.mean((nees >= low) & (nees <= high))
    bounds = f"chi-square {dof} dof, {confidence:.0%} bounds" + (f" for the mean of {runs}" if runs > 1 else "")
    ax.axhspan(low, high, color="tab:green", alpha=0.12, label=bounds)
    ax.axhline(dof, color="tab:green", lw=0.8, ls="--", label=f"expected mean {dof}")
    ax.plot(times, nees, lw=1, color="tab:blue", label=f"{label}: mean {nees.mean():.2f}, {inside:.0%} inside")
    ax.set_yscale("log")
    ax.yaxis.set_major_formatter(FuncFormatter(lambda value, _: f"{value:g}"))
    bottom, top = ax.get_ylim()
    if top < 10 * bottom:  # less than a decade shown: label the minor ticks too, plainly
        ax.yaxis.set_minor_formatter(FuncFormatter(lambda value, _: f"{value:g}"))
    ax.set_xlabel("time [s]")
    ax.set_ylabel("NEES")
    ax.grid(True, alpha=0.3, which="both")
    ax.legend(fontsize="small")
    return ax


FUSION_SLIDERS = {  # FusionSettings field -> (slider label, log10 of its lowest and highest value)
    "floor_speed_sigma_mps": ("floor sigma v [m/s]", -4.0, 0.0),
    "floor_turn_sigma_radps": ("floor sigma omega [rad/s]", -4.0, 0.0),
    "tracking_position_walk_m_per_sqrt_s": ("camera position walk [m/sqrt(s)]", -4.0, 0.0),
    "tracking_yaw_walk_rad_per_sqrt_s": ("camera yaw walk [rad/sqrt(s)]", -5.0, -1.0),
    "accel_mps2": ("accel [m/s^2/sqrt(Hz)]", -2.0, 2.0),
    "angular_accel_radps2": ("angular accel [rad/s^2/sqrt(Hz)]", -2.0, 2.0),
}


def fusion_panel(floor, tracking, truth, settings: FusionSettings | None = None, drifted=None) -> widgets.VBox:
    """The EKF's noise parameters on log-scale sliders (``FUSION_SLIDERS``): the sigmas of the floor's (v, omega), the
    tracking camera's random walks and the process noise; a floor outage (its start and length, seconds: the floor's
    steps inside it not fused); and, when ``drifted`` is given, the tracking camera's drift (scale error %, yaw bias
    mrad/s). On each release ``gpo.fusion.fuse`` runs again.

    ``floor``: the floor odometry with its flow's inlier counts (a ``gpo.pipeline.run.FloorRun``, or anything with its
    ``trajectory``, ``inliers`` and ``spread_px``); ``tracking``: the tracking camera's path of base_link;
    ``truth``: the true path; ``settings``: the ``FusionSettings`` the sliders start from (default: the package's);
    ``drifted(scale_error, yaw_bias_radps)``: the tracking camera's path with that drift (then ``tracking`` is unused).
    Left, the three paths placed on the truth at their first pose; right, their position error along the way. One
    line reads out the fused path's final error (``gpo.metrics.final_error``), the camera's biases as the filter
    estimated them, and how many measurements the NIS gate refused.
    """
    base = settings or FusionSettings()
    style = {"description_width": "initial"}
    controls = {
        name: widgets.FloatLogSlider(
            value=getattr(base, name),
            base=10,
            min=low,
            max=high,
            step=0.1,
            description=label,
            readout_format=".2g",
            continuous_update=False,
            style=style,
        )
        for name, (label, low, high) in FUSION_SLIDERS.items()
    }
    seconds = floor.trajectory.times - floor.trajectory.times[0]
    controls["outage_start"] = slider("outage from [s]", 0.0, 0.0, float(seconds[-1]), 0.5)
    controls["outage_length"] = slider("outage length [s]", 0.0, 0.0, 5.0, 0.5)
    if drifted is not None:
        controls["scale_percent"] = slider("camera scale error [%]", 2.0, -5.0, 5.0, 0.5)
        controls["yaw_bias_mradps"] = slider("camera yaw bias [mrad/s]", 1.0, -5.0, 5.0, 0.5)
    styles = {"tracking camera": {"color": "tab:orange"}, "floor": {"color": "tab:blue"}, "fused": {"color": "tab:red"}}
    spread = getattr(floor, "spread_px", None)

    def redraw(outage_start, outage_length, scale_percent=None, yaw_bias_mradps=None, **sigmas: float) -> None:
        chosen = dataclasses.replace(base, **sigmas)
        camera = tracking if drifted is None else drifted(scale_percent / 100, yaw_bias_mradps / 1e3)
        inliers = np.where((seconds >= outage_start) & (seconds < outage_start + outage_length), 0, floor.inliers)
        plt.close("all")
        try:
            fused = fuse(floor.trajectory, inliers, camera, chosen, spread)
        except FilterDiverged as error:
            print(f"no fused path: {error}")
            return
        paths = {"tracking camera": camera, "floor": floor.trajectory, "fused": fused.trajectory}
        _, (left, right) = plt.subplots(1, 2, figsize=(13, 4.8), gridspec_kw={"width_ratios": [1, 1.2]})
        draw_paths_on_truth(paths, truth, ax=left, styles=styles)
        left.set_title("the paths, each placed on the truth at its start")
        draw_position_errors(paths, truth, ax=right, styles=styles)
        gap = f" (no floor {outage_start:.1f}-{outage_start + outage_length:.1f} s)" if outage_length > 0 else ""
        right.set_title(f"how far from the truth, along the way{gap}")
        error = final_error(fused.trajectory, truth)
        scale, yaw_bias = fused.biases[-1]
        print(
            f"fused: final error {1e3 * error.position_m:.1f} mm ({error.percent:.2f} % of {error.distance_m:.2f} m), "
            f"heading {math.degrees(error.heading_rad):+.2f} deg; camera scale {100 * scale:+.2f} %, yaw bias "
            f"{1e3 * yaw_bias:+.2f} mrad/s as estimated; the NIS gate refused {fused.refused} measurement(s)"
        )
        plt.show()

    sliders = widgets.HBox(list(controls.values()), layout={"flex_flow": "row wrap"})
    return widgets.VBox([sliders, widgets.interactive_output(redraw, controls)])


def arc_steps(seed: int, sources: dict, speed_mps: float, turn_radps: float, seconds: float) -> list[tuple]:
    """Each source's steps along a circular arc (base_link at ``speed_mps`` turning at ``turn_radps``) for ``seconds``,
    with noise seeded by ``seed``: (end time s, source, increment (dx, dy, dtheta), dt s, covariance of (dx, dtheta)),
    in time order. ``sources``: name -> (rate Hz, (sigma of a step's mean speed m/s, of its mean turn rate rad/s));
    the noise is drawn on (dx, dtheta) from ``gpo.fusion.increment_covariance``."""
    rng = np.random.default_rng(seed)
    steps = []
    for name, (rate, sigma) in sources.items():
        covariance = increment_covariance(*sigma, 1 / rate)
        exact = arc_increment(speed_mps, turn_radps, 1 / rate)
        noisy = np.tile(exact, (round(seconds * rate), 1))
        noisy[:, [0, 2]] += rng.multivariate_normal(np.zeros(2), covariance, len(noisy))
        steps += [((k + 1) / rate, name, noisy[k], 1 / rate, covariance) for k in range(len(noisy))]
    return sorted(steps, key=lambda step: step[0])


def filter_steps(steps: list[tuple], used: tuple[str, ...], noise) -> tuple[OdometryFusion, list[tuple]]:
    """An ``OdometryFusion`` with process noise ``noise`` fed the ``arc_steps`` of the sources in ``used``, and its
    (time s, pose (x, y, theta), pose covariance) after each floor step."""
    fusion, kept = OdometryFusion(0.0, noise, sources=used), []
    for time_s, name, increment, dt, covariance in steps:
        if name in used:
            fusion.add(name, time_s, increment, dt, covariance)
            if name == "floor":
                kept.append((time_s, fusion.state[:3], fusion.covariance[:3, :3]))
    return fusion, kept
