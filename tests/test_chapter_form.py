"""Every chapter teaches the same way: cells short enough to read on one screen, and an answer a click away under
every "Try it yourself" item."""

import json
import re
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
