"""Display formulas go to MathJax as the notebooks wrote them, as JupyterLab shows them.

Sphinx wraps a display formula holding a line break (``\\\\``) in a ``split`` environment, where MathJax refuses
``\\tag``: the chapters' matrix equations, tagged with the paper's own numbers, would show as errors. Here such a
formula is sent whole between ``\\[`` and ``\\]``; a labelled one still gets the book's number and its link.
Formulas that Sphinx must assemble (several parts, ``nowrap``, amsmath environments) are left to the renderer
already in place.
"""

from docutils import nodes
from sphinx.application import Sphinx
from sphinx.locale import _
from sphinx.util.math import get_node_equation_number


def _as_written(previous):
    """A MathJax display visitor that sends one-part formulas unchanged and hands the rest to ``previous``."""

    def visit(self, node: nodes.math_block) -> None:
        if node["nowrap"] or "amsmath" in node["classes"] or "\n\n" in node.astext().strip():
            previous(self, node)
            return
        self.body.append(self.starttag(node, "div", CLASS="math notranslate nohighlight"))
        if node["number"]:
            self.body.append(f'<span class="eqno">({get_node_equation_number(self, node)})')
            self.add_permalink_ref(node, _("Link to this equation"))
            self.body.append("</span>")
        opening, closing = self.builder.config.mathjax_display
        self.body.append(f"{opening}{self.encode(node.astext())}{closing}</div>\n")
        raise nodes.SkipNode

    return visit


def _install(app: Sphinx) -> None:
    """Wrap the MathJax display renderer, after MyST-Parser has put its own in place."""
    renderers = app.registry.html_block_math_renderers
    if "mathjax" in renderers:
        visit, depart = renderers["mathjax"]
        renderers["mathjax"] = (_as_written(visit), depart)


def setup(app: Sphinx) -> dict:
    """The Sphinx extension: installed when the builder starts, after MyST-Parser (priority 500)."""
    app.connect("builder-inited", _install, priority=900)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
