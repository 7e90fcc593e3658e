"""The numbers of docs/ring.md's "A result" section, one command:

    python docs/ring_result.py            # the paper's run and its spread over other realisations
    python docs/ring_result.py --quick    # only the paper's run (no spread study)

Prints two Markdown blocks:

1. the paper's case (gamma = 0.6173, kappa = 4000, N = 75 modes, 4500 collisions, modal ring
   integrator, the default ring circumference), the same run as
   ``wavecontact ring --gamma 0.6173 --kappa 4000 --modes 75 --collisions 4500 --out runs/paper``,
   as a table of measured against expected values (Eq. 8, 9, 11 from ``wavecontact.analytic``);
2. the spread over other realisations of the same chaotic run: the ring circumference made
   1 % .. 7 % larger (the collisions until ``E_tr`` relaxes, from 120 collisions each) and three full
   runs 2 %, 4 % and 6 % larger (stationary mean ``E_tr`` against Eq. 8, lag-1 autocorrelation,
   KS p-values on all and on thinned samples).

``python docs/generate.py ring-result ring-spread`` writes both into docs/ring.md (about 3 minutes on
2 cores); tests/test_docs.py re-runs the first collisions of the paper's run and checks the relaxation
count and the Eq. 8 / Eq. 11 columns.
"""

from __future__ import annotations

import argparse
import os
import resource
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))

from wavecontact.scene import two_rods_on_a_ring
from wavecontact.studies.ring import run_ring
from wavecontact.studies.ring_statistics import relaxation_collisions

GAMMA, KAPPA, MODES, COLLISIONS = 0.6173, 4000.0, 75, 4500
SHORT_RUN = 120  # collisions of the relaxation-only realisations
LARGER = (0.01, 0.02, 0.03, 0.04, 0.05, 0.06, 0.07)  # relative increases of the circumference
FULL = (0.02, 0.04, 0.06)


def paper_run_table() -> str:
    """The measured-against-expected table of the paper's run."""
    start, cpu = time.perf_counter(), time.process_time()
    run = run_ring(GAMMA, KAPPA, modes=MODES, collisions=COLLISIONS, progress=False)
    wall, cpu = time.perf_counter() - start, time.process_time() - cpu
    stats = run.statistics()
    peak_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    eq8 = stats.equilibrium_translational_energy
    se = stats.translational_energy_standard_error
    mean = stats.mean_translational_energy
    eta_se = stats.spectral_entropy_standard_error
    rows = [
        ("collisions until `E_tr` is in its stationary band", f"{stats.relaxation_collisions}",
         '"about 60" (paper)'),
        (f"stationary mean `E_tr` (collisions {stats.transient + 1}-{stats.collisions})",
         f"{mean:.6f} +- {se:.2g} ({mean / eq8:.3f} x Eq. 8, {abs(mean - eq8) / se:.1f} standard errors)",
         f"Eq. 8: {eq8:.7f}"),
        (f"KS test against Eq. 9 (every {stats.ks_stride}th value, {stats.ks_samples} values)",
         f"D = {stats.ks_statistic:.3f}, p = {stats.ks_pvalue:.2g}", "law not rejected if p is not small"),
        ("stationary mean `eta`", f"{stats.mean_spectral_entropy:.4f} +- {eta_se:.1g}",
         (f"Eq. 11: {stats.equilibrium_spectral_entropy:.4f} (finite-N value "
         f"{stats.equilibrium_spectral_entropy_finite:.4f})")),
        ("collisions until `eta` settles", f"{stats.entropy_settling_collisions}", '"about 5" (paper; see below)'),
        ("`C_eps(1) / C_eps(0)`", f"{stats.restitution_correlation_coefficient_lag1:.3f}", "small"),
        ("largest relative drift of the total energy", f"{stats.energy_drift:.2g}", "0"),
    ]
    lines = [(f"gamma = {GAMMA}, kappa = {KAPPA:g}, N = {MODES}, {COLLISIONS} collisions: {wall:.1f} s wall time "
             f"for the run ({cpu:.1f} s CPU time; on a busy machine the wall time is longer), "
             f"peak memory {peak_mb:.0f} MB"), "",
             "| quantity | measured | expected |", "|---|---|---|"]
    lines += [f"| {a} | {b} | {c} |" for a, b, c in rows]
    return "\n".join(lines)


def spread_table() -> str:
    """Relaxation counts and stationary statistics over other ring circumferences."""
    base = two_rods_on_a_ring(GAMMA, KAPPA).ring_circumference
    counts = []
    for larger in (0.0, *LARGER):
        run = run_ring(GAMMA, KAPPA, modes=MODES, collisions=SHORT_RUN, progress=False,
                       circumference=base * (1 + larger))
        counts.append(relaxation_collisions(run.translational_energy, run.statistics().equilibrium_translational_energy))
    shown = ", ".join("never" if c is None else str(c) for c in counts)
    settled = sorted(c for c in counts if c is not None)
    lines = [(f"collisions until `E_tr` relaxes, circumference 0 %, 1 %, ..., 7 % larger ({SHORT_RUN} collisions each): "
             f"{shown} (median {settled[len(settled) // 2] if settled else 'none'})"), "",
             ("| circumference | stationary mean `E_tr` / Eq. 8 | standard errors from Eq. 8 | lag-1 autocorrelation "
             "of `E_tr` | KS p, thinned | KS p, all values |"), "|---|---:|---:|---:|---:|---:|"]
    for larger in FULL:
        stats = run_ring(GAMMA, KAPPA, modes=MODES, collisions=COLLISIONS, progress=False,
                         circumference=base * (1 + larger)).statistics()
        eq8, mean, se = (stats.equilibrium_translational_energy, stats.mean_translational_energy,
                         stats.translational_energy_standard_error)
        lines.append(f"| +{larger:.0%} | {mean / eq8:.3f} | {abs(mean - eq8) / se:.1f} | "
                     f"{stats.translational_energy_autocorrelation_lag1:.2f} | {stats.ks_pvalue:.2g} | "
                     f"{stats.ks_pvalue_all_samples:.1g} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="only the paper's run")
    parser.add_argument("--only", choices=("paper", "spread"), help="print one of the two blocks")
    args = parser.parse_args(argv)
    if args.only != "spread":
        print(paper_run_table())
    if not args.quick and args.only != "paper":
        if args.only is None:
            print()
        print(spread_table())
    return 0


if __name__ == "__main__":
    sys.exit(main())
