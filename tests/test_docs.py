"""The documentation says what the commands print.

Cheap generated blocks are re-run whole and compared (wall times masked); the expensive ones
are spot-checked: a few of their numbers recomputed here, or compared with independent values
(MODEL.md, Eq. 11). Every `wavecontact ...` command shown in README.md and docs/ must parse.
"""

from __future__ import annotations

import importlib.util
import math
import re
import shlex
import sys
from pathlib import Path

import pytest

import wavecontact
from wavecontact.cli import build_parser

ROOT = Path(__file__).resolve().parent.parent
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


def _generator():
    spec = importlib.util.spec_from_file_location("docs_generate", ROOT / "docs" / "generate.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up
    spec.loader.exec_module(module)
    return module


generate = _generator()
BLOCKS = {block.name: block for block in generate.BLOCKS}


def block_text(name: str) -> str:
    block = BLOCKS[name]
    body = generate.page_blocks(ROOT / block.page).get(name)
    assert body is not None, f"{block.page} lacks the generated block {name}"
    assert body.strip(), f"{block.page}: block {name} is empty; run python docs/generate.py {name}"
    return body


def test_every_marked_block_has_a_generator_and_every_generator_a_block():
    marked = {}
    for page in PAGES:
        for name in generate.page_blocks(page):
            marked[name] = str(page.relative_to(ROOT))
    assert marked == {name: block.page for name, block in BLOCKS.items()}


@pytest.mark.parametrize("name", sorted(n for n, b in BLOCKS.items() if b.cheap))
def test_cheap_blocks_are_what_their_commands_print(name):
    fresh = generate.render(BLOCKS[name])
    assert generate.mask_times(block_text(name)) == generate.mask_times(fresh), (
        f"{BLOCKS[name].page} is out of date: python docs/generate.py {name}")


def test_masking_hides_wall_times_only():
    row = "      400   0.753013243099  1.827e-09    2.03          28.235      3320"
    compare = "fem     P1 lumped, 100 elements              0.64669776105   6.7e-07     13.243 1.2e+05 element_steps"
    masked = generate.mask_times(row + "\nsolve 3.11 ms, numba kernel preparation 560 ms (23.4 s)\n" + compare)
    assert "0.753013243099  1.827e-09    2.03" in masked and "3320" in masked
    assert "28.235" not in masked and "3.11" not in masked and "560" not in masked and "23.4" not in masked
    assert "0.64669776105   6.7e-07" in masked and "13.243" not in masked and "1.2e+05 element_steps" in masked


def _converge_rows(text: str) -> dict:
    """``{(label, elements): restitution text}`` of a `wavecontact converge` output."""
    rows, label = {}, None
    for line in text.splitlines():
        heading = re.match(r"^(P\d \w+): observed order", line)
        if heading:
            label = heading.group(1)
            continue
        row = re.match(r"^\s+(\d+)\s+(\d\.\d+)\s", line)
        if row and label:
            rows[(label, int(row.group(1)))] = row.group(2)
    return rows


@pytest.mark.parametrize(("name", "kappa", "contact"), [("convergence-kappa-20", 20.0, "exponential"),
                                                       ("convergence-kappa-inf", math.inf, "hard")])
def test_convergence_tables_hold_what_the_solver_gives(name, kappa, contact):
    text = block_text(name)
    rows = _converge_rows(text)
    assert {label for label, _ in rows} == {"P1 lumped", "P1 consistent", "P2 lumped", "P2 consistent"}
    assert {n for _, n in rows} == {25, 50, 100, 200, 400}
    reference = float(re.search(r"reference epsilon = (\S+)", text).group(1))
    # MODEL.md section 5 (independent of this package) and the hard-core limit epsilon = gamma
    assert reference == pytest.approx(0.7530132413 if math.isfinite(kappa) else 0.6, abs=1e-9)
    for (label, elements) in (("P1 lumped", 25), ("P2 lumped", 25)):
        order, mass = int(label[1]), label.split()[1]
        result = wavecontact.collide(0.6, kappa, solver="fem", contact=contact, elements=elements, order=order,
                                     mass=mass)
        assert f"{result.restitution:.12f}" == rows[(label, elements)], (name, label, elements)


def test_equipartition_table_matches_eq_11():
    text = block_text("ring-equipartition")
    rows = re.findall(r"^\| (\d+) \| (\d\.\d{4}) \| (\d\.\d{4}) \|", text, flags=re.MULTILINE)
    assert [int(n) for n, _, _ in rows] == [10, 20, 40, 75, 150]
    for n, eq11, finite in rows:
        # Eq. 11 of the paper (MODEL.md 4): <eta> = 0.423 / ln(2 N)
        assert float(eq11) == pytest.approx(0.423 / math.log(2 * int(n)), abs=6e-4)
        assert abs(float(finite) - float(eq11)) < 0.01  # finite-N mean close to the large-N law


def test_compare_page_uses_the_model_reference():
    text = block_text("usage-compare")
    reference = float(re.search(r"reference epsilon = (\S+)", text).group(1))
    assert reference == pytest.approx(0.646697087, abs=1e-9)  # MODEL.md section 5


def _shown_commands():
    """Every `wavecontact ...` line in a code block of the pages (continuations joined)."""
    for page in PAGES:
        inside, lines = False, []
        for line in page.read_text().splitlines():
            if line.startswith("```"):
                inside = not inside
                continue
            if inside:
                lines.append(line)
        joined = re.sub(r"\\\n\s*", " ", "\n".join(lines))
        for line in joined.splitlines():
            line = line.strip().removeprefix("$ ").split("#")[0].strip()
            if line.startswith("wavecontact ") and not re.search(r"\[|\||\.\.\.", line):
                yield page.name, line  # a command (a synopsis with [options] or ... is not)


def test_every_command_shown_in_the_docs_parses():
    parser = build_parser()
    shown = list(_shown_commands())
    assert len(shown) >= 10
    for page, line in shown:
        argv = shlex.split(line)[1:]
        try:
            parser.parse_args(argv)
        except SystemExit as exc:
            if argv[-1:] in (["--help"], ["--version"]) and exc.code == 0:
                continue
            pytest.fail(f"{page}: `{line}` does not parse")


def test_examples_page_shows_every_example_and_its_figure():
    text = (ROOT / "docs" / "examples.md").read_text()
    sections = re.split(r"^## ", text, flags=re.MULTILINE)
    for script in sorted((ROOT / "examples").glob("[!_]*.py")):
        (section,) = [s for s in sections if f"examples/{script.name}" in s]
        figures = re.findall(r"\(figures/examples/([\w.-]+\.png)\)", section)
        assert figures, f"docs/examples.md shows no figure of {script.name}"
        for figure in figures:
            assert (ROOT / "docs" / "figures" / "examples" / figure).exists()


@pytest.mark.slow
def test_every_command_shown_in_the_docs_runs(tmp_path):
    """A fresh user's walk through README.md and docs/: each command shown ends with status 0
    (run in an empty directory, so the files it writes land there)."""
    import os
    import subprocess

    seen = set()
    for page, line in _shown_commands():
        if line in seen:
            continue
        seen.add(line)
        done = subprocess.run([sys.executable, "-m", "wavecontact", *shlex.split(line)[1:]], cwd=tmp_path,
                              env={**os.environ, "PYTHONPATH": str(ROOT)}, capture_output=True, text=True,
                              timeout=1800, check=False)
        assert done.returncode == 0, f"{page}: `{line}` failed:\n{done.stderr[-2000:]}"
