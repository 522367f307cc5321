"""The one fingerprint of the code a cached result went through (``gpo.io.fingerprint.sources``): the modules it
runs, found by reading imports, transitively, including those inside functions; a change to any of them is a cache
miss, a change elsewhere is not."""

import shutil
import subprocess
import sys
from pathlib import Path

from gpo.experiments.runs import RUN_MODULES
from gpo.io import cache
from gpo.io.fingerprint import PACKAGE_ROOT, imports, sources

PACKAGE = {
    "gpo/__init__.py": "",
    "gpo/stage/__init__.py": "from gpo.stage.run import run\n",
    "gpo/stage/run.py": "import numpy as np\nfrom . import helper\n\ndef run():\n    from gpo.deep import x\n",
    "gpo/stage/helper.py": "VALUE = 1\n",
    "gpo/deep.py": "x = 2\n",
    "gpo/elsewhere.py": "import gpo.deep\n",
}


def _write(root: Path) -> Path:
    for name, text in PACKAGE.items():
        (root / name).parent.mkdir(parents=True, exist_ok=True)
        (root / name).write_text(text)
    return root


def test_the_sources_follow_imports_at_any_depth_and_inside_functions(tmp_path):
    root = _write(tmp_path)
    found = {path.relative_to(root).as_posix() for path in sources("gpo.stage.run", root=root)}
    assert found == set(PACKAGE) - {"gpo/elsewhere.py"}
    read = imports(PACKAGE["gpo/stage/run.py"], "gpo.stage")
    assert [(entry.line, entry.module, entry.at_import) for entry in read] == [
        (1, "numpy", True),
        (2, "gpo.stage", True),
        (2, "gpo.stage.helper", True),
        (5, "gpo.deep", False),
        (5, "gpo.deep.x", False),
    ]


def test_a_change_to_a_module_a_result_went_through_is_a_cache_miss(tmp_path):
    root = _write(tmp_path)
    before = cache.key("run", sources=sources("gpo.stage.run", root=root))
    (root / "gpo/elsewhere.py").write_text("import gpo.deep\nCHANGED = True\n")
    assert cache.key("run", sources=sources("gpo.stage.run", root=root)) == before
    (root / "gpo/deep.py").write_text("x = 3\n")  # imported only inside a function
    assert cache.key("run", sources=sources("gpo.stage.run", root=root)) != before


def test_a_kept_floor_run_goes_stale_when_the_board_or_the_mount_changes(tmp_path):
    """The chessboard routes run through the board's and the mount's modules: a change to either is a new key for the
    chapters' kept floor runs (``gpo.experiments.runs.floor_run``), measured on a copy of the package."""
    copy = tmp_path / "copy"
    shutil.copytree(PACKAGE_ROOT / "gpo", copy / "gpo", ignore=shutil.ignore_patterns("__pycache__"))
    hashed = {path.relative_to(copy).as_posix() for path in sources(*RUN_MODULES, root=copy)}
    assert {"gpo/cameras/targets.py", "gpo/cameras/mount.py", "gpo/floor_image/ortho.py"} <= hashed
    assert not {path for path in hashed if path.startswith(("gpo/book/", "gpo/cli/", "gpo/experiments/"))}
    before = cache.key("sample.bag", sources=sources(*RUN_MODULES, root=copy))
    for module in ("gpo/cameras/targets.py", "gpo/cameras/mount.py"):
        with (copy / module).open("a") as source:
            source.write("\n# changed\n")
        after = cache.key("sample.bag", sources=sources(*RUN_MODULES, root=copy))
        assert after != before, module
        before = after


def test_what_a_floor_run_loads_is_hashed():
    """Every module of gpo that importing a floor run's modules loads is among its sources."""
    program = (
        f"import sys, {', '.join(RUN_MODULES)}\n"
        "print(*(m.__file__ for m in list(sys.modules.values()) if m.__name__.startswith('gpo')))"
    )
    loaded = subprocess.run([sys.executable, "-c", program], capture_output=True, text=True, check=True).stdout.split()
    assert {Path(path).resolve() for path in loaded} <= {path.resolve() for path in sources(*RUN_MODULES)}
