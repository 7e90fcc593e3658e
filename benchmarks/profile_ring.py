"""Where the ring run of Fig. 1 spends its time, and what the collocation changed, one command:

    python benchmarks/profile_ring.py [--collisions 1000] [--realisations 5] [--update-docs]

Runs ``run_ring(0.6173, 4000, modes=75, ...)`` (what ``wavecontact ring --gamma 0.6173 --kappa 4000
--modes 75 --collisions M --out DIR`` runs, checkpoints in a temporary directory every 100
collisions, then the statistics and the three figures) once per realisation and integrator:
the exponential collocation with the rules before the quick ones (``collocation, before``:
``wavecontact.modal.ring.QUICK_NEWTON = False``) and with them (``collocation``, the
default now); ``--methods collocation, sampled`` adds the rule before that (every step at most
``TOP_STEP_PHASE``, ``FREE_STEP_RUNGS = 0``) and ``splitting`` the kick-rotate-kick splitting
(``step_method='splitting'``).
Realisations differ in the ring circumference (1.5 % steps, as in ``wavecontact equipartition``).
All times are CPU seconds of this process (``time.process_time``): other jobs on a shared machine
stretch the wall time, not these. The numba kernels are compiled (or loaded) before timing.

Prints four Markdown tables:

1. CPU time per phase (median over the realisations): free flight between collisions (the
   flight to the next contact, replayed from the state before every 10th collision and scaled
   to all), contact integration (the rest of the compiled integrator's time), of which the
   omitted modes' static correction (the cost per step with the pair's compliance less the cost per
   step without it, on every 50th collision), per-collision records (Python bookkeeping),
   checkpoints, the data files, the statistics and the figures at the end. The ring reports no
   per-collision error estimate, so that row is zero;
2. CPU time and steps per collision against the collision's own softness
   ``kappa_j = alpha |w_j| l / c`` (``w_j`` its approach speed), pooled over the realisations;
3. each collision's restitution error against the collocation at tolerance 1e-7 and a quarter of
   its largest step (which agreed with the splitting at a sixteenth of its default step to 8e-9,
   the splitting's own error there, on 20 states) from the same start states (every
   ``--accuracy-every`` collision of the first realisation, at most its first 1000);
4. the statistics of every realisation (Eq. 8, KS test against Eq. 9, Eq. 11, relaxation, C(1)/C(0),
   energy drift) for both integrators, with their mean and spread over the realisations.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import sys
import tempfile
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(1, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # the checkout this script lives in

import itertools

from docs_block import run_and_write

import wavecontact.modal.ring as ring_module
import wavecontact.studies.ring as ring_study
from wavecontact.plotting.ring import plot_ring_figures
from wavecontact.scene import two_rods_on_a_ring
from wavecontact.solvers import get_solver
from wavecontact.studies.ring import RingRun, run_ring

GAMMA = 0.6173
KAPPA = 4000.0
MODES = 75
# the ring's collocation rules before the quick ones (QUICK_NEWTON of wavecontact.modal.ring; ONSET_EFOLDS as then)
BEFORE_QUICK = {"QUICK_NEWTON": False, "ONSET_EFOLDS": 30.0}
# label -> (step_method, the settings of wavecontact.modal.ring it runs with)
VARIANTS = {"splitting": ("splitting", {"FREE_STEP_RUNGS": 0}),
            "collocation, sampled": ("collocation", {"FREE_STEP_RUNGS": 0, **BEFORE_QUICK}),
            "collocation, before": ("collocation", BEFORE_QUICK),
            "collocation": ("collocation", {})}
METHODS = ("collocation, before", "collocation")


@contextlib.contextmanager
def rules(method: str):
    """Run with the settings of the variant ``method`` in :mod:`wavecontact.modal.ring` (restored after)."""
    settings = VARIANTS[method][1]
    kept = {name: getattr(ring_module, name) for name in settings}
    for name, value in settings.items():
        setattr(ring_module, name, value)
    try:
        yield
    finally:
        for name, value in kept.items():
            setattr(ring_module, name, value)
STEP_IN_CIRCUMFERENCE = 0.015
FLIGHT_SAMPLE = 10  # the free flight is replayed before every so many collisions
CORRECTION_SAMPLE = 50  # the static correction's cost is measured on every so many collisions
ACCURACY_SAMPLE = 25  # start states of the accuracy table
SOFTNESS_BINS = (0.0, 100.0, 200.0, 400.0, 800.0, np.inf)
REFERENCE_TOLERANCE = 1e-7


def circumference(realisation: int) -> float:
    """Ring circumference of realisation ``r`` (the default one made ``1.5 r`` % larger)."""
    return two_rods_on_a_ring(GAMMA, KAPPA).ring_circumference * (1.0 + STEP_IN_CIRCUMFERENCE * realisation)


def simulation(method: str, length: float, **options):
    """A ring simulation of the variant ``method`` (a key of :data:`VARIANTS`)."""
    engine = get_solver("modal")
    with rules(method):  # FREE_STEP_RUNGS is read when the collocation tables are made
        return engine.simulate(two_rods_on_a_ring(GAMMA, KAPPA, length),
                               engine.options({"modes": MODES, "step_method": VARIANTS[method][0], **options}))


def without_compliance(sim):
    """The same ring with the static correction's compliance set to zero (for its cost per step)."""
    sim.system.pair_compliance[:] = 0.0
    for pair in getattr(sim, "_pairs", ()):
        pair.compliance = 0.0
    return sim


class _Clock:
    """CPU seconds spent inside the wrapped functions."""

    def __init__(self):
        self.seconds = 0.0

    def wrap(self, function):
        def timed(*args, **kwargs):
            started = time.process_time()
            try:
                return function(*args, **kwargs)
            finally:
                self.seconds += time.process_time() - started
        return timed


class _Instrumented:
    """A ring simulation whose collisions are timed; replays a sample of them for the phase split."""

    def __init__(self, method: str, length: float):
        self.sim = simulation(method, length)
        self.kernel = _Clock()
        self.sim.system.run_episode = self.kernel.wrap(self.sim.system.run_episode)
        for pair in getattr(self.sim, "_pairs", ()):
            pair.collide = self.kernel.wrap(pair.collide)
        self.instrumentation = 0.0  # CPU of the replays and copies (not part of the run)
        self.flight_shadow = simulation(method, length)
        self.with_c = simulation(method, length)
        self.without_c = without_compliance(simulation(method, length))
        self.rows = []  # (cpu, kernel cpu, steps, E_tr before) per collision
        self.flight = []  # CPU of the replayed flights
        self.correction = []  # (steps, cpu with compliance, steps, cpu without)
        self.reduced_mass = self.sim.reduced_mass
        self.total_energy = self.sim.total_energy

    def get_state(self):
        return self.sim.get_state()

    def set_state(self, state):
        self.sim.set_state(state)

    def next_collision(self):
        index = self.sim.collisions
        started = time.process_time()
        state = self.sim.get_state() if index % FLIGHT_SAMPLE == 0 or index % CORRECTION_SAMPLE == 0 else None
        self.instrumentation += time.process_time() - started
        kernel_before = self.kernel.seconds
        started = time.process_time()
        record = self.sim.next_collision()
        spent = time.process_time() - started
        self.rows.append((spent, self.kernel.seconds - kernel_before, record.steps,
                          record.translational_energy_before))
        started = time.process_time()
        if index % FLIGHT_SAMPLE == 0:
            self.flight_shadow.set_state(state)
            started = time.process_time()
            self.flight_shadow._run_until(0)
            self.flight.append(time.process_time() - started)
        if index % CORRECTION_SAMPLE == 0:
            measured = []
            for shadow in (self.with_c, self.without_c):
                shadow.set_state(state)
                started = time.process_time()
                steps = shadow.next_collision().steps
                measured += [steps, time.process_time() - started]
            self.correction.append(measured)
        self.instrumentation += time.process_time() - started
        return record


def profile_run(method: str, realisation: int, collisions: int) -> dict:
    """One instrumented ring run plus the end of the command (statistics, figures); CPU seconds per phase."""
    instrumented = {}

    def factory(scene, options):
        instrumented["sim"] = _Instrumented(method, scene.ring_circumference)
        return instrumented["sim"]

    checkpoint_clock, files_clock = _Clock(), _Clock()
    saved = ring_study._write_checkpoint, RingRun.save_npz, RingRun.save_csv
    ring_study._write_checkpoint = checkpoint_clock.wrap(saved[0])
    RingRun.save_npz = files_clock.wrap(saved[1])
    RingRun.save_csv = files_clock.wrap(saved[2])
    try:
        with tempfile.TemporaryDirectory() as out, rules(method):
            started = time.process_time()
            run = run_ring(GAMMA, KAPPA, MODES, collisions, out_dir=out, progress=False,
                           circumference=circumference(realisation), simulation_factory=factory,
                           solver_options={"step_method": VARIANTS[method][0]})
            run_cpu = time.process_time() - started
            started = time.process_time()
            stats = run.statistics()
            statistics_cpu = time.process_time() - started
            started = time.process_time()
            plot_ring_figures(run, out, stats)
            figures_cpu = time.process_time() - started
    finally:
        ring_study._write_checkpoint = saved[0]
        RingRun.save_npz, RingRun.save_csv = saved[1], saved[2]
    sim = instrumented["sim"]
    rows = np.array(sim.rows)
    kernel = sim.kernel.seconds  # the splitting's kernel calls and the collocation's collisions
    run_cpu -= sim.instrumentation
    flight = float(np.mean(sim.flight)) * collisions
    correction = np.array(sim.correction)
    per_step_with = correction[:, 1].sum() / correction[:, 0].sum()
    per_step_without = correction[:, 3].sum() / correction[:, 2].sum()
    steps = rows[:, 2].sum()
    phases = {
        "free flight between collisions": flight,
        "contact integration": kernel - flight,
        "  of which the omitted modes' static correction": (per_step_with - per_step_without) * steps,
        "error estimates (none per collision)": 0.0,
        "per-collision records and the run's loop": run_cpu - kernel - checkpoint_clock.seconds
        - files_clock.seconds,
        "checkpoints (every 100 collisions)": checkpoint_clock.seconds,
        "data files (ring.npz, ring.csv)": files_clock.seconds,
        "statistics": statistics_cpu,
        "figures": figures_cpu,
    }
    phases["whole command (run + statistics + figures)"] = run_cpu + statistics_cpu + figures_cpu
    return {"phases": phases, "rows": rows, "run": run, "stats": stats}


def phase_table(results: dict, collisions: int, realisations: int) -> list[str]:
    methods = list(results)
    lines = [(f"CPU seconds per phase, {collisions} collisions, median over {realisations} realisations "
             "(ring circumference +0 %, +1.5 %, ...):"), "",
             "| phase | " + " | ".join(methods) + " |", "|---|" + "---:|" * len(methods)]
    for phase in results[methods[0]][0]["phases"]:
        cells = [f"{np.median([r['phases'][phase] for r in results[m]]):.2f}" for m in methods]
        lines.append(f"| {phase} | " + " | ".join(cells) + " |")
    spread = ", ".join(
        f"{m}: " + " / ".join(f"{r['phases']['whole command (run + statistics + figures)']:.1f}" for r in results[m])
        for m in methods)
    return [*lines, "", f"Whole command per realisation (CPU s): {spread}."]


def softness_table(results: dict) -> list[str]:
    methods = list(results)
    lines = [("Per collision against its softness `kappa_j = alpha |w_j| l / c` (pooled over the realisations; "
             "CPU ms and steps are medians):"), "",
             "| kappa_j | " + " | ".join(f"{m}: collisions | ms | steps" for m in methods) + " |",
             "|---|" + "---:|---:|---:|" * len(methods)]
    for low, high in itertools.pairwise(SOFTNESS_BINS):
        cells = []
        for m in methods:
            rows = np.concatenate([r["rows"] for r in results[m]])
            kappa_j = KAPPA * 2.0 * np.sqrt(rows[:, 3])  # E_tr = mu w^2 / 2 with mu = 1/2
            inside = (kappa_j >= low) & (kappa_j < high)
            if inside.any():
                cells.append(f"{inside.sum()} | {1e3 * np.median(rows[inside, 0]):.2f} | "
                             f"{np.median(rows[inside, 2]):.0f}")
            else:
                cells.append("0 | - | -")
        label = f"{low:g}-{high:g}" if np.isfinite(high) else f">= {low:g}"
        lines.append(f"| {label} | " + " | ".join(cells) + " |")
    return lines


def accuracy_table(collisions: int, every: int) -> list[str]:
    """Restitution error of each integrator from the same start states, against a tight collocation."""
    base = simulation("collocation", circumference(0))
    states = []
    for j in range(collisions):
        if j % every == 0 and j > 0:
            states.append(base.get_state())
        base.next_collision()

    def restitutions(method, **options):
        values = []
        with rules(method):
            for state in states:
                sim = simulation(method, circumference(0), **options)
                sim.set_state(state)
                values.append(sim.next_collision().restitution)
        return np.array(values)

    phase = ring_module.TOP_STEP_PHASE
    ring_module.TOP_STEP_PHASE = phase / 4.0
    try:  # every step sampled (no long steps), a quarter of the sampling step, the rules before the quick ones
        reference = restitutions("collocation, sampled", collocation_tolerance=REFERENCE_TOLERANCE)
    finally:
        ring_module.TOP_STEP_PHASE = phase
    lines = [(f"Restitution error per collision against the collocation at tolerance {REFERENCE_TOLERANCE:g} and a "
             f"quarter of the sampling step, every step sampled ({len(states)} start states, every {every}th "
             f"collision of the first {collisions} of the first realisation):"), "",
             "| integrator | median | 90 % | 99 % | max | collisions above 1e-6 |", "|---|---:|---:|---:|---:|---:|"]
    for label, method, options in (
        ("splitting, default step", "splitting", {}),
        ("collocation, every step sampled (the ring two changes ago)", "collocation, sampled", {}),
        ("collocation, long steps where the force is negligible (the ring before)", "collocation, before", {}),
        ("collocation, quick Newton (the ring now)", "collocation", {}),
    ):
        error = np.abs(restitutions(method, **options) - reference)
        q50, q90, q99 = np.quantile(error, [0.5, 0.9, 0.99])
        lines.append(f"| {label} | {q50:.1e} | {q90:.1e} | {q99:.1e} | {error.max():.1e} | {(error > 1e-6).sum()} |")
    return lines


STATISTICS = (
    ("collisions until E_tr relaxes", lambda s: s.relaxation_collisions),
    ("stationary mean E_tr / Eq. 8", lambda s: s.mean_translational_energy / s.equilibrium_translational_energy),
    ("KS p, thinned", lambda s: s.ks_pvalue),
    ("stationary mean eta", lambda s: s.mean_spectral_entropy),
    ("collisions until eta settles", lambda s: s.entropy_settling_collisions),
    ("C_eps(1) / C_eps(0)", lambda s: s.restitution_correlation_coefficient_lag1),
    ("mean restitution", lambda s: s.mean_restitution),
    ("largest energy drift", lambda s: s.energy_drift),
)


def statistics_table(results: dict) -> list[str]:
    methods = list(results)
    lines = [("The statistics of every realisation (the same circumferences for both integrators; a chaotic run, "
             "so each integrator gives other realisations) and their mean +- standard deviation:"), "",
             "| quantity | " + " | ".join(methods) + " |", "|---|" + "---|" * len(methods)]
    for name, get in STATISTICS:
        cells = []
        for m in methods:
            values = [get(r["stats"]) for r in results[m]]
            numbers = np.array([np.nan if v is None else float(v) for v in values])
            text = ", ".join("n/a" if v is None else f"{float(v):.3g}" for v in values)
            cells.append(f"{text} ({np.nanmean(numbers):.3g} +- {np.nanstd(numbers, ddof=1):.2g})")
        lines.append(f"| {name} | " + " | ".join(cells) + " | " + _agreement(results, get) + " |")
    lines[2] += " same distribution? |"
    lines[3] += "---|"
    return [*lines, "", ("Same distribution? (criterion fixed before the runs): the means of the first and the last "
                         "integrator over their realisations differ by at most twice their combined standard error "
                         "sqrt((s_1^2 + s_2^2) / n).")]


def _agreement(results: dict, get) -> str:
    """Whether the first and the last integrator's means agree within twice their combined standard error."""
    first, last = (np.array([np.nan if get(r["stats"]) is None else float(get(r["stats"])) for r in results[m]])
                   for m in (next(iter(results)), list(results)[-1]))
    first, last = first[np.isfinite(first)], last[np.isfinite(last)]
    if first.size < 2 or last.size < 2:
        return "n/a"
    difference = abs(first.mean() - last.mean())
    bound = 2.0 * np.sqrt(first.var(ddof=1) / first.size + last.var(ddof=1) / last.size)
    return f"{'yes' if difference <= bound else 'NO'} ({difference:.2g} vs {bound:.2g})"


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--collisions", type=int, default=1000)
    parser.add_argument("--realisations", type=int, default=5)
    parser.add_argument("--methods", nargs="+", default=list(METHODS), choices=list(VARIANTS))
    parser.add_argument("--accuracy-every", type=int, default=ACCURACY_SAMPLE,
                        help="start states of the accuracy table: every so many collisions (of at most 1000)")
    parser.add_argument("--update-docs", action="store_true",
                        help="also write the tables into docs/ring.md (between its ring-profile markers)")
    args = parser.parse_args(argv)

    def measure():
        for method in args.methods:  # compile or load the kernels before timing
            run_ring(GAMMA, KAPPA, MODES, 3, progress=False, solver_options={"step_method": VARIANTS[method][0]})
        results = {m: [] for m in args.methods}
        for realisation in range(args.realisations):
            for method in args.methods:  # alternately, so that a change of load hits both
                results[method].append(profile_run(method, realisation, args.collisions))
        print("\n".join(phase_table(results, args.collisions, args.realisations)))
        print()
        print("\n".join(softness_table(results)))
        print()
        print("\n".join(accuracy_table(min(args.collisions, 1000), args.accuracy_every)))
        print()
        print("\n".join(statistics_table(results)))
        print()
        print(f"load average (1, 5, 15 min) at the end: {os.getloadavg()}")

    run_and_write(measure, "ring.md", "ring-profile", args.update_docs,
                  None if argv is None else ["benchmarks/profile_ring.py", *argv])


if __name__ == "__main__":
    main()
