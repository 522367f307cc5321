"""The static book's maths: MathJax from the pinned package, referenced locally, no CDN; formulas as the notebooks
write them; equations labelled in one chapter numbered and referred to from another."""

import shutil
import subprocess
import sys
from pathlib import Path

import nbformat
import pytest
from bs4 import BeautifulSoup

ROOT = Path(__file__).resolve().parents[1]
MATHJAX = "_static/mathjax/MathJax.js?config=TeX-AMS-MML_HTMLorMML-full,Safe"

# two chapters of the table of contents stood in for: one labels an equation each way MyST allows, the other refers
# to both
LABELLING = """# 03 · Labels

$$ u = f \\, \\frac{x}{z} + c $$ (pinhole-projection)

```{math}
:label: floor-scale
s = \\frac{h}{f}
```
"""
REFERRING = "# 05 · References\n\nProjection {eq}`pinhole-projection`, scale {eq}`floor-scale`.\n"


def _chapter(path: Path, markdown: str) -> None:
    """Write a one-cell notebook."""
    nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_markdown_cell(markdown)])
    nbformat.write(nb, path)


@pytest.fixture(scope="module")
def book(tmp_path_factory) -> Path:
    """A book of three chapters: a copy of 06_kinematics and the two stand-ins."""
    notebooks = tmp_path_factory.mktemp("notebooks")
    shutil.copy(ROOT / "notebooks" / "06_kinematics.ipynb", notebooks)
    _chapter(notebooks / "03_ground_plane_image.ipynb", LABELLING)
    _chapter(notebooks / "05_klt_flow.ipynb", REFERRING)
    out = tmp_path_factory.mktemp("book") / "book"
    command = [sys.executable, str(ROOT / "docs" / "build_book.py"), "--notebooks", str(notebooks), "--out", str(out)]
    subprocess.run(command, check=True, capture_output=True)
    return out


def _page(book: Path, name: str) -> BeautifulSoup:
    return BeautifulSoup((book / f"{name}.html").read_text(encoding="utf-8"), "html.parser")


def test_a_chapter_loads_mathjax_from_the_book(book):
    page = _page(book, "06_kinematics")
    sources = [script["src"] for script in page.find_all("script", src=True)]
    assert [source for source in sources if "MathJax.js" in source] == [MATHJAX]
    assert not any("://" in source for source in sources)
    (config,) = page.find_all("script", type="text/x-mathjax-config")
    assert "STIX-Web" in config.string
    for needed in ("MathJax.js", "config/TeX-AMS-MML_HTMLorMML-full.js", "extensions/Safe.js"):
        assert (book / "_static" / "mathjax" / needed).is_file(), needed
    assert any((book / "_static" / "mathjax" / "fonts" / "HTML-CSS" / "STIX-Web" / "woff").rglob("*.woff"))


def test_display_formulas_reach_mathjax_as_written(book):
    """A tagged matrix equation is sent whole: Sphinx's split environment, where \\tag is refused, is not added."""
    displays = [div.get_text() for div in _page(book, "06_kinematics").select("div.math")]
    (matrix,) = [text for text in displays if "\\tag{34}" in text]
    assert "split" not in matrix
    assert len([text for text in displays if "\\tag{" in text]) >= 12  # eqs. 23-34


def test_labelled_equations_are_numbered_and_referred_to_across_chapters(book):
    labelling = _page(book, "03_ground_plane_image")
    for label, number in (("pinhole-projection", "(1)"), ("floor-scale", "(2)")):
        equation = labelling.find("div", id=f"equation-{label}")
        assert equation.select_one("span.eqno").get_text().startswith(number)
    references = _page(book, "05_klt_flow").select("a.reference.internal[href^='03_ground_plane_image.html#']")
    assert [(a["href"].split("#")[1], a.get_text()) for a in references] == [
        ("equation-pinhole-projection", "(1)"),
        ("equation-floor-scale", "(2)"),
    ]
