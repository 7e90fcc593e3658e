"""``wavecontact bath-figure N``: the paper's thermal-bath figures 4, 7, 8 and 9, one command each."""

from __future__ import annotations

import json

import numpy as np

from ..result import to_jsonable
from .common import kappa_value, positive_int
from .ensemble import executor_from


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
    p.add_argument("--seed", type=int, default=None, help="root seed (default: the figure's fixed seed: Fig. 4: 0, 7: 1, 8: 8, 9: 9)")
    p.add_argument("--bath-modes", type=positive_int, default=250, help="nu_max (default 250)")
    where = p.add_mutually_exclusive_group()
    where.add_argument("--workers", type=positive_int, default=1, help="local worker processes")
    where.add_argument("--scheduler", metavar="ADDRESS", help="a running dask.distributed scheduler (default: none, local processes)")
    p.add_argument("--json", metavar="FILE", help="also write the numbers to FILE")
    p.add_argument("--no-progress", dest="progress", action="store_false", help="no progress bar")
    p.set_defaults(run=run)
    return p


def _options(kappa):
    return {}  # the ensemble's defaults (the delay solver's rtol: studies.ensemble.ENSEMBLE_RTOL)


def run(args) -> int:
    from ..plotting import bath as plots
    from ..studies import bath_figures as figures

    seed = {4: 0, 7: 1, 8: 8, 9: 9}[args.figure] if args.seed is None else args.seed
    if args.figure == 4:
        data = figures.noise_covariance(realisations=args.samples or 400, modes=args.bath_modes, seed=seed)
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
        kappa = 250.0 if args.kappa is None else args.kappa
        with executor_from(args.workers, args.scheduler) as executor:
            data = figures.spread_against_temperature(kappa=kappa, samples=args.samples or 2500, seed=seed,
                                                      modes=args.bath_modes, executor=executor,
                                                      progress=args.progress, **_options(kappa))
        plots.save(plots.spread_figure(data), args.out)
        print("gamma    T_B/E_tr  mean eps (SE)        std eps (SE)")
        for a, g in enumerate(data["gamma"]):
            for b, t in enumerate(data["temperature"]):
                print(f"{g:<8} {t:<9.3g} {data['mean'][a, b]:.4f} ({data['mean_error'][a, b]:.4f})  "
                      f"{data['std'][a, b]:.4f} ({data['std_error'][a, b]:.4f})")
    else:
        kappa = 100.0 if args.kappa is None else args.kappa
        with executor_from(args.workers, args.scheduler) as executor:
            results = figures.restitution_law(kappa=kappa, samples=args.samples or 8000, seed=seed,
                                              modes=args.bath_modes, executor=executor, progress=args.progress,
                                              **_options(kappa))
        plots.save(plots.law_figure(results), args.out)
        data = [r.summary() for r in results]
        for s in data:
            print(f"gamma = {s['gamma']}, E_tr/T_B = {1 / s['temperature']:g}: mean eps^2 = {s['mean_eps2']:.4f}, "
                  f"mean eps = {s['mean']:.4f} +- {s['standard_error']:.4f}, std = {s['std']:.4f}")
    if args.json:
        with open(args.json, "w") as handle:
            json.dump(to_jsonable({k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in data.items()})
                      if isinstance(data, dict) else to_jsonable(
                          [{k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in d.items()} for d in data]),
                      handle)
    return 0
