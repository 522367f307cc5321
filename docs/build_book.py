"""Build the executed notebooks into a static HTML book, without running them.

One page per chapter, named as its notebook (nbconvert's "lab" template; figures embedded as data URIs), with
"contents", "previous" and "next" links at its top and bottom, and an index.html listing every chapter's title
and its sections. Chapters follow the order of README.md's chapter table; notebooks it does not list come last.
The ipywidgets panels need no JavaScript: each is shown as it stands in the saved notebook, a line with its
controls' default values followed by the panel's stored output. The formulas are rendered by MathJax 2.7, shipped
with the book from the pinned PyPI package jupyter-server-mathjax (copied to out/book/mathjax/): the pages read
offline, with no CDN.

    python docs/build_book.py --notebooks notebooks --out out/book
"""

import argparse
import html
import shutil
from pathlib import Path

import jupyter_server_mathjax
import nbformat
from bs4 import BeautifulSoup, SoupStrainer
from jinja2 import DictLoader
from nbconvert import HTMLExporter

WIDGET_VIEW = "application/vnd.jupyter.widget-view+json"
WIDGET_STATE = "application/vnd.jupyter.widget-state+json"
README = Path(__file__).resolve().parents[1] / "README.md"
BOOK_TITLE = "gpo — visual odometry from the floor"
MATHJAX = Path(jupyter_server_mathjax.__file__).parent / "static"
MATHJAX_URL = "mathjax/MathJax.js?config=TeX-AMS-MML_HTMLorMML-full,Safe"
"""MathJax relative to a chapter page, with the configuration the package bundles (its only web font is STIX)."""

CHAPTER_TEMPLATE = """{%- extends 'index.html.j2' -%}
{% block extra_css %}
<script type="text/x-mathjax-config">
MathJax.Hub.Config({"HTML-CSS": {availableFonts: [], webFont: "STIX-Web", imageFont: null}});
</script>
<style type="text/css">
nav.book-nav { display: flex; gap: 1.5em; padding: 0.6em 1em; font-family: var(--jp-ui-font-family); }
nav.book-nav a { text-decoration: none; }
p.book-panel { font-family: var(--jp-code-font-family); }
</style>
{% endblock extra_css %}
{% block body_header %}{{ super() }}{{ resources.book_nav }}{% endblock body_header %}
{% block body_footer %}{{ resources.book_nav }}{{ super() }}{% endblock body_footer %}
"""

INDEX_PAGE = """<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8" />
<meta name="viewport" content="width=device-width, initial-scale=1.0">
<title>{title}</title>
<style type="text/css">
body {{ max-width: 52em; margin: 2em auto; padding: 0 1em; font-family: sans-serif; line-height: 1.5; }}
ul.chapters {{ list-style: none; padding-left: 0; }}
ul.chapters > li {{ margin-top: 0.8em; font-weight: bold; }}
ul.chapters ul {{ font-weight: normal; }}
a {{ text-decoration: none; }}
</style>
</head>
<body>
<h1>{title}</h1>
<p>The chapters as they read after a run. The interactive panels are shown at their default settings;
<code>make lab</code> opens the notebooks to move them.</p>
<ul class="chapters">
{chapters}
</ul>
</body>
</html>
"""


def reading_order(paths: list[Path], readme: Path = README) -> list[Path]:
    """The notebooks in the order README.md's chapter table lists them; those it does not list follow by name."""
    text = readme.read_text(encoding="utf-8") if readme.exists() else ""

    def rank(path: Path) -> tuple[bool, int, str]:
        position = text.find(f"{path.stem}.ipynb")
        return position < 0, position, path.name

    return sorted(paths, key=rank)


def chapter_title(nb: nbformat.NotebookNode, default: str) -> str:
    """The notebook's first markdown heading (outside fenced code), without its leading #s; ``default`` if none."""
    for cell in nb.cells:
        if cell.cell_type != "markdown":
            continue
        fenced = False
        for line in cell.source.splitlines():
            if line.lstrip().startswith("```"):
                fenced = not fenced
            elif not fenced and line.startswith("#"):
                return line.lstrip("#").strip()
    return default


def panel_models(state: dict, model_id: str) -> list[dict]:
    """The widget models of the panel rooted at ``model_id``, depth first through their "children"."""
    model = state.get(model_id)
    if model is None:
        return []
    models = [model]
    for child in model["state"].get("children", []):
        models += panel_models(state, child.removeprefix("IPY_MODEL_"))
    return models


def control_value(widget: dict) -> str:
    """A control's value as the panel shows it: the selected option label(s), or the value in its readout format."""
    if "_options_labels" in widget:
        labels, index = widget["_options_labels"], widget.get("index")
        if index is None or index == []:
            return "none"
        return ", ".join(labels[i] for i in index) if isinstance(index, list) else labels[index]
    value, readout = widget["value"], widget.get("readout_format")
    if readout and isinstance(value, int | float) and not isinstance(value, bool):
        return format(value, readout)
    return str(value)


def controls_line(models: list[dict]) -> str:
    """The panel's controls and their default values as one HTML paragraph, e.g. "alpha = 0.60 · beta = 1.10"."""
    controls = [
        f"{html.escape(m['state']['description'])} = {html.escape(control_value(m['state']))}"
        for m in models
        if m["state"].get("description") and ("value" in m["state"] or "index" in m["state"])
    ]
    return '<p class="book-panel">Panel at its defaults: ' + " · ".join(controls) + "</p>"


def static_panel(state: dict, model_id: str) -> list[nbformat.NotebookNode]:
    """The outputs that stand in for one widget view: its controls line, then its Output widgets' stored outputs."""
    models = panel_models(state, model_id)
    outputs = [nbformat.v4.new_output("display_data", data={"text/html": controls_line(models)})]
    for model in models:
        if model["model_name"] == "OutputModel":
            outputs += [nbformat.from_dict(output) for output in model["state"].get("outputs", [])]
    return outputs


def without_widgets(nb: nbformat.NotebookNode) -> nbformat.NotebookNode:
    """A copy of ``nb`` whose widget views are static panels and which carries no widget state."""
    nb = nbformat.from_dict(nb)
    state = nb.metadata.pop("widgets", {}).get(WIDGET_STATE, {}).get("state", {})
    for cell in nb.cells:
        outputs = []
        for output in cell.get("outputs", []):
            view = output.get("data", {}).get(WIDGET_VIEW)
            outputs += static_panel(state, view["model_id"]) if view else [output]
        if cell.cell_type == "code":
            cell.outputs = outputs
    return nb


def navigation(pages: list[str], titles: list[str], k: int) -> str:
    """The contents/previous/next bar of the k-th page; the first and last pages lead back to the contents."""
    previous = (pages[k - 1], titles[k - 1]) if k > 0 else ("index.html", "contents")
    following = (pages[k + 1], titles[k + 1]) if k + 1 < len(pages) else ("index.html", "contents")
    return (
        '<nav class="book-nav">'
        '<a href="index.html" rel="contents">contents</a>'
        f'<a href="{previous[0]}" rel="prev" title="{html.escape(previous[1])}">← previous</a>'
        f'<a href="{following[0]}" rel="next" title="{html.escape(following[1])}">next →</a>'
        "</nav>"
    )


def sections(page: str) -> list[tuple[str, str]]:
    """The (id, text) of each second-level heading of a chapter page, in order (only those with an id)."""
    soup = BeautifulSoup(page, "html.parser", parse_only=SoupStrainer("h2"))
    found = []
    for heading in soup.find_all("h2", id=True):
        for anchor in heading.select("a.anchor-link"):
            anchor.decompose()
        found.append((heading["id"], heading.get_text().strip()))
    return found


def index_entry(page: str, title: str, headings: list[tuple[str, str]]) -> str:
    """One chapter's item in the table of contents: its title, and a list of its sections."""
    items = "".join(f'<li><a href="{page}#{html.escape(i)}">{html.escape(text)}</a></li>' for i, text in headings)
    return f'<li><a href="{page}">{html.escape(title)}</a>\n<ul>{items}</ul></li>'


def build_book(notebooks: Path, out: Path) -> list[Path]:
    """Write one HTML page per notebook of ``notebooks`` and index.html into ``out``; returns the pages written."""
    paths = reading_order(sorted(notebooks.glob("*.ipynb")))
    chapters = [without_widgets(nbformat.read(path, as_version=4)) for path in paths]
    pages = [f"{path.stem}.html" for path in paths]
    titles = [chapter_title(nb, path.stem) for nb, path in zip(chapters, paths, strict=True)]
    exporter = HTMLExporter(
        template_name="lab",
        extra_loaders=[DictLoader({"book.html.j2": CHAPTER_TEMPLATE})],
        template_file="book.html.j2",
        mathjax_url=MATHJAX_URL,
    )
    out.mkdir(parents=True, exist_ok=True)
    shutil.copytree(MATHJAX, out / "mathjax", dirs_exist_ok=True)
    entries = []
    for k, nb in enumerate(chapters):
        nb.metadata["title"] = titles[k]
        body, _ = exporter.from_notebook_node(nb, resources={"book_nav": navigation(pages, titles, k)})
        (out / pages[k]).write_text(body, encoding="utf-8")
        entries.append(index_entry(pages[k], titles[k], sections(body)))
    index = INDEX_PAGE.format(title=html.escape(BOOK_TITLE), chapters="\n".join(entries))
    (out / "index.html").write_text(index, encoding="utf-8")
    return [out / page for page in pages]


def main() -> None:
    """Command line: ``--notebooks DIR`` (default notebooks/) and ``--out DIR`` (default out/book)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--notebooks", type=Path, default=Path("notebooks"), help="the executed notebooks")
    parser.add_argument("--out", type=Path, default=Path("out/book"), help="where the HTML pages go")
    args = parser.parse_args()
    pages = build_book(args.notebooks, args.out)
    print(f"{len(pages)} chapters and index.html written to {args.out}")


if __name__ == "__main__":
    main()
