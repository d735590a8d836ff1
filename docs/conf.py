"""Sphinx configuration of granplate's documentation site.

Build it with ``python -m sphinx -W --keep-going -b html docs docs/_build/html``
(``python -m pip install ".[docs]"`` first). Why Sphinx + the PyData theme + MyST is said
in docs/about-docs.md.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
# the checkout's granplate first, here and in the kernels that execute the tutorials
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(DOCS / "_ext"))
os.environ["PYTHONPATH"] = os.pathsep.join([str(ROOT), *filter(None, [os.environ.get("PYTHONPATH")])])
# the kernels draw inline (matplotlib-inline); a backend set outside would hide the figures
os.environ.pop("MPLBACKEND", None)

from granplate.version import __version__  # noqa: E402

project = "granplate"
author = "the granplate authors"
copyright = "the granplate authors, MIT licence"
release = version = __version__

extensions = [
    "myst_nb",  # MyST Markdown pages and MyST notebooks, executed at build time
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "sphinx.ext.viewcode",
    "sphinxarg.ext",
    "granplate_docs",  # the generated reference pages and the link check (docs/_ext)
]

source_suffix = {".md": "myst-nb", ".ipynb": "myst-nb"}
root_doc = "index"
exclude_patterns = [
    "_build",
    "_generated_src",
    "studies",
    "examples",
    "Thumbs.db",
    ".DS_Store",
    "**.ipynb_checkpoints",
]
# warnings are errors (-W) and every cross-reference must resolve
nitpicky = True
nitpick_ignore_regex = [
    # types from other packages that autodoc names in signatures (no intersphinx: offline)
    (r"py:class", r"(numpy|np|xr|xarray|pathlib|typing|collections|dask|optuna|matplotlib|os)\..*"),
    (r"py:class", r"(Path|Any|Callable|Iterable|Mapping|Sequence|Dataset|DataArray|ndarray|NamedTuple)"),
    (r"py:class", r"granplate\..*"),  # internal classes not part of the public API
    (r"py:class", r"(optional|default.*|array-like|dict of .*|list of .*)"),
]
suppress_warnings = [
    "myst.header",  # a page may start its sections below level 2
    "misc.highlighting_failure",  # a JSON sample with "..." is drawn unhighlighted
    "myst.domains",  # sphinx-argparse's domain cannot answer MyST's any-reference lookups
]

# code blocks without a language (sample output) are drawn as plain text
highlight_language = "none"

# MyST
myst_enable_extensions = ["colon_fence", "deflist", "attrs_inline"]
myst_heading_anchors = 3
myst_all_links_external = False

# notebooks: executed at build time, results kept in a cache keyed by the page's code
nb_execution_mode = os.environ.get("GRANPLATE_DOCS_EXECUTE", "cache")
nb_execution_cache_path = str(DOCS / "_build" / ".jupyter_cache")
nb_execution_timeout = 600
nb_execution_raise_on_error = True
nb_execution_in_temp = True
nb_execution_show_tb = True
nb_merge_streams = True

# autodoc: the public API, from the docstrings (Google/NumPy style through napoleon)
autodoc_default_options = {"members": False, "undoc-members": False}
autodoc_typehints = "description"
autodoc_typehints_format = "short"
autodoc_preserve_defaults = True
autodoc_member_order = "bysource"
napoleon_google_docstring = True
napoleon_numpy_docstring = True

# HTML
html_theme = "pydata_sphinx_theme"
html_title = f"granplate {release}"
html_static_path = ["_static"]
html_css_files = ["granplate.css"]
html_extra_path = ["validation.html"]
html_theme_options = {
    "navbar_align": "left",
    "show_toc_level": 2,
    "navigation_with_keys": False,
    "header_links_before_dropdown": 6,
    "secondary_sidebar_items": ["page-toc"],
    "footer_start": ["copyright"],
    "footer_end": ["sphinx-version"],
}
html_show_sourcelink = False
html_context = {"default_mode": "light"}
