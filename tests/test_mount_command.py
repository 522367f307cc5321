"""``python -m gpo mount`` on the simulator's floor boards, against the rigs' true mounts; and its bad input.

The truth is each rig's mount as ``gpo.sim.rigs`` sets it and the board's place as ``FLOOR_BOARDS`` sets it; the
image is the renderer's, the calibration the rig's own camera written as a Kalibr camchain.
"""

import cv2
import numpy as np
import pytest

from gpo.cameras.files import save_kalibr
from gpo.cameras.mount import floor_angles
from gpo.cameras.targets import FloorBoard
from gpo.cli import main
from gpo.pipeline.schema import load_mount
from gpo.sim.floors import make_floor
from gpo.sim.record import FLOOR_BOARDS, TEXEL_M, floor_board_image
from gpo.sim.render import FloorRenderer
from gpo.sim.rigs import RIGS

HEIGHT_TOL_M = 0.5e-3
ANGLE_TOL_DEG = 0.1
POSITION_TOL_M = 2e-3
KINDS = {"t265": "forward", "downward": "downward"}


def _files(tmp_path, rig_name: str, image=None):
    """The rig's floor-board image and calibration, written into ``tmp_path``."""
    image_path, calib_path = tmp_path / f"{rig_name}.png", tmp_path / f"{rig_name}_calib.yaml"
    cv2.imwrite(str(image_path), floor_board_image(rig_name) if image is None else image)
    save_kalibr(calib_path, {"cam0": RIGS[rig_name]().camera})
    return image_path, calib_path


def _at(placement: FloorBoard) -> list[str]:
    return ["--at", str(placement.x), str(placement.y), str(np.degrees(placement.yaw))]


@pytest.mark.parametrize("rig_name", KINDS)
def test_mount_command_meets_the_targets_on_the_simulated_floor_board(rig_name, tmp_path, capsys):
    rig, placement = RIGS[rig_name](), FLOOR_BOARDS[rig_name]
    image, calib = _files(tmp_path, rig_name)
    out = tmp_path / "mount.yaml"
    args = ["mount", str(image), "--camera", str(calib), "--board", "7x5", "--square", "0.02", "--out", str(out)]
    assert main([*args, *_at(placement)]) == 0
    printed = capsys.readouterr().out
    measured = load_mount(out)
    assert abs(measured.height - rig.mount.height) < HEIGHT_TOL_M
    kind = KINDS[rig_name]
    angles = [floor_angles(m.rotation.inv().apply([0.0, 0.0, 1.0]), kind) for m in (measured, rig.mount)]
    np.testing.assert_allclose(np.degrees(angles[0]), np.degrees(angles[1]), atol=ANGLE_TOL_DEG)
    assert np.degrees((measured.rotation * rig.mount.rotation.inv()).magnitude()) < ANGLE_TOL_DEG
    assert np.linalg.norm(measured.position - rig.mount.position) < POSITION_TOL_M
    assert "height  0.2500" in printed if rig_name == "downward" else "height  0.1200" in printed
    picture = cv2.imread(str(out.with_suffix(".png")))
    assert picture.shape[:2] == (rig.camera.height, rig.camera.width)
    # without the board's place: the same height and floor angles, x = y = yaw = 0 assumed and said so
    bare = tmp_path / "bare.yaml"
    assert main([*args[:-1], str(bare)]) == 0
    assert "x, y, yaw: not measured" in capsys.readouterr().out
    unplaced = load_mount(bare)
    assert abs(unplaced.height - measured.height) < 1e-9 and not unplaced.position[:2].any()
    unplaced_angles = floor_angles(unplaced.rotation.inv().apply([0.0, 0.0, 1.0]), kind)
    np.testing.assert_allclose(unplaced_angles, angles[0], atol=1e-9)


def _fails(argv, capsys) -> str:
    assert main(argv) == 1
    error = capsys.readouterr().err
    assert "Traceback" not in error
    return error


def test_wrong_board_size_two_boards_and_another_camera_are_clear_errors(tmp_path, capsys):
    image, calib = _files(tmp_path, "t265")
    args = ["mount", str(image), "--camera", str(calib), "--square", "0.02", "--out", str(tmp_path / "m.yaml")]
    assert "check --board" in _fails([*args, "--board", "9x7"], capsys)
    assert "more inner corners than 6x5" in _fails([*args, "--board", "6x5"], capsys)
    rig, board = RIGS["t265"](), FLOOR_BOARDS["t265"]
    second = FloorBoard(board.board, board.x - 0.02, board.y + 0.16, board.yaw)
    floor = make_floor("raised", (-1.0, 2.0, -1.5, 1.5), TEXEL_M["t265"], 0)
    two = FloorRenderer(rig, floor).render(np.zeros(3), frame_seed=0, boards=(board, second))
    (tmp_path / "two").mkdir()
    twice, _ = _files(tmp_path / "two", "t265", two)
    assert "two chessboards" in _fails(["mount", str(twice), *args[2:], "--board", "7x5"], capsys)
    _, other = _files(tmp_path, "downward")
    assert "is 848 x 800 pixels but the camera calibration is 752 x 480" in _fails(
        [*args[:3], str(other), *args[4:], "--board", "7x5"], capsys
    )
    assert not (tmp_path / "m.yaml").exists()


def test_a_kind_the_measured_tilt_contradicts_is_refused(tmp_path, capsys):
    """The T265's axis lies 84 deg from straight down (pitched 6 deg below the horizon, gpo.sim.rigs), the downward
    camera's 1 deg: either called the other kind writes nothing (it wrote a mount 86 deg off with exit 0)."""
    for rig_name, wrong, seen, degrees in (("t265", "downward", "forward", 84), ("downward", "forward", "downward", 1)):
        image, calib = _files(tmp_path, rig_name)
        out = tmp_path / f"{rig_name}_mount.yaml"
        error = _fails(["mount", str(image), "--camera", str(calib), "--board", "7x5", "--square", "0.02", "--kind",
                        wrong, "--out", str(out)], capsys)
        assert f"{image}: the camera's optical axis lies {degrees} deg from straight down, so it looks {seen}" in error
        assert f"not {wrong}: give kind '{seen}' or 'auto' (--kind)" in error
        assert not out.exists()


@pytest.mark.parametrize(("rig_name", "square", "height"), [("t265", "0.2", "1.200"), ("downward", "0.2", "2.500"),
                                                             ("t265", "0.002", "0.012")])
def test_a_height_no_camera_of_its_kind_has_is_flagged_and_keeps_a_good_file(rig_name, square, height, tmp_path,
                                                                             capsys):
    """The board's squares are 0.02 m (gpo.sim.record.FLOOR_BOARDS): given ten times too large or too small, the
    camera's height comes out ten times off (0.12 m and 0.25 m truly), outside the kind's HEIGHT_RANGE_M."""
    image, calib = _files(tmp_path, rig_name)
    out = tmp_path / "mount.yaml"
    out.write_text("mount: {position_m: [0.6, 0.0, 0.12], rpy_deg: [1.5, 6.0, 0.0]}  # a good one\n")
    argv = ["mount", str(image), "--camera", str(calib), "--board", "7x5", "--square", square, "--out", str(out)]
    assert main(argv) == 1
    printed = capsys.readouterr()
    assert f"warning: the camera comes out {height} m above the floor" in printed.out
    assert "check the board's square size" in printed.out and f"{out} is kept" in printed.err
    assert out.read_text().endswith("# a good one\n")
    flagged = (tmp_path / "mount.flagged.yaml").read_text()
    assert f"# warning: the camera comes out {height} m above the floor" in flagged  # the flag inside the file
