"""Chapter 06, the bicycle model: its drawing, eq. 30's heading rate against the exact one, the paper's model and
the exact motion under constant steering, and the model's panel."""

from __future__ import annotations

import math

import ipywidgets as widgets
import matplotlib.pyplot as plt
import numpy as np

from gpo.book.panels import slider
from gpo.odometry.kinematics import (
    PaperBicycle,
    arc_increment,
    between,
    exact_velocities,
    integrate,
    paper_heading_rate_ratio,
)


def draw_heading_rate_ratio(wheelbase_m: float, rear_to_reference_m, ax=None, max_steering_deg: float = 60.0):
    """Eq. (30)'s heading rate over the true one (``gpo.odometry.kinematics.paper_heading_rate_ratio``) against the
    steering angle, one curve per reference point l_r in ``rear_to_reference_m`` (metres, a number or a sequence)."""
    from gpo.odometry.kinematics import paper_heading_rate_ratio

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


def constant_steering_paths(
    wheelbase_m: float,
    rear_to_reference_m: float,
    speed_mps: float,
    steering_rad: float,
    duration_s: float,
    rate_hz: float = 30.0,
) -> tuple[np.ndarray, np.ndarray]:
    """base_link's poses (N + 1, 3) over ``duration_s`` of a drive whose virtual front wheel (L ahead of the rear
    axle) moves at ``speed_mps`` in the constant direction ``steering_rad`` in base_link: the exact motion (circular
    arcs, ``gpo.odometry.kinematics.exact_velocities`` and ``arc_increment``) and what the first paper's model
    (``PaperBicycle(wheelbase_m, rear_to_reference_m)``, eqs. 25-34) makes of it, fed each frame (``rate_hz``) with
    the front wheel's displacement as the floor image shows it."""
    dt = 1.0 / rate_hz
    frames = max(1, round(duration_s * rate_hz))
    v, omega = exact_velocities(speed_mps, steering_rad, wheelbase_m)
    increment = arc_increment(v, omega, dt)
    exact = integrate(np.tile(increment, (frames, 1)))
    seen_at = between(increment, [wheelbase_m, 0.0, 0.0])[:2]  # the floor point under the wheel, at the frame's end
    displacement = np.array([wheelbase_m, 0.0]) - seen_at
    model = PaperBicycle(wheelbase_m, rear_to_reference_m)
    paper = [np.zeros(3)]
    for _ in range(frames):
        paper.append(model.step(paper[-1], displacement, dt))
    return exact, np.array(paper)


def bicycle_panel(wheelbase_m: float = 0.8, rear_to_reference_m: float = 0.8, rate_hz: float = 30.0) -> widgets.VBox:
    """The first paper's bicycle model against the exact kinematics: the wheelbase L, the reference point l_r, a
    constant steering angle delta, the front wheel's speed V and how long it drives.

    Left: eq. 30's heading rate over the true one against delta for this L and l_r (``draw_heading_rate_ratio``),
    the chosen delta marked. Right: the path of base_link under constant steering, exact and as the paper's model
    integrates it frame by frame at ``rate_hz`` (``constant_steering_paths``). One line says how far apart they end.
    """
    style = {"description_width": "initial"}
    length = slider("L [m]", wheelbase_m, 0.2, 2.0, 0.05)
    lever = slider("l_r [m]", rear_to_reference_m, 0.0, wheelbase_m, 0.01)
    controls = {
        "wheelbase_m": length,
        "rear_to_reference_m": lever,
        "steering_deg": slider("delta [deg]", 20.0, 0.0, 60.0, 1.0),
        "speed_mps": slider("V [m/s]", 0.5, 0.05, 2.0, 0.05),
        "duration_s": slider("time [s]", 5.0, 0.5, 20.0, 0.5),
    }
    for control in controls.values():
        control.style = style
    controls["steering_deg"].readout_format = ".0f"

    def follow_wheelbase(change) -> None:  # l_r lies between the rear axle and the front wheel
        lever.max = change["new"]

    length.observe(follow_wheelbase, names="value")  # before interactive_output's own observer: l_r is clamped first

    def redraw(wheelbase_m, rear_to_reference_m, steering_deg, speed_mps, duration_s) -> None:
        rear_to_reference_m = min(rear_to_reference_m, wheelbase_m)
        steering = math.radians(steering_deg)
        exact, paper = constant_steering_paths(
            wheelbase_m, rear_to_reference_m, speed_mps, steering, duration_s, rate_hz
        )
        ratio = float(paper_heading_rate_ratio(steering, wheelbase_m, rear_to_reference_m))
        plt.close("all")
        _, (left, right) = plt.subplots(1, 2, figsize=(12, 4.8), gridspec_kw={"width_ratios": [1, 1.1]})
        draw_heading_rate_ratio(wheelbase_m, rear_to_reference_m, ax=left)
        left.plot(steering_deg, ratio, "o", color="tab:red")
        left.set_title(f"L = {wheelbase_m:.2f} m, l_r = {rear_to_reference_m:.2f} m")
        for name, poses, line in (("exact", exact, "-"), ("the paper's model", paper, "--")):
            right.plot(poses[:, 0], poses[:, 1], line, label=name)
            right.plot(*poses[-1, :2], "o", color=right.lines[-1].get_color())
        right.plot(0.0, 0.0, "go", label="start")
        right.set_aspect("equal", adjustable="datalim")
        right.set_xlabel("x [m]")
        right.set_ylabel("y [m]")
        right.grid(True, alpha=0.3)
        right.legend(fontsize="small")
        right.set_title(f"base_link over {duration_s:.1f} s, delta = {steering_deg:.0f} deg, V = {speed_mps:.2f} m/s")
        apart = float(np.hypot(*(paper[-1, :2] - exact[-1, :2])))
        turned = math.degrees(paper[-1, 2] - exact[-1, 2])
        chord = -speed_mps * math.cos(steering) / rate_hz / (2.0 * wheelbase_m)
        print(
            f"eq. 30 turns {ratio:.3f}x as fast as the robot, eq. 26's chord {100 * chord:+.2f} % a frame at "
            f"{rate_hz:.0f} Hz; the paper's model ends {apart:.3f} m from the exact path, heading {turned:+.2f} deg"
        )
        plt.show()

    sliders = widgets.HBox(list(controls.values()), layout={"flex_flow": "row wrap"})
    return widgets.VBox([sliders, widgets.interactive_output(redraw, controls)])


def increments_table(increments: dict) -> str:
    """Planar increments (label -> (dx, dy, dtheta): metres, metres, radians) one a line, in millimetres and
    millidegrees."""
    names = ("dx [mm]", "dy [mm]", "dtheta [mdeg]")
    lines = [f"{'':20}" + "".join(f"{name:>15}" for name in names)]
    for label, increment in increments.items():
        values = 1e3 * np.array([increment[0], increment[1], np.degrees(increment[2])])
        lines.append(f"{label:20}" + "".join(f"{value:15.4f}" for value in values))
    return "\n".join(lines)


SPIN_RATE_HZ = 30.0  # the simulated spin's frame rate
_SPIN_PATCH_PX, _SPIN_PIXEL_M, _SPIN_AHEAD_M = 200, 1e-3, 0.8  # a 0.2 m floor image of 1 mm pixels, 0.8 m ahead
_SPIN_WORLD_PX, _SPIN_ORIGIN_PX = 1600, 200  # the floor's texture (1 mm texels), and where base_link starts in it


def spin_poses(frames: int = 30, blend: int = 10, turn_radps: float = 0.5, speed_mps: float = 0.36) -> np.ndarray:
    """base_link's poses (2 ``frames``, 3) at ``SPIN_RATE_HZ``: a turn on the spot at ``turn_radps``, then straight
    ahead at ``speed_mps``, the one blended into the other over ``blend`` frames (no jump in the floor's speed)."""
    from gpo.odometry.kinematics import compose

    poses, pose = [], np.zeros(3)
    for k in range(2 * frames):
        poses.append(pose)
        ahead = np.clip((k - frames + blend / 2) / blend, 0.0, 1.0)
        pose = compose(pose, [ahead * speed_mps / SPIN_RATE_HZ, 0.0, (1 - ahead) * turn_radps / SPIN_RATE_HZ])
    return np.array(poses)


def spin_images(camera_pixel_px: tuple[int, int], seed: int = 0) -> tuple[list[np.ndarray], np.ndarray]:
    """The floor images (200 x 200, 1 mm pixels, centred 0.8 m ahead of the rear axle) of a robot driving
    ``spin_poses()`` over a grainy floor, and those poses. Each image is made as a camera makes it: the floor sampled
    once per camera pixel, which covers ``camera_pixel_px`` (along the line of sight, across) floor-image pixels, with
    its own noise (3 grey levels, drawn from ``seed``), then resampled to the floor image's pixels. (1, 1) is a camera
    as fine as the floor image; the simulated T265 rig's pixels cover up to about (3, 1) at its patch's far edge."""
    import cv2

    rng = np.random.default_rng(seed)
    grain = cv2.GaussianBlur(
        np.random.default_rng(0).normal(0.0, 1.0, (_SPIN_WORLD_PX, _SPIN_WORLD_PX)).astype(np.float32), (0, 0), 3.0
    )
    floor = cv2.normalize(grain, None, 30, 220, cv2.NORM_MINMAX)
    rows, columns = _SPIN_PATCH_PX // camera_pixel_px[0], _SPIN_PATCH_PX // camera_pixel_px[1]
    v, u = np.meshgrid(
        (np.arange(rows) + 0.5) * _SPIN_PATCH_PX / rows - 0.5,
        (np.arange(columns) + 0.5) * _SPIN_PATCH_PX / columns - 0.5,
        indexing="ij",
    )
    x, y = spin_pixels_to_base(np.column_stack([u.ravel(), v.ravel()])).T.reshape(2, rows, columns)
    poses, images = spin_poses(), []
    for pose in poses:
        cos, sin = np.cos(pose[2]), np.sin(pose[2])
        world = [
            (pose[i] + a * x + b * y) / _SPIN_PIXEL_M + _SPIN_ORIGIN_PX for i, a, b in ((0, cos, -sin), (1, sin, cos))
        ]
        seen = cv2.remap(floor, *(w.astype(np.float32) for w in world), cv2.INTER_LINEAR)
        seen += rng.normal(0.0, 3.0, seen.shape).astype(np.float32)
        resampled = cv2.resize(seen, (_SPIN_PATCH_PX, _SPIN_PATCH_PX), interpolation=cv2.INTER_LINEAR)
        images.append(np.clip(resampled, 0, 255).astype(np.uint8))
    return images, poses


def spin_pixels_to_base(pixels) -> np.ndarray:
    """Pixels (N, 2) (u right, v down) of ``spin_images``' floor images to floor points (N, 2) in base_link, metres:
    the image's up is forward, its right the robot's right."""
    pixels = np.asarray(pixels, dtype=float)
    centre = _SPIN_PATCH_PX / 2
    return np.column_stack(
        [_SPIN_AHEAD_M + (centre - pixels[:, 1]) * _SPIN_PIXEL_M, (centre - pixels[:, 0]) * _SPIN_PIXEL_M]
    )
