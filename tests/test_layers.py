"""The three layers' rule (ARCHITECTURE.md), read from every module's source: what each layer may import when it is
imported. The method (``gpo/*.py``) imports no plotting, no widgets, neither the simulator nor the book; the simulated
world (``gpo/sim/``) imports nothing of the method's odometry, fusion, evaluation or sweeps, nor the book; the book
(``gpo/book/``) may import anything. A command may still import what it alone uses inside its function."""

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "gpo"
FORBIDDEN = {  # layer -> the modules (and their submodules) it must not import at module level
    "method": ("matplotlib", "ipywidgets", "gpo.sim", "gpo.book"),
    "sim": ("gpo.pipeline", "gpo.fusion", "gpo.metrics", "gpo.batch", "gpo.book", "matplotlib", "ipywidgets"),
    "book": (),
}


def layer_of(path: Path) -> str:
    """The layer of a module of the package by its folder: ``gpo/sim/`` the simulated world, ``gpo/book/`` the book,
    ``gpo/`` itself the method."""
    parts = path.relative_to(PACKAGE).parts
    return {"sim": "sim", "book": "book"}.get(parts[0], "method") if len(parts) > 1 else "method"


def module_level_imports(source: str, package: str) -> list[tuple[int, str]]:
    """(line, module) of every import run when a module of ``package`` (e.g. ``gpo.sim``) with this source is
    imported: those in its body and in the bodies of its top-level ``if``/``try``/``with`` blocks, not those inside a
    function or class, nor under ``if TYPE_CHECKING:``. Relative imports are resolved against ``package``;
    ``from gpo import sim`` counts as ``gpo.sim``."""
    found = []

    def visit(statements):
        for node in statements:
            if isinstance(node, ast.Import):
                found.extend((node.lineno, alias.name) for alias in node.names)
            elif isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level:
                    parent = package.split(".")[: len(package.split(".")) - node.level + 1]
                    base = ".".join([*parent, *([base] if base else [])])
                found.append((node.lineno, base))
                found.extend((node.lineno, f"{base}.{alias.name}") for alias in node.names)
            elif isinstance(node, ast.If):
                if not (isinstance(node.test, ast.Name) and node.test.id == "TYPE_CHECKING"):
                    visit(node.body)
                visit(node.orelse)
            elif isinstance(node, ast.Try):
                for block in (node.body, *(handler.body for handler in node.handlers), node.orelse, node.finalbody):
                    visit(block)
            elif isinstance(node, ast.With):
                visit(node.body)

    visit(ast.parse(source).body)
    return found


def violations(source: str, layer: str, package: str) -> list[str]:
    """Each module-level import statement of ``source`` that ``layer`` forbids, as "line N: module" (the first
    forbidden name it imports)."""
    found = {}
    for line, module in module_level_imports(source, package):
        if any(module == banned or module.startswith(f"{banned}.") for banned in FORBIDDEN[layer]):
            found.setdefault(line, f"line {line}: {module}")
    return list(found.values())


MODULES = sorted(PACKAGE.rglob("*.py"))


def test_every_layer_has_its_modules():
    layers = {layer_of(path) for path in MODULES}
    assert layers == set(FORBIDDEN)
    assert {path.name for path in MODULES if layer_of(path) == "book"} >= {"figures.py", "ch09_table4.py"}


@pytest.mark.parametrize("path", MODULES, ids=lambda path: str(path.relative_to(PACKAGE.parent)))
def test_a_module_imports_only_what_its_layer_may(path):
    package = ".".join(path.relative_to(PACKAGE.parent).parent.parts)
    layer = layer_of(path)
    assert violations(path.read_text(encoding="utf-8"), layer, package) == [], f"{path} ({layer} layer)"


SYNTHETIC = '''
from __future__ import annotations
import numpy as np
from typing import TYPE_CHECKING
if TYPE_CHECKING:
    from matplotlib.figure import Figure
try:
    import matplotlib.pyplot as plt
except ImportError:
    plt = None
from gpo import sim
from .. import fusion
from ..book import figures

def later():
    import ipywidgets
    from gpo.pipeline.run import run
'''


def test_the_check_finds_a_forbidden_import_wherever_it_runs_at_import_time():
    """A synthetic module: the imports run at import time are found (in a ``try``, written ``from gpo import sim``
    or relative: in ``gpo.sim``, ``..`` is ``gpo``), those under ``TYPE_CHECKING`` or inside a function are not."""
    assert violations(SYNTHETIC, "method", "gpo") == ["line 8: matplotlib.pyplot", "line 11: gpo.sim"]
    assert violations(SYNTHETIC, "sim", "gpo.sim") == [
        "line 8: matplotlib.pyplot",
        "line 12: gpo.fusion",
        "line 13: gpo.book",
    ]
    assert violations(SYNTHETIC, "book", "gpo.book") == []


def test_the_check_fails_a_method_module_that_imports_the_simulator():
    """The test above over a module of the method with one import added: it fails, naming the line."""
    source = (PACKAGE / "pipeline.py").read_text(encoding="utf-8") + "\nfrom gpo.sim.record import recording\n"
    found = violations(source, "method", "gpo")
    assert found == [f"line {source.count(chr(10))}: gpo.sim.record"]
    assert violations(source.replace("gpo.sim.record", "gpo.io.trajectory"), "method", "gpo") == []
