"""Math rendered to MathML when the site is built: no script, no network, a saved page keeps its equations.

Sphinx's ``mathjax`` renderer writes the LaTeX into the page and loads MathJax from a CDN to typeset it in the
browser, so an offline machine shows the raw LaTeX. Here ``latex2mathml`` (a pure-Python converter, pinned in the
``docs`` extra) turns each ``$...$`` and ``$$...$$`` into MathML at build time; browsers render MathML natively
(MathML Core: Chromium, Firefox, Safari). A formula the converter cannot read stops the build with its text.
"""

from __future__ import annotations

from docutils import nodes
from latex2mathml.converter import convert
from sphinx.errors import ExtensionError
from sphinx.util.math import get_node_equation_number


def to_mathml(latex: str, display: bool) -> str:
    """``latex`` as one ``<math>`` element (``display="block"`` for a displayed equation)."""
    try:
        return convert(latex.strip(), display="block" if display else "inline")
    except Exception as exc:  # the converter raises its own exception types, one per kind of bad input
        raise ExtensionError(f"math that latex2mathml cannot convert: {latex!r} ({type(exc).__name__}: {exc})") from exc


def _block_latex(text: str) -> str:
    """One LaTeX string for a displayed block: paragraphs (equations separated by a blank line) stacked."""
    parts = [p.strip() for p in text.split("\n\n") if p.strip()]
    if len(parts) == 1:
        return parts[0]
    return r"\begin{aligned}" + r"\\".join(parts) + r"\end{aligned}"


def visit_math(self, node: nodes.math) -> None:
    self.body.append(self.starttag(node, "span", "", CLASS="math"))
    self.body.append(to_mathml(node.astext(), display=False))
    self.body.append("</span>")
    raise nodes.SkipNode


def visit_displaymath(self, node: nodes.math_block) -> None:
    self.body.append(self.starttag(node, "div", CLASS="math"))
    if node["number"]:
        number = get_node_equation_number(self, node)
        self.body.append(f'<span class="eqno">({number})')
        self.add_permalink_ref(node, "Link to this equation")
        self.body.append("</span>")
    self.body.append(to_mathml(_block_latex(node.astext()), display=True))
    self.body.append("</div>\n")
    raise nodes.SkipNode


def setup(app):
    app.add_html_math_renderer("mathml", (visit_math, None), (visit_displaymath, None))
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
