"""The cells a chapter's panels need, on small notebooks whose answer is known, and on every chapter: each needed
cell's names are bound by a needed cell before it."""

from __future__ import annotations

import ast
import json
from pathlib import Path

import nbformat
import pytest
from needed_cells import WIDGET_VIEW, cell_names, cells_panels_need, code_cells

ROOT = Path(__file__).resolve().parents[2]
PANEL_OUTPUT = {"output_type": "display_data", "data": {WIDGET_VIEW: {"model_id": "0"}}, "metadata": {}}


def _notebook(tmp_path, sources: list[str], panels: set[int]) -> Path:
    notebook = nbformat.v4.new_notebook()
    for index, source in enumerate(sources):
        cell = nbformat.v4.new_code_cell(source)
        if index in panels:
            cell.outputs = [nbformat.from_dict(PANEL_OUTPUT)]
        notebook.cells.append(cell)
    path = tmp_path / "chapter.ipynb"
    path.write_text(json.dumps(notebook))
    return path


def test_a_panel_needs_what_binds_and_changes_its_names_and_nothing_else(tmp_path):
    sources = [
        "import numpy as np\nfrom gpo.book import panels",  # 0: binds np and panels
        "slow = np.ones(10**6).sum()",  # 1: nobody reads slow
        "config = {'window': 9}",  # 2: bound, read by the panel
        "config['window'] = 15",  # 3: changes config
        "np.random.seed(0)",  # 4: a function of a module: changes nothing the panel reads
        "frames = []\nfor k in range(3):\n    frames.append(k)",  # 5: binds frames, changes it in a loop
        "print(slow)",  # 6: after the panel
        "panels.flow_panel(config, frames)",  # 7: the panel
    ]
    assert cells_panels_need(_notebook(tmp_path, sources, panels={7})) == [0, 2, 3, 5, 7]


def test_a_name_bound_again_ends_the_walk_back_for_it(tmp_path):
    sources = ["x = 1", "x = 2", "y = x", "show(y)"]
    assert cells_panels_need(_notebook(tmp_path, sources, panels={3})) == [1, 2, 3]
    assert cell_names("x = x + 1").reads == {"x"}


def test_a_cells_own_names_are_not_read_from_cells_before_it(tmp_path):
    own = [
        "total = 0\nfor row in rows:\n    total = total + row",  # a loop's variable; total bound in the cell first
        "def signed(value, decimals):\n    rounded = round(value, decimals)\n    return rounded",  # parameters, locals
        "squares = [k * k for k in ks]\nwith open(path) as f:\n    text = f.read()",  # comprehension and `as` names
        "try:\n    pass\nexcept ValueError as error:\n    print(error)",
    ]
    assert [sorted(cell_names(source).reads) for source in own] == [["rows"], [], ["ks", "path"], []]
    assert "k" not in cell_names(own[2]).binds  # a comprehension's variable stays in the comprehension
    sources = ["row = 1\nvalue = 2", "slow = [row for row in range(3)]", "def f(value):\n    return value", "show(f)"]
    assert cells_panels_need(_notebook(tmp_path, sources, panels={3})) == [2, 3]


def test_two_panels_need_the_union_of_their_cells(tmp_path):
    sources = ["a = 1", "b = 2", "show(a)", "c = 3", "show(b)"]
    assert cells_panels_need(_notebook(tmp_path, sources, panels={2, 4})) == [0, 1, 2, 4]


@pytest.mark.parametrize("notebook", sorted((ROOT / "notebooks").glob("*.ipynb")), ids=lambda path: path.stem)
def test_every_name_a_needed_cell_reads_is_bound_by_a_needed_cell_before_it(notebook):
    cells = code_cells(notebook)
    bound: set[str] = set()
    for index in cells_panels_need(notebook):
        source = "".join(cells[index]["source"])
        names = cell_names(source)
        local = {  # a function's parameters and variables
            node.arg if isinstance(node, ast.arg) else node.id
            for node in ast.walk(ast.parse(source))
            if isinstance(node, ast.arg) or (isinstance(node, ast.Name) and isinstance(node.ctx, ast.Store))
        }
        bound |= names.binds
        assert names.reads - local <= bound, f"code cell {index} reads {sorted(names.reads - local - bound)}"
