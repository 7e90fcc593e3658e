"""Sphinx configuration of the wavecontact documentation site.

    pip install -e ".[docs]"
    python -m sphinx -W -b html docs docs/_build/html        # the site; warnings are errors
    python -m sphinx -W -b linkcheck docs docs/_build/linkcheck  # every link between pages and to files

The Markdown pages of docs/ are read as they are (MyST); the API reference is generated from the
numpydoc docstrings (autosummary + numpydoc); the examples' gallery is docs/examples.md, whose
outputs and figures ``python docs/generate.py`` writes from the scripts themselves.
"""

from __future__ import annotations

import os
import sys
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urlsplit

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))  # document this checkout, not whichever copy is installed
os.environ.setdefault("MPLBACKEND", "Agg")

import wavecontact

project = "wavecontact"
author = "the wavecontact authors"
copyright = "the wavecontact authors, MIT licence"
release = version = wavecontact.__version__

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
    "numpydoc",
]

source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
root_doc = "index"
exclude_patterns = ["_build", "**/__pycache__", "figures/**/*.md"]

# MyST: the pages are GitHub-flavoured Markdown; headings get anchors so "page.md#section" links resolve
myst_enable_extensions = ["dollarmath", "colon_fence", "deflist"]
myst_heading_anchors = 4

# API reference: one page per module, members listed from the docstrings
autosummary_generate = True
autosummary_imported_members = False
# each object documented once, on the page of the module that defines it (a package's re-exports are
# listed there, not described again)
autodoc_default_options = {"members": True, "ignore-module-all": True, "show-inheritance": True}
autodoc_typehints = "none"  # the numpydoc Parameters sections say the types and units
# the summary column of autosummary's tables is a docstring's first sentence, cut at the first ". " that
# is not an abbreviation: see setup() below for the paper's "Eq. 16", "Fig. 5", "Sec. V"
# the page contents beside an API page list a class's members under the class: "solve()", not "DelaySolver.solve()"
toc_object_entries_show_parents = "hide"
numpydoc_show_class_members = False  # autosummary lists them; numpydoc's own table would list them twice
numpydoc_class_members_toctree = False

html_theme = "pydata_sphinx_theme"
html_title = f"wavecontact {version}"
html_theme_options = {
    "header_links_before_dropdown": 3,  # with 4 the search box wrapped under the links at 1280 px
    "navbar_align": "left",
    "navigation_depth": 2,
    "show_toc_level": 2,
    "secondary_sidebar_items": ["page-toc"],
    "footer_start": ["copyright"],
    "footer_end": [],
}
html_static_path = ["_static"]
html_css_files = ["wavecontact.css"]
# the guide's pages are single pages: no empty "Section Navigation" column beside them (the API
# reference keeps its module tree)
html_sidebars = {path.stem: [] for path in Path(__file__).parent.glob("*.md")}

# no network here except package registries: the link check covers the pages' own links (between
# pages, to anchors and to files in the repository); external addresses are listed, not fetched
linkcheck_ignore = [r"https?://.*"]
linkcheck_anchors = True


# -- link check of the built site -------------------------------------------------------------------
# MyST already refuses (as a warning, an error under -W) a link to a page, heading or file it cannot
# resolve while reading; this check reads the written HTML and refuses any relative href or src
# whose file or #anchor is missing, which also covers figures and the generated API pages.


class _Links(HTMLParser):
    """The ``id`` attributes of one HTML page and its relative ``href``/``src`` targets."""

    def __init__(self):
        super().__init__()
        self.ids, self.targets = set(), []

    def handle_starttag(self, tag, attrs):
        for name, value in attrs:
            if name in ("id", "name") and value:
                self.ids.add(value)
            elif name in ("href", "src") and value and not urlsplit(value).scheme and not value.startswith("//"):
                self.targets.append(value)


def broken_links(html_dir: Path) -> list[str]:
    """``"page: target"`` for every relative link of the site whose file or anchor does not exist."""
    html_dir = html_dir.resolve()
    pages = {path: _Links() for path in html_dir.rglob("*.html") if "_static" not in path.parts}
    for path, links in pages.items():
        links.feed(path.read_text(encoding="utf-8"))
    broken = []
    for path, links in pages.items():
        for target in links.targets:
            parts = urlsplit(target)
            file = (path.parent / unquote(parts.path)).resolve() if parts.path else path
            if file.is_dir():
                file = file / "index.html"
            if not file.exists():
                broken.append(f"{path.relative_to(html_dir)}: {target}")
            elif parts.fragment and file.suffix == ".html" and unquote(parts.fragment) not in pages[file].ids:
                broken.append(f"{path.relative_to(html_dir)}: {target} (no such anchor)")
    return broken


def _check_links(app, exception):
    if exception is not None or app.builder.format != "html":
        return
    from sphinx.util import logging

    logger = logging.getLogger(__name__)
    for link in broken_links(Path(app.outdir)):
        logger.warning("broken link in %s", link)


# abbreviations that do not end a sentence, besides Sphinx's own ("e.g.", "i.e.", ...): the docstrings cite
# the paper as "Eq. 16", "Fig. 5", "Sec. V", "App. B" (also first: "Fig. 5: epsilon against kappa.");
# without these a summary reads "The delay equation (Eq." or just "Fig."
CITATION_ABBREVIATIONS = ("Eq.", "Eqs.", "Fig.", "Figs.", "Sec.", "App.", "Ref.")


def setup(app):
    from sphinx.ext import autosummary  # here, not at the top: the tests read this file without Sphinx

    autosummary.WELL_KNOWN_ABBREVIATIONS = (*autosummary.WELL_KNOWN_ABBREVIATIONS, *CITATION_ABBREVIATIONS)
    app.connect("build-finished", _check_links)
