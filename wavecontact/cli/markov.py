"""``wavecontact markov``: successive collisions as a Markov chain of E_tr (Sec. VII, Eq. 27-36, Fig. 10)."""

from __future__ import annotations

import json
import math
from pathlib import Path

from ..solvers import solver_names
from .common import (
    FIGURE_SUFFIXES,
    files_summary,
    gamma_value,
    kappa_value,
    nonnegative_int,
    positive_float,
    positive_int,
    report_written,
)
from .costs import add_work_option, check_run, thermal_samples_cost
from .executors import executor_from
from .guard import check_outputs, refuse_unused


def add_parser(subparsers):
    p = subparsers.add_parser(
        "markov",
        help="collisions as a Markov chain of the translational energy: Boltzmann stationary state (Fig. 10)",
        description="Run CHAINS independent chains of STEPS collisions E_tr -> eps^2 E_tr, eps^2 drawn by "
        "solving a thermal collision (solve), from a restitution table (table) or by Glauber's rule "
        "(glauber), with the bath temperature fixed (Eq. 30-32) or updated by energy conservation (Eq. 28). "
        "Prints the stationary mean of E_tr/T_B^0, the fraction below T_B^0 and a KS test against Eq. 30.",
    )
    p.add_argument("--gamma", type=gamma_value, required=True, help="length ratio l1/l2 in (0, 1]")
    p.add_argument("--kappa", type=kappa_value, default=math.inf,
                   help="alpha V l / c in (0, inf] of each solved collision (default inf: hard core)")
    p.add_argument("--chains", type=positive_int, default=1, help="independent chains (default 1)")
    p.add_argument("--steps", type=positive_int, default=10_000, help="collisions per chain (default 10000)")
    p.add_argument("--seed", type=nonnegative_int, default=0, help="root seed (default 0)")
    p.add_argument("--rule", choices=("solve", "table", "glauber"), default="solve",
                   help="where eps^2 comes from (default solve)")
    p.add_argument("--table", metavar="FILE", help="restitution table (.npz/.json) for --rule table")
    p.add_argument("--bath", choices=("fixed", "conserved"), default="fixed",
                   help="bath temperature held at T_B^0 (Eq. 30) or updated by energy conservation (Eq. 28)")
    p.add_argument("--modes-per-rod", type=positive_int, default=250, help="N_mod of Eq. 28/31 (default 250)")
    p.add_argument("--initial-energy", type=positive_float, default=1.0,
                   help="E_tr(0)/T_B^0 (default 1.0; with --bath conserved at most 2 N_mod + 1)")
    p.add_argument("--bath-modes", type=positive_int, default=250,
                   help="excited modes per rod nu_max in each solved collision (default 250)")
    p.add_argument("--solver", choices=solver_names(), default=None,
                   help="solver of each collision for --rule solve (default delay)")
    p.add_argument("--burn-in", type=nonnegative_int, default=None,
                   help="steps discarded before the stationary statistics (default: from the relaxation)")
    p.add_argument("--workers", type=nonnegative_int, default=0,
                   help="worker processes (default 0: run here)")
    p.add_argument("--scheduler", metavar="ADDRESS", help="run the chains on a dask.distributed scheduler (default: none, local processes)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--plot", metavar="FILE", help="write Fig. 10 (distribution of E_tr/T_B^0) to FILE")
    p.add_argument("--out", metavar="DIR", help="write markov.npz and summary.json into DIR (and each finished "
                   "batch of chains: the same command again resumes)")
    p.add_argument("--overwrite", action="store_true",
                   help="replace another Markov run found in DIR instead of refusing")
    p.add_argument("--no-progress", dest="progress", action="store_false", help="no progress bar")
    add_work_option(p)
    p.set_defaults(run=run)
    return p


def run(args) -> int:
    from ..errors import InvalidParameterError
    from ..io.run_controller import RunSettings
    from ..studies.markov import MarkovSpec, markov_chains

    if args.burn_in is not None and args.burn_in > args.steps - 2:
        raise InvalidParameterError(f"--burn-in must be at most steps - 2 = {args.steps - 2}, got {args.burn_in}")
    if args.rule != "table" and args.table:
        raise InvalidParameterError("--table is used only with --rule table")
    if args.steps < 4:
        raise InvalidParameterError(f"--steps must be at least 4 for the statistics, got {args.steps}")
    if args.scheduler and args.workers:
        raise InvalidParameterError("give either --workers or --scheduler, not both")
    if args.rule != "solve":
        refuse_unused({"--solver": args.solver, "--kappa": None if math.isinf(args.kappa) else args.kappa,
                       "--bath-modes": None if args.bath_modes == 250 else args.bath_modes},
                      f"with --rule {args.rule} (they set the solved collisions of --rule solve)")
    solver = args.solver or "delay"
    MarkovSpec(args.gamma, args.kappa, args.rule, args.chains, args.steps, args.seed, args.bath, args.modes_per_rod,
               args.initial_energy, args.bath_modes, solver, {}, args.table)  # refuses before any work
    out = Path(args.out) if args.out else None
    check_outputs(files=[("--plot", args.plot, FIGURE_SUFFIXES)],
                  directories=[("--out", args.out, ("markov.npz", "summary.json", "markov.json"))])
    if args.rule == "solve":
        check_run(args, f"markov: {args.chains} x {args.steps} solved collisions",
                  thermal_samples_cost(args.chains * args.steps, args.kappa, args.bath_modes, solver, args.gamma),
                  "use fewer --chains, --steps or --bath-modes, or --rule table")
    with executor_from(args.workers, args.scheduler) as executor:
        result = markov_chains(
            args.gamma, kappa=args.kappa, rule=args.rule, chains=args.chains, steps=args.steps, seed=args.seed,
            bath=args.bath, modes_per_rod=args.modes_per_rod, initial_energy=args.initial_energy,
            bath_modes=args.bath_modes, solver=solver, table=args.table,
            run=RunSettings(executor=executor, progress=None if args.progress else False, out=args.out,
                            overwrite=args.overwrite),
        )
    summary = result.summary(args.burn_in)
    written = []
    if out is not None:
        from ..io.run_controller import write_summary

        written.append(result.save(out))
        write_summary(out / "summary.json", summary)
        written += [out / "summary.json", out / "markov.json", files_summary(out, "chains_*.npz")]
    if args.plot:
        from ..plotting.markov import plot_stationary_distribution

        plot_stationary_distribution(result, args.plot, args.burn_in)
        written.append(args.plot)
    summary["files_written"] = report_written(written)
    if args.json:
        print(json.dumps(summary))
        return 0
    print(f"Markov chain, rule {summary['rule']}, bath {summary['bath']}: {summary['chains']} chain(s) x "
          f"{summary['steps']} steps, gamma = {summary['gamma']:g}, burn-in {summary['burn_in']}")
    print(f"  mean E_tr/T_B^0 (stationary)   {summary['mean_energy']:.4f} +- "
          f"{summary['mean_energy_standard_error']:.4f}   (Boltzmann, Eq. 30: 1)")
    print(f"  fraction below T_B^0           {summary['fraction_below_bath_temperature']:.4f} +- "
          f"{summary['fraction_below_bath_temperature_standard_error']:.4f}   "
          f"(Boltzmann: {summary['boltzmann_fraction_below']:.4f})")
    print(f"  standard errors from the integrated autocorrelation time {summary['integrated_autocorrelation_time']:.2f} "
          f"steps (window {summary['autocorrelation_window']}, {summary['effective_samples']:.0f} effective states"
          f"{'' if summary['autocorrelation_time_reliable'] else '; chains shorter than 50 tau: a rough estimate'})")
    print(f"  KS test against exp(-E/T_B^0)  D = {summary['ks_statistic']:.4f}, p = {summary['ks_pvalue']:.3g} "
          f"({summary['ks_samples']} states, every {summary['ks_stride']}th)")
    return 0
