"""The first paper's Table 4 on the simulated 12-17 m paths, and the second paper's Table 2 metrics of the same runs.

Rows (``ROWS``): the tracking camera's own odometry; GPO (the paper's bicycle model on the median vector) on the
plain GPI and on the ortho-rectified GPI; the EKF of GPO and the tracking camera on each; and beside the paper's
method, the exact arc (``gpo-exact``) and the rigid fit (``gpo-rigid``) on both images, the EKF of each on the
ortho-GPI, and the second paper's floor feature odometer (``features``) on the ortho-GPI.
Columns: the paths ``long1``-``long3`` (``PATHS``: a loop, S-curves with a U-turn, stop-and-go; 15.3-16.0 m) and
their mean. The first paper's number is its "translation error": the final position error after placing the first
pose on the truth (``gpo.metrics.translation_error``). The headline of its introduction, 0.058 m of "mean localization
error" for the EKF, is that error averaged over its three tests (its Table 4: 0.0579 m); ``Table4.format_mean`` prints
beside it the other reading of the words, the mean position error along each path.

Both chessboard routes are calibrated on one frame of ``FLOOR_BOARDS["t265"]``
(``gpo.experiments.runs.route_config``), as
chapter 04 does. Each floor run is kept on disk (``gpo.experiments.runs.floor_run``), so that ``python -m gpo table4``
computes them once and chapter 09 reads them back. The EKF runs on the kept floor run.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gpo.experiments.runs import floor_run, route_config
from gpo.fusion import fuse
from gpo.io.bag import Recording
from gpo.metrics import Evaluation, evaluate
from gpo.pipeline.config import OdometryConfig, load_config
from gpo.pipeline.run import tracking_path
from gpo.sim.record import GROUND_TRUTH_TOPIC, recording

PATHS = ("long1", "long2", "long3")
ROUTE_NAMES = {"gpi": "GPI", "ortho-gpi": "ortho-GPI", "analytic": "analytic"}


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
        """(rows, paths) the mean localization error along each path: the mean position error over the path (the
        APE's mean) after placing the first pose on the truth, metres. (The first paper's 0.058 m is its Table 4's
        average translation error; this is the other reading of its words.)"""
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


def format_fusion_accuracy(results: dict, outages_only: bool = False) -> str:
    """The fused row against its sources over many drifts of the tracking camera, as rounded text.

    ``results`` is what ``benchmarks/fusion_accuracy.py --write`` saves: per run the preset, the final errors (% of
    the distance) of the floor alone, the camera alone and the EKF; its summary, the worst against the targets
    (fused <= 1.1 x the better source, never more than 0.02 % above it; with floor outages, fused <= 0.3 %).
    ``outages_only``: the presets with floor outages alone.
    """
    runs = [run for run in results["runs"] if run["preset"].endswith("-outages") or not outages_only]
    lines = [f"{'[% of the distance]':<22}{'runs':>5}{'floor':>8}{'camera, median':>16}{'fused, median':>15}"
             f"{'worst':>8}"]
    for preset in dict.fromkeys(entry["preset"] for entry in runs):
        chosen = [run for run in runs if run["preset"] == preset]
        fused = [run["fused_final_percent"] for run in chosen]
        lines.append(f"{preset:<22}{len(chosen):5d}{np.median([run['floor_final_percent'] for run in chosen]):8.2f}"
                     f"{np.median([run['camera_final_percent'] for run in chosen]):16.2f}"
                     f"{np.median(fused):15.3f}{max(fused):8.3f}")
    summary = results["summary"]
    if not outages_only:
        lines.append(f"where both sources work, fused <= 1.1 x the better source in {summary['runs_within']} runs "
                     f"(worst {summary['worst_ratio']:.3f} x, at most {summary['worst_excess_percent']:.4f} % above "
                     "it; targets 1.1 x and 0.02 %)")
    outages = [run["fused_final_percent"] for run in results["runs"] if run["preset"].endswith("-outages")]
    lines.append(f"with floor outages, fused at most {max(outages):.3f} % (target 0.3 %: met in "
                 f"{sum(value <= 0.3 for value in outages)} of {len(outages)} runs)")
    return "\n".join(lines)
