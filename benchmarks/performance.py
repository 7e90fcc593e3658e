"""Speed against error for every solver and discretization; writes docs/performance.md.

One command regenerates the report and its figures:

    python benchmarks/performance.py            # full report (about 15-30 minutes on 2 cores)
    python benchmarks/performance.py --quick    # smaller meshes and fewer repeats, for a look

Sections of the report: the machine and library versions; error against wall
time (Pareto fronts) for kappa in {20, 100, 1e4, 1e6, inf} and gamma in
{0.6, 0.2173}; peers measured in the same run at matched accuracy (JiTCDDE on
the delay equation, scipy solve_ivp DOP853/Radau on the modal equations, a
plain scikit-fem + scipy.sparse loop on the FE equations); how the cost grows
with elements, modes and kappa; a recommendation table (cheapest method per
target error); and where a method fails (its error message, not a number).
"""

from __future__ import annotations

import argparse
import datetime
import importlib
import json
import math
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE / "peers"))
sys.path.insert(0, str(ROOT))  # this checkout's package, not whichever one is installed

from compile_times import compile_section
from discretization_table import HEADING, discretization_block, runs_from_tables

import wavecontact
from wavecontact.plotting.compare import comparison_figure, method_family
from wavecontact.studies.compare import Method, compare_solvers

GAMMAS = (0.6, 0.2173)
KAPPAS = (20.0, 100.0, 1e4, 1e6, math.inf)
DISCRETIZATIONS = ((1, "lumped"), (1, "consistent"), (2, "lumped"), (2, "consistent"))
TARGETS = (1e-3, 1e-6, 1e-9)
TIME_CAP = 5.0  # s: larger resolutions of a family are skipped once one run takes longer
REPEAT_BELOW = 1.0  # s: runs shorter than this are repeated and the median kept


def median_time(function, repeats):
    times, value = [], None
    for _ in range(repeats):
        started = time.perf_counter()
        value = function()
        times.append(time.perf_counter() - started)
    return float(np.median(times)), value


def kappa_text(kappa):
    return "inf" if math.isinf(kappa) else f"{kappa:g}"


def methods_for(quick):
    elements = (25, 50, 100, 200, 400) if quick else (25, 50, 100, 200, 400, 800, 1600, 3200)
    modes = (10, 20, 40, 80) if quick else (10, 20, 40, 80, 160)
    families = [[Method("delay", {"rtol": r}, f"rtol={r:.0e}") for r in (1e-3, 1e-5, 1e-7, 1e-9, 1e-11)]]
    for order, mass in DISCRETIZATIONS:
        families.append([
            Method("fem", {"elements": n, "order": order, "mass": mass}, f"P{order} {mass}, {n} elements",
                   "element_steps")
            for n in elements
        ])
    for correction in (True, False):
        name = "static correction" if correction else "plain truncation"
        families.append([
            Method("modal", {"modes": n, "static_correction": correction, "correction": "static" if correction
                             else "none"}, f"{n} modes, {name}", "modes")
            for n in modes
        ])
    return families


def pareto_case(gamma, kappa, families, repeats):
    """All families on one case; a family stops growing once a run exceeds TIME_CAP."""
    rows = []
    if math.isinf(kappa):  # the delay solver's hard-core recursion has no tolerance
        families = [[Method("delay", {}, "hard-core recursion")]] + [f for f in families if f[0].solver != "delay"]
    for family in families:
        for method in family:
            table = compare_solvers(gamma, kappa, [method], repeats=1, progress=False, warmup=False)
            row = table.rows[0]
            if row.ok and row.wall_time_s < REPEAT_BELOW and repeats > 1:
                # short runs are noisy: keep the median of several
                table = compare_solvers(gamma, kappa, [method], repeats=repeats, progress=False, warmup=False)
                row = table.rows[0]
            rows.extend(table.rows)
            if row.ok and row.wall_time_s > TIME_CAP:
                break
    table.rows = rows
    return table


def section_machine(command):
    import scipy
    import skfem

    versions = {"python": platform.python_version(), "numpy": np.__version__, "scipy": scipy.__version__,
                "scikit-fem": getattr(skfem, "__version__", "?"), "wavecontact": wavecontact.__version__}
    for name in ("numba", "meshio", "matplotlib", "jitcdde"):
        try:
            versions[name] = importlib.import_module(name).__version__
        except (ImportError, AttributeError):
            versions[name] = "not installed"
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    lines = [
        f"Generated {datetime.datetime.now(datetime.UTC):%Y-%m-%d %H:%M UTC} by `{command}`.",
        "",
        f"Machine: {cpu}, {os.cpu_count()} cores, {platform.system()} {platform.release()}.",
        "",
        "| library | version |",
        "|---|---|",
        *(f"| {k} | {v} |" for k, v in versions.items()),
    ]
    return "\n".join(lines)


def draw_pareto_figures(tables, figure_dir) -> list:
    """One figure per gamma (a panel per kappa); returns the file names."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    names = []
    for gamma in GAMMAS:
        fig = Figure(figsize=(16, 4.8), layout="constrained")
        FigureCanvasAgg(fig)
        axes = fig.subplots(1, len(KAPPAS))
        for ax, kappa in zip(axes, KAPPAS):
            comparison_figure(tables[(gamma, kappa)], ax=ax, legend=False)
        handles = {}
        for ax in axes:
            for handle, label in zip(*ax.get_legend_handles_labels()):
                handles.setdefault(label, handle)
        fig.legend(list(handles.values()), list(handles), loc="outside lower center", ncol=len(handles), fontsize=8)
        name = f"pareto_gamma_{gamma:g}.png"
        fig.savefig(figure_dir / name, dpi=110)
        names.append(name)
    return names


def tables_from_json(path) -> dict:
    """The comparison tables saved in performance_data.json, keyed by (gamma, kappa)."""
    from wavecontact.studies.compare import ComparisonRow, ComparisonTable, method_labels

    # rows saved before they carried their series and point label: from the method of that label
    known = {(m.solver, m.describe()): m for family in methods_for(False) + [[Method("delay", {}, "hard-core recursion")]]
             for m in family}
    tables = {}
    for record in json.loads(Path(path).read_text()).values():
        kappa = math.inf if record["kappa"] == "inf" else float(record["kappa"])
        rows = [ComparisonRow(**row) for row in record["rows"]]
        for row in rows:
            method = known.get((row.solver, row.resolution))
            if not row.family and method is not None:
                row.family, row.point = method_labels(method)
        tables[(record["gamma"], kappa)] = ComparisonTable(record["gamma"], kappa, record["reference"],
                                                           record["reference_source"], rows)
    return tables


def section_pareto(tables, figure_dir):
    out = ["## Error against wall time", "",
           ("Every solver and discretization on the same collisions; the error is against the delay "
           "equation at rtol = 1e-13 (the exact hard-core recursion for kappa = inf). Times are medians "
           "of repeated runs of the whole `collide` call, set-up included. Points at 1e-16 are exact "
           "to round-off. Each point is labelled with its resolution (elements on the short rod, modes "
           "per rod, or the delay solver's rtol). A run the solver refused (it raised an error rather "
           "than return a number it cannot vouch for) has no point; those runs are listed under "
           "*Failures and breakdowns* below."), ""]
    for name, gamma in zip(draw_pareto_figures(tables, figure_dir), GAMMAS):
        out += [f"![error against time, gamma = {gamma:g}](figures/{name})", ""]
    out += ["### Failures and breakdowns", "",
            ("A method that cannot give a trustworthy number raises an error; it is listed here with "
            "its message. No point of the sweep is NaN, inf or silently wrong unless listed as such."), "",
            "| gamma | kappa | method | outcome |", "|---|---|---|---|"]
    silent = 0
    for (gamma, kappa), table in tables.items():
        for row in table.rows:
            if not row.ok:
                out.append(f"| {gamma:g} | {kappa_text(kappa)} | {row.solver}: {row.resolution} | "
                           f"error: {row.status.splitlines()[0][:160]} |")
            elif not math.isfinite(row.restitution):
                silent += 1
                out.append(f"| {gamma:g} | {kappa_text(kappa)} | {row.solver}: {row.resolution} | "
                           f"NON-FINITE {row.restitution} |")
    out += ["", f"Non-finite values returned without an error: {silent}.", ""]
    out += ["### Smallest error reached by each method family", "",
            "| gamma | kappa | " + " | ".join(_families(tables)) + " |",
            "|---|---|" + "---|" * len(_families(tables))]
    for (gamma, kappa), table in tables.items():
        best = {}
        for row in table.rows:
            if row.ok:
                family = _family(row)
                best[family] = min(best.get(family, math.inf), row.error)
        cells = [f"{best[f]:.1e}" if f in best else "failed" for f in _families(tables)]
        out.append(f"| {gamma:g} | {kappa_text(kappa)} | " + " | ".join(cells) + " |")
    return "\n".join(out)


def _family(row):
    return method_family(row)


def _families(tables):
    seen = []
    for table in tables.values():
        for row in table.rows:
            family = _family(row)
            if family not in seen:
                seen.append(family)
    return seen


def recommendations(tables):
    """Cheapest row with error <= target, per (kappa, target), gamma = 0.6."""
    lines = ["| kappa | target error | cheapest method | error | time (ms) |", "|---|---|---|---|---|"]
    for kappa in KAPPAS:
        table = tables[(GAMMAS[0], kappa)]
        for target in TARGETS:
            good = [r for r in table.rows if r.ok and r.error <= target]
            if not good:
                lines.append(f"| {kappa_text(kappa)} | {target:.0e} | none reached it | | |")
                continue
            best = min(good, key=lambda r: r.wall_time_s)
            lines.append(f"| {kappa_text(kappa)} | {target:.0e} | {best.solver}: {best.resolution} | "
                         f"{best.error:.1e} | {1e3 * best.wall_time_s:.3g} |")
    return "\n".join(lines)


def section_peers(repeats, quick):
    out = ["## Peers at matched accuracy (same run)", ""]
    # delay equation vs JiTCDDE
    out += ["### Delay equation: wavecontact vs JiTCDDE", ""]
    try:
        from jitcdde_delay import JitcddePeer, timed_restitution

        peer = JitcddePeer(0.6, t_max=60.0)
        out += [(f"JiTCDDE compiles its C code once ({peer.compile_time:.2f} s, not counted below). Both "
                "solvers are run at the loosest tolerance whose error is <= 1e-9."), "",
                "| kappa | JiTCDDE (ms) | error | wavecontact (ms) | error | speed-up |", "|---|---|---|---|---|---|"]
        for kappa in (20.0, 100.0, 1000.0):
            exact = wavecontact.collide(0.6, kappa, rtol=1e-13).restitution
            theirs = ours = None
            for rtol in (1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12):
                seconds, value = timed_restitution(peer, kappa, rtol, repeats=1)
                if math.isfinite(value) and abs(value - exact) <= 1e-9:
                    seconds, value = timed_restitution(peer, kappa, rtol, repeats=max(3, repeats))
                    theirs = (seconds, abs(value - exact))
                    break
            for rtol in (1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10):
                value = wavecontact.collide(0.6, kappa, rtol=rtol).restitution
                if abs(value - exact) <= 1e-9:
                    seconds, _ = median_time(lambda r=rtol, k=kappa: wavecontact.collide(0.6, k, rtol=r),
                                             10 * repeats)
                    ours = (seconds, abs(value - exact))
                    break
            if theirs and ours:
                out.append(f"| {kappa:g} | {1e3 * theirs[0]:.2f} | {theirs[1]:.1e} | {1e3 * ours[0]:.3f} | "
                           f"{ours[1]:.1e} | {theirs[0] / ours[0]:.0f}x |")
            else:
                out.append(f"| {kappa:g} | {'n/a' if not theirs else theirs} | | {ours} | | |")
    except ImportError as exc:
        out.append(f"JiTCDDE not installed ({exc}); `pip install jitcdde` to include it.")
    out.append("")
    # modal equations vs solve_ivp
    out += ["### Modal equations: wavecontact vs scipy solve_ivp", ""]
    try:
        import modal_solve_ivp

        modes = 40 if quick else 75
        kappa = 100.0
        reference, _ = modal_solve_ivp.restitution(0.6, kappa, modes, 1e-12)
        # like for like: the peers integrate the modal equations with the static correction, so wavecontact
        # solves those same equations (correction='static'), without its error estimate
        same = {"modes": modes, "correction": "static", "estimate_error": False}
        result = wavecontact.collide(0.6, kappa, solver="modal", **same)
        ours_error = abs(result.restitution - reference)
        ours_time, _ = median_time(lambda: wavecontact.collide(0.6, kappa, solver="modal", **same), repeats)
        # the default solve (end-response correction) and its error estimate, each timed on its own
        exact = wavecontact.collide(0.6, kappa, rtol=1e-13).restitution
        plain = float(np.median([wavecontact.collide(0.6, kappa, solver="modal", modes=modes,
                                                     estimate_error=False).wall_time_s for _ in range(repeats)]))
        default = wavecontact.collide(0.6, kappa, solver="modal", modes=modes)
        runs = [wavecontact.collide(0.6, kappa, solver="modal", modes=modes) for _ in range(repeats)]
        estimated = float(np.median([r.wall_time_s for r in runs]))
        # the estimate's own share, timed inside each solve (a difference of two medians can come out negative)
        estimate_share = float(np.median([r.diagnostics["error_estimate_seconds"] for r in runs]))
        out += [(f"gamma = 0.6, kappa = {kappa:g}, N = {modes} modes per rod. The peers integrate the modal "
                 "equations with the static correction; wavecontact is timed on the same equations "
                 "(`correction='static'`, `estimate_error=False`: one solve, no error-estimate reruns). Error "
                 "against those equations solved by DOP853 at rtol = 1e-12; each peer at the loosest tolerance "
                 "at least as accurate as wavecontact. Times are medians of whole `collide` calls."), "",
                "| integrator | rtol | error | median time (ms) | wavecontact speed-up |", "|---|---|---|---|---|",
                f"| wavecontact modal, static correction | default | {ours_error:.1e} | {1e3 * ours_time:.2f} | 1x |"]
        for method in ("DOP853", "Radau"):
            found = None
            for rtol in (1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10):
                try:
                    value, seconds = modal_solve_ivp.restitution(0.6, kappa, modes, rtol, method=method)
                except RuntimeError as exc:
                    found = ("failed", str(exc))
                    break
                if abs(value - reference) <= max(ours_error, 1e-12):
                    runs = [modal_solve_ivp.restitution(0.6, kappa, modes, rtol, method=method)[1]
                            for _ in range(max(1, repeats // 2))]
                    found = (rtol, abs(value - reference), float(np.median(runs)))
                    break
                if seconds > 120:
                    found = ("too slow", f"{seconds:.0f} s at rtol {rtol:g} with error {abs(value - reference):.1e}")
                    break
            if found is None:
                out.append(f"| {method} | down to 1e-10 | not as accurate | | |")
            elif isinstance(found[0], str):
                out.append(f"| {method} | {found[0]} | {found[1]} | | |")
            else:
                out.append(f"| {method} | {found[0]:.0e} | {found[1]:.1e} | {1e3 * found[2]:.1f} | "
                           f"{found[2] / ours_time:.0f}x |")
        out += ["", ("The default modal solve (end-response correction, exact for uniform rods) is a different "
                     "model from the peers' equations, so it is listed apart; its error is against the delay "
                     "equation at rtol = 1e-13. The error estimate reruns the collocation at a tenth of its "
                     "tolerance; its share is timed inside each solve (`diagnostics['error_estimate_seconds']`). "
                     "Times of this table are the solver's `wall_time_s`, medians."), "",
                "| wavecontact modal, default options | error against the delay equation | median time (ms) |",
                "|---|---|---|",
                f"| estimate_error=False | {abs(default.restitution - exact):.1e} | {1e3 * plain:.2f} |",
                (f"| estimate_error=True (the default) | {abs(default.restitution - exact):.1e} | "
                 f"{1e3 * estimated:.2f} (of which the estimate: {1e3 * estimate_share:.2f}) |")]
    except ImportError as exc:
        out.append(f"modal peer unavailable: {exc}")
    out.append("")
    # FE loop vs plain scipy.sparse loop
    out += ["### Finite elements: wavecontact's time loop vs a plain scikit-fem + scipy.sparse loop", ""]
    from fem_scipy_loop import scipy_fem_run

    from wavecontact.fem.simulation import build_setup, run_collision

    out += [("Same mesh, P1 lumped, kappa = 100; cost per element-step of the time loop (set-up excluded "
            "for both)."), "", ("| elements | wavecontact (ns / element-step) | scipy.sparse loop (ns / element-step) "
            "| speed-up |"), "|---|---|---|---|"]
    for elements in ((400, 800) if quick else (800, 3200)):
        setup = build_setup(wavecontact.two_rods(0.6, 100.0), elements=elements)
        first = run_collision(setup)
        element_steps = first["steps"] * sum(d.n_elements for d in setup.rods)
        ours, _ = median_time(lambda s=setup: run_collision(s), max(3, repeats))
        peer = [scipy_fem_run(0.6, 100.0, elements, courant=0.99) for _ in range(max(1, repeats // 2))]
        peer_seconds = float(np.median([p[1] for p in peer]))
        peer_steps = peer[0][3]
        a, b = 1e9 * ours / element_steps, 1e9 * peer_seconds / peer_steps
        out.append(f"| {elements} | {a:.2f} | {b:.1f} | {b / a:.0f}x |")
    return "\n".join(out)


def section_growth(repeats, quick, figure_dir):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    out = ["## How the cost grows", ""]
    fig = Figure(figsize=(14, 4), layout="constrained")
    FigureCanvasAgg(fig)
    ax_el, ax_modes, ax_kappa = fig.subplots(1, 3)
    # elements
    elements = (100, 200, 400, 800) if quick else (100, 200, 400, 800, 1600, 3200, 6400, 12800)
    times = [median_time(lambda n=n: wavecontact.collide(0.6, 100.0, solver="fem", elements=n), repeats)[0]
             for n in elements]
    top = len(elements) // 2
    slope = np.polyfit(np.log(elements[top:]), np.log(times[top:]), 1)[0]
    ax_el.loglog(elements, times, "s-", label=f"fem P1 lumped (slope {slope:.2f} on the finest half)")
    ax_el.set_xlabel("elements on the short rod")
    ax_el.set_title(r"fem, P1 lumped: $\gamma$ = 0.6, $\kappa$ = 100", fontsize=9)
    ax_el.legend()
    out.append(f"* FE, P1 lumped, kappa = 100, whole `collide` call: time ~ elements^{slope:.2f} over "
               f"{elements[top]}-{elements[-1]} elements (an explicit loop over every element would grow like "
               "elements x steps, i.e. about 2; the exact lattice costs O(1) per step plus O(elements) per "
               "check, so about 1 at most; the set-up (assembly, stable step) dominates on coarse meshes). Times: "
               + ", ".join(f"{n}: {1e3 * t:.3g} ms" for n, t in zip(elements, times)) + ".")
    # modes
    modes = (10, 20, 40, 80) if quick else (10, 20, 40, 80, 160, 320)
    times = [median_time(lambda n=n: wavecontact.collide(0.6, 100.0, solver="modal", modes=n), repeats)[0]
             for n in modes]
    slope = np.polyfit(np.log(modes), np.log(times), 1)[0]
    ax_modes.loglog(modes, times, "^-", label=f"modal (slope {slope:.2f})")
    ax_modes.set_xlabel("modes per rod")
    ax_modes.set_title(r"modal, static correction: $\gamma$ = 0.6, $\kappa$ = 100", fontsize=9)
    ax_modes.legend()
    out.append(f"* Modal, kappa = 100: time ~ modes^{slope:.2f} over {modes[0]}-{modes[-1]} modes.")
    # kappa
    kappas = (10.0, 100.0, 1e3, 1e4, 1e5, 1e6)
    rows = ["", "| kappa | delay (ms) | fem P1 lumped 800 (ms) | modal 80 (ms) |", "|---|---|---|---|"]
    series = {"delay": [], "fem": [], "modal": []}
    for kappa in kappas:
        cells = []
        for solver, options in (("delay", {}), ("fem", {"elements": 800}), ("modal", {"modes": 80})):
            try:
                seconds, _ = median_time(
                    lambda k=kappa, s=solver, o=options: wavecontact.collide(0.6, k, solver=s, **o), repeats)
                series[solver].append(seconds)
                cells.append(f"{1e3 * seconds:.3g}")
            except wavecontact.WavecontactError as exc:
                series[solver].append(math.nan)
                cells.append(f"error: {str(exc)[:60]}")
        rows.append(f"| {kappa:g} | " + " | ".join(cells) + " |")
    for solver, marker in (("delay", "o-"), ("fem", "s-"), ("modal", "^-")):
        ax_kappa.loglog(kappas, series[solver], marker, label=solver)
    ax_kappa.set_xlabel(r"$\kappa = \alpha V l / c$")
    ax_kappa.set_title(r"$\gamma$ = 0.6; delay rtol 1e-11, fem 800 el., modal 80", fontsize=9)
    ax_kappa.legend()
    for ax in (ax_el, ax_modes, ax_kappa):
        ax.set_ylabel("wall time per collision (s)")
        ax.grid(True, which="both", alpha=0.3)
    out.append("* Against kappa (gamma = 0.6):")
    out += rows
    fig.savefig(figure_dir / "cost_growth.png", dpi=110)
    out += ["", "![cost growth](figures/cost_growth.png)"]
    return "\n".join(out)


RING_BLOCK = "ring-performance"


def section_ring(collisions, realisations, command):
    """The paper's Fig. 1 command (``wavecontact ring --gamma 0.6173 --kappa 4000 --modes 75``): CPU seconds of the
    run plus its statistics and figures, per integrator (``benchmarks/profile_ring.py`` measures and splits them)."""
    import profile_ring

    methods = ("collocation", "collocation, before")
    for method in methods:  # compile or load the kernels before timing
        profile_ring.run_ring(profile_ring.GAMMA, profile_ring.KAPPA, profile_ring.MODES, 3, progress=False,
                              solver_options={"step_method": profile_ring.VARIANTS[method][0]})
    counts = {"collocation": realisations, "collocation, before": realisations}
    labels = {"collocation": "exponential collocation, quick Newton (default)",
              "collocation, before": ("exponential collocation, long steps where the force is negligible "
                                      "(before: QUICK_NEWTON = False)")}
    whole = "whole command (run + statistics + figures)"
    runs = {method: [] for method in methods}
    for r in range(realisations):  # alternately, so that a change of load hits both collocation rules
        for method in methods:
            if r < counts[method]:
                runs[method].append(profile_ring.profile_run(method, r, collisions))
    rows = []
    for method in methods:
        seconds = [run["phases"][whole] for run in runs[method]]
        contact = [1e3 * run["phases"]["contact integration"] / collisions for run in runs[method]]
        rows.append(f"| {labels[method]} | {collisions} | {len(seconds)} | {np.median(seconds):.1f} | "
                    f"{min(seconds):.1f}-{max(seconds):.1f} | {np.median(contact):.2f} |")
    load = os.getloadavg()
    return "\n".join([
        (f"`{command}` at {datetime.datetime.now(datetime.UTC):%Y-%m-%d %H:%M UTC}, load average {load[0]:.1f} "
        f"(1 min) on {os.cpu_count()} cores at the end. CPU seconds of this process (`time.process_time`; other "
        "jobs stretch the wall time, not these) for `wavecontact ring --gamma 0.6173 --kappa 4000 --modes 75 "
        f"--collisions {collisions} --out DIR` done in-process (the run with its checkpoints and data files, "
        "the statistics, the three figures; warm numba cache); realisations differ in the ring circumference "
        "(+0 %, +1.5 %, ...). Where the time goes: docs/ring.md, `python benchmarks/profile_ring.py`."),
        "",
        "| ring integrator | collisions | realisations | CPU s, median | range | contact ms per collision |",
        "|---|---:|---:|---:|---:|---:|",
        *rows,
    ])


def update_ring_block(report: Path, body: str) -> None:
    """Replace the ring block of ``report`` (between its markers) by ``body``."""
    text = report.read_text()
    start, end = f"<!-- {RING_BLOCK}:start -->", f"<!-- {RING_BLOCK}:end -->"
    if text.count(start) != 1 or text.count(end) != 1:
        raise SystemExit(f"{report} needs exactly one pair of markers {start} ... {end}")
    head, rest = text.split(start, 1)
    _, tail = rest.split(end, 1)
    report.write_text(f"{head}{start}\n{body}\n{end}{tail}")


def update_readme(table_text):
    readme = ROOT / "README.md"
    text = readme.read_text()
    start, end = "<!-- recommendations:start -->", "<!-- recommendations:end -->"
    if start in text and end in text:
        head, rest = text.split(start, 1)
        _, tail = rest.split(end, 1)
        readme.write_text(f"{head}{start}\n{table_text}\n{end}{tail}")


def main(argv=None):
    parser = argparse.ArgumentParser(description="Regenerate docs/performance.md and its figures.")
    parser.add_argument("--quick", action="store_true", help="smaller resolutions and repeats")
    parser.add_argument("--repeats", type=int, default=None, help="median over this many runs (default 3, quick 1)")
    parser.add_argument("--out", default=str(ROOT / "docs"), help="directory of performance.md (default docs/)")
    parser.add_argument("--growth-only", action="store_true",
                        help="re-measure only the last section (how the cost grows) and its figure")
    parser.add_argument("--ring-only", action="store_true",
                        help="re-measure only the ring run of Fig. 1 (its block in performance.md)")
    parser.add_argument("--ring-collisions", type=int, default=4500, help="collisions of the ring run (default 4500)")
    parser.add_argument("--ring-realisations", type=int, default=5,
                        help="realisations of the ring run with the default integrator (default 5)")
    parser.add_argument("--pareto-figures-only", action="store_true",
                        help="redraw the error-against-time figures from figures/performance_data.json, no runs")
    parser.add_argument("--compile-times-only", action="store_true",
                        help="re-measure only the compile-time table (benchmarks/compile_times.py --update-docs)")
    args = parser.parse_args(argv)
    if args.compile_times_only:
        from compile_times import main as compile_times_main

        compile_times_main(["--update-docs"])
        return
    repeats = args.repeats or (1 if args.quick else 3)
    out_dir = Path(args.out)
    figure_dir = out_dir / "figures"
    figure_dir.mkdir(parents=True, exist_ok=True)
    command = "python benchmarks/performance.py" + (" --quick" if args.quick else "") + (
        f" --repeats {args.repeats}" if args.repeats else "")
    if args.growth_only:
        report = out_dir / "performance.md"
        head, marker, _ = report.read_text().partition("## How the cost grows")
        if not marker:
            parser.error(f"{report} has no section 'How the cost grows'")
        for solver, options in (("delay", {}), ("fem", {"elements": 50}), ("modal", {"modes": 10})):
            wavecontact.collide(0.6, 100.0, solver=solver, **options)  # compile the kernels before timing
        stamp = f"{datetime.datetime.now(datetime.UTC):%Y-%m-%d %H:%M UTC}"
        note = (f"Re-measured {stamp} by `{command} --growth-only` (the sections above are from the run named at "
                "the top).")
        growth = section_growth(repeats, args.quick, figure_dir).replace(
            "## How the cost grows\n", f"## How the cost grows\n\n{note}\n", 1)
        report.write_text(head + growth + "\n")
        print(f"wrote {report} (last section) and {figure_dir / 'cost_growth.png'}", file=sys.stderr)
        return
    if args.ring_only:
        report = out_dir / "performance.md"
        ring_command = f"python benchmarks/performance.py --ring-only --ring-collisions {args.ring_collisions} " \
                       f"--ring-realisations {args.ring_realisations}"
        update_ring_block(report, section_ring(args.ring_collisions, args.ring_realisations, ring_command))
        print(f"wrote {report} (block {RING_BLOCK})", file=sys.stderr)
        return
    if args.pareto_figures_only:
        for name in draw_pareto_figures(tables_from_json(figure_dir / "performance_data.json"), figure_dir):
            print(f"wrote {figure_dir / name}", file=sys.stderr)
        return

    for solver, options in (("delay", {}), ("fem", {"elements": 50}), ("modal", {"modes": 10})):
        wavecontact.collide(0.6, 100.0, solver=solver, **options)  # compile the kernels before timing
    families = methods_for(args.quick)
    tables = {}
    for gamma in GAMMAS:
        for kappa in KAPPAS:
            started = time.perf_counter()
            tables[(gamma, kappa)] = pareto_case(gamma, kappa, families, repeats)
            print(f"gamma = {gamma:g}, kappa = {kappa_text(kappa)}: {time.perf_counter() - started:.0f} s",
                  file=sys.stderr)
    recommendation = recommendations(tables)

    (figure_dir / "performance_data.json").write_text(json.dumps(
        {f"{g:g},{kappa_text(k)}": t.to_dict() for (g, k), t in tables.items()}, indent=1))
    parts = [
        "# Performance: speed against error",
        "",
        section_machine(command),
        "",
        "## Which method to use",
        "",
        "The cheapest measured method (gamma = 0.6) that reaches each target error, from the runs below.",
        "",
        recommendation,
        "",
        f"## {HEADING}",
        "",
        discretization_block(runs_from_tables(tables), command),
        "",
        section_pareto(tables, figure_dir),
        "",
        section_peers(repeats, args.quick),
        "",
        compile_section(),
        "",
        "## The ring run of Fig. 1",
        "",
        f"<!-- {RING_BLOCK}:start -->",
        section_ring(args.ring_collisions, args.ring_realisations, command),
        f"<!-- {RING_BLOCK}:end -->",
        "",
        section_growth(repeats, args.quick, figure_dir),
        "",
    ]
    (out_dir / "performance.md").write_text("\n".join(parts))
    if out_dir.resolve() == (ROOT / "docs").resolve():
        update_readme(recommendation)  # only the report that docs/ links to feeds the README
    print(f"wrote {out_dir / 'performance.md'}", file=sys.stderr)


if __name__ == "__main__":
    main()
