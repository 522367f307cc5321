"""The static book's formulas render in the browser with the network off: MathJax comes with the book."""

import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

CHAPTER = "06_kinematics"


def test_formulas_render_offline(browser, tmp_path):
    notebooks = tmp_path / "notebooks"
    notebooks.mkdir()
    shutil.copy(ROOT / "notebooks" / f"{CHAPTER}.ipynb", notebooks)
    out = tmp_path / "book"
    command = [sys.executable, str(ROOT / "docs" / "build_book.py"), "--notebooks", str(notebooks), "--out", str(out)]
    subprocess.run(command, check=True, capture_output=True)

    page = browser.new_page()
    refused = []

    def offline(route):
        if route.request.url.startswith("file://"):
            route.continue_()
        else:
            refused.append(route.request.url)
            route.abort()

    page.route("**/*", offline)
    try:
        page.goto((out / f"{CHAPTER}.html").as_uri())
        page.wait_for_function(
            "window.MathJax && MathJax.Hub && MathJax.Hub.queue.pending === 0 && MathJax.Hub.queue.running === 0"
            " && document.querySelectorAll('.MathJax_Display').length > 0",
            timeout=120_000,
        )
        displayed = page.locator(".MathJax_Display").count()
        errors = page.locator(".MathJax_Error, .merror").count()
        markdown = "\n".join(page.locator(".jp-RenderedMarkdown").all_inner_texts())
    finally:
        page.close()
    assert displayed >= 12, f"only {displayed} display formulas rendered"  # eqs. 23-34 at least
    assert errors == 0
    assert "$$" not in markdown and "\\tag{" not in markdown, "raw LaTeX left in the page"
    assert not any("mathjax" in url.lower() for url in refused), refused
