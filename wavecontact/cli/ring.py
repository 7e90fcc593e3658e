"""``wavecontact ring``: many successive collisions of two rods on a ring (Fig. 1-3)."""

from __future__ import annotations

import csv
import json
import math
import sys
from pathlib import Path

from ..solvers.auto_ring import CHECK_EVERY, DEFAULT_TOLERANCE, ERROR_QUANTILE, choose_modes
from .common import (
    add_ring_options,
    files_summary,
    gamma_value,
    kappa_value,
    nonnegative_int,
    positive_float,
    positive_int,
    report_written,
)
from .costs import add_work_option, check_run, ring_cost
from .guard import check_outputs

SUMMARY_NAME = "summary.json"
SPECTRUM_NAME = "modal_spectrum.csv"



def add_parser(subparsers):
    p = subparsers.add_parser(
        "ring",
        help="many collisions of two rods on a ring: relaxation to equipartition (Fig. 1-3)",
        description="Start two rods of length ratio gamma maximally far apart on a ring with a cold bath, "
        "let them collide COLLISIONS times, and write per-collision data (ring.npz, ring.csv), the "
        "statistics (summary.json, modal_spectrum.csv) and Fig. 1-3 into DIR. A checkpoint in DIR "
        "of the same run is resumed automatically.",
    )
    p.add_argument("--gamma", type=gamma_value, required=True, help="length ratio l1/l2 in (0, 1]")
    p.add_argument("--kappa", type=kappa_value, required=True, help="alpha V l / c in (0, inf]")
    p.add_argument("--modes", type=positive_int, default=None,
                   help="modes per rod N (default: the fewest predicted to meet --tolerance)")
    p.add_argument("--tolerance", type=positive_float, default=None,
                   help=f"tolerance on each collision's restitution error from truncating the modes (absolute; "
                        f"default {DEFAULT_TOLERANCE:g}): without --modes it chooses N (the fewest predicted to "
                        f"keep {ERROR_QUANTILE * 100:g} %% of the collisions within it); with --modes it is reported "
                        f"against; the first and every {CHECK_EVERY}th collision is checked against a run of it "
                        f"with 2N modes")
    p.add_argument("--collisions", type=positive_int, required=True, help="number of collisions M")
    add_ring_options(p)
    p.add_argument("--checkpoint-every", type=positive_int, default=100, metavar="K",
                   help="write a checkpoint every K collisions")
    p.add_argument("--overwrite", action="store_true",
                   help="replace a checkpoint of another run found in DIR instead of refusing it")
    p.add_argument("--transient", type=nonnegative_int, default=None,
                   help="collisions discarded before stationary averages (default: chosen from the relaxation)")
    p.add_argument("--max-lag", type=positive_int, default=20, help="largest lag k of C_eps(k)")
    p.add_argument("--json", action="store_true", help="print the summary (summary.json) as one JSON object")
    add_work_option(p)
    p.set_defaults(run=run)
    return p


def _log(message: str) -> None:
    print(f"wavecontact ring: {message}", file=sys.stderr, flush=True)


def _write_spectrum(path: Path, spectrum) -> None:
    with open(path, "w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(["mode", "w_rod1", "w_rod2"])
        for nu in range(spectrum.shape[1]):
            writer.writerow([nu + 1, repr(float(spectrum[0, nu])), repr(float(spectrum[1, nu]))])


def _format(value, spec=".4g") -> str:
    return "n/a" if value is None or (isinstance(value, float) and math.isnan(value)) else format(value, spec)


def output_names() -> tuple:
    """Every file ``ring`` writes into ``--out``."""
    from ..plotting.ring import FIGURE_NAMES
    from ..studies.ring import CHECKPOINT_NAME, DATA_CSV_NAME, DATA_NPZ_NAME

    return (CHECKPOINT_NAME, DATA_NPZ_NAME, DATA_CSV_NAME, SUMMARY_NAME, SPECTRUM_NAME, *FIGURE_NAMES.values())


def run(args) -> int:
    from ..errors import InvalidParameterError
    from ..io.run_controller import write_summary
    from ..plotting.ring import plot_ring_figures
    from ..studies.ring import CHECKPOINT_NAME, run_ring

    out = Path(args.out)
    if args.collisions < 4:
        raise InvalidParameterError(f"--collisions must be at least 4 for the statistics, got {args.collisions}")
    if args.transient is not None and args.transient > args.collisions - 3:
        raise InvalidParameterError(
            f"--transient must be at most collisions - 3 = {args.collisions - 3}, got {args.transient}"
        )
    check_outputs(directories=[("--out", args.out, output_names())])
    choice = choose_modes(args.gamma, args.kappa, args.collisions, modes=args.modes, tolerance=args.tolerance,
                          static_correction=args.static_correction, max_work=args.max_work)
    if choice.chosen:
        _log(f"modes: {choice.reason}")
    check_run(args, f"ring: {args.collisions} collisions at N = {choice.modes}",
              ring_cost(args.kappa, [choice.modes], args.collisions), "use fewer --collisions or --modes")
    ring_run = run_ring(
        args.gamma,
        args.kappa,
        choice.modes,
        args.collisions,
        out_dir=out,
        checkpoint_every=args.checkpoint_every,
        progress=args.progress,
        tolerance=choice,
        solver_options={"static_correction": args.static_correction},
        log=_log,
        overwrite=args.overwrite,
    )
    stats = ring_run.statistics(transient=args.transient, max_lag=args.max_lag)
    summary = {
        "gamma": ring_run.gamma,
        "kappa": ring_run.kappa if math.isfinite(ring_run.kappa) else "inf",
        "static_correction": ring_run.static_correction,
        "wall_time_s": ring_run.wall_time_s,
        "resumed_from": ring_run.resumed_from,
        **stats.as_dict(),
        "accuracy": ring_run.metadata.get("accuracy"),
    }
    summary.pop("mean_relative_spectrum")
    write_summary(out / SUMMARY_NAME, summary)
    _write_spectrum(out / SPECTRUM_NAME, stats.mean_relative_spectrum)
    figures = plot_ring_figures(ring_run, out, stats)
    rows = files_summary(out, f"{Path(CHECKPOINT_NAME).stem}.rows-*.npz")  # the checkpoint's rows (RowChunks)
    files = report_written([out / CHECKPOINT_NAME, rows, out / "ring.npz", out / "ring.csv", out / SUMMARY_NAME,
                            out / SPECTRUM_NAME, *figures])
    if args.json:
        print(json.dumps({**summary, "files_written": files}))
        return 0

    ratio = stats.mean_translational_energy / stats.equilibrium_translational_energy
    print(f"{ring_run.n_collisions} collisions (gamma = {ring_run.gamma:g}, kappa = {ring_run.kappa:g}, "
          f"N = {ring_run.modes}) in {ring_run.wall_time_s:.1f} s; stationary from collision {stats.transient}")
    print(f"  E_tr relaxed after {_format(stats.relaxation_collisions, 'd')} collisions; stationary mean "
          f"{stats.mean_translational_energy:.5g} +- {stats.translational_energy_standard_error:.2g} "
          f"vs Eq. 8 {stats.equilibrium_translational_energy:.5g} (ratio {ratio:.3f})")
    print(f"  KS test of stationary E_tr against Eq. 9 ({stats.ks_samples} values, stride {stats.ks_stride}): D = {stats.ks_statistic:.4f}, p = {stats.ks_pvalue:.3g} (all values: p = "
          f"{stats.ks_pvalue_all_samples:.3g}; lag-1 autocorrelation of E_tr "
          f"{stats.translational_energy_autocorrelation_lag1:+.3f})")
    print(f"  spectral entropy: stationary mean {stats.mean_spectral_entropy:.4f} +- "
          f"{stats.spectral_entropy_standard_error:.1g} vs Eq. 11 {stats.equilibrium_spectral_entropy:.4f} "
          f"(finite-N value {stats.equilibrium_spectral_entropy_finite:.4f}); settled after "
          f"{_format(stats.entropy_settling_collisions, 'd')} collisions")
    print(f"  restitution: mean {stats.mean_restitution:.4f}, C(1)/C(0) = "
          f"{stats.restitution_correlation_coefficient_lag1:+.3f}; energy drift {stats.energy_drift:.2e}")
    accuracy = summary["accuracy"]
    if accuracy is not None:
        print(f"  modes: {accuracy['reason']}")
        print(f"  per-collision error checks: {accuracy['checks']['verdict']}")
    return 0
