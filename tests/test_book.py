"""The static HTML book of `make book`: built from the committed notebooks, checked against the notebooks' own JSON,
README.md's chapter table and docs/book/."""

import functools
import hashlib
import json
import math
import re
import subprocess
import sys
from pathlib import Path

import pytest
import yaml
from bs4 import BeautifulSoup

ROOT = Path(__file__).resolve().parents[1]
NOTEBOOKS = sorted((ROOT / "notebooks").glob("*.ipynb"))
BOOK_SOURCE = ROOT / "docs" / "book"
VIEW = "application/vnd.jupyter.widget-view+json"


def _digest(paths: list[Path]) -> str:
    """The hash of the files' bytes, in order."""
    return hashlib.sha256(b"".join(path.read_bytes() for path in paths)).hexdigest()


@pytest.fixture(scope="module")
def book(tmp_path_factory) -> Path:
    """The book, built once by the command line into a temporary directory; the notebooks are left as they were."""
    out = tmp_path_factory.mktemp("book") / "book"
    before = _digest(NOTEBOOKS)
    command = [sys.executable, str(ROOT / "docs" / "build_book.py"), "--notebooks", str(ROOT / "notebooks")]
    subprocess.run([*command, "--out", str(out)], check=True, capture_output=True)
    assert _digest(NOTEBOOKS) == before
    return out


@functools.cache
def _soup(path: Path) -> BeautifulSoup:
    """A page, parsed once."""
    return BeautifulSoup(path.read_text(encoding="utf-8"), "html.parser")


def _notebook(path: Path) -> dict:
    """A notebook's JSON."""
    return json.loads(path.read_text(encoding="utf-8"))


def _markdown_headings(nb: dict) -> list[str]:
    """Every markdown heading line of the notebook outside fenced code, as written."""
    headings = []
    for cell in nb["cells"]:
        if cell["cell_type"] == "markdown":
            fenced = False
            for line in "".join(cell["source"]).splitlines():
                fenced ^= line.lstrip().startswith("```")
                if not fenced and line.startswith("#"):
                    headings.append(line)
    return headings


def _plain(text: str) -> str:
    """A heading as the page shows it: no leading #s, no code or emphasis marks, typographic apostrophes."""
    return re.sub(r"[`*]", "", text.lstrip("#")).replace("'", "\u2019").strip()


def _readme_parts() -> dict[str, list[str]]:
    """The notebooks named by README.md's chapter tables, in its order, by the heading of the part above each table."""
    text = (ROOT / "README.md").read_text(encoding="utf-8").split("\n## Chapters\n", 1)[1].split("\n## ", 1)[0]
    return {
        heading: re.findall(r"^\| \[`([^`]+)`\]\(notebooks/\1\.ipynb\)", table, flags=re.MULTILINE)
        for heading, table in re.findall(r"^### (.+?)\n(.*?)(?=^### |\Z)", text, flags=re.MULTILINE | re.DOTALL)
    }


def _readme_chapters() -> list[str]:
    """The notebooks named by README.md's chapter tables, in its order."""
    return [name for names in _readme_parts().values() for name in names]


def _toc_parts() -> dict[str, list[str]]:
    """docs/book/_toc.yml's parts: each caption and its pages, in order."""
    parts = yaml.safe_load((BOOK_SOURCE / "_toc.yml").read_text())["parts"]
    return {part["caption"]: [entry["file"] for entry in part["chapters"]] for part in parts}


def _toc() -> list[str]:
    """docs/book/_toc.yml's pages after the front page, in order."""
    return [page for pages in _toc_parts().values() for page in pages]


def _state(nb: dict) -> dict:
    """The notebook's saved widget models, by model id."""
    return nb["metadata"].get("widgets", {}).get("application/vnd.jupyter.widget-state+json", {}).get("state", {})


def _reachable(state: dict, model_id: str) -> list[dict]:
    """The model states below a widget view, following "IPY_MODEL_" references in "children"."""
    found, todo = [], [model_id]
    while todo:
        model = state[todo.pop()]
        found.append(model)
        todo += [child.removeprefix("IPY_MODEL_") for child in model["state"].get("children", [])]
    return found


def _views(nb: dict) -> list[str]:
    """The model ids of the notebook's widget-view outputs, in order."""
    outputs = [output for cell in nb["cells"] for output in cell.get("outputs", [])]
    return [output["data"][VIEW]["model_id"] for output in outputs if VIEW in output.get("data", {})]


def _shown_controls(line) -> dict[str, str]:
    """The "name = value" pairs of one static panel line."""
    items = line.get_text().split(": ", 1)[1].split(" · ")
    return dict(item.strip().rpartition(" = ")[::2] for item in items)


def _expected(control: dict) -> str | float | None:
    """What a control's default should read: its option label(s), its bool, or its number (None: not a control)."""
    if "_options_labels" in control:
        index, labels = control["index"], control["_options_labels"]
        if index is None or index == []:
            return "none"
        return ", ".join(labels[i] for i in index) if isinstance(index, list) else labels[index]
    value = control.get("value")
    return str(value) if isinstance(value, bool) else value


def test_the_table_of_contents_follows_the_readme_and_holds_every_notebook():
    chapters = _readme_chapters()
    assert sorted(chapters) == sorted(path.stem for path in NOTEBOOKS)
    assert _toc() == [*chapters, "references"]


def test_the_book_has_two_parts_the_method_then_the_lab():
    parts = _toc_parts()
    assert list(parts) == ["The method", "The lab", "References"]
    assert _readme_parts() == {"The method": parts["The method"], "The lab": parts["The lab"]}
    assert all(name[:2].isdigit() for name in parts["The method"])
    assert parts["The lab"] and not any(name[:2].isdigit() for name in parts["The lab"])


def test_the_sidebar_lists_the_pages_in_reading_order(book):
    order = ["index", *_toc()]
    for name in order:
        nav = _soup(book / f"{name}.html").select_one("nav.bd-docs-nav")
        assert [caption.get_text(strip=True) for caption in nav.select("p.caption")] == list(_toc_parts()), name
        links = [a["href"].removesuffix(".html") for a in nav.select("a.reference.internal")]
        assert [link if link != "#" else name for link in links] == order, name


def test_every_page_leads_on_through_the_book(book):
    order = ["index", *_toc()]
    for k, name in enumerate(order):
        head = _soup(book / f"{name}.html").head
        following, previous = head.find("link", rel="next"), head.find("link", rel="prev")
        assert (following["href"] if following else None) == (f"{order[k + 1]}.html" if k + 1 < len(order) else None)
        assert (previous["href"] if previous else None) == (f"{order[k - 1]}.html" if k else None)


def test_the_front_page_links_every_chapter_and_its_sections(book):
    parts = _soup(book / "index.html").select("div.toctree-wrapper")
    assert [part.select_one("p.caption").get_text(strip=True) for part in parts] == list(_toc_parts())
    for part, pages in zip(parts, _toc_parts().values(), strict=True):
        chapters = [link["href"] for link in part.find_all("a", href=True) if "#" not in link["href"]]
        assert chapters == [f"{page}.html" for page in pages]
    links = [link for part in parts for link in part.find_all("a", href=True)]
    for notebook in NOTEBOOKS:
        page = f"{notebook.stem}.html"
        assert (book / page).is_file()
        headings = _markdown_headings(_notebook(notebook))
        titles = [link.get_text() for link in links if link["href"] == page]
        assert titles == [_plain(headings[0])], notebook.stem
        sections = {link.get_text() for link in links if link["href"].startswith(page + "#")}
        assert {_plain(h) for h in headings if h.startswith("## ")} <= sections, notebook.stem


def test_every_anchor_of_the_front_page_exists(book):
    ids = {}
    for link in _soup(book / "index.html").select("div.toctree-wrapper a[href]"):
        page, _, anchor = link["href"].partition("#")
        if page not in ids:
            ids[page] = {tag["id"] for tag in _soup(book / page).find_all(id=True)}
        assert not anchor or anchor in ids[page], link["href"]


def test_the_search_index_holds_every_chapter(book):
    assert (book / "search.html").is_file()
    index = (book / "searchindex.js").read_text(encoding="utf-8")
    found = json.loads(index[index.index("(") + 1 : index.rindex(")")])
    assert set(found["docnames"]) == {"index", *_toc()}
    docnames = found["docnames"]

    def pages(stem: str) -> set[str]:
        """The pages a word (as stemmed) is found on, in their text or their headings."""
        found_in = []
        for where in (found["terms"], found["titleterms"]):
            listed = where.get(stem, [])
            found_in += listed if isinstance(listed, list) else [listed]
        return {docnames[k] for k in found_in}

    assert "02_cubemap" in pages("cubemap")
    assert "06_kinematics" in pages("bicycl")


def test_the_two_papers_are_cited_by_title(book):
    references = _soup(book / "references.html").get_text()
    for entry in re.findall(r"title\s*=\s*\{\{(.+)\}\},", (BOOK_SOURCE / "references.bib").read_text(encoding="utf-8")):
        assert entry in " ".join(references.split())
        assert entry in " ".join(_soup(book / "index.html").get_text().split())
    citations = _soup(book / "index.html").select('a[href^="references.html#"]')
    assert len(citations) == 2


def test_nothing_is_loaded_from_the_web(book):
    for page in book.glob("*.html"):
        soup = _soup(page)
        for tag, attribute in (("script", "src"), ("link", "href"), ("img", "src"), ("iframe", "src")):
            for element in soup.find_all(tag, attrs={attribute: True}):
                assert "//" not in element[attribute], (page.name, str(element)[:200])
        assert "require.js" not in page.read_text(encoding="utf-8")


def test_no_widget_views_and_no_widget_manager(book):
    for page in book.glob("*.html"):
        text = page.read_text(encoding="utf-8")
        assert VIEW not in text
        assert "application/vnd.jupyter.widget-state+json" not in text
        assert "@jupyter-widgets/html-manager" not in text


def test_the_eucm_panel_shows_its_default_alpha(book):
    state = _state(_notebook(ROOT / "notebooks" / "01_eucm_model.ipynb"))
    (alpha,) = [m["state"]["value"] for m in state.values() if m["state"].get("description") == "alpha"]
    assert f"alpha = {alpha:.2f}" in _soup(book / "01_eucm_model.html").get_text()


@pytest.mark.parametrize("notebook", NOTEBOOKS, ids=lambda path: path.stem)
def test_panels_show_their_defaults_and_every_figure(book, notebook):
    nb, page = _notebook(notebook), _soup(book / f"{notebook.stem}.html")
    state, lines = _state(nb), page.select("p.book-panel")
    assert len(lines) == len(_views(nb))
    panels = [_reachable(state, view) for view in _views(nb)]
    for models, line in zip(panels, lines, strict=True):
        shown = _shown_controls(line)
        for control in (model["state"] for model in models if model["state"].get("description")):
            expected = _expected(control)
            if isinstance(expected, float | int):
                assert math.isclose(float(shown[control["description"]]), expected, rel_tol=0.05, abs_tol=0.005)
            elif expected is not None:
                assert shown[control["description"]] == expected
    outputs = [out for cell in nb["cells"] for out in cell.get("outputs", [])]
    outputs += [
        out for models in panels for m in models if m["model_name"] == "OutputModel" for out in m["state"]["outputs"]
    ]
    images = page.select("main img")
    assert len(images) >= sum("image/png" in output.get("data", {}) for output in outputs)
    assert all((book / image["src"]).is_file() for image in images if not image["src"].startswith("data:"))
