"""Matplotlib figures shared by the notebooks and the command line."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.collections import LineCollection, PatchCollection, PolyCollection
from matplotlib.patches import Circle
from matplotlib.ticker import FuncFormatter
from matplotlib.transforms import Affine2D

from gpo.camera import EUCM, Pinhole
from gpo.rig import Rig, floor_points, rays_in_base

SURFACE_COLOURS = {"floor": "tab:brown", "left wall": "tab:blue", "right wall": "tab:green", "front wall": "tab:purple"}


def room_grid_lines(
    height: float = 0.12, half_width: float = 2.0, depth: float = 4.0, wall_height: float = 2.0, spacing: float = 0.25
) -> dict[str, list[np.ndarray]]:
    """Grid lines on the floor and walls of a box-shaped room, in the camera optical frame.

    The camera stands ``height`` metres above the floor looking straight ahead along the floor
    (optical axis level); the room spans ``x`` in [-half_width, half_width] metres, ``z`` in
    [-depth, depth] (so the floor also continues behind the camera) and the walls rise
    ``wall_height`` metres above the floor. Lines are ``spacing`` metres apart and each is a
    (200, 3) polyline, so that its curved image can be drawn.

    Returns a dict surface name -> list of polylines, with the surfaces of ``SURFACE_COLOURS``.
    """
    t = np.linspace(0.0, 1.0, 200)[:, None]
    floor_y, ceiling_y = height, height - wall_height

    def segment(start, end):
        return np.asarray(start, dtype=float) + t * (np.asarray(end, dtype=float) - np.asarray(start, dtype=float))

    def ticks(low, high):
        return np.arange(np.ceil(low / spacing), np.floor(high / spacing) + 1) * spacing

    lines: dict[str, list[np.ndarray]] = {name: [] for name in SURFACE_COLOURS}
    for x in ticks(-half_width, half_width):
        lines["floor"].append(segment([x, floor_y, -depth], [x, floor_y, depth]))
        lines["front wall"].append(segment([x, floor_y, depth], [x, ceiling_y, depth]))
    for z in ticks(-depth, depth):
        lines["floor"].append(segment([-half_width, floor_y, z], [half_width, floor_y, z]))
    for side, x in (("left wall", -half_width), ("right wall", half_width)):
        for z in ticks(-depth, depth):
            lines[side].append(segment([x, floor_y, z], [x, ceiling_y, z]))
        for y in ticks(ceiling_y, floor_y):
            lines[side].append(segment([x, y, -depth], [x, y, depth]))
    for y in ticks(ceiling_y, floor_y):
        lines["front wall"].append(segment([-half_width, y, depth], [half_width, y, depth]))
    return lines


def draw_room_in_image(camera: EUCM | Pinhole, ax=None, **room) -> plt.Axes:
    """Draw where ``room_grid_lines(**room)`` lands in ``camera``'s image, with the image border.

    Invalid projections (NaN) break the lines instead of joining them across the image.
    For an EUCM with alpha > 0.5, the dashed ellipse bounds the pixels that have a ray.
    """
    if ax is None:
        _, ax = plt.subplots(figsize=(6.4, 6.4 * camera.height / camera.width))
    for surface, polylines in room_grid_lines(**room).items():
        for index, polyline in enumerate(polylines):
            uv, _ = camera.project(polyline)
            ax.plot(uv[:, 0], uv[:, 1], color=SURFACE_COLOURS[surface], lw=0.7, label=surface if index == 0 else None)
    if isinstance(camera, EUCM) and camera.alpha > 0.5:
        r_max = 1.0 / np.sqrt(camera.beta * (2.0 * camera.alpha - 1.0))
        phi = np.linspace(0.0, 2.0 * np.pi, 361)
        ax.plot(
            camera.cx + camera.fx * r_max * np.cos(phi),
            camera.cy + camera.fy * r_max * np.sin(phi),
            "k--",
            lw=0.8,
            label="edge of the valid region",
        )
    ax.add_patch(plt.Rectangle((-0.5, -0.5), camera.width, camera.height, fill=False, color="k", lw=1.2))
    ax.set_xlim(-0.5, camera.width - 0.5)
    ax.set_ylim(camera.height - 0.5, -0.5)
    ax.set_aspect("equal")
    ax.set_xlabel("u [px]")
    ax.set_ylabel("v [px]")
    ax.legend(loc="lower right", fontsize="small", framealpha=0.9)
    return ax


def draw_projection_curves(cameras: dict[str, EUCM | Pinhole], ax=None, max_angle_deg: float = 135.0) -> plt.Axes:
    """Image radius (pixels from the principal point) against the angle off the optical axis.

    Each camera is probed along its +x axis, so the curve is r(theta) = u(theta) - cx; the
    curve stops where the projection becomes invalid.
    """
    if ax is None:
        _, ax = plt.subplots(figsize=(6.4, 4.0))
    theta = np.radians(np.linspace(0.0, max_angle_deg, 541))
    rays = np.stack([np.sin(theta), np.zeros_like(theta), np.cos(theta)], axis=-1)
    for label, camera in cameras.items():
        uv, _ = camera.project(rays)
        ax.plot(np.degrees(theta), uv[:, 0] - camera.principal_point[0], label=label)
    ax.set_xlabel("angle off the optical axis [deg]")
    ax.set_ylabel("image radius [px]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize="small")
    return ax


def field_of_view_text(camera) -> str:
    """The camera's field of view as one line of text, in degrees."""
    angles = np.degrees(camera.field_of_view())
    parts = [
        f"{name} {angle:.1f} deg" if np.isfinite(angle) else f"{name} n/a (border outside the valid region)"
        for name, angle in zip(("horizontal", "vertical", "diagonal"), angles, strict=True)
    ]
    return "field of view: " + ", ".join(parts)


def draw_rig_footprint(rig: Rig, ax=None, max_range: float = 1.5, step: int = 8, color: str = "tab:blue") -> plt.Axes:
    """Top view (``base_link``, metres) of the floor the rig's camera sees within ``max_range`` metres.

    Each dot is the floor point of one pixel of a grid every ``step`` pixels; pixels whose ray misses
    the floor, or meets it further than ``max_range`` from the camera, are left out.
    """
    if ax is None:
        _, ax = plt.subplots(figsize=(5, 5))
    pixels = rig.camera.pixel_grid()[::step, ::step]
    rays, valid = rays_in_base(rig, pixels)
    points, hits = floor_points(rig, rays)
    with np.errstate(invalid="ignore"):
        seen = valid & hits & (np.linalg.norm(points - rig.mount.position[:2], axis=-1) <= max_range)
    ax.plot(points[seen, 0], points[seen, 1], ".", ms=1, color=color, label=f"floor seen by {rig.name}")
    ax.plot(*rig.mount.position[:2], "^", ms=9, color="k", label="camera")
    ax.set_aspect("equal")
    ax.set_xlabel("x forward [m]")
    ax.set_ylabel("y left [m]")
    return ax


def draw_paths(paths: dict, ax=None, styles: dict | None = None) -> plt.Axes:
    """Top view of trajectories (label -> ``gpo.trajectory.Trajectory``), x and y in metres, with the start marked."""
    if ax is None:
        _, ax = plt.subplots(figsize=(7, 5))
    styles = styles or {}
    for label, trajectory in paths.items():
        ax.plot(trajectory.positions[:, 0], trajectory.positions[:, 1], label=label, **styles.get(label, {}))
    first = next(iter(paths.values()))
    ax.plot(*first.positions[0, :2], "go", label="start")
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.legend(fontsize="small")
    return ax


def draw_residuals(result, ax=None, scale: float | None = None) -> plt.Axes:
    """Residual vectors of a ``gpo.calibrate.CalibrationResult`` over its image, magnified ``scale`` times
    (by default so that an RMS-sized residual is drawn 10 px long)."""
    if ax is None:
        _, ax = plt.subplots(figsize=(6.4, 6.0))
    if scale is None:
        scale = float(10 ** np.round(np.log10(10.0 / max(result.rms_px, 1e-6))))
    corners = np.concatenate([result.corners[i] for i in result.used])
    residuals = np.concatenate([result.residuals[i] for i in result.used])
    ax.quiver(
        corners[:, 0],
        corners[:, 1],
        residuals[:, 0],
        residuals[:, 1],
        angles="xy",
        scale_units="xy",
        scale=1.0 / scale,
        width=0.003,
        color="tab:red",
    )
    ax.plot(corners[:, 0], corners[:, 1], ".", ms=1.5, color="0.4")
    ax.set_xlim(-0.5, result.camera.width - 0.5)
    ax.set_ylim(result.camera.height - 0.5, -0.5)
    ax.set_aspect("equal")
    ax.set_xlabel("u [px]")
    ax.set_ylabel("v [px]")
    ax.set_title(f"{result.model}: residuals x{scale:.0f}, RMS {result.rms_px:.3f} px")
    return ax


def draw_view_errors(result, ax=None) -> plt.Axes:
    """RMS reprojection error of every view of a ``CalibrationResult``; views left out are marked."""
    if ax is None:
        _, ax = plt.subplots(figsize=(7, 3))
    views = sorted(result.view_rms_px)
    colours = ["tab:blue" if i in result.used else "tab:gray" for i in views]
    ax.bar([str(i) for i in views], [result.view_rms_px[i] for i in views], color=colours)
    for i in sorted(result.dropped):
        ax.annotate("left out", (str(i), 0), rotation=90, ha="center", va="bottom", fontsize="x-small")
    ax.set_xlabel("view")
    ax.set_ylabel("RMS [px]")
    return ax


def draw_floor_image(image, floor, ax=None, mount=None, axes_length: float = 0.1) -> plt.Axes:
    """A floor image (``gpo.ground.FloorImage`` ``floor``) drawn where it lies in ``base_link``, seen from above.

    Forward (+x) is up and left (+y) to the left, in metres; every pixel is put where ``floor.affine`` puts it, so
    a GPI, an ortho-GPI and an analytic image line up on the same axes. base_link's origin is drawn with its x
    and y axes ``axes_length`` metres long, and the camera at ``mount.position`` (a ``CameraMount``) when given.
    """
    if ax is None:
        _, ax = plt.subplots(figsize=(5, 6))
    affine = floor.affine
    # pixel (u, v) -> plot (horizontal, vertical) = (y, x) in base_link: the affine map's rows swapped
    to_plot = Affine2D(np.vstack([affine[1], affine[0], [0.0, 0.0, 1.0]]))
    pixels = (-0.5, floor.width - 0.5, floor.height - 0.5, -0.5)
    artist = ax.imshow(image, cmap="gray", vmin=0, vmax=255, extent=pixels, interpolation="nearest")
    artist.set_transform(to_plot + ax.transData)
    ax.annotate("", (0.0, axes_length), (0.0, 0.0), arrowprops={"arrowstyle": "->", "color": "tab:red", "lw": 2})
    ax.annotate("", (axes_length, 0.0), (0.0, 0.0), arrowprops={"arrowstyle": "->", "color": "tab:green", "lw": 2})
    ax.text(0.0, 1.1 * axes_length, "x", color="tab:red", ha="center", va="bottom")
    ax.text(1.1 * axes_length, 0.0, "y", color="tab:green", ha="right", va="center")
    ax.text(0.0, -0.2 * axes_length, "base_link", ha="center", va="top", fontsize="small")
    x_min, x_max, y_min, y_max = floor.extent
    points = [(y_min, x_min), (y_max, x_max), (-0.3 * axes_length, -0.5 * axes_length), (1.3 * axes_length, 0.0)]
    if mount is not None:
        ax.plot(mount.position[1], mount.position[0], "^", ms=9, color="tab:orange")
        ax.annotate("camera", (mount.position[1], mount.position[0]), (8, -4), textcoords="offset points")
        points.append((mount.position[1], mount.position[0]))
    horizontal, vertical = np.array(points).T
    margin = 0.05 * max(np.ptp(horizontal), np.ptp(vertical))
    ax.set_xlim(horizontal.max() + margin, horizontal.min() - margin)  # y grows to the left
    ax.set_ylim(vertical.min() - margin, vertical.max() + margin)
    ax.set_aspect("equal")
    ax.set_xlabel("y, left [m]")
    ax.set_ylabel("x, forward [m]")
    return ax


FLOW_COLOURS = {"inlier": "tab:green", "outlier": "tab:red", "median": "tab:blue", "mean": "tab:orange"}


def draw_flow_vectors(image, measurement, ax=None, scale: float = 1.0) -> plt.Axes:
    """A floor image with the kept tracks of a ``gpo.flow.FlowMeasurement``: each an arrow from where it started,
    ``scale`` times its length; inliers (near the median vector) and outliers in two colours (``FLOW_COLOURS``)."""
    if ax is None:
        _, ax = plt.subplots(figsize=(5, 5))
    ax.imshow(image, cmap="gray", vmin=0, vmax=255)
    start, vectors = measurement.start, measurement.vectors
    for chosen, kind in ((measurement.inlier, "inlier"), (~measurement.inlier, "outlier")):
        if chosen.any():
            ax.quiver(
                start[chosen, 0],
                start[chosen, 1],
                vectors[chosen, 0],
                vectors[chosen, 1],
                angles="xy",
                scale_units="xy",
                scale=1.0 / scale,
                width=0.005,
                color=FLOW_COLOURS[kind],
                label=f"{int(chosen.sum())} {kind}{'s' if chosen.sum() != 1 else ''}",
            )
    if len(start):
        ax.legend(loc="lower right", fontsize="small", framealpha=0.8)
    ax.set_xlim(-0.5, image.shape[1] - 0.5)
    ax.set_ylim(image.shape[0] - 0.5, -0.5)
    ax.set_axis_off()
    return ax


def draw_flow_scatter(measurement, ax=None) -> plt.Axes:
    """The first paper's Fig. 17: every kept track's motion vector (du, dv) pixels as a point, inliers and outliers
    apart, with the median vector and the mean vector marked. v grows downwards, as in the image."""
    if ax is None:
        _, ax = plt.subplots(figsize=(5, 5))
    vectors = measurement.vectors
    for chosen, kind in ((measurement.inlier, "inlier"), (~measurement.inlier, "outlier")):
        if chosen.any():
            ax.plot(*vectors[chosen].T, ".", ms=5, color=FLOW_COLOURS[kind], label=f"{kind}s")
    if np.isfinite(measurement.median).all():
        for name, marker in (("median", "*"), ("mean", "X")):
            du, dv = getattr(measurement, name)
            ax.plot(du, dv, marker, ms=14, mec="k", color=FLOW_COLOURS[name], label=f"{name} ({du:+.2f}, {dv:+.2f})")
    ax.set_aspect("equal", adjustable="datalim")
    if not ax.yaxis_inverted():
        ax.invert_yaxis()
    ax.grid(True, alpha=0.3)
    ax.set_xlabel("du [px] (right)")
    ax.set_ylabel("dv [px] (down)")
    if len(vectors):
        ax.legend(fontsize="small")
    return ax


def draw_heading_rate_ratio(wheelbase_m: float, rear_to_reference_m, ax=None, max_steering_deg: float = 60.0):
    """Eq. (30)'s heading rate over the true one (``gpo.kinematics.paper_heading_rate_ratio``) against the steering
    angle, one curve per reference point l_r in ``rear_to_reference_m`` (metres, a number or a sequence)."""
    from gpo.kinematics import paper_heading_rate_ratio

    if ax is None:
        _, ax = plt.subplots(figsize=(6, 4))
    steering = np.radians(np.linspace(0.0, max_steering_deg, 321))
    for lever in np.atleast_1d(rear_to_reference_m):
        ratio = paper_heading_rate_ratio(steering, wheelbase_m, float(lever))
        ax.plot(np.degrees(steering), ratio, label=f"$l_r$ = {lever:.2f} m ({lever / wheelbase_m:.2f} L)")
    ax.axhline(1.0, color="k", lw=0.8, ls=":")
    ax.set_xlabel(r"steering angle $\delta$ [deg]")
    ax.set_ylabel("heading rate: eq. 30 / exact")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize="small")
    return ax


def draw_bicycle(wheelbase_m: float, rear_to_reference_m: float, steering_rad: float, ax=None) -> plt.Axes:
    """Top view of the first paper's bicycle model in base_link (x forward to the right, y left upwards): the rear
    axle at the origin, the virtual front wheel a wheelbase L ahead turned by the steering angle delta and moving at
    V, the reference point l_r ahead of the rear axle moving in the direction of the slip angle beta, and the turning
    centre on the rear axle's line with the reference point's radius R (eqs. 28-29). ``steering_rad`` in (0, 80 deg]."""
    from matplotlib.patches import Arc, Rectangle

    if ax is None:
        _, ax = plt.subplots(figsize=(7, 6))
    length, lever, delta = float(wheelbase_m), float(rear_to_reference_m), float(steering_rad)
    beta = float(np.arctan(lever * np.tan(delta) / length))
    centre = np.array([0.0, length / np.tan(delta)])
    arrow = 0.45 * length
    ax.add_patch(Rectangle((-0.2 * length, -0.22 * length), 1.4 * length, 0.44 * length, color="0.92", zorder=0))
    wheel = 0.12 * length
    ax.plot([-wheel, wheel], [0.0, 0.0], color="k", lw=6, solid_capstyle="butt")
    ax.plot(
        length + wheel * np.array([-np.cos(delta), np.cos(delta)]),
        wheel * np.array([-np.sin(delta), np.sin(delta)]),
        color="0.4",
        lw=6,
        solid_capstyle="butt",
        alpha=0.6,
    )
    ax.plot([0.0, length], [0.0, 0.0], color="0.3", lw=1)
    points = {
        "rear axle (base_link)": (0.0, "k"),
        "reference point": (lever, "tab:purple"),
        "virtual front wheel": (length, "tab:blue"),
    }
    for name, (x, colour) in points.items():
        ax.plot(x, 0.0, "o", color=colour, ms=7, zorder=3)
        ax.annotate(
            name,
            (x, 0.0),
            (0, 14 if x == lever else -20),
            textcoords="offset points",
            ha="center",
            color=colour,
            fontsize="small",
        )
    for x, (dx, dy), colour, name in (
        (length, (np.cos(delta), np.sin(delta)), "tab:blue", "$V$"),
        (lever, (np.cos(beta), np.sin(beta)), "tab:purple", "$V_r$"),
    ):
        ax.annotate(
            "", (x + arrow * dx, arrow * dy), (x, 0.0), arrowprops={"arrowstyle": "-|>", "color": colour, "lw": 2}
        )
        ax.text(x + 1.08 * arrow * dx, 1.08 * arrow * dy, name, color=colour, fontsize="large")
    for x, angle, name, colour in ((length, delta, r"$\delta$", "tab:blue"), (lever, beta, r"$\beta$", "tab:purple")):
        radius = 0.5 * arrow
        ax.add_patch(Arc((x, 0.0), 2 * radius, 2 * radius, theta1=0.0, theta2=np.degrees(angle), color=colour))
        ax.text(
            x + 1.1 * radius * np.cos(angle / 2),
            1.1 * radius * np.sin(angle / 2),
            name,
            color=colour,
            fontsize="small",
            va="center",
        )
    ax.plot([0.0, 1.2 * length], [0.0, 0.0], color="0.6", lw=0.8, ls=":")
    for x, colour in ((0.0, "k"), (lever, "tab:purple"), (length, "tab:blue")):
        ax.plot([centre[0], x], [centre[1], 0.0], color=colour, lw=0.8, ls="--")
    ax.plot(*centre, "+", ms=12, color="k")
    ax.annotate("turning centre", centre, (6, 6), textcoords="offset points", fontsize="small")
    middle = (centre + np.array([lever, 0.0])) / 2
    ax.text(middle[0] + 0.03 * length, middle[1], "$R$", color="tab:purple", fontsize="large")
    for x0, x1, y, name in ((0.0, length, -0.38 * length, "$L$"), (0.0, lever, -0.53 * length, "$l_r$")):
        if x1 > x0:
            ax.annotate("", (x1, y), (x0, y), arrowprops={"arrowstyle": "<->", "color": "0.3"})
            ax.text((x0 + x1) / 2, y - 0.02 * length, name, ha="center", va="top")
    ax.set_aspect("equal")
    ax.set_xlim(-0.45 * length, 1.7 * length)
    ax.set_ylim(-0.68 * length, centre[1] + 0.2 * length)
    ax.set_xlabel("x forward [m]")
    ax.set_ylabel("y left [m]")
    return ax


def truth_poses(truth, times) -> np.ndarray:
    """(N, 3) planar poses (x, y, unwrapped yaw) of ``truth`` (a ``Trajectory``) at ``times`` (seconds), linearly
    interpolated between its poses (held at its ends)."""
    yaw = np.unwrap(truth.yaw)
    return np.column_stack([np.interp(times, truth.times, values) for values in (*truth.positions[:, :2].T, yaw)])


def on_truth(estimate, truth):
    """``estimate`` (a ``Trajectory``, in its own odometry frame) with its first pose placed on the truth's pose at its
    first stamp: the papers' alignment, as ``gpo.metrics.final_error`` does it."""
    from scipy.spatial.transform import Rotation

    x, y, yaw = truth_poses(truth, estimate.times[:1])[0]
    start = estimate.positions[0, :2], estimate.yaw[0]
    turn = Rotation.from_euler("z", yaw - start[1])
    shift = np.array([x, y, 0.0]) - turn.apply([*start[0], 0.0])
    return estimate.compose((turn, shift), frame_id=truth.frame_id)


def draw_paths_on_truth(paths: dict, truth, ax=None, styles: dict | None = None) -> plt.Axes:
    """Top view of trajectories (label -> ``Trajectory``) against ``truth``, each placed on the truth at its first
    stamp (``on_truth``); the truth a wide grey line, the start and each path's end marked."""
    if ax is None:
        _, ax = plt.subplots(figsize=(7, 5))
    styles = styles or {}
    ax.plot(*truth.positions[:, :2].T, color="k", lw=5, alpha=0.2, label="truth")
    for label, trajectory in paths.items():
        placed = on_truth(trajectory, truth).positions[:, :2]
        (line,) = ax.plot(*placed.T, label=label, **{"lw": 1.2, **styles.get(label, {})})
        ax.plot(*placed[-1], "o", color=line.get_color(), ms=4)
    ax.plot(*truth.positions[0, :2], "go", label="start")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize="small")
    return ax


def draw_position_errors(paths: dict, truth, ax=None, styles: dict | None = None) -> plt.Axes:
    """How far each trajectory (label -> ``Trajectory``), placed on the truth as ``draw_paths_on_truth`` does, is from
    the truth along the way: millimetres against seconds since the truth's first stamp."""
    if ax is None:
        _, ax = plt.subplots(figsize=(7, 4))
    styles = styles or {}
    for label, trajectory in paths.items():
        placed = on_truth(trajectory, truth)
        apart = np.hypot(*(placed.positions[:, :2] - truth_poses(truth, placed.times)[:, :2]).T)
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


def draw_evaluated_paths(evaluations: dict, ax=None, styles: dict | None = None) -> plt.Axes:
    """Top view of evaluated estimates (label -> ``gpo.metrics.Evaluation``), each where its evaluation's alignment
    put it, over the truth (a wide grey line: the associated truth with the most poses); the start, the truth's end
    (a cross) and each estimate's end (a dot) marked."""
    if ax is None:
        _, ax = plt.subplots(figsize=(7, 5))
    styles = styles or {}
    truth = max((evaluation.truth for evaluation in evaluations.values()), key=len)
    ax.plot(*truth.positions[:, :2].T, color="k", lw=5, alpha=0.2, label="truth")
    for label, evaluation in evaluations.items():
        placed = evaluation.estimate.positions[:, :2]
        (line,) = ax.plot(*placed.T, label=label, **{"lw": 1.2, **styles.get(label, {})})
        ax.plot(*placed[-1], "o", color=line.get_color(), ms=4)
    ax.plot(*truth.positions[0, :2], "go", label="start")
    ax.plot(*truth.positions[-1, :2], "kx", ms=9, mew=2, label="end (truth)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize="small")
    return ax


def draw_evaluation_errors(evaluations: dict, ax=None, styles: dict | None = None, kind: str = "position") -> plt.Axes:
    """Each evaluation's error (label -> ``gpo.metrics.Evaluation``) against the distance the truth travelled from its
    first associated pose, metres: ``kind`` "position" (evo's APE of each pose, millimetres) or "heading" (the
    estimate's yaw minus the truth's, degrees)."""
    errors = {
        "position": (lambda evaluation: 1e3 * evaluation.position_errors_m, "position error [mm]"),
        "heading": (lambda evaluation: np.degrees(evaluation.heading_errors_rad), "heading error [deg]"),
    }
    if kind not in errors:
        raise ValueError(f"unknown kind {kind!r}: expected {' or '.join(errors)}")
    values, ylabel = errors[kind]
    if ax is None:
        _, ax = plt.subplots(figsize=(7, 4))
    styles = styles or {}
    for label, evaluation in evaluations.items():
        ax.plot(evaluation.distances_m, values(evaluation), label=label, **{"lw": 1.2, **styles.get(label, {})})
    if kind == "heading":
        ax.axhline(0.0, color="k", lw=0.8)
    ax.set_xlabel("distance travelled by the truth [m]")
    ax.set_ylabel(ylabel)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize="small")
    return ax


def _frame(image, ax=None) -> plt.Axes:
    """A grey 8-bit frame (H, W) on ``ax`` (a new figure when None), pixel centres at whole (u, v), no axes."""
    if ax is None:
        _, ax = plt.subplots(figsize=(7, 4.5))
    ax.imshow(image, cmap="gray", vmin=0, vmax=255)
    ax.set_xlim(-0.5, image.shape[1] - 0.5)
    ax.set_ylim(image.shape[0] - 0.5, -0.5)
    ax.set_axis_off()
    return ax


def draw_keypoints(image, keypoints, ax=None) -> plt.Axes:
    """A grey frame (H, W) with its keypoints (``gpo.features.Keypoints``, pixels of the full image), each a circle
    of its diameter ``size``."""
    ax = _frame(image, ax)
    circles = [Circle(point, size / 2) for point, size in zip(keypoints.points, keypoints.sizes, strict=True)]
    ax.add_collection(PatchCollection(circles, facecolor="none", edgecolor="yellow", lw=0.8))
    ax.set_title(f"{len(keypoints)} keypoints")
    return ax


MATCH_FATES = {  # a match's fate -> its colour
    "rejected by the histogram filter": "tab:red",
    "rejected by the invariance check": "tab:orange",
    "kept": "tab:green",
    "not filtered: frame flagged": "tab:gray",
}


def match_fates(matches) -> dict[str, np.ndarray]:
    """Which of the M matches of a ``gpo.features.FeatureMatches`` met each fate of ``MATCH_FATES`` (M,) bool. A
    frame flagged before any stage ran keeps none: its matches are all "not filtered: frame flagged"."""
    through_histogram = matches.histogram_kept
    unfiltered = matches.flag is not None and matches.histogram is None and matches.invariance is None
    return {
        "rejected by the histogram filter": ~through_histogram,
        "rejected by the invariance check": through_histogram & ~matches.kept,
        "kept": matches.kept & (not unfiltered),
        "not filtered: frame flagged": matches.kept & unfiltered,
    }


def draw_feature_matches(image, matches, ax=None) -> plt.Axes:
    """The current grey frame (H, W) with every match of a ``gpo.features.FeatureMatches``: a line from its start
    (previous frame) to its end (this frame), pixels of the full image, with a dot at the end, coloured by its fate
    (``MATCH_FATES``, the flagged frame's only when it has some); the legend counts each fate."""
    ax = _frame(image, ax)
    start, end = matches.matched
    fates = match_fates(matches)
    for fate, chosen in fates.items():
        if chosen.any() or fate != "not filtered: frame flagged":
            segments = np.stack([start[chosen], end[chosen]], axis=1)
            colour = MATCH_FATES[fate]
            ax.add_collection(LineCollection(segments, colors=colour, lw=1, label=f"{chosen.sum()} {fate}"))
            ax.plot(*end[chosen].T, ".", ms=3, color=colour)
    ax.legend(loc="lower right", fontsize="small", framealpha=0.8)
    ax.set_title(f"{fates['kept'].sum()} of {len(matches.pairs)} matches kept")
    return ax


def draw_match_histogram(stage, ax=None, label: str = "orientation (deg)") -> plt.Axes:
    """One histogram of the filter (a ``gpo.features.HistogramStage``) as bars over ``label``, the values' unit
    (degrees for the orientation, pixels for the length), with lines at its mean mu and at mu +- sigma and that band
    shaded; the filter keeps a band never narrower than the keypoints' localisation, so it may keep a little more.
    An empty histogram (mean NaN) is drawn without the lines."""
    if ax is None:
        _, ax = plt.subplots(figsize=(6, 3.5))
    ax.stairs(stage.counts, stage.edges, fill=True, color="tab:blue")
    if np.isfinite(stage.mean):
        mean, sigma = stage.mean, stage.sigma
        ax.axvspan(mean - sigma, mean + sigma, color="tab:green", alpha=0.15)
        ax.axvline(mean, color="tab:green", lw=1.2, label=f"mu = {mean:.2f}")
        ax.axvline(mean - sigma, color="tab:green", lw=0.8, ls="--", label=f"mu +- sigma, sigma = {sigma:.2f}")
        ax.axvline(mean + sigma, color="tab:green", lw=0.8, ls="--")
        ax.legend(loc="upper right", fontsize="small")
    ax.set_xlabel(label)
    ax.set_ylabel("matches")
    ax.set_title(f"{int(stage.kept.sum())} of {len(stage.values)} kept")
    return ax


def draw_invariance_loops(image, matches, ax=None, max_loops: int = 60) -> plt.Axes:
    """The loops of the invariance check (the second paper's Algorithm 1, its Figs. 7-8) of a
    ``gpo.features.FeatureMatches`` on the previous grey frame (H, W): each a closed polygon through its matches'
    start points, pixels of the full image, kept loops green and rejected ones red, at most ``max_loops`` of each
    (the first tried). When the check did not run, only the frame."""
    ax = _frame(image, ax)
    check = matches.invariance
    if check is None:
        ax.set_title("the invariance check did not run")
        return ax
    start = matches.matched[0][np.flatnonzero(matches.histogram_kept)]  # the check's input, which its loops index
    loops = np.array(check.loops, dtype=int).reshape(-1, check.cardinality)
    for kept, colour, name in ((True, "tab:green", "kept"), (False, "tab:red", "rejected")):
        shown = loops[check.kept_loops == kept][:max_loops]
        polygons = PolyCollection(start[shown], closed=True, facecolors="none", edgecolors=colour, lw=0.8)
        polygons.set_label(f"{len(shown)} {name} loops shown")
        ax.add_collection(polygons)
    ax.legend(loc="lower right", fontsize="small", framealpha=0.8)
    ax.set_title(f"{int(check.kept_loops.sum())} of {len(loops)} loops kept, C = {check.cardinality}")
    return ax


def draw_sweep(table, parameter: str | None, ax=None, metric: str = "final_error_percent") -> plt.Axes:
    """A sweep's ``metric`` (a column of ``gpo.batch``'s table; default the final position error, % of the distance)
    against ``parameter`` (a ``param.`` column; None: against the recording): thin lines one per recording, the
    thick black line the median over every recording. Where other parameters vary too, each point is the median over
    them. Runs that failed are left out and counted in the title."""
    if ax is None:
        _, ax = plt.subplots(figsize=(6.5, 4))
    good = table[table["status"] != "failed"]
    failed = len(table) - len(good)
    if parameter is None:
        per_recording = good.groupby("recording")[metric].median()
        ax.bar(per_recording.index.astype(str), per_recording.to_numpy(), color="tab:blue")
        ax.set_xlabel("recording")
        ax.tick_params(axis="x", labelrotation=30)
    else:
        values = sorted(good[parameter].dropna().unique(), key=lambda v: (isinstance(v, str), v))
        numeric = all(isinstance(v, (int, float, np.number)) and not isinstance(v, bool) for v in values)
        position = {v: (float(v) if numeric else i) for i, v in enumerate(values)}
        for recording, runs in good.groupby("recording"):
            medians = runs.groupby(parameter)[metric].median()
            ax.plot([position[v] for v in medians.index], medians.to_numpy(), marker="o", lw=1, alpha=0.7,
                    label=str(recording))
        overall = good.groupby(parameter)[metric].median()
        ax.plot([position[v] for v in overall.index], overall.to_numpy(), color="k", lw=2.5, marker="s",
                label="median of all")
        if not numeric:
            ax.set_xticks(list(position.values()), [str(v) for v in values])
        ax.set_xlabel(parameter.removeprefix("param."))
        ax.legend(fontsize="small")
    ax.set_ylabel("final position error [% of distance]" if metric == "final_error_percent" else metric)
    runs_text = f"{len(good)} runs" + (f", {failed} failed (not shown)" if failed else "")
    ax.set_title(runs_text, fontsize="small")
HISTOGRAM_FATES = {  # which histogram dropped a match -> its colour
    "dropped by the orientation band": "tab:red",
    "dropped by the length band": "tab:orange",
    "kept by both bands": "tab:green",
}


def draw_histogram_decisions(image, matches, ax=None, scale: float = 5.0, centre_px=None) -> plt.Axes:
    """The histogram filter's decisions (the second paper's mu +- sigma bands) on the grey frame (H, W): each match
    vector of a ``gpo.features.FeatureMatches`` drawn from its start, ``scale`` times its length, coloured by
    ``HISTOGRAM_FATES``. ``centre_px`` (u, v), pixels: the centre of the frame pair's rotation, marked with a cross,
    or when outside the frame, an arrow from the frame's centre towards it. When the filter did not run, only the
    frame."""
    ax = _frame(image, ax)
    if matches.histogram is None:
        ax.set_title("the histogram filter did not run")
        return ax
    start, end = matches.matched
    orientation, length = matches.histogram
    by_length = length.kept if length is not None else np.zeros(len(start), bool)
    fates = {
        "dropped by the orientation band": ~orientation.kept,
        "dropped by the length band": orientation.kept & ~by_length,
        "kept by both bands": by_length,
    }
    for fate, chosen in fates.items():
        tips = start[chosen] + scale * (end[chosen] - start[chosen])
        lines = LineCollection(np.stack([start[chosen], tips], axis=1), colors=HISTOGRAM_FATES[fate], lw=1.2)
        lines.set_label(f"{chosen.sum()} {fate}")
        ax.add_collection(lines)
        ax.plot(*tips.T, ".", ms=3, color=HISTOGRAM_FATES[fate])
    if centre_px is not None:
        height, width = image.shape
        centre = np.asarray(centre_px, dtype=float)
        if 0 <= centre[0] < width and 0 <= centre[1] < height:
            ax.plot(*centre, "x", ms=12, mew=2.5, color="tab:blue", label="centre of rotation")
        else:
            middle = np.array([width / 2, height / 2])
            towards = (centre - middle) / np.linalg.norm(centre - middle) * 0.3 * min(width, height)
            ax.annotate(
                "", xy=middle + towards, xytext=middle, arrowprops={"arrowstyle": "->", "color": "tab:blue", "lw": 2}
            )
            away = np.hypot(*(centre - middle))
            ax.plot([], [], color="tab:blue", lw=2, label=f"towards the centre of rotation, {away:.0f} px away")
    ax.legend(loc="lower right", fontsize="small", framealpha=0.8)
    ax.set_title(f"the match vectors, {scale:g} times their length")
    return ax
