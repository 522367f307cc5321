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


def _names(node: ast.AST, context: type) -> set[str]:
    """The plain names under ``node`` used in ``context`` (``ast.Load`` or ``ast.Store``)."""
    return {sub.id for sub in ast.walk(node) if isinstance(sub, ast.Name) and isinstance(sub.ctx, context)}


def _own_names(statement: ast.stmt) -> set[str]:
    """The names a statement binds for its own use only and reads after binding: loop and comprehension variables,
    ``as`` names, and a function's parameters and local variables."""
    own = set()
    for node in ast.walk(statement):
        if isinstance(node, ast.For | ast.AsyncFor | ast.comprehension):
            own |= _names(node.target, ast.Store)
        elif isinstance(node, ast.withitem) and node.optional_vars is not None:
            own |= _names(node.optional_vars, ast.Store)
        elif isinstance(node, ast.ExceptHandler) and node.name:
            own.add(node.name)
        elif isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.Lambda):
            arguments = node.args
            own |= {arg.arg for arg in (*arguments.posonlyargs, *arguments.args, *arguments.kwonlyargs,
                                        arguments.vararg, arguments.kwarg) if arg is not None}  # fmt: skip
            for body in node.body if isinstance(node.body, list) else [node.body]:
                own |= _names(body, ast.Store)
    return own


def _comprehension_names(statement: ast.stmt) -> set[str]:
    """The variables of a statement's comprehensions, which Python keeps inside them."""
    return {name for node in ast.walk(statement) if isinstance(node, ast.comprehension)
            for name in _names(node.target, ast.Store)}  # fmt: skip


def cell_names(source: str, modules: frozenset[str] = frozenset()) -> CellNames:
    """What the code of one cell binds, changes and reads. It reads a name when a statement uses it before the cell
    has bound it (reads inside its functions count too, not their own parameters and variables, nor a loop's or a
    comprehension's variable inside it). A call of a function of one of ``modules`` (``np.mean(...)``) changes
    nothing."""
    tree = ast.parse(source)
    binds, changes, reads = set(), set(), set()
    for statement in tree.body:
        reads |= _names(statement, ast.Load) - _own_names(statement) - binds
        if isinstance(statement, ast.Import | ast.ImportFrom):
            binds |= {(alias.asname or alias.name).split(".")[0] for alias in statement.names}
            continue
        if isinstance(statement, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
            binds.add(statement.name)
            continue
        binds |= _names(statement, ast.Store) - _comprehension_names(statement)
        for node in ast.walk(statement):
            if isinstance(node, ast.Attribute | ast.Subscript) and isinstance(node.ctx, ast.Store | ast.Del):
                changes.add(_base_name(node))
            elif isinstance(node, ast.Expr) and isinstance(node.value, ast.Call):
                changes.add(_base_name(node.value.func))
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
