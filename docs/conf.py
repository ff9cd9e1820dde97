"""Sphinx configuration of the piezobearing documentation.

Build: ``sphinx-build -W -b html docs docs/_build/html`` (warnings are errors; the
docs' packages are the ``docs`` extra: ``pip install -e ".[docs]"``).
"""

import sys
from pathlib import Path

import piezobearing

DOCS = Path(__file__).resolve().parent
sys.path.insert(0, str(DOCS / "_ext"))  # the project's own reference generators

project = "piezobearing"
author = "piezobearing contributors"
copyright = "piezobearing contributors, MIT licence"
release = piezobearing.__version__
version = release

extensions = [
    "myst_parser",
    "numpydoc",
    "sphinx.ext.autodoc",
    "piezobearing_mathml",
    "piezobearing_reference",
    "piezobearing_performance",
    "piezobearing_figures",
]

html_math_renderer = "mathml"  # docs/_ext/piezobearing_mathml.py: MathML at build time, no CDN

source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
root_doc = "index"
exclude_patterns = ["_build", "Thumbs.db", ".DS_Store"]

myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence", "deflist"]
myst_heading_anchors = 3

autodoc_default_options = {"members": True, "member-order": "bysource"}
autodoc_typehints = "none"  # numpydoc's Parameters sections carry the types and units
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False

html_theme = "pydata_sphinx_theme"
html_title = f"piezobearing {release}"
html_static_path = ["_static"]
html_css_files = ["piezobearing.css"]
html_theme_options = {
    "logo": {"text": f"piezobearing {release}"},  # the version on every page
    "navigation_depth": 3,
    "show_toc_level": 2,
    "navbar_align": "left",
    "header_links_before_dropdown": 7,
    "footer_start": ["copyright"],
    "footer_end": [],
    # pages whose tables need the whole width: no "on this page" column either
    "secondary_sidebar_items": {"**": ["page-toc", "edit-this-page", "sourcelink"], "validation/sensor_comparison": [], "performance": []},
}
# no section navigation where a page has no section (the top-level pages) or needs the width (the tables)
html_sidebars = {
    page: []
    for page in (
        "index",
        "getting_started",
        "performance",
        "gallery",
        "changelog",
        "validation/sensor_comparison",
        "reference/configuration",
        "reference/cli",
    )
}
html_show_sourcelink = False
