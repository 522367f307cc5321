"""Every chapter teaches the same way: cells short enough to read on one screen, and an answer a click away under
every "Try it yourself" item."""

import json
import re
import statistics
from pathlib import Path

import pytest

NOTEBOOKS = sorted((Path(__file__).resolve().parents[1] / "notebooks").glob("*.ipynb"))
MARKDOWN_LINES = 25  # a screen of text
CODE_LINES = 30  # a cell a reader takes in at once; longer work belongs in the chapter's module
ITEM = re.compile(r"^(?:- |\d+\. |\*\*\d+\. )", re.M)  # "- ...", "1. ..." or "**1. A title.** ..."


def cells(path: Path, kind: str) -> list[str]:
    notebook = json.loads(path.read_text(encoding="utf-8"))
    return ["".join(cell["source"]) for cell in notebook["cells"] if cell["cell_type"] == kind]


def try_it_yourself(markdown: str) -> str:
    """The text of the "Try it yourself" section, up to the next heading of its level or above."""
    heading = re.search(r"^(#+) .*Try it yourself.*$", markdown, re.M)
    assert heading, "no 'Try it yourself' section"
    rest = markdown[heading.end() :]
    following = re.search(rf"^#{{1,{len(heading.group(1))}}} ", rest, re.M)
    return rest[: following.start()] if following else rest


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda path: path.stem)
def test_cells_are_short_enough_to_read_on_one_screen(path):
    long_text = [len(text.splitlines()) for text in cells(path, "markdown") if len(text.splitlines()) > MARKDOWN_LINES]
    long_code = [len(text.splitlines()) for text in cells(path, "code") if len(text.splitlines()) > CODE_LINES]
    assert not long_text, f"markdown cells of {long_text} lines (at most {MARKDOWN_LINES})"
    assert not long_code, f"code cells of {long_code} lines (at most {CODE_LINES})"


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda path: path.stem)
def test_every_exercise_has_its_answer_a_click_away(path):
    section = try_it_yourself("\n\n".join(cells(path, "markdown")))
    items, answers = len(ITEM.findall(section)), section.count("<details><summary>")
    assert items > 0 and answers == items, f"{items} exercises, {answers} answers"


def test_the_section_ends_at_the_next_heading():
    text = "## Try it yourself\n- one\n<details><summary>Answer</summary>a</details>\n## Further reading\n- a book"
    assert ITEM.findall(try_it_yourself(text)) == ["- "]


# The method's chapters (00-10) read as one line each, at the rhythm of the book we admire (STYLE.md, "The book's
# rhythm"): measured as a reader meets a chapter, the way ../shared/tools/book_rhythm.py measures it. The lab's
# chapters (A, B, ...) hold the research and are free of these bounds.
METHOD = [path for path in NOTEBOOKS if path.stem[:2].isdigit()]
LAB = [path for path in NOTEBOOKS if not path.stem[:2].isdigit()]
TAG = re.compile(r"<[^>]+>")
MATH = re.compile(r"\$\$.*?\$\$|\$[^$\n]+\$", re.S)
FENCE = re.compile(r"```.*?```", re.S)
TICK = re.compile(r"`[^`\n]+`")
RHYTHM = {  # measure: (bound, "most" or "least")
    "median_cell_words": (100, "most"),
    "figures_per_1000_words": (2.0, "least"),
    "identifiers_per_1000_words": (8.0, "most"),
    "words_before_code": (400, "most"),
    "most_words_without_a_figure": (800, "most"),
}
IDENTIFIERS_IN_A_CHAPTER_OF_COMMANDS = 25.0  # chapter 10 teaches commands: its identifiers are what a reader types
MACHINERY = re.compile(
    r"\btests?/|\bbenchmarks/|floating-point paths?|\bnbval\b|\bCI\b|\.ci/|\btest_\w+\.py|\btuned?\b|\btuning\b"
)


def words(text: str) -> int:
    """Words a reader sees: tags, formulas, fenced code and code spans left out (a formula or code span is one)."""
    text = FENCE.sub(" ", MATH.sub(" x ", text))
    text = TICK.sub(" x ", TAG.sub(" ", text))
    return len(re.findall(r"[A-Za-z0-9][\w'.,%°-]*", text))


def rhythm(path: Path) -> dict[str, float]:
    notebook = json.loads(path.read_text(encoding="utf-8"))
    prose, identifiers, before_code, seen_code, figures, run, longest = [], 0, 0, False, 0, 0, 0
    for cell in notebook["cells"]:
        source = "".join(cell["source"])
        if cell["cell_type"] == "markdown":
            prose.append(words(source))
            identifiers += len(TICK.findall(FENCE.sub(" ", source)))
            run += prose[-1]
            before_code += 0 if seen_code else prose[-1]
        elif cell["cell_type"] == "code" and source.strip():
            seen_code = True
            pictures = sum(any(k.startswith("image/") for k in out.get("data", {})) for out in cell.get("outputs", []))
            if pictures:
                figures += pictures
                longest, run = max(longest, run), 0
    total = sum(prose) or 1
    return {
        "median_cell_words": statistics.median(prose or [0]),
        "figures_per_1000_words": 1000 * figures / total,
        "identifiers_per_1000_words": 1000 * identifiers / total,
        "words_before_code": before_code,
        "most_words_without_a_figure": max(longest, run),
    }


@pytest.mark.parametrize("path", METHOD, ids=lambda path: path.stem)
def test_a_method_chapter_reads_at_the_books_rhythm(path):
    measured, missed = rhythm(path), []
    for measure, (bound, kind) in RHYTHM.items():
        if measure == "identifiers_per_1000_words" and path.stem.startswith("10_"):
            bound = IDENTIFIERS_IN_A_CHAPTER_OF_COMMANDS
        if (measured[measure] > bound) if kind == "most" else (measured[measure] < bound):
            missed.append(f"{measure} {measured[measure]:.1f} (at {kind} {bound})")
    assert not missed, "; ".join(missed)


@pytest.mark.parametrize("path", METHOD, ids=lambda path: path.stem)
def test_a_method_chapter_never_speaks_of_the_suites_machinery(path):
    found = [
        f"{match.group()!r} in ...{' '.join(text[max(0, match.start() - 40) : match.end() + 30].split())}..."
        for text in (MATH.sub(" ", source) for source in cells(path, "markdown"))
        for match in MACHINERY.finditer(text)
    ]
    assert not found, "\n".join(found)


def test_the_rhythm_is_measured_as_a_reader_meets_it():
    assert words("The median vector, `median_of`, $x = 1$ <b>and</b> 0.07 px.") == 8
    assert MACHINERY.search("as `tests/test_fusion.py` shows") and MACHINERY.search("on every floating-point path")
    assert not MACHINERY.search("the test of the invariance check, attested by the paper")
