"""Chapter 07, the EKF of the floor and the tracking camera: the sample's three sources, noisy steps along an arc and
the filter fed them, clouds of final positions with the filters' ellipses, the gate's log of every step's NIS, paths
placed on the truth, their errors along the way, the NEES between its bounds, and the filter's panel."""

from __future__ import annotations

import contextlib
import dataclasses
import math

import ipywidgets as widgets
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.patches import Ellipse
from matplotlib.ticker import FuncFormatter
from scipy.stats import chi2

import gpo.fusion.ekf
from gpo.book.figures import draw_placed_paths
from gpo.book.panels import slider
from gpo.fusion import FilterDiverged, FusionSettings, OdometryFusion, fuse, increment_covariance
from gpo.io.trajectory import Trajectory
from gpo.metrics import final_error, place_on_truth, truth_poses
from gpo.odometry.kinematics import arc_increment, between, compose

SOURCE_STYLES = {  # the colours every figure of the chapter gives each source
    "tracking camera": {"color": "tab:orange"},
    "floor (gpo-exact)": {"color": "tab:blue"},
    "fused": {"color": "tab:red"},
}


def sample_sources(settings: FusionSettings | None = None):
    """The sample recording's three paths: its floor odometry (chapter 06's ``gpo-exact`` on the analytic floor image,
    a ``gpo.pipeline.run.FloorRun`` with each step's inliers and spread, kept on disk), its tracking camera's odometry
    turned into base_link (``gpo.pipeline.run.tracking_path``) and the motion capture's truth: (floor, tracking,
    truth)."""
    from gpo.experiments.runs import floor_run, route_config
    from gpo.io.bag import Recording
    from gpo.pipeline.run import tracking_path
    from gpo.sim.record import GROUND_TRUTH_TOPIC, recording

    bag = recording("sample", progress=False)
    floor = floor_run(bag, route_config("gpo-exact", "analytic"))
    with Recording(bag) as recorded:
        truth = recorded.trajectory(GROUND_TRUTH_TOPIC)
        tracking = tracking_path(recorded, settings or FusionSettings())
    return floor, tracking, truth


def ellipse_scale(confidence: float = 0.95) -> float:
    """How many standard deviations a 2-D Gaussian's ``confidence`` ellipse reaches: sqrt of chi-square 2 dof."""
    return math.sqrt(chi2.ppf(confidence, 2))


def covariance_ellipse(ax, centre, covariance, confidence: float = 0.95, **style) -> Ellipse:
    """Draw on ``ax`` the ellipse about ``centre`` (2,) that a 2-D Gaussian of ``covariance`` (2, 2) falls in with
    probability ``confidence``; ``style`` goes to matplotlib's ``Ellipse`` (unfilled by default)."""
    centre = tuple(float(value) for value in centre)  # a copy: the caller's array may move on
    values, vectors = np.linalg.eigh(np.asarray(covariance, dtype=float))
    width, height = 2 * ellipse_scale(confidence) * np.sqrt(np.maximum(values, 0.0))
    angle = math.degrees(math.atan2(vectors[1, 1], vectors[0, 1]))
    patch = Ellipse(centre, height, width, angle=angle, **{"fill": False, "lw": 1.5, **style})
    ax.add_patch(patch)
    return patch


def inside_ellipse(points, centre, covariance, confidence: float = 0.95) -> np.ndarray:
    """Whether each of ``points`` (N, 2) lies inside the ``confidence`` ellipse of ``covariance`` about ``centre``."""
    offsets = np.asarray(points, dtype=float) - centre
    squared = np.einsum("ni,ni->n", offsets, np.linalg.solve(covariance, offsets.T).T)
    return squared <= chi2.ppf(confidence, 2)


def draw_clouds(clouds: dict, ax=None, styles: dict | None = None, confidence: float = 0.95) -> plt.Axes:
    """Final position errors as clouds, each with its filter's own ellipse: ``clouds`` label -> (points (N, 2) in
    metres, covariance (2, 2) in m^2, the filter's, centred on the truth); drawn in millimetres, with how many points
    fall inside the ellipse in the legend."""
    if ax is None:
        _, ax = plt.subplots(figsize=(6, 6))
    styles = styles or {}
    for label, (points, covariance) in clouds.items():
        points = np.asarray(points, dtype=float)
        inside = inside_ellipse(points, np.zeros(2), covariance, confidence)
        style = {"color": "k", **styles.get(label, {})}
        ax.plot(
            *(1e3 * points.T),
            "o",
            ms=3.5,
            alpha=0.6,
            color=style["color"],
            label=f"{label}: {inside.sum()} of {len(points)} inside",
        )
        covariance_ellipse(ax, (0.0, 0.0), 1e6 * np.asarray(covariance), confidence, **style)
    ax.plot(0, 0, "k+", ms=12, mew=2)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x error [mm]")
    ax.set_ylabel("y error [mm]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize="small", title=f"the filters' {confidence:.0%} ellipses", title_fontsize="small")
    return ax


def model_draws(state, noise, dt: float, steps: int, count: int, seed: int) -> np.ndarray:
    """Robots drawn from the filter's own process model: ``count`` of them start at ``state`` (x, y, theta, v, omega)
    and drive ``steps`` steps of ``dt`` seconds along arcs, their v and omega each step moved by white accelerations
    of the densities in ``noise`` (a ``ProcessNoise``; variance q^2 / dt held over the step). Their poses (steps, count,
    3) after each step."""
    rng = np.random.default_rng(seed)
    poses = np.tile(np.asarray(state[:3], dtype=float), (count, 1))
    velocity = np.tile(np.asarray(state[3:5], dtype=float), (count, 1))
    sigma = np.array([noise.accel_mps2, noise.angular_accel_radps2]) / math.sqrt(dt)
    kept = []
    for _ in range(steps):
        accel = rng.standard_normal((count, 2)) * sigma
        step = arc_increment(velocity[:, 0] + 0.5 * dt * accel[:, 0], velocity[:, 1] + 0.5 * dt * accel[:, 1], dt)
        poses = compose(poses, step)
        velocity = velocity + dt * accel
        kept.append(poses)
    return np.array(kept)


def final_offset(estimate, truth) -> np.ndarray:
    """How far ``estimate``'s last position lies from the truth's at the same time (x, y metres), in the estimate's own
    frame: the truth seen from its pose at the estimate's first stamp, as a filter started there sees it."""
    true = truth_poses(truth, estimate.times[[0, -1]])
    return estimate.positions[-1, :2] - between(true[0], true[1])[:2]


def relocalised(path, at_s: float, shift_m) -> Trajectory:
    """A copy of ``path`` whose poses from ``at_s`` seconds after its first on are moved by ``shift_m`` (x, y metres):
    a tracking camera that relocalised, its pose jumping once."""
    positions = path.positions.copy()
    positions[path.times - path.times[0] >= at_s, :2] += shift_m
    return Trajectory(
        path.stamps_ns, positions, path.quaternions, frame_id=path.frame_id, child_frame_id=path.child_frame_id
    )


@contextlib.contextmanager
def gate_log(gate: float | None = None):
    """Within the block, every step ``gpo.fusion.OdometryFusion`` offers its NIS gate is logged: yields a list that
    fills with (time s, source, NIS, fused) in the order the steps come. ``gate``: the gate to use instead of
    ``gpo.fusion.ekf.MAX_NIS`` (``math.inf``: no gate). Steps not measured, or not starting where the source's last
    ended, never reach the gate and are not logged."""
    ekf, log, seen = gpo.fusion.ekf, [], []
    add, nis, limit = ekf.OdometryFusion.add, ekf._nis, ekf.MAX_NIS

    def logged_nis(innovation, spread):
        seen.append(nis(innovation, spread))
        return seen[-1]

    def logged_add(self, source, time_s, *args, **kwargs):
        seen.clear()
        fused = add(self, source, time_s, *args, **kwargs)
        if seen:
            log.append((time_s, source, seen[-1], fused))
        return fused

    ekf.OdometryFusion.add, ekf._nis = logged_add, logged_nis
    ekf.MAX_NIS = limit if gate is None else gate
    try:
        yield log
    finally:
        ekf.OdometryFusion.add, ekf._nis, ekf.MAX_NIS = add, nis, limit


def draw_nis(log: list, start_s: float = 0.0, ax=None, gate: float | None = None, styles: dict | None = None):
    """The NIS of every step in a ``gate_log`` against time (seconds after ``start_s``), a series per source, on a log
    scale, with chi-square 2 dof's 95 % point and the gate (default ``gpo.fusion.ekf.MAX_NIS``); refused steps
    circled."""
    if ax is None:
        _, ax = plt.subplots(figsize=(9, 3.5))
    styles = styles or {}
    gate = gpo.fusion.ekf.MAX_NIS if gate is None else gate
    for source in dict.fromkeys(entry[1] for entry in log):
        times = np.array([entry[0] for entry in log if entry[1] == source]) - start_s
        values = np.array([entry[2] for entry in log if entry[1] == source])
        ax.plot(times, values, ".", ms=3, label=f"{source} steps", **styles.get(source, {}))
    refused = np.array([(entry[0] - start_s, entry[2]) for entry in log if not entry[3]]).reshape(-1, 2)
    if len(refused):
        ax.plot(*refused.T, "o", ms=10, mfc="none", mec="k", label="refused")
    ax.axhline(chi2.ppf(0.95, 2), color="tab:green", ls="--", lw=1, label="95 % of correct steps below")
    if math.isfinite(gate):
        ax.axhline(gate, color="k", lw=1, label=f"the gate, {gate:g}")
    ax.set_yscale("log")
    ax.yaxis.set_major_formatter(FuncFormatter(lambda value, _: f"{value:g}"))
    ax.set_xlabel("time [s]")
    ax.set_ylabel("NIS")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize="small")
    return ax


def draw_lag(times, speed, behind: dict, dt: float, axes=None) -> np.ndarray:
    """How far filters run behind the truth (``behind``: label -> metres at ``times``) on a robot whose ``speed``
    (m/s at ``times``) changes: the speed above, the distances below in millimetres, with v dt / 2, half a step of
    ``dt`` seconds."""
    if axes is None:
        _, axes = plt.subplots(2, 1, figsize=(10, 5.5), sharex=True, gridspec_kw={"height_ratios": [1, 2]})
    top, bottom = axes
    top.plot(times, speed, "k")
    top.set_ylabel("speed [m/s]")
    top.grid(True, alpha=0.3)
    for (label, distance), color in zip(behind.items(), ("tab:purple", "tab:red", "tab:blue"), strict=False):
        bottom.plot(times, 1e3 * np.asarray(distance), color=color, label=label)
    bottom.plot(times, 1e3 * np.asarray(speed) * dt / 2, "k--", lw=1, label="v dt / 2: half a step's distance")
    bottom.set_xlabel("time [s]")
    bottom.set_ylabel("behind the truth [mm]")
    bottom.grid(True, alpha=0.3)
    bottom.legend(fontsize="small")
    return axes


def step_errors(path, truth) -> tuple[np.ndarray, np.ndarray]:
    """Each step of ``path`` and the truth's over the same interval, as mean velocities (N-1, 3: along m/s, across
    m/s, turn rad/s), each step seen from its start: (read, true)."""
    planar = np.column_stack([path.positions[:, :2], path.yaw])
    true = truth_poses(truth, path.times)
    dt = np.diff(path.times)[:, None]
    return between(planar[:-1], planar[1:]) / dt, between(true[:-1], true[1:]) / dt


def draw_quality(quality_px, errors_mps, sigma_mps, reference_px, ax=None) -> plt.Axes:
    """Each floor step's speed error (m/s, drawn in mm/s) against its flow's quality, the median's scatter
    sigma / sqrt(n) in pixels, with the band of two standard deviations the filter gives a step of that quality:
    ``sigma_mps`` at the ``reference_px`` quality, its variance times (1 + (q / q_ref)^2) / 2."""
    if ax is None:
        _, ax = plt.subplots(figsize=(7, 4))
    ax.plot(quality_px, 1e3 * np.asarray(errors_mps), ".", ms=4, color="tab:blue", label="a floor step")
    grid = np.linspace(0.0, 1.05 * np.max(quality_px), 200)
    band = 2e3 * sigma_mps * np.sqrt(0.5 * (1 + (grid / reference_px) ** 2))
    ax.fill_between(grid, -band, band, color="tab:red", alpha=0.15, label="± 2 sigma, as the filter weighs it")
    ax.axvline(reference_px, color="k", ls=":", lw=1, label="the reference quality")
    ax.set_xlabel("the flow's median scatter, sigma_px / sqrt(n) [px]")
    ax.set_ylabel("speed error of the step [mm/s]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize="small")
    return ax


def draw_bias_estimates(true, estimates, sigmas, axes=None) -> np.ndarray:
    """The filter's final estimates of the camera's scale error and yaw bias (each ± 2 standard deviations) against
    the simulator's true values, one point per drift: ``true``, ``estimates``, ``sigmas`` (N, 2: scale as a share,
    yaw bias rad/s), drawn in % and mrad/s on two axes, the line where estimate and truth agree."""
    if axes is None:
        _, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    for k, (ax, factor, name) in enumerate(
        zip(axes, (100, 1e3), ("scale error [%]", "yaw bias [mrad/s]"), strict=True)
    ):
        x, y, e = (factor * np.asarray(values)[:, k] for values in (true, estimates, sigmas))
        ax.errorbar(x, y, yerr=2 * e, fmt="o", color="tab:red", ms=4, capsize=3, label="estimate ± 2 sigma")
        reach = 1.15 * max(np.abs(x).max(), np.abs(y).max())
        ax.plot([-reach, reach], [-reach, reach], "k--", lw=1, label="estimate = truth")
        ax.set_xlabel(f"the simulator's {name}")
        ax.set_ylabel(f"the filter's {name}")
        ax.set_aspect("equal")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize="small")
    return axes


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
