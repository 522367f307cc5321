"""The words follow the results: every number a chapter's prose states is backed by the cells beside it.

A chapter is read in sections: a section runs from a heading (of any level) to the next one. A number in a markdown
cell (one with a decimal point, or a whole number followed by a unit: 7°, 12 %, 93 mm, 848 px, 3x) must be one of:

- **printed** by an output of a code cell of its own section (the same digits; a sign or thousands separator aside),
  or written in one of those code cells, where the reader sees it set. Digits printed in another section do not count:
  a sentence is checked against the output it describes, not against any output of the chapter;
- **marked** by the span around it, whose title says where it comes from:
  - ``<span title="printed in: Lucas-Kanade">0.072 px</span>``: a number printed in another section of the chapter,
    named by its heading's text (a "Paper and suite" box looking back, an exercise's answer); the number must be
    printed there;
  - ``<span title="the first paper, Table 4">0.058 m</span>`` (or "the second paper, ..."): a paper's figure, which
    must occur in that paper's text where the papers are at hand (``GPO_PAPERS_DIR``, else ``../shared/papers``);
  - ``<span title="= 752 / 600 * 0.25">0.31 m</span>``: a worked figure, the expression after "=" evaluated and
    rounded to the digits shown;
  - ``<span title="constant: the simulated T265 rig's height">0.12 m</span>``: a fixed constant of the suite or of
    the world, which must occur in gpo's sources or shipped configs.

Numbers in formulas ($...$), in code spans and in links are not prose; nor are section numbers (§3.3.1, Section 3.6).
"""

from __future__ import annotations

import ast
import json
import math
import operator
import os
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
NOTEBOOKS = sorted((ROOT / "notebooks").glob("*.ipynb"))
PAPERS = {"the first paper": "000_", "the second paper": "001_"}

UNIT = r"(?:°|%|‰|mm²|mm|cm|km|m²|m/s|m\b|px|\u00d7(?!\s*\d)|x\b|Hz|ms|s\b|rad\b|mrad\b|deg\b|frames\b|GB|MB|kB)"
NUMBER = re.compile(rf"(?<![\w.,/#§-])(?:\d{{1,3}}(?:,\d{{3}})+|\d+)(?:\.\d+)?(?=\s?{UNIT})|(?<![\w.,/#§])\d+\.\d+")
DECIMAL_ONLY = re.compile(r"(?<![\w.,/#§])\d+\.\d+(?![\d.]*\d)")
NOT_PROSE = re.compile(
    r"\$\$.*?\$\$|\$[^$\n]+\$"  # formulas
    r"|```.*?```|`[^`\n]*`"  # code
    r"|\]\([^)]*\)|https?://\S+"  # link targets
    r"|(?:§|[Ss]ections? |[Ee]qs?\. |[Ff]igs?\. |[Tt]ables? |[Aa]lgorithm |[Cc]hapters? |CC BY(?:-SA)? |v)"
    r"[\d.]+(?:[\u2013-][\d.]+)?",  # references to sections, equations, figures, tables, licences and versions
    re.S,
)
SPAN = re.compile(r'<span title="([^"]*)">(.*?)</span>', re.S)
HEADING = re.compile(r"^#{1,6} +(.+)$", re.M)
PRINTED_IN = "printed in: "
PRINTED_NUMBER = re.compile(r"\d+(?:\.\d+)?")

OPERATORS = {
    ast.Add: operator.add,
    ast.Sub: operator.sub,
    ast.Mult: operator.mul,
    ast.Div: operator.truediv,
    ast.Pow: operator.pow,
    ast.USub: operator.neg,
}
FUNCTIONS = {name: getattr(math, name) for name in ("sqrt", "tan", "atan", "sin", "cos", "radians", "degrees", "pi")}


def evaluate(expression: str) -> float:
    """The value of an arithmetic expression of numbers, + - * / **, and math's sqrt, tan, atan, sin, cos,
    radians, degrees and pi: what a worked figure's title may hold."""

    def value(node: ast.AST) -> float:
        if isinstance(node, ast.Constant) and isinstance(node.value, int | float):
            return node.value
        if isinstance(node, ast.BinOp) and type(node.op) in OPERATORS:
            return OPERATORS[type(node.op)](value(node.left), value(node.right))
        if isinstance(node, ast.UnaryOp) and type(node.op) in OPERATORS:
            return OPERATORS[type(node.op)](value(node.operand))
        if isinstance(node, ast.Name) and node.id == "pi":
            return math.pi
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id in FUNCTIONS:
            return FUNCTIONS[node.func.id](*(value(argument) for argument in node.args))
        raise ValueError(f"not a worked figure's expression: {ast.unparse(node)}")

    return value(ast.parse(expression.strip().replace("\u00d7", "*").replace("\u2212", "-"), mode="eval").body)


def canonical(number: str) -> str:
    """'1,000.50' -> '1000.50': the digits as printed, without thousands separators."""
    return number.replace(",", "")


def prose_numbers(text: str) -> list[tuple[str, str]]:
    """The numbers a markdown text states outside formulas, code, links and references, each with its context."""
    prose = NOT_PROSE.sub(" ", text)
    return [
        (canonical(match.group()), prose[max(0, match.start() - 50) : match.end() + 20])
        for match in NUMBER.finditer(prose)
    ]


def printed_numbers(notebook: dict) -> set[str]:
    """Every number in the chapter's text outputs and in its code cells' sources."""
    texts = []
    for cell in notebook["cells"]:
        if cell["cell_type"] != "code":
            continue
        texts.append("".join(cell["source"]))
        for output in cell.get("outputs", []):
            texts.append("".join(output.get("text", "")))
            for kind in ("text/plain", "text/markdown", "text/html", "text/latex"):
                texts.append("".join(output.get("data", {}).get(kind, "")))
    return {canonical(number) for number in PRINTED_NUMBER.findall(canonical("\n".join(texts)))}


def sections(notebook: dict) -> list[tuple[str, list[int]]]:
    """The chapter's sections in order: each heading's text and the indices of its cells, up to the next heading.
    Cells before the first heading form a section of their own, named ""."""
    found: list[tuple[str, list[int]]] = [("", [])]
    for index, cell in enumerate(notebook["cells"]):
        heading = HEADING.search("".join(cell["source"])) if cell["cell_type"] == "markdown" else None
        if heading:
            found.append((heading_text(heading.group(1)), []))
        found[-1][1].append(index)
    return [(name, cells) for name, cells in found if cells]


def heading_text(line: str) -> str:
    """A heading as a reader names it: without its marks, emphasis or formulas' dollars."""
    return " ".join(re.sub(r"[*_`$]", "", line).split())


def printed_by_section(notebook: dict) -> tuple[dict[int, set[str]], dict[str, set[str]]]:
    """The numbers printed in each cell's own section (by cell index), and in each section (by its heading)."""
    by_cell, by_heading = {}, {}
    for name, indices in sections(notebook):
        numbers = printed_numbers({"cells": [notebook["cells"][index] for index in indices]})
        by_heading.setdefault(name, set()).update(numbers)
        by_cell.update(dict.fromkeys(indices, numbers))
    return by_cell, by_heading


def markdown_cells(notebook: dict) -> list[tuple[int, str]]:
    return [
        (index, "".join(cell["source"]))
        for index, cell in enumerate(notebook["cells"])
        if cell["cell_type"] == "markdown"
    ]


def spans(notebook: dict) -> list[tuple[int, str, str]]:
    """(cell index, title, text) of every marked figure."""
    return [(index, title, text) for index, source in markdown_cells(notebook) for title, text in SPAN.findall(source)]


def papers_dir() -> Path | None:
    candidates = [os.environ.get("GPO_PAPERS_DIR"), ROOT.parent / "shared" / "papers"]
    return next((Path(path) for path in candidates if path and Path(path).is_dir()), None)


def load(path: Path) -> dict:
    return json.loads(path.read_text(encoding="utf-8"))


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda path: path.stem)
def test_every_number_in_the_prose_is_printed_in_its_section_or_marked(path):
    notebook = load(path)
    printed, _ = printed_by_section(notebook)
    unbacked = []
    for index, source in markdown_cells(notebook):
        for number, context in prose_numbers(SPAN.sub(" ", source)):
            if number not in printed[index]:
                unbacked.append(f"cell {index}: {number}  | ...{' '.join(context.split())}...")
    assert not unbacked, f"{len(unbacked)} numbers printed by no output of their section:\n" + "\n".join(unbacked)


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda path: path.stem)
def test_numbers_printed_in_another_section_are_printed_there(path):
    notebook = load(path)
    _, printed = printed_by_section(notebook)
    wrong = []
    for index, title, text in spans(notebook):
        if not title.startswith(PRINTED_IN):
            continue
        heading = heading_text(title[len(PRINTED_IN) :])
        if heading not in printed:
            wrong.append(f"cell {index}: no section is headed {heading!r}")
            continue
        wrong += [
            f"cell {index}: {n} is not printed in {heading!r}"
            for n in PRINTED_NUMBER.findall(canonical(text))
            if n not in printed[heading]
        ]
    assert not wrong, "\n".join(wrong)


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda path: path.stem)
def test_worked_figures_are_what_their_expression_gives(path):
    wrong = []
    for index, title, text in spans(load(path)):
        if not title.startswith("="):
            continue
        numbers = DECIMAL_ONLY.findall(text) or re.findall(r"\d+", text)
        assert len(numbers) == 1, f"cell {index}: a worked figure marks one number, got {text!r}"
        shown = numbers[0]
        decimals = len(shown.split(".")[1]) if "." in shown else 0
        if abs(round(abs(evaluate(title[1:])), decimals) - float(shown)) > 0.5 * 10**-decimals:
            wrong.append(f"cell {index}: {text} but {title[1:].strip()} = {evaluate(title[1:]):.6g}")
    assert not wrong, "\n".join(wrong)


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda path: path.stem)
def test_constants_occur_in_the_code(path):
    sources = "\n".join(
        file.read_text(encoding="utf-8")
        for pattern in ("gpo/**/*.py", "gpo/configs/*.yaml")
        for file in ROOT.glob(pattern)
    )
    code = {canonical(number) for number in PRINTED_NUMBER.findall(sources)} | printed_numbers(load(path))
    missing = []
    for index, title, text in spans(load(path)):
        if title.startswith(("=", PRINTED_IN, *PAPERS)):
            continue
        assert title.startswith("constant: "), (
            f"cell {index}: a span's title names a paper, '= ...', '{PRINTED_IN}...' or 'constant: '"
        )
        missing += [f"cell {index}: {n} ({title})" for n in PRINTED_NUMBER.findall(canonical(text)) if n not in code]
    assert not missing, "constants that occur nowhere in gpo's code or configs:\n" + "\n".join(missing)


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda path: path.stem)
def test_the_papers_figures_occur_in_the_papers(path):
    folder = papers_dir()
    if folder is None:
        pytest.skip("the papers' text is not at hand (GPO_PAPERS_DIR)")
    texts = {name: next(folder.glob(f"{prefix}*.txt")).read_text(encoding="utf-8") for name, prefix in PAPERS.items()}
    numbers = {name: {canonical(n) for n in PRINTED_NUMBER.findall(canonical(text))} for name, text in texts.items()}
    missing = []
    for index, title, text in spans(load(path)):
        paper = next((name for name in PAPERS if title.startswith(name)), None)
        if paper is not None:
            missing += [
                f"cell {index}: {n} ({title})"
                for n in PRINTED_NUMBER.findall(canonical(text))
                if n not in numbers[paper]
            ]
    assert not missing, "figures marked as a paper's that its text does not hold:\n" + "\n".join(missing)


@pytest.mark.parametrize(
    ("text", "numbers"),
    [
        ("the paper's model ends 7° short, 0.166 m and 12 % off", ["7", "0.166", "12"]),
        ("eqs. 25\u201334, §3.3.1, Section 3.6, CC BY 4.0 and $x = 0.5$ and `0.03`", []),
        ("a board of 8 \u00d7 6 squares, 1,234.5 mm", ["1234.5"]),
    ],
)
def test_prose_numbers_reads_what_a_reader_reads(text, numbers):
    assert [number for number, _ in prose_numbers(text)] == numbers


def test_a_number_is_checked_against_its_own_section_only():
    def markdown(text):
        return {"cell_type": "markdown", "source": text}

    def code(printed):
        return {"cell_type": "code", "source": "", "outputs": [{"output_type": "stream", "text": printed}]}

    notebook = {
        "cells": [
            markdown("## Lucas-Kanade"),
            code("converged to 0.072 px"),
            markdown("It settles to 0.072 px."),
            markdown("## The *median*"),
            code("median 1.711 px"),
            markdown("The median ends 0.072 px off, 1.711 px at worst."),
        ]
    }
    by_cell, by_heading = printed_by_section(notebook)
    assert [name for name, _ in sections(notebook)] == ["Lucas-Kanade", "The median"]
    assert "0.072" in by_cell[2] and "0.072" not in by_cell[5] and "1.711" in by_cell[5]
    assert by_heading["Lucas-Kanade"] == {"0.072"}


def test_a_worked_expression_is_evaluated():
    assert evaluate("752 / 600 \u00d7 0.25") == pytest.approx(0.31333, abs=1e-5)
    assert evaluate(" 0.5 / 30 / 0.001") == pytest.approx(16.667, abs=1e-3)  # as a title writes it: "= 0.5 / 30 ..."
    assert evaluate("degrees(atan(0.5))") == pytest.approx(26.565, abs=1e-3)
    with pytest.raises(ValueError):
        evaluate("__import__('os')")
