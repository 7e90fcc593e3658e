"""``wavecontact bath-figure N``: the paper's thermal-bath figures 4, 7, 8 and 9, one command each."""

from __future__ import annotations

import json

import numpy as np

from ..result import to_jsonable
from .common import FIGURE_SUFFIXES, kappa_value, nonnegative_int, positive_int, report_written
from .costs import add_work_option, check_run, covariance_cost, thermal_samples_cost
from .executors import executor_from
from .guard import check_outputs, refuse_unused

#: The paper's sizes and seeds of each figure (used when --samples / --kappa / --seed are left out).
DEFAULT_SAMPLES = {4: 400, 8: 2500, 9: 8000}
DEFAULT_KAPPA = {8: 250.0, 9: 100.0}
DEFAULT_SEED = {4: 0, 7: 1, 8: 8, 9: 9}


def add_parser(subparsers):
    p = subparsers.add_parser(
        "bath-figure",
        help="the paper's Fig. 4, 7, 8 or 9 (thermal bath) with its numbers",
        description="Fig. 4: covariance of sampled noise against Eq. 19.  Fig. 7: W(tau) of one realisation at "
        "kappa = 5 and 100.  Fig. 8: mean and spread of epsilon against T_B/E_tr (gamma = 0.6173, 0.2173).  "
        "Fig. 9: p(eps^2) and D(eps^2) for (gamma, E_tr/T_B) = (0.6173, 10), (0.6173, 1), (0.2173, 1).",
    )
    p.add_argument("figure", type=int, choices=(4, 7, 8, 9), help="which figure of the paper: 4, 7, 8 or 9")
    p.add_argument("--out", metavar="FILE", required=True, help="image file (PNG/PDF/SVG)")
    p.add_argument("--samples", type=positive_int,
                   help="realisations (Fig. 4) or samples per point (Fig. 8, 9) (default: the paper's: Fig. 4: 400, Fig. 8: 2500, Fig. 9: 8000)")
    p.add_argument("--kappa", type=kappa_value, help="softness; 'inf': the hard-core mode (default: the paper's: Fig. 8: 250, Fig. 9: 100)")
    p.add_argument("--seed", type=nonnegative_int, default=None, help="root seed (default: the figure's fixed seed: Fig. 4: 0, 7: 1, 8: 8, 9: 9)")
    p.add_argument("--bath-modes", type=positive_int, default=250, help="nu_max (default 250)")
    where = p.add_mutually_exclusive_group()
    where.add_argument("--workers", type=positive_int, default=1, help="local worker processes")
    where.add_argument("--scheduler", metavar="ADDRESS", help="a running dask.distributed scheduler (default: none, local processes)")
    p.add_argument("--json", metavar="FILE", help="also write the numbers to FILE")
    p.add_argument("--no-progress", dest="progress", action="store_false", help="no progress bar")
    add_work_option(p)
    p.set_defaults(run=run)
    return p


def _options(kappa):
    return {}  # the ensemble's defaults (the delay solver's rtol: studies.ensemble.ENSEMBLE_RTOL)


def check(args) -> None:
    """Refuse, before any work, options the figure does not use, bad outputs and too large a run."""
    from ..studies import bath_figures as figures

    unused = {}
    if args.figure in (4, 7):
        unused["--kappa"] = args.kappa
        unused["--workers"] = None if args.workers == 1 else args.workers
        unused["--scheduler"] = args.scheduler
    if args.figure == 7:
        unused["--samples"] = args.samples
    refuse_unused(unused, f"by Fig. {args.figure}")
    check_outputs(files=[("--out", args.out, FIGURE_SUFFIXES), ("--json", args.json, (".json",))])
    samples = args.samples or DEFAULT_SAMPLES.get(args.figure, 0)
    if args.figure == 4:
        cost = covariance_cost(samples, args.bath_modes)
    elif args.figure == 7:
        cost = thermal_samples_cost(2, 5.0, args.bath_modes)
    elif args.figure == 8:
        kappa = DEFAULT_KAPPA[8] if args.kappa is None else args.kappa
        cost = thermal_samples_cost(samples * 2 * len(figures.FIG8_TEMPERATURES), kappa, args.bath_modes)
    else:
        kappa = DEFAULT_KAPPA[9] if args.kappa is None else args.kappa
        cost = thermal_samples_cost(samples * len(figures.FIG9_CASES), kappa, args.bath_modes)
    check_run(args, f"bath-figure {args.figure}", cost, "use fewer --samples or --bath-modes")


def run(args) -> int:
    from ..plotting import bath as plots
    from ..studies import bath_figures as figures

    check(args)
    seed = DEFAULT_SEED[args.figure] if args.seed is None else args.seed
    if args.figure == 4:
        data = figures.noise_covariance(realisations=args.samples or DEFAULT_SAMPLES[4], modes=args.bath_modes, seed=seed)
        plots.save(plots.covariance_figure(data), args.out)
        worst = float(np.max(np.abs(data["sampled"] - data["eq19"]) / np.maximum(data["band"], 1e-300)))
        print(f"C_Q/sigma^2 at tau = 0: sampled {data['sampled'][0]:.4f} +- {data['band'][0] / 2:.4f}, "
              f"Eq. 19 {data['eq19'][0]:.4f}; largest |sampled - Eq. 19| = {worst:.2f} x (2 SE)")
    elif args.figure == 7:
        data = figures.stochastic_histories(seed=seed, modes=args.bath_modes)
        plots.save(plots.histories_figure(data, 0.6, 1.0), args.out)
        for h in data:
            print(f"kappa = {h['kappa']:g}: epsilon = {h['restitution']:.6f}")
    elif args.figure == 8:
        kappa = DEFAULT_KAPPA[8] if args.kappa is None else args.kappa
        with executor_from(args.workers, args.scheduler) as executor:
            data = figures.spread_against_temperature(kappa=kappa, samples=args.samples or DEFAULT_SAMPLES[8], seed=seed,
                                                      modes=args.bath_modes, executor=executor,
                                                      progress=args.progress, **_options(kappa))
        plots.save(plots.spread_figure(data), args.out)
        print("gamma    T_B/E_tr  mean eps (SE)        std eps (SE)")
        for a, g in enumerate(data["gamma"]):
            for b, t in enumerate(data["temperature"]):
                print(f"{g:<8} {t:<9.3g} {data['mean'][a, b]:.4f} ({data['mean_error'][a, b]:.4f})  "
                      f"{data['std'][a, b]:.4f} ({data['std_error'][a, b]:.4f})")
    else:
        kappa = DEFAULT_KAPPA[9] if args.kappa is None else args.kappa
        with executor_from(args.workers, args.scheduler) as executor:
            results = figures.restitution_law(kappa=kappa, samples=args.samples or DEFAULT_SAMPLES[9], seed=seed,
                                              modes=args.bath_modes, executor=executor, progress=args.progress,
                                              **_options(kappa))
        plots.save(plots.law_figure(results), args.out)
        data = [r.summary() for r in results]
        for s in data:
            print(f"gamma = {s['gamma']}, E_tr/T_B = {1 / s['temperature']:g}: mean eps^2 = {s['mean_eps2']:.4f}, "
                  f"mean eps = {s['mean']:.4f} +- {s['standard_error']:.4f}, std = {s['std']:.4f}")
    written = [args.out]
    if args.json:
        from ..io.files import atomic_write

        record = (to_jsonable({k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in data.items()})
                  if isinstance(data, dict) else to_jsonable(
                      [{k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in d.items()} for d in data]))
        written.append(atomic_write(args.json, lambda handle: json.dump(record, handle), binary=False))
    report_written(written)
    return 0
