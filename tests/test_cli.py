"""The command line: ``python -m gpo demo`` writes what it says it writes."""

import subprocess
import sys

import numpy as np

from gpo.camera import T265_LIKE


def test_demo_writes_figures_and_the_field_of_view_table(tmp_path):
    result = subprocess.run(
        [sys.executable, "-m", "gpo", "demo", "--out", str(tmp_path)], capture_output=True, text=True, check=True
    )
    assert str(tmp_path) in result.stdout
    for name in ("fisheye_room_grid.png", "projection_curves.png"):
        assert (tmp_path / name).read_bytes().startswith(b"\x89PNG")
    table = (tmp_path / "field_of_view.txt").read_text().splitlines()
    horizontal = np.degrees(T265_LIKE.field_of_view()[0])
    assert table[0].startswith("EUCM alpha=0.6, beta=1.1:") and f"horizontal {horizontal:.1f} deg" in table[0]


def test_unknown_command_fails_with_usage():
    result = subprocess.run([sys.executable, "-m", "gpo", "fly"], capture_output=True, text=True)
    assert result.returncode == 2 and "invalid choice: 'fly'" in result.stderr
