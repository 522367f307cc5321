"""The first paper's Table 4 on the simulated 12-17 m paths, and the second paper's Table 2 metrics of the same runs.

Rows (``ROWS``): the tracking camera's own odometry; GPO (the paper's bicycle model on the median vector) on the
plain GPI and on the ortho-rectified GPI; the EKF of GPO and the tracking camera on each; and beside the paper's
method, the exact arc (``gpo-exact``) and the rigid fit (``gpo-rigid``) on both images, the EKF of each on the
ortho-GPI, and the second paper's floor feature odometer (``features``) on the ortho-GPI.
Columns: the paths ``long1``-``long3`` (``PATHS``: a loop, S-curves with a U-turn, stop-and-go; 15.3-16.0 m) and
their mean. The first paper's number is its "translation error": the final position error after placing the first
pose on the truth (``gpo.metrics.translation_error``); its abstract's headline (0.058 m) is the *mean* localization
error over each test, averaged (``Table4.format_mean``).

Both chessboard routes are calibrated on one frame of ``FLOOR_BOARDS["t265"]`` (``board_image_path``), as chapter 04
does. A floor run (``floor_run``) takes a few seconds a path; each is kept in the cache's ``runs`` folder
(``gpo.cache``), keyed by the recording, the whole config and the source of every module a run goes through, so that
``python -m gpo table4`` computes them once and chapter 09 reads them back. The EKF runs on the kept floor run.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
from scipy.spatial.transform import Rotation

import gpo
import gpo.cache
from gpo.bag import Recording
from gpo.fusion import fuse
from gpo.metrics import Evaluation, evaluate
from gpo.pipeline import OdometryConfig, config_to_dict, load_config, run, tracking_path
from gpo.sim.motion import TrackingDrift, named_plan, tracking_odometry
from gpo.sim.record import (
    FLOOR_BOARDS,
    GROUND_TRUTH_TOPIC,
    START_NS,
    fingerprint_sources,
    floor_board_image,
    recording,
)
from gpo.sim.rigs import RIGS
from gpo.trajectory import Trajectory, base_from_sensor_odometry

PATHS = ("long1", "long2", "long3")
ROUTE_NAMES = {"gpi": "GPI", "ortho-gpi": "ortho-GPI", "analytic": "analytic"}
# the modules a floor run goes through: a change in any of them makes the kept runs stale
RUN_MODULES = (
    "bag.py", "camera.py", "cubemap.py", "features.py", "flow.py", "ground.py", "kinematics.py", "pipeline.py",
)


@dataclass(frozen=True)
class Row:
    """One row of the table: ``source`` camera (the tracking camera alone), floor (``method`` on the floor image of
    ``route``) or fused (the EKF of that floor odometry and the tracking camera)."""

    source: str
    method: str | None = None
    route: str | None = None

    @property
    def label(self) -> str:
        if self.source == "camera":
            return "tracking camera (T265)"
        name = {"gpo": "GPO", "gpo-exact": "GPO-exact", "gpo-rigid": "GPO-rigid", "features": "features"}[self.method]
        name = f"EKF ({name} + T265)" if self.source == "fused" else name
        return f"{name}, {ROUTE_NAMES[self.route]}"


ROWS = (
    Row("camera"),
    Row("floor", "gpo", "gpi"),
    Row("floor", "gpo", "ortho-gpi"),
    Row("fused", "gpo", "gpi"),
    Row("fused", "gpo", "ortho-gpi"),
    Row("floor", "gpo-exact", "gpi"),
    Row("floor", "gpo-exact", "ortho-gpi"),
    Row("floor", "gpo-rigid", "gpi"),
    Row("floor", "gpo-rigid", "ortho-gpi"),
    Row("fused", "gpo-exact", "ortho-gpi"),
    Row("fused", "gpo-rigid", "ortho-gpi"),
    Row("floor", "gpo-exact", "analytic"),
    Row("floor", "gpo-rigid", "analytic"),
    Row("floor", "features", "ortho-gpi"),
)


@dataclass(frozen=True)
class FloorRun:
    """A floor run's path of base_link (``trajectory``), the flow's inlier tracks behind each step (0 where the
    step was coasted, held or first), its speed, frames per second, and the inliers' spread (pixels, NaN where
    unknown) behind each step."""

    trajectory: Trajectory
    inliers: np.ndarray
    frames_per_second: float
    spread_px: np.ndarray | None = None


def drifted_tracking(path: str, drift: TrackingDrift, seed: int) -> Trajectory:
    """The fisheye rig's tracking camera along the named ``path`` with ``drift`` seeded by ``seed``, stamped as the
    recordings are and turned into base_link through the rig's mount: a new drift without a new rendering."""
    mount = RIGS["t265"]().mount
    odometry = tracking_odometry(named_plan(path), mount, 200.0, drift, seed, START_NS)
    start = (Rotation.identity(), np.zeros(3))
    return base_from_sensor_odometry(odometry, (mount.body_rotation, mount.position), start)


def board_image_path() -> Path:
    """A PNG of the simulated T265 rig's view of ``FLOOR_BOARDS["t265"]`` (written into the cache on first use, keyed
    by the simulator's sources like the recordings)."""
    path = gpo.cache.path("recordings", "floor_board_t265", gpo.cache.key(sources=fingerprint_sources()), ".png")
    if not path.exists():
        gpo.cache.write(path, lambda partial: cv2.imwrite(str(partial), floor_board_image("t265")))
    return path


def route_config(method: str, route: str, base: OdometryConfig | None = None) -> OdometryConfig:
    """``base`` (default: the shipped config) with ``method`` on the floor image of ``route``; the chessboard routes
    calibrated on ``board_image_path()``."""
    base = base or load_config()
    if route == "analytic":
        return base.replace(method=method, route=route)
    return base.replace(method=method, route=route, board_image=board_image_path(), board=FLOOR_BOARDS["t265"])


def floor_run(bag, config: OdometryConfig, cache: bool = True) -> FloorRun:
    """``gpo.pipeline.run`` of ``bag`` with ``config`` (a floor method), read from the disk cache when kept."""
    path = _run_path(Path(bag), config)
    if cache and path.exists():
        with np.load(path) as kept:
            poses = kept["poses"]
            trajectory = Trajectory.from_planar(kept["stamps_ns"], *poses.T, frame_id="odom")
            spread = kept["spread_px"] if "spread_px" in kept.files else None  # kept before spreads were
            return FloorRun(trajectory, kept["inliers"], float(kept["frames_per_second"]), spread)
    result = run(bag, config, progress=False)
    if result.error:
        raise ValueError(f"{bag}: the floor run stopped early, {result.error}")
    kept = [r for r in result.records if r.status != "skipped"]
    done = FloorRun(
        result.floor_trajectory,
        np.array([r.inliers if r.status == "measured" else 0 for r in kept]),
        result.frames_per_second,
        np.array([r.spread_px for r in kept]),
    )
    if cache:
        planar = np.column_stack([done.trajectory.positions[:, :2], done.trajectory.yaw])
        arrays = {
            "stamps_ns": done.trajectory.stamps_ns,
            "poses": planar,
            "inliers": done.inliers,
            "frames_per_second": done.frames_per_second,
            "spread_px": done.spread_px,
        }
        gpo.cache.write(path, lambda partial: np.savez(partial, **arrays))
    return done


def _run_path(bag: Path, config: OdometryConfig) -> Path:
    document = config_to_dict(config)
    document.get("floor_image", {}).pop("board_image", None)  # the image's content is fixed by the sources below
    package = Path(gpo.__file__).parent
    sources = [*(package / module for module in RUN_MODULES), package / "sim" / "record.py"]  # record: the board
    key = gpo.cache.key(bag.name, document, sources=sources)
    return gpo.cache.path("runs", f"{bag.stem}-{config.method}-{config.route}", key, ".npz")


@dataclass(frozen=True)
class Table4:
    """Every row's ``Evaluation`` (first pose on the truth) on every path: ``evaluations[row][path]``."""

    rows: tuple[Row, ...]
    paths: tuple[str, ...]
    evaluations: dict[Row, dict[str, Evaluation]]
    frames_per_second: dict[Row, float]

    def translation_errors_m(self) -> np.ndarray:
        """(rows, paths) the first paper's translation error, metres."""
        return np.array([[self.evaluations[row][path].final.position_m for path in self.paths] for row in self.rows])

    def mean_errors_m(self) -> np.ndarray:
        """(rows, paths) the first paper's headline measure, the mean localization error: the mean position error
        over the path (the APE's mean) after placing the first pose on the truth, metres."""
        return np.array([[float(self.evaluations[row][path].ape_m.mean) for path in self.paths] for row in self.rows])

    def format_mean(self) -> str:
        """The mean localization error per path and averaged, with the final (translation) error's mean beside it."""
        means, finals = self.mean_errors_m(), self.translation_errors_m()
        header = f"{'mean localization error [m]':<38}" + "".join(f"{path:>9}" for path in self.paths)
        lines = [header + f"{'mean':>9}{'final, mean':>13}"]
        for row, values, final in zip(self.rows, means, finals, strict=True):
            cells = "".join(f"{value:9.3f}" for value in values)
            lines.append(f"{row.label:<38}{cells}{values.mean():9.3f}{final.mean():13.3f}")
        return "\n".join(lines)

    def percent(self) -> np.ndarray:
        """(rows, paths) the same in % of the distance travelled."""
        return np.array([[self.evaluations[row][path].final.percent for path in self.paths] for row in self.rows])

    def format(self) -> str:
        """The paper's Table 4 layout: translation error in metres per path and its mean, with % beside it."""
        errors, percent = self.translation_errors_m(), self.percent()
        distances = [self.evaluations[self.rows[0]][path].final.distance_m for path in self.paths]
        header = f"{'translation error [m] (% of distance)':<38}"
        header += (
            "".join(f"{f'{path} ({d:.1f} m)':>17}" for path, d in zip(self.paths, distances, strict=True))
            + f"{'mean':>17}"
        )
        lines = [header]
        for row, metres, share in zip(self.rows, errors, percent, strict=True):
            cells = [*zip(metres, share, strict=True), (metres.mean(), share.mean())]
            lines.append(f"{row.label:<38}" + "".join(f"{m:>8.3f} ({p:5.2f} %)" for m, p in cells))
        return "\n".join(lines)

    def format_table2(self) -> str:
        """The second paper's Table 2 metrics of every row, averaged over the paths."""
        names = ("positioning_rmse_m", "heading_rmse_deg", "final_error_mm", "final_error_percent")
        names += ("relative_error_percent",)
        header = f"{'mean over ' + ', '.join(self.paths):<38}{'pos. RMSE':>11}{'head. RMSE':>12}"
        header += f"{'final':>10}{'final':>9}{'relative':>10}"
        units = f"{'':<38}{'[m]':>11}{'[deg]':>12}{'[mm]':>10}{'[%]':>9}{'[%]':>10}"
        lines = [header, units]
        for row in self.rows:
            metrics = [self.evaluations[row][path].table2() for path in self.paths]
            mean = {name: float(np.mean([m[name] for m in metrics])) for name in names}
            lines.append(
                f"{row.label:<38}{mean['positioning_rmse_m']:>11.3f}{mean['heading_rmse_deg']:>12.2f}"
                f"{mean['final_error_mm']:>10.1f}{mean['final_error_percent']:>9.3f}"
                f"{mean['relative_error_percent']:>10.3f}"
            )
        return "\n".join(lines)


def reproduce_table4(paths=PATHS, rows=ROWS, base: OdometryConfig | None = None, cache: bool = True) -> Table4:
    """Every row of ``rows`` on every preset of ``paths`` (rendered on first use), evaluated against the truth."""
    base = base or load_config()
    evaluations = {row: {} for row in rows}
    speeds = {row: [] for row in rows}
    for path in paths:
        bag = recording(path, progress=False)
        with Recording(bag) as recorded:
            truth = recorded.trajectory(GROUND_TRUTH_TOPIC)
            tracking = tracking_path(recorded, base.fusion)
        for row in rows:
            if row.source == "camera":
                estimate = tracking
            else:
                floor = floor_run(bag, route_config(row.method, row.route, base), cache)
                speeds[row].append(floor.frames_per_second)
                estimate = floor.trajectory
                if row.source == "fused":
                    estimate = fuse(floor.trajectory, floor.inliers, tracking, base.fusion, floor.spread_px).trajectory
            evaluations[row][path] = evaluate(estimate, truth)
    rates = {row: float(np.mean(values)) if values else float("nan") for row, values in speeds.items()}
    return Table4(tuple(rows), tuple(paths), evaluations, rates)
