"""The documentation says what the commands print.

Cheap generated blocks are re-run whole and compared (wall times masked); the expensive ones
are spot-checked: a few of their numbers recomputed here, or compared with independent values
(MODEL.md, Eq. 8, Eq. 11). Every `wavecontact ...` command shown in README.md and docs/ must parse,
and the cheap ones run (docs/run_commands.py; `python docs/run_commands.py --all` runs every one).
"""

from __future__ import annotations

import importlib.util
import math
import re
import shlex
import sys
from pathlib import Path

import numpy as np
import pytest

import wavecontact
from wavecontact.cli import build_parser

ROOT = Path(__file__).resolve().parent.parent
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


def _load(name):
    spec = importlib.util.spec_from_file_location(f"docs_{name}", ROOT / "docs" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up
    spec.loader.exec_module(module)
    return module


generate = _load("generate")
BLOCKS = {block.name: block for block in generate.BLOCKS}
commands = _load("run_commands")


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


SCRIPT_BLOCK = re.compile(r"<!-- (?P<name>[\w.-]+):(?:start|begin) -->\n(?P<body>.*?)<!-- (?P=name):end -->", re.DOTALL)


def test_every_script_written_block_has_a_writer_and_names_its_command():
    """Blocks that scripts write (`--update-docs`; not docs/generate.py's): non-empty and named by some
    script in benchmarks/ or docs/; the benchmark blocks also start with the command that wrote them."""
    scripts = "\n".join(path.read_text() for folder in ("benchmarks", "docs") for path in (ROOT / folder).glob("*.py"))
    bodies = {}
    for page in PAGES:
        for match in SCRIPT_BLOCK.finditer(page.read_text()):
            if not match["name"].startswith("generated:"):
                bodies[match["name"]] = (page.name, match["body"].strip())
    for name, (page, body) in bodies.items():
        assert body, f"{page}: block {name} is empty"
        assert re.search(rf"(?:[\"']|<!-- ){re.escape(name)}[\"':]", scripts), f"{page}: no script names block {name}"
    for name in ("bench-fem", "profile-explicit-step", "interleaved-lanes", "bench-modal", "bench-two-materials", "bench_markov",
                 "markov-fig10", "markov-balance", "markov-samples", "markov-cooling", "markov-defect", "markov-nu-max", "bench-bath",
                 "fem-cost-model", "bath-studies-boltzmann", "bath-studies-uptake", "bath-studies-grid",
                 "bath-studies-modes", "bath-studies-kappa"):
        page, body = bodies[name]
        assert body.startswith("`python "), f"{page}: block {name} does not start with its command"


@pytest.mark.parametrize("name", sorted(n for n, b in BLOCKS.items() if b.cheap))
def test_cheap_blocks_are_what_their_commands_print(name):
    fresh = generate.render(BLOCKS[name], write_figures=False)
    assert generate.mask(BLOCKS[name], block_text(name)) == generate.mask(BLOCKS[name], fresh), (
        f"{BLOCKS[name].page} is out of date: python docs/generate.py {name}")


# The expensive blocks that CI re-runs whole after the default run (.ci/run: ``-m docs_ci``, kernels cached
# by the run before): together about SECOND_PASS_SECONDS s on 2 cores; the cheap blocks run in every pass
# (test above) and ``python -m pytest -m slow -k expensive_blocks`` (or ``python docs/generate.py --check``,
# the same comparison) runs every block.
SECOND_PASS = ("convergence-kappa-20", "convergence-kappa-inf", "fem-two-materials", "fem-remainder-orders",
               "fem-discretizations", "fem-discretizations-100", "fem-quadrature", "fem-gamma-one", "fem-dispersive",
               "materials-striker", "example-compare_discretizations_and_solvers", "example-mesh_convergence_study",
               "example-paraview_fields", "example-restitution_map_gamma_kappa")
# measured by python docs/generate.py --check on a fresh clone (it prints each block's time): the convergence
# blocks 19.3 + 14.8 s at load 11.5, the rest 2-6 s each (41 s together) at load 4-6. Re-measured whole on a
# fresh worktree at load 7-14 (every block up to date): these 14 blocks 242 s together, 133 s of it the first
# block compiling on an empty numba cache, then 4-23 s each; the left-out blocks 11-55 s each (usage-compare 11,
# materials-map 19, modal-accuracy 20, the ring blocks 22-43, theory 42, the long examples 48-55), except
# fem-default 187 s and ring-spread 339 s
SECOND_PASS_SECONDS = 75  # these 14 tests: 44.8 s wall at load 4 (pytest -m docs_ci, kernels cached)


@pytest.mark.slow
@pytest.mark.parametrize("name", [pytest.param(name, marks=pytest.mark.docs_ci) if name in SECOND_PASS else name
                                  for name in sorted(n for n, b in BLOCKS.items() if not b.cheap)])
def test_expensive_blocks_are_what_their_commands_print(name):
    """What ``python docs/generate.py --check`` compares, block by block (wall times masked)."""
    block = BLOCKS[name]
    fresh = generate.render(block, write_figures=False)
    current = block_text(name)
    assert generate.mask(block, current) == generate.mask(block, fresh), (
        f"{block.page} is out of date (python docs/generate.py {name}):\n{generate.stale_lines(block, current, fresh)}")


def test_second_pass_blocks_are_expensive_blocks():
    assert set(SECOND_PASS) <= {n for n, b in BLOCKS.items() if not b.cheap}


def test_error_estimate_tuning_figures_are_what_the_stored_sweeps_give():
    """docs/error_estimates.md section 1: the ratios the FE estimate's orders rest on (seconds: it reads
    the stored sweeps, no solve)."""
    spec = importlib.util.spec_from_file_location("estimate_tuning_figures",
                                                  ROOT / "benchmarks" / "estimate_tuning_figures.py")
    script = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(script)
    text = (ROOT / "docs" / "error_estimates.md").read_text()
    block = text.split("<!-- tuning-figures:start -->\n", 1)[1].split("<!-- tuning-figures:end -->", 1)[0]
    assert block == "\n".join(script.table([2027, 2028, 2029, 2030])) + "\n", (
        "stale: python benchmarks/estimate_tuning_figures.py --update-docs")


def test_checking_a_page_writes_no_figure_into_the_repository():
    """``generate.py --check`` renders with ``write_figures=False``: the example's figures go to a scratch
    directory, and its output still names docs/figures as the page does."""
    block = BLOCKS["example-restitution_vs_kappa"]
    figures = ROOT / "docs" / "figures"
    before = {p: p.stat().st_mtime_ns for p in figures.rglob("*") if p.is_file()}
    fresh = generate.render(block, write_figures=False)
    after = {p: p.stat().st_mtime_ns for p in figures.rglob("*") if p.is_file()}
    assert after == before
    assert "docs/figures/examples" in fresh and "/tmp" not in fresh and "figures/examples" in block_text(block.name)


def test_masking_hides_wall_times_only():
    row = "      400   0.753013243099  1.827e-09    2.03          28.235      3320"
    compare = "fem     P1 lumped, 100 elements              0.64669776105   6.7e-07     13.243 1.2e+05 element_steps"
    masked = generate.mask_times(row + "\nsolve 3.11 ms, numba kernel preparation 560 ms (23.4 s)\n" + compare)
    assert "0.753013243099  1.827e-09    2.03" in masked and "3320" in masked
    assert "28.235" not in masked and "3.11" not in masked and "560" not in masked and "23.4" not in masked
    assert "0.64669776105   6.7e-07" in masked and "13.243" not in masked and "1.2e+05 element_steps" in masked


def test_masking_ignores_the_padding_of_a_time_of_another_width():
    block = BLOCKS["convergence-kappa-20"]
    fast = "      100   0.753013094070  1.472e-07    2.79           3.377       830"
    slow = "      100   0.753013094070  1.472e-07    2.79          29.974       830"
    assert generate.mask(block, fast) == generate.mask(block, slow)
    assert generate.mask(block, fast) != generate.mask(block, fast.replace("1.472e-07", "1.473e-07"))


def test_every_column_of_wall_times_is_masked_and_nothing_else():
    """A printed table's time column (``time [ms]``, ``time (ms)``, ``median ms``...) differs from run to run:
    a new run's times must not make a block stale, a changed epsilon or error must."""
    block = BLOCKS["example-compare_discretizations_and_solvers"]
    text = block_text(block.name)
    rows = [line for line in text.splitlines() if line.startswith(("delay ", "fem P1 lumped"))]
    assert len(rows) == 2
    slower = text
    for row in rows:
        cells = row.rsplit(None, 1)
        slower = slower.replace(row, f"{cells[0]}  {float(cells[1]) * 7.3 + 100:.3f}")
    assert slower != text and generate.mask(block, slower) == generate.mask(block, text)
    epsilon = rows[0].split()[1]
    changed = text.replace(epsilon, epsilon[:-1] + ("1" if epsilon[-1] != "1" else "2"), 1)
    assert generate.mask(block, changed) != generate.mask(block, text)
    # in every block, other digits under a time column's header leave the masked text as it was
    columns = 0
    for name, block in BLOCKS.items():
        span, lines = None, []
        for line in block_text(name).split("\n"):
            header = generate.TIME_HEADER.search(line)
            if header:
                span, columns = header.span(), columns + 1
            elif not line.strip():
                span = None
            elif span is not None:
                cell = re.sub(r"\d", "7", line[span[0]:span[1]])
                line = line[:span[0]] + cell + line[span[1]:]
            lines.append(line)
        assert generate.mask(block, "\n".join(lines)) == generate.mask(block, block_text(name)), name
    assert columns >= 5


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


def test_every_command_shown_in_the_docs_parses():
    parser = build_parser()
    shown = [(page, line) for page, line in commands.shown_commands() if line.startswith("wavecontact ")]
    assert len(shown) >= 10
    for page, line in shown:
        argv = shlex.split(line)[1:]
        try:
            parser.parse_args(argv)
        except SystemExit as exc:
            if argv[-1:] in (["--help"], ["--version"]) and exc.code == 0:
                continue
            pytest.fail(f"{page}: `{line}` does not parse")


def test_every_command_is_found_and_the_cheap_list_is_current():
    shown = {line: page for page, line in commands.shown_commands()}
    assert "wavecontact collide --gamma 0.6 --kappa 100" in shown  # README's quickstart, after its `&&`
    assert not any(line.startswith("wavecontact.") for line in shown)  # Python code is not a command
    stale = sorted(commands.CHEAP - set(shown))
    assert not stale, f"docs/run_commands.py lists commands no page shows: {stale}"
    runnable = [line for line in shown if commands.classify(line) != "not run"]
    for line in runnable:
        commands.argv_of(line)  # every command shown can be started


# commands whose output a cheap generated block already re-runs and compares are not run twice
RUN_BY_BLOCKS = {generate.display(argv) for block in generate.BLOCKS if block.cheap for argv in block.commands}


@pytest.mark.parametrize("command", sorted(commands.CHEAP - RUN_BY_BLOCKS))
def test_cheap_command_shown_in_the_docs_runs(command, tmp_path, monkeypatch, capsys):
    """A user's walk through the pages (the expensive commands: python docs/run_commands.py --all).
    --help pages are compared whole by the usage-help block.

    As ``commands.run`` does it (an empty directory holding the checkout's directories the command names;
    status 0; every output path written), through the CLI's ``main`` in this process: a new interpreter per
    command only paid the imports again.  ``python docs/run_commands.py`` runs them as processes."""
    from wavecontact.cli import main

    words = shlex.split(command)
    assert words[0] == "wavecontact", command
    commands.prepare_scratch(command, tmp_path)
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("COLUMNS", "100")
    try:
        status = main(words[1:])
    except SystemExit as ended:  # --help and --version end through argparse
        status = ended.code
    err = capsys.readouterr().err
    assert status in (0, None), f"{command}: exit status {status}: {err.strip()[-1500:]}"
    missing = commands.missing_outputs(command, tmp_path)
    assert not missing, f"{command}: did not write {', '.join(missing)}"


def test_written_paths_are_the_output_options():
    line = "wavecontact collide --solver fem --plot w.png --fields out/ --xt-plot xt.png --json --out a b --no-progress"
    assert commands.written_paths(line) == ["w.png", "out/", "xt.png", "a", "b"]


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
def test_every_command_shown_in_the_docs_runs():
    """Every command, expensive ones and examples included (tens of minutes)."""
    assert commands.main(["--all"]) == 0


def _table_rows(name: str) -> list:
    """The cells of every data row of a generated Markdown table."""
    rows = []
    for line in block_text(name).splitlines():
        if line.startswith("|") and not line.startswith("|---"):
            rows.append([cell.strip() for cell in line.strip("|").split("|")])
    return rows[1:]  # without the header


def test_fem_accuracy_tables_hold_what_the_solver_gives():
    """A cheap cell of each generated table of docs/fem.md, recomputed (the coarsest meshes)."""
    sys.path.insert(0, str(ROOT / "tests"))
    from test_fem_far_ends import ALUMINIUM, STEEL, characteristic_impact

    # two materials against the characteristic solution (exact, independent of the FE code)
    row = next(r for r in _table_rows("fem-two-materials") if r[0].startswith("aluminium") and r[1] == "200")
    exact, _ = characteristic_impact(STEEL, ALUMINIUM, 1.0, 0.0)
    assert row[0] == f"aluminium 0.3 m (exact {exact:.10f})"
    result = wavecontact.solve(wavecontact.Scene(rods=(STEEL, ALUMINIUM), velocities=(1.0, 0.0),
                                                 contact=wavecontact.Hard()), "fem", elements=200)
    assert abs(result.restitution - exact) < 1e-12 and abs(float(row[3])) < 1e-12
    # fixed remainders and the default table, against the delay solver at rtol = 1e-13
    reference = wavecontact.collide(0.6, 100, solver="delay", rtol=1e-13).restitution
    assert abs(reference - 0.6466970871) < 1e-9  # MODEL.md section 5
    (zero,) = [r for r in _table_rows("fem-remainder-orders") if r[0] == "0"]
    error = abs(wavecontact.collide(0.6, 100, solver="fem", elements=24).restitution - reference)
    assert zero[1:3] == ["24", f"{error:.1e}"]
    (row,) = [r for r in _table_rows("fem-default") if r[:2] == ["0.6", "100"]]
    error = wavecontact.collide(0.6, 100, solver="fem", elements=200).restitution - reference
    assert row[2] == f"{error:+.1e}"
    (hard,) = [r for r in _table_rows("fem-default") if r[:2] == ["0.6", "inf"]]
    assert all(abs(float(cell)) < 1e-12 for cell in hard[2:])  # the exact lattice: epsilon = gamma
    # other discretizations at kappa = 20: P2 lumped on 24 elements; observed orders near 2 and 1
    kappa20 = wavecontact.collide(0.6, 20, solver="delay", rtol=1e-13).restitution
    rows = _table_rows("fem-discretizations")
    (p2,) = [r for r in rows if r[:2] == ["P2 lumped", "auto (force)"]]
    assert p2[2] == f"{abs(wavecontact.collide(0.6, 20, solver='fem', elements=24, order=2).restitution - kappa20):.1e}"
    for r in rows:
        assert abs(float(r[-1]) - (2.0 if r[1].startswith("auto") else 1.0)) < 0.3, r


def test_modal_accuracy_block_holds_what_the_solver_gives():
    text = block_text("modal-accuracy")
    (line,) = [x for x in text.splitlines() if x.split()[:2] == ["static", "10"]]
    error = abs(wavecontact.collide(0.1, math.inf, solver="modal", modes=10, correction="static").restitution - 0.1)
    assert line.split()[2] == f"{error:.2e}" and "(0.1, inf)" in line  # hard limit: epsilon = gamma
    worst = [float(x.split()[2]) for x in text.splitlines() if x.strip().startswith("end-response")]
    assert len(worst) == 3 and max(worst) < 1e-6  # issue 13's target, met at 10 modes


def test_two_material_contacts_block_agrees_with_the_one_contact_proof():
    text = block_text("theory-two-material-contacts")
    assert "0 with more than one contact, 0 whose gap shrinks" in text  # docs/theory.md proves it
    assert "0 with a second force pulse" in text
    change = float(re.search(r"30 more round trips (\S+)", text).group(1))
    assert change < 1e-12


def test_ring_result_matches_the_first_collisions_and_eq_8_and_11():
    from wavecontact.studies.ring import run_ring
    from wavecontact.studies.ring_statistics import relaxation_collisions

    rows = {r[0]: r for r in _table_rows("ring-result")}
    modes = 75
    eq8 = 0.5 / (2 * (2 * modes + 1))  # mu V^2 / (2 (2N + 1)), mu = 1/2 (MODEL.md 4)
    (mean_row,) = [r for k, r in rows.items() if k.startswith("stationary mean `E_tr`")]
    assert mean_row[2] == f"Eq. 8: {eq8:.7f}"
    (eta_row,) = [r for k, r in rows.items() if k.startswith("stationary mean `eta`")]
    harmonic = sum(1.0 / k for k in range(1, 2 * modes + 1))
    finite = 1 - (harmonic - 1) / math.log(2 * modes)  # <h> = H_2N - 1 for uniform weights on the simplex
    assert eta_row[2] == f"Eq. 11: {0.423 / math.log(2 * modes):.4f} (finite-N value {finite:.4f})"
    # the relaxation count needs only the first collisions of the (deterministic) run
    relaxed = int(rows["collisions until `E_tr` is in its stationary band"][1])
    run = run_ring(0.6173, 4000, modes=modes, collisions=relaxed + 21, progress=False)
    assert relaxation_collisions(run.translational_energy, eq8) == relaxed
    spread = block_text("ring-spread")
    assert re.search(r"\(120 collisions each\): (\d+)", spread).group(1) == str(relaxed)  # the same run


def test_ring_page_finite_n_entropy_differences():
    """docs/ring.md: Eq. 11 and the finite-N mean differ by 5 % at N = 12 and 0.8 % at N = 75."""
    text = (ROOT / "docs" / "ring.md").read_text()
    assert "differ by 5 % at\n`N = 12` and by 0.8 % at `N = 75`" in text
    for modes, percent in ((12, 5.0), (75, 0.8)):
        harmonic = sum(1.0 / k for k in range(1, 2 * modes + 1))
        eq11, finite = 0.423 / math.log(2 * modes), 1 - (harmonic - 1) / math.log(2 * modes)
        assert round(100 * (eq11 - finite) / eq11, 1) == pytest.approx(percent, abs=0.05 * percent + 0.05)


def test_equipartition_variants_match_eq_11():
    text = block_text("ring-equipartition-variants")
    rows = re.findall(r"^\| (\d+) \| (\d\.\d{4}) \| (\d\.\d{4}) \|", text, flags=re.MULTILINE)
    assert [int(n) for n, _, _ in rows] == [75, 75, 75]
    for n, eq11, _ in rows:
        assert float(eq11) == pytest.approx(0.423 / math.log(2 * int(n)), abs=6e-4)


def _map_tables(text: str) -> dict:
    """``{kappa text: {(Z2/Z1, T1/T2): epsilon}}`` of the tables `wavecontact map` prints."""
    tables, kappa, columns = {}, None, None
    for line in text.splitlines():
        heading = re.match(r"epsilon for kappa = ([^\s:]+)", line)
        if heading:
            kappa, tables[heading.group(1)] = heading.group(1), {}
        elif line.startswith("| Z2/Z1"):
            columns = [float(c) for c in line.strip("|").split("|")[1:]]
        elif kappa and re.match(r"^\| [\d.]+ \|", line):
            cells = [c.strip() for c in line.strip("|").split("|")]
            for t, value in zip(columns, cells[1:]):
                tables[kappa][(float(cells[0]), t)] = float(value)
    return tables


def test_material_map_table_holds_the_known_lines_and_the_page_reads_it_right():
    tables = _map_tables(block_text("materials-map"))
    assert set(tables) == {"inf", "100"}
    for (z, t), epsilon in tables["inf"].items():
        if z == 1:  # equal impedances: the paper's collision, epsilon = gamma = min(T1/T2, T2/T1)
            assert epsilon == pytest.approx(min(t, 1 / t), rel=3e-3)  # the column labels have 3 digits
        if t == 1:  # equal transit times: elastic
            assert epsilon == 1.0
    for kappa in ("inf", "100"):  # symmetric under exchanging the rods: (Z2/Z1, T1/T2) -> (Z1/Z2, T2/T1)
        rows = sorted({z for z, _ in tables[kappa]})
        columns = sorted({t for _, t in tables[kappa]})
        for i, z in enumerate(rows):
            for j, t in enumerate(columns):
                assert tables[kappa][(z, t)] == tables[kappa][(rows[-1 - i], columns[-1 - j])]
    # the prose of docs/materials.md: 0.98 or more at Z2/Z1 = 0.01 and 100; 0.147 instead of 0.1
    page = (ROOT / "docs" / "materials.md").read_text()
    assert "(0.98 or more at `Z2/Z1 = 0.01` and `100`)" in page and "(0.147 instead of\n  0.1 at `T1/T2 = 0.1`)" in page
    for kappa in ("inf", "100"):
        assert min(e for (z, _), e in tables[kappa].items() if z in (0.01, 100)) >= 0.98
    assert round(tables["100"][(1.0, 0.1)], 3) == 0.147 and tables["inf"][(1.0, 0.1)] == 0.1


def test_fem_page_claims_about_its_tables_hold():
    """The sentences of docs/fem.md section 7 that summarise the generated tables."""
    rows = [(float(r[0]), float(r[1]), [abs(float(c)) for c in r[2:]]) for r in _table_rows("fem-default")]
    for gamma, kappa, (n200, n800, n3200) in rows:
        if kappa <= 1e3:  # "every entry is below 1e-6 at 800 elements, for every gamma"
            assert n800 < 1e-6, (gamma, kappa)
        elif kappa < math.inf:  # "below 1e-4 at 800 elements and below 7e-6 at 3200"
            assert n800 < 1e-4 and n3200 < 7e-6, (gamma, kappa)
        if kappa == 0.1:  # "its error there is at most 1.2e-8"
            assert n3200 <= 1.2e-8
    # equal rods at unresolved stiffness: epsilon low by about 0.68 / kappa on every mesh (section 7)
    (row,) = [r for r in _table_rows("fem-gamma-one") if r[0] == "1e+06"]
    assert all(abs(float(c) - 0.68e-6) < 0.1e-6 for c in row[1:] if c)
    error = abs(wavecontact.collide(1.0, 1e6, solver="fem", elements=800).restitution - 1.0)
    assert row[1] == f"{error:.1e}"
    (quad,) = [r for r in _table_rows("fem-quadrature") if r[:2] == ["0.95", "100"]]
    exact = wavecontact.collide(0.95, 100, solver="delay", rtol=1e-13).restitution
    assert quad[2] == f"{wavecontact.collide(0.95, 100, solver='fem', elements=800).restitution - exact:+.1e}"


def test_dispersive_table_shows_two_thirds_and_its_first_cell():
    rows = _table_rows("fem-dispersive")
    assert len(rows) == 3 and all(abs(float(r[-1]) - 2 / 3) < 0.1 for r in rows)  # d ~ (c t h^2)^(1/3)
    (p2,) = [r for r in rows if r[0] == "P2 lumped"]
    assert p2[1] == f"{abs(wavecontact.collide(0.6, math.inf, solver='fem', elements=200, order=2).restitution - 0.6):.1e}"


def _script_block(page: str, name: str) -> str:
    """The body of a block that a script writes (``<!-- name:start -->``) on docs/``page``."""
    text = (ROOT / "docs" / page).read_text()
    match = re.search(rf"<!-- {re.escape(name)}:start -->\n(.*?)<!-- {re.escape(name)}:end -->", text, re.DOTALL)
    assert match and match.group(1).strip(), f"docs/{page}: block {name} missing or empty"
    return match.group(1)


def _markdown_rows(text: str) -> list:
    return [[c.strip() for c in line.strip("|").split("|")] for line in text.splitlines()
            if line.startswith("|") and not line.startswith("|---")][1:]


def test_fem_cost_model_block_counts_what_the_solver_runs():
    """docs/fem.md section 4: the steps and nodes of each row are those of the FE solver's own run, and the
    columns obey the model (loop = steps c_step + the checks' share)."""
    rows = _markdown_rows(_script_block("fem.md", "fem-cost-model"))
    assert len(rows) == 4
    for contact, elements, nodes, steps, checks, loop, c_step, c_node, share, _set_up in rows:
        kappa = math.inf if contact == "hard" else float(contact.split("=")[1])
        result = wavecontact.collide(0.6, kappa, solver="fem", elements=int(elements))
        assert int(steps) == result.work["steps"] - 1  # the timed runs stop one step before the stopping check
        assert int(nodes) == sum(result.work["elements"]) + 2  # two P1 rods: elements + 1 nodes each
        share = float(share.rstrip(" %")) / 100
        assert float(steps) * float(c_step) * 1e-3 == pytest.approx((1 - share) * float(loop), rel=0.05, abs=0.01)
        checks_ms = float(checks) * float(c_node) * float(nodes) * 1e-6
        assert checks_ms == pytest.approx(share * float(loop), rel=0.1, abs=0.02)


def test_markov_cooling_block_holds_the_deterministic_limits():
    """docs/markov.md: after one collision from a cold bath the vibration rule leaves gamma^2 E_tr(0)
    (epsilon = gamma exactly), Glauber's rule 0 (Eq. 36); both end near the Boltzmann mean."""
    text = _script_block("markov.md", "markov-cooling")
    start = float(re.search(r"`E_tr\(0\) = (\S+) T_B\^0`", text).group(1))
    rows = _markdown_rows(text)
    first = rows[0]
    assert float(first[1].split()[0]) == pytest.approx(0.6**2 * start, abs=1e-4)
    assert float(first[2]) == 0.0
    vibration, glauber = (int(x) for x in rows[1][1:])
    assert glauber == 1 and vibration > glauber  # Glauber's new energy does not depend on the old one
    assert all(abs(float(x) - 1.0) < 0.15 for x in rows[2][1:])


def test_markov_page_claims_about_the_boltzmann_defect_hold():
    """docs/markov.md: at 250 modes the defect is below 0.01 per collision and falls as nu_max grows; the
    chains' stationary mean at 250 modes lies more than 3 standard errors below Eq. 30's 1, and rises
    with nu_max (the nu_max study)."""
    rows = {int(r[0]): float(r[4]) for r in _markdown_rows(_script_block("markov.md", "bath-studies-boltzmann"))}
    assert -0.01 < rows[250] < 0 and rows[8] < rows[32] < rows[128] < 0
    study = {int(r[0]): [float(x) for x in re.findall(r"[-\d.]+", r[1])]
             for r in _markdown_rows(_script_block("markov.md", "markov-nu-max"))}
    mean, error = study[250]
    assert mean < 1.0 - 3.0 * error
    assert study[125][0] < study[250][0] < study[1000][0]


def test_no_page_or_docstring_cites_the_specification_outside_the_repository():
    """The pages and the package must not send a reader to MODEL.md, which is not in the repository."""
    files = [*PAGES, *sorted((ROOT / "wavecontact").rglob("*.py"))]
    citing = [str(f.relative_to(ROOT)) for f in files if "MODEL.md" in f.read_text(encoding="utf-8")]
    assert not citing, f"these cite MODEL.md, which is not in the repository: {citing}"


def test_bath_figure_outputs_on_the_page_are_the_stored_runs():
    """docs/bath.md section 8 shows what `wavecontact bath-figure N` printed (docs/figures/bath/figN.txt),
    and Fig. 8's table holds the numbers of the same run's JSON."""
    import json

    text = (ROOT / "docs" / "bath.md").read_text()
    folder = ROOT / "docs" / "figures" / "bath"
    for n in (4, 7, 8, 9):
        shown = re.search(rf"!\[Fig. {n}\]\(figures/bath/fig{n}.png\)\n\n```\n(.*?)```", text, re.DOTALL)
        assert shown, f"docs/bath.md shows no output under Fig. {n}"
        assert shown.group(1).strip() == (folder / f"fig{n}.txt").read_text().strip(), f"Fig. {n} output differs"
    record = json.loads((folder / "fig8.json").read_text())
    rows = [line.split() for line in (folder / "fig8.txt").read_text().splitlines()[1:]]
    for i, gamma in enumerate(record["gamma"]):
        for j, temperature in enumerate(record["temperature"]):
            (row,) = [r for r in rows if float(r[0]) == gamma and float(r[1]) == temperature]
            assert row[2] == f"{record['mean'][i][j]:.4f}" and row[4] == f"{record['std'][i][j]:.4f}"
            assert record["mean_error"][i][j] == pytest.approx(record["std"][i][j] / math.sqrt(record["samples"]),
                                                               rel=0.01)


def test_bath_page_claims_about_modes_and_kappa_hold():
    """docs/bath.md sections 6-7: the mean changes from 250 to 1000 modes by a small fraction of the 0.025
    once claimed, within about two standard errors; from kappa = 50 on the paired difference to the hard
    core is within about two standard errors and below a 2500-sample point's standard error."""
    modes = _script_block("bath.md", "bath-studies-modes")
    changes = re.findall(r"T_B/E_tr 1: mean from 250 to 1000 modes ([-+][\d.]+) \+- ([\d.]+)", modes)
    assert len(changes) == 2
    for change, error in changes:
        assert abs(float(change)) < 0.025 / 4 and abs(float(change)) < 2.5 * float(error)
    for row in _markdown_rows(_script_block("bath.md", "bath-studies-kappa")):
        if row[0] in ("50", "100", "250"):
            std = float(row[2])
            difference, error = (float(x) for x in row[3].replace("(", " ").replace(")", " ").split())
            assert abs(difference) < 2.2 * error and abs(difference) < std / 50, row[0]


def test_usage_page_shows_the_help_of_every_subcommand():
    import argparse

    (sub,) = [a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction)]
    text = block_text("usage-help")
    for name in sub.choices:
        assert f"$ wavecontact {name} --help\n" in text, f"docs/usage.md does not show `wavecontact {name} --help`"


def _results_table(text: str, header_start: str) -> list:
    """The rows (header first) of the markdown table whose header line starts with ``header_start``."""
    lines = text.splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith(header_start))
    rows = []
    for line in lines[start:]:
        if not line.startswith("|"):
            break
        if not line.startswith("|---"):
            rows.append([c.strip() for c in line.strip("|").split("|")])
    return rows


def test_gas_page_quotes_the_heapq_ratio_of_its_bench_block():
    """docs/gas.md's prose quotes the kernel-against-heapq ratio of the bench_gas block (written by
    ``python benchmarks/bench_gas.py --update-docs``) and says whether it meets the 50x goal."""
    text = (ROOT / "docs" / "gas.md").read_text()
    block = text.split("<!-- bench_gas:begin -->", 1)[1].split("<!-- bench_gas:end -->", 1)[0]
    row = next(line for line in block.splitlines() if line.startswith("| wavecontact kernel (numba) |"))
    ratio = int(row.split("|")[-2].strip().rstrip("x"))
    prose = " ".join(text.split("<!-- bench_gas:end -->", 1)[1].split())
    verdict = "short of the 50x goal" if ratio < 50 else "meeting the 50x goal"
    assert f"the ratio is {ratio}x in CPU time, {verdict}" in prose, (ratio, verdict)


def test_gas_page_quotes_the_generated_gas_tables():
    """docs/gas.md's prose quotes numbers of the generated docs/gas_vibration_results.md
    (written by ``python docs/gas_study.py vibration``): they must be that page's current values, and
    the interpolated gamma = 0.85 last row it quotes must be what the shipped law gives."""
    from wavecontact.gas.collision_law import default_law

    prose = " ".join((ROOT / "docs" / "gas.md").read_text().split())
    results = (ROOT / "docs" / "gas_vibration_results.md").read_text()
    below = _results_table(results, "| gamma | direct, x = 1e-5 |")[1:]
    assert len(below) == 3
    for _gamma, direct, last, _gain in below:
        assert re.search(rf"{re.escape(direct)} (?:direct )?against {re.escape(last)}\b", prose), (direct, last)
    law_rows = _results_table(results, "| gamma | x = 1e-4 |")
    column = law_rows[0].index("x = 1e-4")
    warm = [float(row[column].split()[0]) for row in law_rows[1:] if float(row[0]) < 1]
    assert f"`eps^2` of {min(warm):.3g} to {max(warm):.3g} at `x = 1e-4`" in prose
    # the gamma = 0.85 last row, interpolated by the law itself (mid-point rule in the uniform u)
    law = default_law()
    u = (np.arange(2000) + 0.5) / 2000
    mean = float(np.mean([np.atleast_1d(law.draw(0.85, 1e-4, v, 0.5))[0] for v in u]))
    assert f"gives about {round(mean)} where the direct solves give" in prose
    direct = _results_table(results, "| gamma | x = 1e-1 |")
    row = next(r for r in direct if r[0] == "0.85")
    direct_mean = float(row[direct[0].index("x = 1e-5")].split()[0])
    assert 4.5 <= direct_mean / mean <= 5.5, "gas.md says the rule underestimates by a factor of about five"
    gas = _results_table(results, "| seed | fixed r (N_c) |")
    beyond = [int(r[gas[0].index("draws below the law's last row")]) for r in gas[1:]]
    beyond.append(int(re.search(r"draws below the law's last row: (\d+)", results).group(1)))
    assert f"{min(beyond)} to {max(beyond)} draws per run" in prose


def test_bath_page_quotes_its_ensemble_and_bench_blocks():
    """docs/bath.md's prose around the ensemble-accuracy and bench-bath blocks quotes ranges
    derived from them: the standard error of a 2500-sample mean and the cost of the new
    ensemble defaults against the previous setting."""
    prose = " ".join((ROOT / "docs" / "bath.md").read_text().split())
    accuracy = _markdown_rows(_script_block("bath.md", "ensemble-accuracy").split("\n\n")[1])
    se = [float(row[6]) * math.sqrt(200 / 2500) for row in accuracy if row[2] == "ensemble default"]
    assert len(se) == 6
    assert f"error of {min(se):.1g} to {max(se):.1g} at the six points" in prose
    defaults = [row for row in accuracy if row[2] == "ensemble default"]
    shifts = [abs(float(row[3].split()[0])) / float(row[3].split()[1].strip("()")) for row in defaults]
    assert max(shifts) <= 2.5, "bath.md says the defaults move the mean by at most 2.5 paired standard errors"
    bench = _markdown_rows(_script_block("bath.md", "bench-bath"))
    same = [float(row[1].split()[0]) for row in bench if row[0] == "delay sample, kappa 250, nu_max 250 (CPU)"]
    before = next(float(row[1].split()[0]) for row in bench
                  if row[0] == "delay sample, kappa 250, nu_max 250, rtol 1e-6 Gauss-Kronrod (CPU)")
    assert len(same) == 2
    assert f"cost {min(same) / before:.2f} to {max(same) / before:.2f} of it" in prose


def test_every_cell_of_the_fem_default_table_fits_the_limit_its_command_states():
    """``python docs/generate.py --check`` must be able to rerun the table: each FE solve's estimated cost
    (what the solver checks before it starts; read from its refusal at max_work=1) is within the
    ``--max-work`` that the command shown in docs/fem.md passes."""
    from wavecontact.errors import LimitError

    (command,) = BLOCKS["fem-default"].commands
    stated = float(command[command.index("--max-work") + 1])
    assert f"`$ {generate.display(command)}`" in block_text("fem-default")
    for gamma, kappa in [(float(r[0]), float(r[1])) for r in _table_rows("fem-default")]:
        if math.isinf(kappa):
            continue
        with pytest.raises(LimitError) as refusal:
            wavecontact.collide(gamma, kappa, solver="fem", elements=3200, max_work=1)
        work = float(re.search(r"about ([\d.e+]+) updates", str(refusal.value)).group(1))
        assert work <= stated, f"gamma {gamma}, kappa {kappa}: {work:.2g} updates > --max-work {stated:g}"
