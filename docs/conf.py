"""Sphinx configuration of pinbore's documentation: `make docs` builds it into build/docs/html.

Sphinx with MyST: the pages are Markdown (as the README and CHANGELOG are), autodoc reads the
docstrings, and the scene reference is generated from the scene models themselves
(docs/_ext/scene_reference.py), so neither can drift from the code. The build is offline: no
intersphinx, no theme or asset fetched from the network.
"""

import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
# The pages document the installed pinbore (`make` installs this checkout editable); the
# repository's root, which `python -m sphinx` run there puts first on the path, holds the
# roof's folder pinbore/ alone and would shadow it.
sys.path[:] = [p for p in sys.path if Path(p or ".").resolve() != ROOT]
sys.path.insert(0, str(DOCS / "_ext"))

project = "pinbore"
author = "the pinbore authors"
copyright = "pinbore authors"

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "scene_reference",     # docs/_ext: the scene keys from the pydantic models
    "package_modules",     # docs/_ext: the API pages list the modules they find
    "bench_table",         # docs/_ext: chosen columns of a bench/*.csv
    "demo_pages",          # docs/_ext: each script of demos/ (docs/demos links there) a page
]

source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
root_doc = "index"
# (.py is a demo's suffix, demo_pages: this file and the extensions are no pages)
exclude_patterns = ["_build", "schemas", "conf.py", "_ext"]
templates_path = []

# MyST: Markdown links to pages and files are checked like Sphinx references (a broken one
# is a warning, and warnings fail the build), `$...$` and `$$...$$` are maths.
myst_enable_extensions = ["colon_fence", "deflist"]
myst_all_links_external = False
myst_heading_anchors = 3
suppress_warnings = []

# Every cross-reference must resolve (sphinx-build -n). Autodoc still names a few classes from
# outside the project (pydantic's BaseModel as a base, numpy.ndarray and argparse's parser as
# property types, a property typed by a string) and classes built inside functions (the
# mechanism scene's tables made per kind): with no intersphinx (offline) they cannot resolve,
# so they are ignored; a reference to any other name of the project must resolve.
nitpicky = True
nitpick_ignore_regex = [
    ("py:class", r"(pydantic|numpy|argparse|typing|collections)\..*"),
    ("py:class", r"string"),
    ("py:class", r"pinbore\..*<locals>\..*"),
]

# The docstrings are plain text (formulas, tables, lists written for a terminal), not reST:
# package_modules shows them preformatted, as written.
autodoc_typehints = "none"
autodoc_member_order = "bysource"
autodoc_default_options = {"members": True, "show-inheritance": False}

# plain text unless a code block names its language (the docstrings, the scene tables' docstrings)
highlight_language = "text"

# The PyData theme (pydata-sphinx-theme, in the docs extra and requirements.lock), as NumPy and
# SciPy use: its tables scroll inside themselves, so the benchmark tables fit the page at any
# width. Its assets are in the package: nothing is fetched at build time or when a page opens.
html_theme = "pydata_sphinx_theme"
html_title = "pinbore"
html_static_path = []
html_theme_options = {
    "navbar_end": ["theme-switcher"],         # no icon links (they point outside)
    "secondary_sidebar_items": ["page-toc"],  # the page's sections, no "edit" or "source" links
    "show_toc_level": 2,
    "navigation_depth": 3,
    "sidebar_includehidden": False,           # no empty "Section Navigation" beside a page without subpages
    "footer_start": ["copyright"],
    "footer_end": [],
}
html_last_updated_fmt = None
html_copy_source = False
html_show_sourcelink = False
