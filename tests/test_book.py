"""The static HTML book of `make book`: built from the committed notebooks, checked against the notebooks' own JSON."""

import functools
import hashlib
import json
import math
import subprocess
import sys
from pathlib import Path

import pytest
from bs4 import BeautifulSoup

ROOT = Path(__file__).resolve().parents[1]
NOTEBOOKS = sorted((ROOT / "notebooks").glob("*.ipynb"))
VIEW = "application/vnd.jupyter.widget-view+json"


def _digest(paths: list[Path]) -> str:
    """The hash of the files' bytes, in order."""
    return hashlib.sha256(b"".join(path.read_bytes() for path in paths)).hexdigest()


@pytest.fixture(scope="module")
def book(tmp_path_factory) -> Path:
    """The book, built once by the command line into a temporary directory; the notebooks are left as they were."""
    out = tmp_path_factory.mktemp("book")
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


def test_one_page_per_notebook_and_an_index_linking_every_section(book):
    index = _soup(book / "index.html")
    links = [a["href"] for a in index.find_all("a", href=True)]
    for notebook in NOTEBOOKS:
        page = f"{notebook.stem}.html"
        assert (book / page).is_file()
        headings = _markdown_headings(_notebook(notebook))
        title = index.find("a", href=page)
        assert title.get_text() == headings[0].lstrip("#").strip()
        sections = [link for link in links if link.startswith(page + "#")]
        assert len(sections) == sum(heading.startswith("## ") for heading in headings)
    assert sorted(path.name for path in book.glob("*.html")) == sorted(
        ["index.html", *(f"{n.stem}.html" for n in NOTEBOOKS)]
    )


def test_every_anchor_of_the_index_exists(book):
    ids = {}
    for link in _soup(book / "index.html").find_all("a", href=True):
        page, _, anchor = link["href"].partition("#")
        if page not in ids:
            ids[page] = {tag["id"] for tag in _soup(book / page).find_all(id=True)}
        assert not anchor or anchor in ids[page], link["href"]


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
    assert len(page.find_all("img")) >= sum("image/png" in output.get("data", {}) for output in outputs)


def test_every_page_leads_to_the_contents_and_on_through_the_book(book):
    page = _soup(book / "index.html").select_one("ul.chapters > li > a")["href"]
    visited = [page]
    while (page := _soup(book / page).find("a", rel="next")["href"]) != "index.html":
        visited.append(page)
        assert len(visited) <= len(NOTEBOOKS)
    assert sorted(visited) == sorted(f"{n.stem}.html" for n in NOTEBOOKS)
    for k, name in enumerate(visited):
        soup = _soup(book / name)
        for rel in ("contents", "prev", "next"):
            links = soup.find_all("a", rel=rel)
            assert len(links) == 2, (name, rel)
            assert all((book / link["href"]).is_file() for link in links)
        assert soup.find("a", rel="prev")["href"] == (visited[k - 1] if k else "index.html")
