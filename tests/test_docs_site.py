"""The documentation site builds with warnings as errors, and its link check finds broken links.

The build (``python -m sphinx -W -b html docs docs/_build/html``, the command README.md gives) takes
a minute or two and needs the ``docs`` extra, so it is marked slow and skipped when Sphinx or one of
its extensions is not installed. The link check of docs/conf.py is tested on a small site written
here, so that a check that passes everything would fail.
"""

from __future__ import annotations

import importlib.util
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


def _conf():
    spec = importlib.util.spec_from_file_location("docs_conf", ROOT / "docs" / "conf.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_link_check_finds_missing_files_and_anchors(tmp_path):
    (tmp_path / "api").mkdir()
    (tmp_path / "figure.png").write_bytes(b"\x89PNG\r\n\x1a\n")
    (tmp_path / "index.html").write_text(
        '<h1 id="top">x</h1><a href="#top">ok</a><a href="api/page.html#solve">ok</a><img src="figure.png">'
        '<a href="https://example.org/none">external, not checked</a>'
        '<a href="api/page.html#nowhere">bad anchor</a><a href="missing.html">bad file</a>'
        '<img src="figures/missing.png"><a href="#absent">bad anchor here</a>')
    (tmp_path / "api" / "page.html").write_text('<dt id="solve">solve</dt><a href="../index.html#top">ok</a>')
    broken = _conf().broken_links(tmp_path)
    assert sorted(broken) == sorted([
        "index.html: api/page.html#nowhere (no such anchor)",
        "index.html: missing.html",
        "index.html: figures/missing.png",
        "index.html: #absent (no such anchor)",
    ])


def test_every_markdown_page_is_in_the_site():
    """A page of docs/ left out of the toctree would be built but unreachable (Sphinx warns, -W fails);
    this says which one without building."""
    index = (ROOT / "docs" / "index.md").read_text()
    listed = set(re.findall(r"^([\w/]+)$", index, flags=re.MULTILINE))
    pages = {p.stem for p in (ROOT / "docs").glob("*.md")} - {"index"}
    assert pages <= listed, f"pages missing from docs/index.md's toctree: {sorted(pages - listed)}"


def test_api_summaries_do_not_stop_at_the_papers_equation_numbers(monkeypatch):
    """The API tables show each docstring's first sentence; "(Eq. 16)" does not end it once conf.setup ran."""
    autosummary = pytest.importorskip("sphinx.ext.autosummary", reason="pip install -e '.[docs]' builds the site")
    from docutils.frontend import get_default_settings
    from docutils.parsers.rst import Parser

    settings = get_default_settings(Parser)
    doc = ["The delay equation (Eq. 16) for the velocity, as in Fig. 5 and", "Sec. V. It holds for two rods."]
    assert autosummary.extract_summary(doc, settings) == "The delay equation (Eq."  # Sphinx alone
    monkeypatch.setattr(autosummary, "WELL_KNOWN_ABBREVIATIONS", autosummary.WELL_KNOWN_ABBREVIATIONS)

    class App:
        def connect(self, event, handler):
            pass

    _conf().setup(App())
    assert autosummary.extract_summary(doc, settings) == ("The delay equation (Eq. 16) for the velocity, "
                                                          "as in Fig. 5 and Sec. V.")
    assert autosummary.extract_summary(["Fig. 5: epsilon against kappa. Second."], settings) == (
        "Fig. 5: epsilon against kappa.")
    assert autosummary.extract_summary(["First, e.g. this. Second."], settings) == "First, e.g. this."


@pytest.mark.slow
def test_site_builds_with_warnings_as_errors(tmp_path):
    for module in ("sphinx", "myst_parser", "numpydoc", "pydata_sphinx_theme"):
        pytest.importorskip(module, reason="pip install -e '.[docs]' builds the site")
    out = tmp_path / "html"
    done = subprocess.run([sys.executable, "-m", "sphinx", "-W", "-q", "-b", "html", "docs", str(out)],
                          cwd=ROOT, capture_output=True, text=True, timeout=1800, check=False)
    assert done.returncode == 0, done.stderr[-4000:]
    # what a reader opens: the front page, the API page of the entry point, the gallery with its figures
    assert "collide" in (out / "index.html").read_text()
    api = (out / "api" / "generated" / "wavecontact.api.html").read_text()
    assert 'id="wavecontact.api.collide"' in api and "Parameters" in api
    gallery = (out / "examples.html").read_text()
    examples = sorted(p.stem for p in (ROOT / "examples").glob("[!_]*.py"))
    for name in examples:
        assert f"{name}.py" in gallery, f"the gallery lacks examples/{name}.py"
    images = re.findall(r'<img [^>]*src="([^"]+)"', gallery)
    assert len(images) >= len(examples) and all((out / src).exists() for src in images)
