"""The static book ships its maths renderer: MathJax from the pinned package, referenced locally, no CDN."""

import shutil
import subprocess
import sys
from pathlib import Path

from bs4 import BeautifulSoup

ROOT = Path(__file__).resolve().parents[1]


def test_a_chapter_loads_mathjax_from_the_book(tmp_path):
    notebooks = tmp_path / "notebooks"
    notebooks.mkdir()
    shutil.copy(ROOT / "notebooks" / "06_kinematics.ipynb", notebooks)
    out = tmp_path / "book"
    command = [sys.executable, str(ROOT / "docs" / "build_book.py"), "--notebooks", str(notebooks), "--out", str(out)]
    subprocess.run(command, check=True, capture_output=True)
    page = BeautifulSoup((out / "06_kinematics.html").read_text(encoding="utf-8"), "html.parser")
    sources = [script["src"] for script in page.find_all("script", src=True)]
    mathjax = [source for source in sources if "MathJax.js" in source]
    assert mathjax == ["mathjax/MathJax.js?config=TeX-AMS-MML_HTMLorMML-full,Safe"]
    assert not any("mathjax" in source.lower() and "://" in source for source in sources)
    for needed in ("MathJax.js", "config/TeX-AMS-MML_HTMLorMML-full.js", "extensions/Safe.js"):
        assert (out / "mathjax" / needed).is_file(), needed
    assert any((out / "mathjax" / "fonts" / "HTML-CSS" / "STIX-Web" / "woff").rglob("*.woff"))
