"""What a module runs: its source file and those of every module of gpo it imports, transitively, read (``ast``) and
never executed.

A result kept in the cache (a recording, a floor run, a sweep's run) is named by a key that hashes, beside its
inputs, the sources of the code that made it (``sources``), so that a change to any module it went through makes a
new file instead of serving a stale one. An import inside a function counts as well as one at the top: the code a
result goes through imports some modules only when it needs them. The layering test (``tests/test_layers.py``) reads
the same imports (``imports``) to hold each layer to what it may import.
"""

from __future__ import annotations

import ast
import functools
from dataclasses import dataclass
from pathlib import Path

PACKAGE_ROOT = Path(__file__).resolve().parents[2]
"""The folder holding the ``gpo`` package."""


@dataclass(frozen=True)
class Import:
    """One module an import statement names: its ``line``, the dotted ``module`` (``from a import b`` names ``a`` and
    ``a.b``, whichever of them is a module) and whether it runs when the importing module is imported
    (``at_import``: at module level, or in a top-level ``if``, ``try`` or ``with``; not under ``if TYPE_CHECKING:``,
    nor inside a function or class)."""

    line: int
    module: str
    at_import: bool


def imports(source: str, package: str) -> list[Import]:
    """Every import of the module with this ``source`` in ``package`` (its dotted parent, e.g. ``gpo.sim``), relative
    imports resolved against it; ``from gpo import sim`` names ``gpo`` and ``gpo.sim``."""
    found: list[Import] = []

    def names(node: ast.Import | ast.ImportFrom) -> list[str]:
        if isinstance(node, ast.Import):
            return [alias.name for alias in node.names]
        base = node.module or ""
        if node.level:
            parts = package.split(".")
            base = ".".join([*parts[: len(parts) - node.level + 1], *([base] if base else [])])
        return [base, *(f"{base}.{alias.name}" for alias in node.names)]

    def visit(statements, at_import: bool) -> None:
        for node in statements:
            if isinstance(node, ast.Import | ast.ImportFrom):
                found.extend(Import(node.lineno, name, at_import) for name in names(node))
            elif isinstance(node, ast.If):
                checking = isinstance(node.test, ast.Name) and node.test.id == "TYPE_CHECKING"
                visit(node.body, at_import and not checking)
                visit(node.orelse, at_import)
            elif isinstance(node, ast.Try):
                for block in (node.body, *(handler.body for handler in node.handlers), node.orelse, node.finalbody):
                    visit(block, at_import)
            elif isinstance(node, ast.With):
                visit(node.body, at_import)
            elif isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
                visit(node.body, False)
            else:
                for child in ast.iter_child_nodes(node):
                    if isinstance(child, ast.stmt):
                        visit([child], False)

    visit(ast.parse(source).body, True)
    return found


def module_file(module: str, root: Path = PACKAGE_ROOT) -> Path | None:
    """The source file of the dotted ``module`` under ``root`` (a package's ``__init__.py``), or None."""
    path = root.joinpath(*module.split("."))
    for candidate in (path.with_suffix(".py"), path / "__init__.py"):
        if candidate.is_file():
            return candidate
    return None


def module_name(path: Path, root: Path = PACKAGE_ROOT) -> str:
    """The dotted name of the module in the file ``path`` under ``root``."""
    parts = path.relative_to(root).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def sources(*modules: str, root: Path = PACKAGE_ROOT) -> list[Path]:
    """The files of ``modules`` and of every module of gpo they import, transitively, with the ``__init__.py`` of each
    package on the way: what running them can execute. Sorted, so that a key hashes them in one order."""
    seen: dict[str, Path] = {}
    pending = list(modules)
    while pending:
        module = pending.pop()
        if module in seen or module.split(".")[0] != "gpo":
            continue
        path = module_file(module, root)
        if path is None:
            continue
        seen[module] = path
        package = module if path.name == "__init__.py" else module.rpartition(".")[0]
        parts = package.split(".")
        pending.extend(".".join(parts[: i + 1]) for i in range(len(parts)))
        pending.extend(_imported(path, path.stat().st_mtime_ns, package))
    return sorted(set(seen.values()))


@functools.lru_cache(maxsize=1024)
def _imported(path: Path, modified_ns: int, package: str) -> tuple[str, ...]:
    """The modules the file ``path`` imports (read again when its modification time changes)."""
    return tuple(found.module for found in imports(path.read_text(encoding="utf-8"), package))
