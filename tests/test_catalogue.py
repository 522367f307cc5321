"""README.md's account of the reliability catalogue, ``tests/test_bad_input.py``, kept true: the number of its cases
as pytest collects them, and every command its cases run named."""

import ast
import os
import re
import subprocess
import sys
from pathlib import Path

from gpo.cli import COMMANDS

ROOT = Path(__file__).resolve().parents[1]
CATALOGUE = ROOT / "tests" / "test_bad_input.py"


def readme_paragraph() -> str:
    """The README's paragraph that names the catalogue."""
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    return next(paragraph for paragraph in text.split("\n\n") if "`tests/test_bad_input.py`" in paragraph)


def test_the_readme_gives_the_number_of_cases_pytest_collects():
    collected = subprocess.run(
        [sys.executable, "-m", "pytest", "--collect-only", "-q", "-p", "no:cacheprovider", "-o", "addopts=",
         str(CATALOGUE)],
        capture_output=True, text=True, check=True, cwd=ROOT, env={**os.environ, "PYTHONPATH": str(ROOT)},
    ).stdout
    cases = sum(line.startswith("tests/test_bad_input.py::") for line in collected.splitlines())
    stated = re.search(r"\*\*(\d+) cases\*\*", readme_paragraph())
    assert stated, "README.md's catalogue paragraph gives no '**N cases**'"
    assert int(stated[1]) == cases, f"README.md says {stated[1]} cases; the catalogue holds {cases}: update README.md"


def test_the_readme_names_every_command_the_catalogue_runs():
    """A command a case runs is the first word of an argument list, as ``check(capsys, ..., ["run", bag, ...])``."""
    names = {command.NAME for command in COMMANDS}
    tree = ast.parse(CATALOGUE.read_text(encoding="utf-8"))
    run = {
        node.elts[0].value
        for node in ast.walk(tree)
        if isinstance(node, ast.List) and node.elts and isinstance(node.elts[0], ast.Constant)
        and node.elts[0].value in names
    }
    assert run >= {"info", "run", "evaluate", "calibrate", "simulate"}  # the walk finds what the catalogue runs
    paragraph = readme_paragraph()
    missing = sorted(name for name in run if f"`{name}`" not in paragraph)
    assert not missing, f"the catalogue runs {missing}, which README.md's catalogue paragraph does not name"
