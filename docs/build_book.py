"""Build the executed notebooks into the static HTML book of `make book`, without running them.

The book is a Jupyter Book 1 (Sphinx, MyST-NB, sphinx-book-theme): its configuration, table of contents, front page
and references are in docs/book/. This script lays them in a temporary folder beside the output with a copy of each
chapter listed in docs/book/_toc.yml, builds that folder with ``jupyter-book build`` and renames the HTML into place:
a search page, the chapters in a sidebar, each page's sections beside it, the papers as citations.

Two things are done here because the book must read offline:

- the ipywidgets panels need no JavaScript: each widget view becomes what it stands for in the saved notebook, a
  line with its controls' default values followed by the panel's stored output, and the widget state is dropped
  (MyST-NB would otherwise load a widget manager and require.js from the web);
- the formulas are rendered by MathJax 2.7 from the pinned PyPI package jupyter-server-mathjax, copied among the
  book's static files (docs/book/_config.yml points ``mathjax_path`` at it): no CDN.

A notebook that the table of contents does not list stops the build; a chapter missing from ``--notebooks`` is left
out of the book, so that a few chapters build on their own.

    python docs/build_book.py --notebooks notebooks --out out/book
"""

import argparse
import html
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import jupyter_server_mathjax
import nbformat
import yaml

WIDGET_VIEW = "application/vnd.jupyter.widget-view+json"
WIDGET_STATE = "application/vnd.jupyter.widget-state+json"
BOOK = Path(__file__).resolve().parent / "book"
MATHJAX = Path(jupyter_server_mathjax.__file__).parent / "static"
JUPYTER_BOOK = Path(sys.executable).with_name("jupyter-book")


def toc_chapters(toc: Path = BOOK / "_toc.yml") -> list[str]:
    """The file names (without suffix) of the table of contents' chapters, part after part, in reading order."""
    return [
        entry["file"] for part in yaml.safe_load(toc.read_text(encoding="utf-8"))["parts"] for entry in part["chapters"]
    ]


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


def lay_out_sources(notebooks: Path, source: Path) -> list[str]:
    """Fill ``source`` with the book's own files, MathJax and a static copy of each chapter found in ``notebooks``;
    its _toc.yml lists only those chapters. Returns the chapters laid out, in reading order."""
    chapters = toc_chapters()
    found = {path.stem: path for path in notebooks.glob("*.ipynb")}
    unlisted = sorted(set(found) - set(chapters))
    if unlisted:
        raise SystemExit(f"{BOOK / '_toc.yml'} does not list {', '.join(unlisted)}: add each in its reading place")
    shutil.copytree(BOOK, source, ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copytree(MATHJAX, source / "_assets" / "mathjax")
    present = [name for name in chapters if name in found or (BOOK / f"{name}.md").is_file()]
    for name in present:
        if name in found:
            nb = without_widgets(nbformat.read(found[name], as_version=4))
            nbformat.write(nb, source / f"{name}.ipynb")
    toc = yaml.safe_load((BOOK / "_toc.yml").read_text(encoding="utf-8"))
    for part in toc["parts"]:
        part["chapters"] = [entry for entry in part["chapters"] if entry["file"] in present]
    toc["parts"] = [part for part in toc["parts"] if part["chapters"]]
    (source / "_toc.yml").write_text(yaml.safe_dump(toc, sort_keys=False), encoding="utf-8")
    return [name for name in present if name in found]


def build_book(notebooks: Path, out: Path) -> list[Path]:
    """Build the book of the notebooks in ``notebooks`` into ``out`` (replaced whole); returns the chapter pages."""
    if not JUPYTER_BOOK.is_file():
        raise SystemExit(f"no {JUPYTER_BOOK}: jupyter-book is installed from environment.txt")
    out = out.resolve()
    out.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=out.parent, prefix=f".{out.name}-") as work:
        source = Path(work) / "source"
        chapters = lay_out_sources(notebooks, source)
        command = [str(JUPYTER_BOOK), "build", str(source), "--path-output", work, "--builder", "html", "--all"]
        done = subprocess.run([*command, "--warningiserror", "--keep-going", "--quiet"], capture_output=True, text=True)
        if done.returncode:
            raise SystemExit(f"jupyter-book build failed:\n{done.stdout}{done.stderr}")
        if out.exists():
            shutil.rmtree(out)
        (Path(work) / "_build" / "html").rename(out)
    return [out / f"{name}.html" for name in chapters]


def main() -> None:
    """Command line: ``--notebooks DIR`` (default notebooks/) and ``--out DIR`` (default out/book)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--notebooks", type=Path, default=Path("notebooks"), help="the executed notebooks")
    parser.add_argument("--out", type=Path, default=Path("out/book"), help="where the HTML pages go")
    args = parser.parse_args()
    pages = build_book(args.notebooks, args.out)
    print(f"{len(pages)} chapters, index.html and search.html written to {args.out}")


if __name__ == "__main__":
    main()
