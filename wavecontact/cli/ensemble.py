"""``wavecontact ensemble``: the law of the stochastic restitution at one (gamma, kappa, T_B/E_tr)."""

from __future__ import annotations

import json
import math
from pathlib import Path

from ..errors import InvalidParameterError
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
    solvers_with_option,
)
from .costs import add_work_option, check_run, thermal_samples_cost
from .executors import executor_from
from .guard import check_outputs

#: What ``--out DIR`` holds besides the finished batches (batch_*.npz).
OUT_FILES = ("ensemble.json", "samples.npz", "summary.json")


def _temperature(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise InvalidParameterError(f"--temperature (T_B/E_tr) must be a number >= 0, got {text!r}") from None
    if not (math.isfinite(value) and value >= 0.0):
        raise InvalidParameterError(f"--temperature (T_B/E_tr) must be finite and >= 0, got {text!r}")
    return value


def add_parser(subparsers):
    p = subparsers.add_parser(
        "ensemble",
        help="many thermal collisions: mean, spread and law of epsilon",
        description="Collide SAMPLES independent realisations of the thermal bath (T_B/E_tr = R) and report the "
        "mean and standard deviation of epsilon with standard errors, and the law of epsilon^2. "
        "Sample j's seed is SeedSequence(SEED).spawn(...)[j]: the samples do not depend on the workers.",
    )
    p.add_argument("--gamma", type=gamma_value, required=True, help="length ratio l1/l2 in (0, 1]")
    p.add_argument("--kappa", type=kappa_value, required=True, help="alpha V l / c in (0, inf]; 'inf' = hard core")
    p.add_argument("--temperature", type=str, required=True, metavar="R", help="T_B / E_tr >= 0")
    p.add_argument("--samples", type=positive_int, required=True, help="number of collisions")
    p.add_argument("--seed", type=nonnegative_int, required=True, help="root seed (>= 0)")
    p.add_argument("--bath-modes", type=positive_int, default=250, help="modes per rod nu_max (default 250)")
    p.add_argument("--solver", choices=solver_names(), default="delay", help="solver of each collision")
    where = p.add_mutually_exclusive_group()
    where.add_argument("--workers", type=positive_int, default=1, help="local worker processes (default 1)")
    where.add_argument("--scheduler", metavar="ADDRESS", help="a running dask.distributed scheduler (default: none, local processes)")
    p.add_argument("--batch-size", type=positive_int, default=256, help="samples per task (default 256)")
    p.add_argument("--rtol", type=positive_float, help="delay solver tolerance (default 1e-3 in ensembles: see docs/bath.md)")
    p.add_argument("--out", metavar="DIR", help="keep every finished batch here; a rerun resumes")
    p.add_argument("--overwrite", action="store_true",
                   help="replace another ensemble found in DIR (its description and batches) instead of refusing")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--plot", metavar="FILE", help="draw p(eps^2) and D(eps^2) with confidence bands")
    p.add_argument("--no-progress", dest="progress", action="store_false", help="no progress bar")
    add_work_option(p)
    p.set_defaults(run=run)
    return p


def run(args) -> int:
    from ..io.run_controller import RunSettings
    from ..studies.ensemble import EnsembleSpec, ensemble

    temperature = _temperature(args.temperature)
    options = {}
    if args.rtol is not None:
        taking = solvers_with_option("rtol")
        if args.solver not in taking:
            raise InvalidParameterError(f"--rtol applies to --solver {' or '.join(taking)}, not {args.solver}")
        options["rtol"] = args.rtol
    EnsembleSpec(args.gamma, args.kappa, temperature, args.samples, args.seed, bath_modes=args.bath_modes,
                 solver=args.solver, options=options, batch_size=args.batch_size)  # refuses before any work
    check_outputs(files=[("--plot", args.plot, FIGURE_SUFFIXES)], directories=[("--out", args.out, OUT_FILES)])
    check_run(args, f"ensemble: {args.samples} samples",
              thermal_samples_cost(args.samples, args.kappa, args.bath_modes, args.solver, args.gamma, options),
              "use fewer --samples or --bath-modes")
    with executor_from(args.workers, args.scheduler) as executor:
        settings = RunSettings(executor=executor, batch_size=args.batch_size, out=args.out,
                               progress=args.progress and not args.json, overwrite=args.overwrite)
        result = ensemble(args.gamma, args.kappa, temperature, args.samples, args.seed, solver=args.solver,
                          bath_modes=args.bath_modes, run=settings, **options)
    summary = result.summary()
    written = []
    if args.out:
        result.save(args.out)
        out = Path(args.out)
        written += [out / name for name in OUT_FILES]
        written.append(files_summary(out, "batch_*.npz"))
    if args.plot:
        from ..plotting.bath import plot_law

        written.append(plot_law(result, args.plot))
    summary["files_written"] = report_written(written)
    if args.json:
        print(json.dumps(summary))
    else:
        print(f"gamma = {result.spec.gamma:g}, kappa = {summary['kappa']}, T_B/E_tr = {args.temperature}, "
              f"nu_max = {result.spec.bath_modes}, {summary['samples']} samples (seed {result.spec.seed})")
        print(f"mean epsilon = {summary['mean']:.5f} +- {summary['standard_error']:.5f}")
        if result.grid_bias is not None:
            bias = result.grid_bias
            print(f"grid bias of the mean = {bias.value:.2e} +- {bias.standard_error:.1e} ({bias.samples} samples rerun "
                  f"at {bias.check_resolution} points per period); total error of the mean = {result.total_error:.5f}")
        print(f"std  epsilon = {summary['std']:.5f} +- {summary['std_standard_error']:.5f}")
        print(f"mean epsilon^2 = {summary['mean_eps2']:.5f}")
    return 0
