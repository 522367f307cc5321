"""Figures more than one chapter draws, and the command line's: paths seen from above (alone, or placed on the
truth), a floor image where it lies in base_link, a sweep's errors."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.transforms import Affine2D


def draw_paths(paths: dict, ax=None, styles: dict | None = None) -> plt.Axes:
    """Top view of trajectories (label -> ``gpo.io.trajectory.Trajectory``), x and y in metres, with the start
    marked."""
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


def draw_placed_paths(placed: dict, truth, ax=None, styles: dict | None = None, truth_end: bool = False) -> plt.Axes:
    """Top view of paths already placed on ``truth`` (label -> (N, 2) x, y metres) over it: the truth a wide grey
    line, the start and each path's end (a dot) marked, and with ``truth_end`` the truth's end (a cross)."""
    if ax is None:
        _, ax = plt.subplots(figsize=(7, 5))
    styles = styles or {}
    ax.plot(*truth.positions[:, :2].T, color="k", lw=5, alpha=0.2, label="truth")
    for label, positions in placed.items():
        (line,) = ax.plot(*positions.T, label=label, **{"lw": 1.2, **styles.get(label, {})})
        ax.plot(*positions[-1], "o", color=line.get_color(), ms=4)
    ax.plot(*truth.positions[0, :2], "go", label="start")
    if truth_end:
        ax.plot(*truth.positions[-1, :2], "kx", ms=9, mew=2, label="end (truth)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize="small")
    return ax


def draw_floor_image(image, floor, ax=None, mount=None, axes_length: float = 0.1) -> plt.Axes:
    """A floor image (``gpo.floor_image.image.FloorImage`` ``floor``) drawn where it lies in ``base_link``, seen from
    above.

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
    return ax
