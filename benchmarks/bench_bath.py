"""Thermal-bath performance: one command, one table (issue 11, "Performance").

    python benchmarks/bench_bath.py            # everything (several minutes on a shared 2-core machine)
    python benchmarks/bench_bath.py --quick    # smaller sample counts
    python benchmarks/bench_bath.py --hard-core-only   # rows 1 and the Fig. 8 hard-core row (about a minute);
                                                       # with --update-docs it replaces only those rows

    python benchmarks/bench_bath.py --full     # row 3 at kappa = 250 in full (50,000 samples, under
                                               # 30 s on a quiet 2-core machine) instead of a subset
    python benchmarks/bench_bath.py --kappa-250-only [--full]   # only the kappa = 250 rows of 2 and 3

Rows:
1. the stochastic hard-core mode (kappa = inf): samples per CPU second on one core at 8 (the default) and
   4 grid points per period of the fastest mode, with the mean error against 32 points on the same samples;
2. one finite-kappa sample as an ensemble computes it (its defaults ENSEMBLE_DELAY_OPTIONS: rtol
   1e-3, Lobatto-Kronrod rule, 16 noise table nodes a period; no energy split; batches of 64 samples), CPU ms per sample (median
   of 3 batches) against kappa (nu_max 250) and nu_max (kappa 250); at kappa 250 also at rtol 1e-6
   with the Gauss-Kronrod rule (the setting before), and one ``collide()`` with its defaults
   (rtol 1e-11, energy split) for comparison (benchmarks/ensemble_accuracy.py measures what the
   tolerance costs in accuracy);
3. the Fig. 8 set (2 gamma x 10 T_B/E_tr x 2500 = 50,000 collisions, nu_max = 250) through
   the parallel path (2 local worker processes): hard-core mode in full; kappa = 250 on
   100 samples a point (2,000), extrapolated, or in full with --full;
4. peers on one realisation (kappa 100, nu_max 50), each at a per-sample error far below the
   standard error of a 2500-sample ensemble mean (matched accuracy of the mean): JiTCDDE with
   the noise as input, scipy solve_ivp (DOP853) on the modal equations with the thermal start;
   time ratios to wavecontact's delay solver in the same run;
5. Dask: samples per second with 1 and 2 local workers, and the overhead per task.

Timings are medians of repeats; the machine is shared with other jobs, so absolute
numbers vary from run to run (the load average is printed).
"""

from __future__ import annotations

import argparse
import logging
import math
import os
import resource
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import asdict
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from timing import median_time

import wavecontact
from wavecontact.api import solve
from wavecontact.bath import ThermalBath
from wavecontact.bath.collide import thermal_scene
from wavecontact.bath.scene import scene_noise
from wavecontact.studies.bath_figures import FIG8_TEMPERATURES, spread_against_temperature
from wavecontact.studies.ensemble import ENSEMBLE_DELAY_OPTIONS, EnsembleSpec, ensemble, run_batch

GAMMA = 0.6173
PREVIOUS = {"rtol": 1e-6, "quadrature": "gauss-kronrod", "noise_resolution": 32}  # the ensemble setting before


ROWS: list = []  # the table as printed, for --update-docs
DOCS = Path(__file__).resolve().parent.parent / "docs"


def row(name, value, note=""):
    line = f"| {name:<58} | {value:>14} | {note} |"
    ROWS.append(line)
    print(line)


def _row_name(line):
    return line.split("|")[1].strip() if line.startswith("|") else None


def update_docs(header, partial=False):
    """Write the table into docs/bath.md (between its bench-bath markers) and docs/figures/bath/bench.txt.

    ``partial``: replace only the rows measured in this run (matched by their quantity) and
    say so under the header, keeping the other rows of the last full run.
    """
    table = "\n".join([header, "", "| quantity | value | note |", "|---|---|---|", *ROWS])
    if partial:
        page = DOCS / "bath.md"
        start, end = "<!-- bench-bath:start -->", "<!-- bench-bath:end -->"
        old = page.read_text(encoding="utf-8").split(start, 1)[1].split(end, 1)[0].strip("\n").splitlines()
        new = {_row_name(line): line for line in ROWS}
        missing = set(new) - {_row_name(line) for line in old}
        if missing:
            raise SystemExit(f"--update-docs with --hard-core-only: no row named {sorted(missing)} in docs/bath.md; "
                             "run the full benchmark")
        note = f"Hard-core rows re-measured by {header}"
        lines = [new.get(_row_name(line), line) for line in old if not line.startswith("Hard-core rows re-measured")]
        table = "\n".join([lines[0], note, *lines[1:]])
    (DOCS / "figures" / "bath" / "bench.txt").write_text(table + "\n", encoding="utf-8")
    page = DOCS / "bath.md"
    text = page.read_text(encoding="utf-8")
    start, end = "<!-- bench-bath:start -->", "<!-- bench-bath:end -->"
    before, rest = text.split(start, 1)
    _old, after = rest.split(end, 1)
    page.write_text(f"{before}{start}\n{table}\n{end}{after}", encoding="utf-8")


def hard_core_rate(samples, resolution):
    """Samples per CPU second (one core, serial ensemble) and the grid's mean error on the same samples.

    The error is the paired mean of epsilon minus epsilon at 32 points per period (first order in
    the step, so the remaining error of the reference is about a quarter of the mean error at 8)."""
    ensemble(GAMMA, math.inf, 1.0, 8, 0, hard_core_resolution=resolution)  # kernels ready
    seconds = []
    for _ in range(3):
        started = time.process_time()
        result = ensemble(GAMMA, math.inf, 1.0, samples, 1, hard_core_resolution=resolution)
        seconds.append(time.process_time() - started)
    subset = min(samples, 2000)
    fine = ensemble(GAMMA, math.inf, 1.0, subset, 1, hard_core_resolution=32).restitution
    difference = result.restitution[:subset] - fine
    return samples / sorted(seconds)[1], float(difference.mean()), float(difference.std() / math.sqrt(subset))


def delay_sample_cpu(kappa, modes, count=64, temperature=1.0, options=None):
    """CPU seconds per ensemble sample (``run_batch`` of ``count`` samples, median of 3 batches;
    the ensemble's default options unless ``options``, no energy split)."""
    spec = EnsembleSpec(GAMMA, kappa, temperature, 3 * count, 3, bath_modes=modes, options=options or {})
    fields = asdict(spec)
    run_batch(fields, 0, 2)  # kernels ready
    times = []
    for start in range(0, 3 * count, count):
        started = time.process_time()
        run_batch(fields, start, start + count)
        times.append((time.process_time() - started) / count)
    return float(np.median(times))


def collide_default_cpu(kappa=250.0, modes=250, count=4):
    """Median CPU seconds of ``collide(gamma, kappa, bath_temperature=1, ...)`` with its defaults."""
    wavecontact.collide(GAMMA, kappa, bath_temperature=1.0, bath_modes=modes, seed=0, estimate_error=False)
    times = []
    for seed in range(count):
        started = time.process_time()
        wavecontact.collide(GAMMA, kappa, bath_temperature=1.0, bath_modes=modes, seed=seed, estimate_error=False)
        times.append(time.process_time() - started)
    return float(np.median(times))


def _children_cpu():
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def fig8_parallel(kappa, samples, gammas=(0.6173, 0.2173), temperatures=FIG8_TEMPERATURES):
    """Wall seconds, sample count and worker CPU seconds (start-up excluded) of the Fig. 8 set on 2 processes,
    run as ``wavecontact bath-figure 8 --workers 2`` runs it (``spread_against_temperature``, batches of 256).

    The workers' CPU time is read once they have exited (``RUSAGE_CHILDREN``);
    the CPU of a pool that only starts up and warms its kernels is measured
    first and subtracted.
    """
    def warm(pool):
        ensemble(GAMMA, kappa, 1.0, 4, 0, executor=pool, batch_size=1)  # workers import and load kernels

    before = _children_cpu()
    with ProcessPoolExecutor(2) as pool:
        warm(pool)
    start_up = _children_cpu() - before
    before = _children_cpu()
    with ProcessPoolExecutor(2) as pool:
        warm(pool)
        started = time.perf_counter()
        spread_against_temperature(gammas, temperatures, kappa, samples, 8, executor=pool)  # bath-figure 8's path
        wall = time.perf_counter() - started
    cpu = _children_cpu() - before - start_up
    return wall, len(gammas) * len(temperatures) * samples, cpu


def fig8_hard_core(samples):
    """The Fig. 8 set in the hard-core mode through 2 worker processes: wall seconds, the workers' CPU
    seconds (read from the finished children, so the load of other jobs does not count) and samples."""
    seconds, count, cpu = fig8_parallel(math.inf, samples)
    return seconds, cpu, count


def fig8_hard_core_row(quick):
    seconds, cpu, count = fig8_hard_core(250 if quick else 2500)
    row(f"Fig. 8 set, hard-core mode, {count} samples, 2 workers", f"{seconds:.1f} s",
        f"wall; workers' CPU {cpu:.1f} s = {count / cpu:,.0f} samples per CPU second; target <= 30 s")


def peers(modes=50, kappa=100.0, seed=3):
    """One realisation: wavecontact's delay solver, JiTCDDE with input, solve_ivp DOP853 on the modal system."""
    scene = thermal_scene(GAMMA, kappa, ThermalBath(1.0, modes), seed)
    reference = solve(scene, "delay", rtol=1e-11).restitution
    ours = solve(scene, "delay", energy_split=False, **ENSEMBLE_DELAY_OPTIONS)  # as an ensemble sample
    ours_time = median_time(lambda: solve(scene, "delay", energy_split=False, **ENSEMBLE_DELAY_OPTIONS), 5)
    # the delay solver's own accuracy at this tolerance: its error estimate, checked against the reference
    out = {"reference": reference, "ours": (ours.restitution, ours_time)}
    a0 = kappa * scene.gaps[0]
    span = ours.time[-1]
    try:
        from peers.jitcdde_thermal import restitution as jitcdde_restitution

        tables = scene_noise(scene, kappa, a0, 32)
        for rtol in (1e-5, 1e-7):
            eps, wall, compiled = jitcdde_restitution(GAMMA, kappa, scene, rtol, a0, tables, span)
            out[f"jitcdde rtol={rtol:g}"] = (eps, wall, compiled)
    except ImportError:
        out["jitcdde"] = None
    from peers.modal_solve_ivp import restitution as ivp_restitution

    for n_modes, rtol in ((2 * modes, 1e-8),):
        eps, wall = ivp_restitution(GAMMA, kappa, n_modes, rtol, scene=scene)
        out[f"DOP853 modes={n_modes} rtol={rtol:g}"] = (eps, wall)
    return out


def dask_scaling(samples):
    from distributed import Client, LocalCluster

    rates = {}
    for workers in (1, 2):
        with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None,
                          silence_logs=logging.ERROR) as cluster, \
                Client(cluster) as client:
            ensemble(GAMMA, math.inf, 1.0, 2 * workers, 0, executor=client, batch_size=1)  # warm workers
            started = time.perf_counter()
            ensemble(GAMMA, math.inf, 1.0, samples, 5, executor=client, batch_size=250)
            rates[workers] = samples / (time.perf_counter() - started)
            if workers == 2:
                executor = client.get_executor(pure=False)
                started = time.perf_counter()
                futures = [executor.submit(abs, -j) for j in range(400)]
                [f.result() for f in futures]
                rates["overhead"] = (time.perf_counter() - started) / 400
    return rates


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer samples")
    parser.add_argument("--hard-core-only", action="store_true",
                        help="only the hard-core rows (1 and the Fig. 8 hard-core row), about a minute")
    parser.add_argument("--full", action="store_true", help="the Fig. 8 set at kappa = 250 in full (50,000 samples)")
    parser.add_argument("--kappa-250-only", action="store_true",
                        help="only the finite-kappa rows at kappa 250 (one sample's cost, the Fig. 8 set)")
    parser.add_argument("--update-docs", action="store_true",
                        help="write the table into docs/bath.md section 9 and docs/figures/bath/bench.txt")
    args = parser.parse_args(argv)
    quick = args.quick
    logging.getLogger("distributed").setLevel(logging.ERROR)
    flags = "".join(f" --{name}" for name, on in (("quick", quick), ("full", args.full), ("kappa-250-only", args.kappa_250_only)) if on)
    header = (f"`python benchmarks/bench_bath.py{flags}`: "
              f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores at the start; wavecontact "
              f"{wavecontact.__version__}")
    print(header)
    print("| quantity | value | note |")
    if args.kappa_250_only:
        delay_rows(quick, args.full)
        return 0
    for resolution in (8, 4):
        rate, bias, bias_error = hard_core_rate(500 if quick else 5000, resolution)
        row(f"hard-core mode (gamma 0.6173, T_B/E_tr 1, nu_max 250), {resolution} points/period, CPU",
            f"{rate:,.0f} /s", f"per core, target >= 20,000 /s; mean error {bias:+.1e} +- {bias_error:.0e}")
    if args.hard_core_only:
        fig8_hard_core_row(quick)
        if args.update_docs:
            update_docs(header.replace("bench_bath.py", "bench_bath.py --hard-core-only", 1), partial=True)
        return 0
    delay_rows(quick, args.full, sweep=True)
    fig8_hard_core_row(quick)
    peer_rows()
    scaling = dask_scaling(400 if quick else 4000)
    row("Dask LocalCluster, hard-core samples/s, 1 worker", f"{scaling[1]:,.0f} /s")
    row("Dask LocalCluster, hard-core samples/s, 2 workers", f"{scaling[2]:,.0f} /s",
        f"speed-up {scaling[2] / scaling[1]:.2f}")
    row("Dask overhead per task (2 workers, trivial task)", f"{1e3 * scaling['overhead']:.2f} ms")
    if args.update_docs:
        update_docs(header)
    return 0


def delay_rows(quick, full, sweep=False):
    """The finite-kappa rows: one sample's CPU cost (against kappa and nu_max with ``sweep``) and the
    Fig. 8 set at kappa 250 through 2 worker processes (a subset, extrapolated, unless ``full``)."""
    default = "ensemble defaults (rtol 1e-3, Lobatto-Kronrod, 16 noise nodes), no energy split"
    for kappa in (5.0, 20.0, 50.0, 100.0, 250.0, 1000.0, 1e4) if sweep else (250.0,):
        row(f"delay sample, kappa {kappa:g}, nu_max 250 (CPU)", f"{1e3 * delay_sample_cpu(kappa, 250):.2f} ms",
            f"{default}; target 1.2 ms at kappa 250")
    for modes in (50, 250, 1000) if sweep else ():
        row(f"delay sample, kappa 250, nu_max {modes} (CPU)", f"{1e3 * delay_sample_cpu(250.0, modes):.2f} ms",
            default)
    row("delay sample, kappa 250, nu_max 250, rtol 1e-6 Gauss-Kronrod (CPU)",
        f"{1e3 * delay_sample_cpu(250.0, 250, options=PREVIOUS):.2f} ms",
        "the previous ensemble setting, for comparison")
    if sweep:
        row("collide(0.6173, 250, T_B/E_tr 1, nu_max 250), its defaults (CPU)",
            f"{1e3 * collide_default_cpu():.2f} ms", "rtol 1e-11, energy split")
    per_point = 2500 if full else (10 if quick else 100)
    seconds, count, cpu = fig8_parallel(250.0, per_point)
    note = (f"; {cpu / 2:.0f} s at 2 full cores" if full else
            f"; extrapolated to 50,000: {seconds / count * 50000:.0f} s wall, {cpu / count * 50000 / 2:.0f} s at 2 "
            "full cores")
    row(f"Fig. 8 set at kappa 250: {count} samples, 2 workers", f"{seconds:.1f} s",
        f"{count / seconds / 2:,.0f} samples/s/core wall, {1e3 * cpu / count:.2f} ms CPU per sample{note}; "
        "target <= 30 s")


def peer_rows():
    result = peers()
    reference = result.pop("reference")
    ours_time = result["ours"][1]
    for name, value in result.items():
        if value is None:
            row(name, "not installed", "pip install jitcdde symengine")
            continue
        note = f"abs(eps - ref) = {abs(value[0] - reference):.1e}"
        if name != "ours":
            note += f", {value[1] / ours_time:.0f}x ours"
        if len(value) == 3:
            note += f", compile {value[2]:.1f} s"
        row(f"peer, one sample (kappa 100, nu_max 50): {name}", f"{value[1]:.4f} s", note)


if __name__ == "__main__":
    sys.exit(main())
