"""The package's layers (ARCHITECTURE.md), read from every module's source with the imports the cache's fingerprint
reads (``gpo.io.fingerprint.imports``): an import inside a function counts as well as one at the top.

- A module imports modules of gpo only from its own layer or a layer below it: the core (camera models, bags,
  trajectories, the cache) at the bottom; the method and the simulated world beside each other above it, never
  importing each other; the experiments above both; the book above them; the command line on top, which nothing
  imports (the book runs commands as a user does, ``python -m gpo`` in a subprocess).
- Within the core and the method, the stages read in the order they run, and a stage never imports a later one.
- No import cycles between modules, even through an import inside a function.
- Plotting and widgets only in the book and the command line.
- No module over 600 lines without a one-line reason at its top.
"""

import graphlib
from pathlib import Path

import pytest

from gpo.io.fingerprint import PACKAGE_ROOT, imports, module_file, module_name

PACKAGE = PACKAGE_ROOT / "gpo"

LAYERS = {  # layer -> its packages and modules, in the order the method runs where it has stages
    "core": ("gpo.cameras", "gpo.io"),
    "method": (
        "gpo.floor_image",
        "gpo.motion",
        "gpo.odometry",
        "gpo.fusion",
        "gpo.metrics",
        "gpo.pipeline",
        "gpo.batch",
    ),
    "world": ("gpo.sim",),
    "experiments": ("gpo.experiments",),
    "book": ("gpo.book",),
    "cli": ("gpo.cli", "gpo.__main__"),
}
BELOW = {  # layer -> the layers whose modules it may import besides its own
    "core": set(),
    "method": {"core"},
    "world": {"core"},
    "experiments": {"core", "method", "world"},
    "book": {"core", "method", "world", "experiments"},
    "cli": {"core", "method", "world", "experiments", "book"},
}
STAGES = (*LAYERS["core"], *LAYERS["method"])
"""The stages of the method in the order a frame goes through them: each imports only the ones before it."""
DRAWING = ("matplotlib", "ipywidgets")
DRAWING_LAYERS = {"book", "cli"}
LONG_MODULE_LINES = 600
LONG_MODULE_REASON = "# long:"  # a module over LONG_MODULE_LINES says why on a line starting so, at its top


def _within(module: str, home: str) -> bool:
    return module == home or module.startswith(f"{home}.")


def layer_of(module: str) -> str | None:
    """The layer of a dotted module of gpo (None for the ``gpo`` package itself, which imports nothing)."""
    for layer, homes in LAYERS.items():
        if any(_within(module, home) for home in homes):
            return layer
    return None


def stage_of(module: str) -> int | None:
    """The place of the module's stage in ``STAGES``, or None outside the core and the method."""
    return next((index for index, home in enumerate(STAGES) if _within(module, home)), None)


def problems(module: str, source: str, root: Path = PACKAGE_ROOT) -> list[str]:
    """Each import of the module ``module`` (with this ``source``) its layer forbids, as "line N: module (why)"."""
    package = module if module_file(module, root) and module_file(module, root).name == "__init__.py" else (
        module.rpartition(".")[0]
    )
    layer, stage = layer_of(module), stage_of(module)
    found = {}
    for imported in imports(source, package):
        name = imported.module
        why = None
        if name.split(".")[0] in DRAWING and layer not in DRAWING_LAYERS:
            why = "plotting or widgets below the book"
        elif name.startswith("gpo.") and module_file(name, root) is not None:
            other = layer_of(name)
            if other is not None and other != layer and other not in BELOW[layer]:
                why = f"the {layer} layer imports the {other} layer"
            elif stage is not None and stage_of(name) is not None and stage_of(name) > stage:
                why = f"a stage imports a later one ({STAGES[stage_of(name)]})"
        if why:
            found.setdefault(imported.line, f"line {imported.line}: {name} ({why})")
    return list(found.values())


MODULES = {module_name(path): path for path in sorted(PACKAGE.rglob("*.py"))}


def test_every_module_is_in_one_layer_and_every_layer_has_modules():
    assert [module for module in MODULES if layer_of(module) is None] == ["gpo"]
    assert {layer_of(module) for module in MODULES} - {None} == set(LAYERS)
    assert "gpo.book.figures" in MODULES and "gpo.cli.run" in MODULES and "gpo.odometry.estimators.paper" in MODULES


@pytest.mark.parametrize("module", MODULES, ids=str)
def test_a_module_imports_only_what_its_layer_and_stage_may(module):
    assert problems(module, MODULES[module].read_text(encoding="utf-8")) == []


def import_graph() -> dict[str, set[str]]:
    """module -> the modules of gpo it imports (a package imported by name is its ``__init__``)."""
    graph = {}
    for module, path in MODULES.items():
        package = module if path.name == "__init__.py" else module.rpartition(".")[0]
        named = {found.module for found in imports(path.read_text(encoding="utf-8"), package)}
        graph[module] = {name for name in named if name in MODULES and name != module}
    return graph


def test_no_import_cycles():
    """A module importing its own package's ``__init__`` (to read a registry) is not a cycle when the ``__init__``
    does not import it back; any loop of imports is."""
    graphlib.TopologicalSorter(import_graph()).static_order()  # raises CycleError naming the loop


def test_a_long_module_says_why_at_its_top():
    for module, path in MODULES.items():
        lines = path.read_text(encoding="utf-8").splitlines()
        if len(lines) > LONG_MODULE_LINES:
            assert any(line.lower().startswith(LONG_MODULE_REASON) for line in lines[:30]), f"{module}: {len(lines)}"


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


def test_the_check_finds_a_forbidden_import_wherever_it_is():
    """A synthetic module: the imports are found wherever they are (in a ``try``, written ``from gpo import sim`` or
    relative, inside a function, under ``TYPE_CHECKING``)."""
    as_motion = problems("gpo.motion.synthetic", SYNTHETIC)
    assert [entry.split(" (")[0] for entry in as_motion] == [
        "line 6: matplotlib.figure",
        "line 8: matplotlib.pyplot",
        "line 11: gpo.sim",
        "line 12: gpo.fusion",
        "line 13: gpo.book",
        "line 16: ipywidgets",
        "line 17: gpo.pipeline.run",
    ]
    assert "a stage imports a later one (gpo.fusion)" in as_motion[3]
    assert "the method layer imports the world layer" in as_motion[2]
    assert problems("gpo.cli.synthetic", SYNTHETIC) == []
    assert problems("gpo.book.synthetic", SYNTHETIC) == []


def test_the_check_fails_a_method_module_that_imports_the_simulator_or_the_command_line():
    """The test above over a real module of the method with one import added: it fails, naming the line."""
    source = MODULES["gpo.pipeline.run"].read_text(encoding="utf-8")
    for added, layer in (("gpo.sim.record", "world"), ("gpo.cli.run", "cli")):
        changed = source + f"\n\ndef later():\n    import {added}\n"
        assert problems("gpo.pipeline.run", changed) == [
            f"line {changed.count(chr(10))}: {added} (the method layer imports the {layer} layer)"
        ]
    assert problems("gpo.pipeline.run", source + "\nimport gpo.io.trajectory\n") == []


def test_the_cycle_check_sees_imports_inside_functions():
    """``gpo demo`` imports the book's figures only when it draws: the graph the cycle check sorts has that edge."""
    assert "gpo.book.figures" in import_graph()["gpo.cli.demo"]
