"""The first paper's Table 1 on the simulated T265 rig: is the ortho-rectified ground image metric?

A 2 x 4-square block (40 x 80 mm) of a chessboard of 20.0 mm squares lying on the floor is measured
in the plain GPI, in the ortho-rectified GPI and, as the measurement's own floor, in the analytic
route's image with the rig's true mount. The tables are built once, on one frame of
``FLOOR_BOARDS["t265"]``; the board is then rendered at many other placements and measured with
``gpo.ground.measure_block`` in the images the fixed tables make of each frame.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from gpo.ground import BLOCK_SQUARES, BlockMeasurement, FloorImage, analytic_table, chessboard_route, measure_block
from gpo.sim.floors import make_floor
from gpo.sim.record import FLOOR_BOARDS, TEXEL_M
from gpo.sim.render import FloorRenderer
from gpo.sim.rigs import t265_rig

TABLE1_EXTENT = ((0.70, 0.94), (-0.10, 0.10))
"""The ortho-GPI of Table 1, (x_range, y_range) metres in base_link: room for the board at each placement."""
TABLE1_SHIFTS = ((-0.015, 0.012), (-0.015, 0.015), (-5.0, 5.0))
"""Ranges of the board's placements measured: dx, dy (m) and yaw (degrees) from ``FLOOR_BOARDS["t265"]``."""
ROOM_FLOOR_M = (-1.0, 2.0, -1.5, 1.5)  # the floor rendered around the robot for Table 1, (x_min, x_max, y_min, y_max)


def table1_placements(count: int = 24, seed: int = 1) -> list[tuple[float, float, float]]:
    """``count`` placements (dx m, dy m, yaw degrees) of the board, uniform in ``TABLE1_SHIFTS``, seeded."""
    rng = np.random.default_rng(seed)
    return [tuple(float(rng.uniform(*limits)) for limits in TABLE1_SHIFTS) for _ in range(count)]


@dataclass(frozen=True)
class Table1Row:
    """One image's line of Table 1: the means over the placements of (a + c) / 2, (b + d) / 2 (mm) and the area
    S (mm^2), their errors against the truth (40 mm, 80 mm, 3200 mm^2 for 20 mm squares), and the RMS error of a
    single placement's sides (both kinds together) and area."""

    image: str
    short_mm: float
    long_mm: float
    area_mm2: float
    short_error_mm: float
    long_error_mm: float
    area_error_mm2: float
    single_side_rms_mm: float
    single_area_rms_mm2: float


def reproduce_table1(
    metres_per_pixel: float = 1e-3, placements=None, seed: int = 0, cache: bool = True
) -> tuple[Table1Row, Table1Row, Table1Row]:
    """The paper's Table 1 on the simulated T265 rig: a 2 x 4-square block (40 x 80 mm) measured in the GPI, the
    ortho-GPI and, as the measurement's own floor, the analytic route's image with the rig's true mount.

    The chessboard route is calibrated (``chessboard_route``) on one frame of ``FLOOR_BOARDS["t265"]``; the board
    is then rendered at each of ``placements`` (default ``table1_placements()``; other places, other noise) and
    its centre block measured (``measure_block``) in the images the fixed tables make of that frame. The
    ortho-GPI covers ``TABLE1_EXTENT`` at ``metres_per_pixel``: 1 mm, where the 20 mm squares are 20 pixels
    wide. Finer grids only magnify the fisheye's blur (about 1 mm across the view, 2 mm along it here) and the
    corners are found less well; a single placement's sides scatter by a few hundredths of a millimetre
    whatever the table (see the analytic row), so the table reports means over many placements.
    """
    rig, calibration_board = t265_rig(), FLOOR_BOARDS["t265"]
    renderer = FloorRenderer(rig, make_floor("raised", ROOM_FLOOR_M, TEXEL_M["t265"], seed))
    frame = renderer.render(np.zeros(3), frame_seed=seed, boards=(calibration_board,))
    floor = FloorImage.top_view(*TABLE1_EXTENT, metres_per_pixel)
    ortho = chessboard_route(frame, rig.camera, calibration_board, floor, cache=cache)
    tables = {
        "GPI": ortho.gpi.table,
        "ortho-GPI": ortho.table,
        "analytic": analytic_table(rig.camera, rig.mount, floor, cache=cache),
    }
    measured = {name: [] for name in tables}
    for index, (dx, dy, yaw_deg) in enumerate(table1_placements() if placements is None else placements, start=1):
        board = dataclasses.replace(
            calibration_board, x=calibration_board.x + dx, y=calibration_board.y + dy, yaw=math.radians(yaw_deg)
        )
        frame = renderer.render(np.zeros(3), frame_seed=seed + index, boards=(board,))
        for name, table in tables.items():
            measured[name].append(measure_block(table.apply(frame), table.floor, board))
    square = calibration_board.board.square
    return tuple(_table1_row(name, blocks, square) for name, blocks in measured.items())


def _table1_row(name: str, blocks: list[BlockMeasurement], square: float) -> Table1Row:
    short_true, long_true = BLOCK_SQUARES[1] * square * 1e3, BLOCK_SQUARES[0] * square * 1e3
    short = np.array([block.short_m for block in blocks]) * 1e3
    long = np.array([block.long_m for block in blocks]) * 1e3
    area = np.array([block.area_m2 for block in blocks]) * 1e6
    area_true = short_true * long_true
    side_errors = np.concatenate([short - short_true, long - long_true])
    return Table1Row(
        name,
        float(short.mean()),
        float(long.mean()),
        float(area.mean()),
        float(short.mean() - short_true),
        float(long.mean() - long_true),
        float(area.mean() - area_true),
        float(np.sqrt(np.mean(side_errors**2))),
        float(np.sqrt(np.mean((area - area_true) ** 2))),
    )


def format_table1(rows) -> str:
    """Table 1 as rounded text: the means of (a+c)/2, (b+d)/2 and S with their errors, and a single placement's
    RMS errors."""
    lines = [
        f"{'image':<10}{'(a+c)/2 mm':>11}{'error':>8}{'(b+d)/2 mm':>12}{'error':>8}{'S mm^2':>9}{'error':>8}"
        f"{'single: side rms':>18}{'S rms':>7}"
    ]
    for row in rows:
        lines.append(
            f"{row.image:<10}{row.short_mm:>11.3f}{row.short_error_mm:>+8.3f}{row.long_mm:>12.3f}"
            f"{row.long_error_mm:>+8.3f}{row.area_mm2:>9.1f}{row.area_error_mm2:>+8.2f}"
            f"{row.single_side_rms_mm:>18.3f}{row.single_area_rms_mm2:>7.2f}"
        )
    return "\n".join(lines)
