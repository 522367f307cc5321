"""The static book in the browser with the network off: its formulas render (MathJax comes with the book) and its
search finds a chapter; no page asks for anything but its own files."""

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]

CHAPTER = "06_kinematics"
MATHJAX_DONE = (
    "window.MathJax && MathJax.Hub && MathJax.Hub.queue.pending === 0 && MathJax.Hub.queue.running === 0"
    " && document.querySelectorAll('.MathJax_Display').length > 0"
)


@pytest.fixture(scope="module")
def book(tmp_path_factory) -> Path:
    """A book of the one chapter."""
    notebooks = tmp_path_factory.mktemp("notebooks")
    shutil.copy(ROOT / "notebooks" / f"{CHAPTER}.ipynb", notebooks)
    out = tmp_path_factory.mktemp("book") / "book"
    command = [sys.executable, str(ROOT / "docs" / "build_book.py"), "--notebooks", str(notebooks), "--out", str(out)]
    subprocess.run(command, check=True, capture_output=True)
    return out


@pytest.fixture
def offline_page(browser):
    """A new page that may load files only; ``page.refused`` lists every other address it asked for."""
    page = browser.new_page()
    page.refused = []

    def offline(route):
        if route.request.url.startswith("file://"):
            route.continue_()
        else:
            page.refused.append(route.request.url)
            route.abort()

    page.route("**/*", offline)
    try:
        yield page
    finally:
        page.close()


def test_formulas_render_offline(book, offline_page):
    page = offline_page
    page.goto((book / f"{CHAPTER}.html").as_uri())
    page.wait_for_function(MATHJAX_DONE, timeout=120_000)
    displayed = page.locator(".MathJax_Display").count()
    # MathJax's errors, and its noErrors extension's frame around TeX it could not typeset
    errors = page.locator(".MathJax_Error, .merror, .noError").count()
    text = page.locator("main").inner_text()
    assert displayed >= 12, f"only {displayed} display formulas rendered"  # eqs. 23-34 at least
    assert errors == 0
    assert "$$" not in text and "\\tag{" not in text and "\\[" not in text, "raw LaTeX left in the page"
    assert page.refused == []


def test_search_finds_the_chapter_offline(book, offline_page):
    page = offline_page
    page.goto((book / "search.html").as_uri() + "?q=bicycle")
    page.wait_for_selector("#search-results ul.search li a", timeout=60_000)
    found = page.locator("#search-results ul.search li a").evaluate_all("links => links.map(a => a.href)")
    assert any(address.split("?")[0].endswith(f"/{CHAPTER}.html") for address in found), found
    assert page.refused == []
