"""Floor runs the chapters share, kept on disk: a floor method's config on a route, a floor run computed once and read
back, and the tracking camera with a drift of one's choosing.

A floor run (``floor_run``) takes a few seconds a path; each is kept in the cache's ``runs`` folder (``gpo.io.cache``),
keyed by the recording, the whole config and the source of every module a run goes through (``RUN_MODULES``), so
that ``python -m gpo table4`` computes them once and chapters 07-09 read them back.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

import gpo
import gpo.io.cache
from gpo.io.fingerprint import sources
from gpo.io.trajectory import Trajectory, base_from_sensor_odometry
from gpo.pipeline.config import OdometryConfig, config_to_dict, load_config
from gpo.pipeline.run import FloorRun, run
from gpo.sim.drift import TrackingDrift, tracking_odometry
from gpo.sim.paths import named_plan
from gpo.sim.record import FLOOR_BOARDS, START_NS, floor_board_path
from gpo.sim.rigs import RIGS

RUN_MODULES = ("gpo.pipeline.run", "gpo.sim.record")
"""What a kept floor run goes through (the odometry, and the simulator that drew the floor board's image): a change in
any module they import makes the kept runs stale (``gpo.io.fingerprint.sources``)."""

ROUTE_NAMES = {"gpi": "GPI", "ortho-gpi": "ortho-GPI", "analytic": "analytic"}
"""Each route's floor image as the book names it: the plain ground plane image and the ortho-rectified one, both
calibrated on a floor board (chapters 03-04), and the analytic table from the calibration and the mount alone."""


def drifted_tracking(path: str, drift: TrackingDrift, seed: int) -> Trajectory:
    """The fisheye rig's tracking camera along the named ``path`` with ``drift`` seeded by ``seed``, stamped as the
    recordings are and turned into base_link through the rig's mount: a new drift without a new rendering."""
    mount = RIGS["t265"]().mount
    odometry = tracking_odometry(named_plan(path), mount, 200.0, drift, seed, START_NS)
    start = (Rotation.identity(), np.zeros(3))
    return base_from_sensor_odometry(odometry, (mount.body_rotation, mount.position), start)


def route_config(method: str, route: str, base: OdometryConfig | None = None) -> OdometryConfig:
    """``base`` (default: the shipped config) with ``method`` on the floor image of ``route``; the chessboard routes
    calibrated on the simulated T265 rig's view of its floor board (``gpo.sim.record.floor_board_path``)."""
    base = base or load_config()
    if route == "analytic":
        return base.replace(method=method, route=route)
    return base.replace(method=method, route=route, board_image=floor_board_path("t265"), board=FLOOR_BOARDS["t265"])


def floor_run(bag, config: OdometryConfig, cache: bool = True) -> FloorRun:
    """The ``FloorRun`` of ``gpo.pipeline.run`` of ``bag`` with ``config`` (a floor method), read from the disk cache
    when kept, else run and kept there (on a full disk, returned without being kept)."""
    path = _run_path(Path(bag), config)
    if cache and gpo.io.cache.intact(path):
        with np.load(path) as kept:
            poses = kept["poses"]
            trajectory = Trajectory.from_planar(kept["stamps_ns"], *poses.T, frame_id="odom")
            spread = kept["spread_px"] if "spread_px" in kept.files else None  # kept before spreads were
            return FloorRun(trajectory, kept["inliers"], float(kept["frames_per_second"]), spread)
    result = run(bag, config, progress=False)
    if result.error:
        raise ValueError(f"{bag}: the floor run stopped early, {result.error}")
    done = result.floor_run
    if cache:
        planar = np.column_stack([done.trajectory.positions[:, :2], done.trajectory.yaw])
        arrays = {
            "stamps_ns": done.trajectory.stamps_ns,
            "poses": planar,
            "inliers": done.inliers,
            "frames_per_second": done.frames_per_second,
            "spread_px": done.spread_px,
        }
        gpo.io.cache.keep(path, lambda partial: np.savez(partial, **arrays))
    return done


def _run_path(bag: Path, config: OdometryConfig) -> Path:
    document = config_to_dict(config)
    document.get("floor_image", {}).pop("board_image", None)  # the image's content is fixed by the sources below
    key = gpo.io.cache.key(bag.name, document, sources=sources(*RUN_MODULES))
    return gpo.io.cache.path("runs", f"{bag.stem}-{config.method}-{config.route}", key, ".npz")
