"""Which cells of a chapter its widget panels need: the panels' cells and, walking back, every cell that binds or
changes a name a needed cell reads.

nbval runs every cell of every chapter; the browser test runs only what its panels need, read from the code with
``ast``. A cell counts as changing a name when it assigns to one of its attributes or items or calls one of its
methods (``config.window = 9``, ``frames[0] = ...``, ``paths.append(...)``), so a cell that might prepare a panel's
input is kept. A needed cell left out would stop its panel with a NameError or a wrong figure, which the test sees.
"""

from __future__ import annotations

import ast
import builtins
import json
from dataclasses import dataclass
from pathlib import Path

WIDGET_VIEW = "application/vnd.jupyter.widget-view+json"
BUILTINS = frozenset(dir(builtins))


@dataclass(frozen=True)
class CellNames:
    """The names a cell ``binds`` outright, the names it ``changes`` in place and the names it ``reads``."""

    binds: frozenset[str]
    changes: frozenset[str]
    reads: frozenset[str]


def _base_name(node: ast.AST) -> str | None:
    """``x`` of ``x``, ``x.a.b``, ``x[i]`` or ``x.f(...)``; None for anything else."""
    while isinstance(node, ast.Attribute | ast.Subscript | ast.Call):
        node = node.func if isinstance(node, ast.Call) else node.value
    return node.id if isinstance(node, ast.Name) else None


def cell_names(source: str, modules: frozenset[str] = frozenset()) -> CellNames:
    """What the code of one cell binds, changes and reads (reads inside its functions count too). A call of a
    function of one of ``modules`` (``np.mean(...)``) changes nothing."""
    tree = ast.parse(source)
    binds, changes = set(), set()
    for statement in tree.body:
        if isinstance(statement, ast.Import | ast.ImportFrom):
            binds |= {(alias.asname or alias.name).split(".")[0] for alias in statement.names}
            continue
        if isinstance(statement, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
            binds.add(statement.name)
            continue
        for node in ast.walk(statement):
            if isinstance(node, ast.Name) and isinstance(node.ctx, ast.Store):
                binds.add(node.id)
            elif isinstance(node, ast.Attribute | ast.Subscript) and isinstance(node.ctx, ast.Store | ast.Del):
                changes.add(_base_name(node))
            elif isinstance(node, ast.Expr) and isinstance(node.value, ast.Call):
                changes.add(_base_name(node.value.func))
    reads = {node.id for node in ast.walk(tree) if isinstance(node, ast.Name) and not isinstance(node.ctx, ast.Store)}
    return CellNames(frozenset(binds), frozenset(changes - modules - {None}), frozenset(reads - BUILTINS))


def imported(source: str) -> set[str]:
    """The names a cell's import statements bind."""
    return {(alias.asname or alias.name).split(".")[0] for statement in ast.parse(source).body
            if isinstance(statement, ast.Import | ast.ImportFrom) for alias in statement.names}  # fmt: skip


def code_cells(notebook: Path) -> list[dict]:
    """The chapter's code cells, in order."""
    return [cell for cell in json.loads(notebook.read_text())["cells"] if cell["cell_type"] == "code"]


def panel_cells(cells: list[dict]) -> list[int]:
    """Indices (among the code cells) of the cells whose saved outputs show a widget."""
    return [index for index, cell in enumerate(cells)
            if any(WIDGET_VIEW in output.get("data", {}) for output in cell.get("outputs", []))]  # fmt: skip


def cells_panels_need(notebook: Path) -> list[int]:
    """Indices (among the code cells, ascending) of the panels' cells and every earlier cell they need."""
    cells = code_cells(notebook)
    sources = ["".join(cell["source"]) for cell in cells]
    modules = frozenset().union(*map(imported, sources))
    names = [cell_names(source, modules) for source in sources]
    panels = set(panel_cells(cells))
    needed, wanted = [], set()
    for index in reversed(range(max(panels, default=-1) + 1)):
        cell = names[index]
        if index in panels or wanted & (cell.binds | cell.changes):
            needed.append(index)
            wanted = (wanted - cell.binds) | cell.reads
    return sorted(needed)
