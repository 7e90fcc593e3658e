"""``wavecontact equipartition``: how many collisions the modes need to reach equipartition, per N (Fig. 2)."""

from __future__ import annotations

import json
import math
from pathlib import Path

from .common import add_ring_options, gamma_value, kappa_value, number_type, positive_int, report_written
from .costs import add_work_option, check_run, ring_cost
from .guard import check_outputs

ENTROPY_NAME = "entropy.csv"
SUMMARY_NAME = "equipartition.json"
FIGURE_NAME = "fig2_equipartition_vs_modes.png"


_threshold = number_type(lambda v: math.isfinite(v) and v > 1.0, "a finite number > 1")


def add_parser(subparsers):
    p = subparsers.add_parser(
        "equipartition",
        help="spectral entropy after each collision for several mode counts (Fig. 2), and its settling time",
        description="For each N, start two rods on a ring with a cold bath REALISATIONS times (ring "
        "circumferences 1.5 percent apart), record the spectral entropy eta (Eq. 10) after each of COLLISIONS "
        "collisions, and report the collision at which eta first falls below THRESHOLD times its "
        "equipartition mean. Writes entropy.csv, equipartition.json and the figure into DIR.",
    )
    p.add_argument("--gamma", type=gamma_value, required=True, help="length ratio l1/l2 in (0, 1]")
    p.add_argument("--kappa", type=kappa_value, required=True, help="alpha V l / c in (0, inf]")
    p.add_argument("--modes", type=positive_int, nargs="+", required=True, help="modes per rod, one or more N >= 2")
    p.add_argument("--collisions", type=positive_int, default=100, help="collisions per realisation")
    p.add_argument("--realisations", type=positive_int, default=5, help="realisations per N")
    p.add_argument("--threshold", type=_threshold, default=1.5,
                   help="settled when eta <= THRESHOLD x its equipartition mean")
    add_ring_options(p)
    p.add_argument("--json", action="store_true", help="print the summary as JSON instead of a table")
    add_work_option(p)
    p.set_defaults(run=run)
    return p


def run(args) -> int:
    from ..errors import InvalidParameterError
    from ..plotting.equipartition import plot_equipartition
    from ..studies.equipartition import equipartition_by_modes

    out = Path(args.out)
    if min(args.modes) < 2:
        raise InvalidParameterError(f"--modes: every N must be at least 2, got {min(args.modes)}")
    check_outputs(directories=[("--out", args.out, (ENTROPY_NAME, SUMMARY_NAME, FIGURE_NAME))])
    check_run(args, f"equipartition: {args.realisations} x {args.collisions} collisions at N = "
              f"{', '.join(map(str, args.modes))}", ring_cost(args.kappa, args.modes, args.collisions, args.realisations),
              "use fewer --collisions, --realisations or --modes")
    study = equipartition_by_modes(
        args.gamma, args.kappa, modes=args.modes, collisions=args.collisions, realisations=args.realisations,
        threshold=args.threshold, static_correction=args.static_correction, progress=args.progress,
    )
    out.mkdir(parents=True, exist_ok=True)
    study.save_csv(out / ENTROPY_NAME)
    summary = {
        "gamma": study.gamma,
        "kappa": study.kappa if math.isfinite(study.kappa) else "inf",
        "collisions": args.collisions,
        "realisations": args.realisations,
        "threshold": study.threshold,
        "static_correction": args.static_correction,
        "wall_time_s": study.wall_time_s,
        "settling_exponent": study.scaling_exponent(),
        "modes": study.table(),
    }
    with open(out / SUMMARY_NAME, "w") as handle:
        json.dump(summary, handle, indent=2)
        handle.write("\n")
    figure = plot_equipartition(study, out / FIGURE_NAME)
    files = report_written([out / ENTROPY_NAME, out / SUMMARY_NAME, figure])
    if args.json:
        print(json.dumps({**summary, "files_written": files}, indent=2))
        return 0
    print(f"equipartition of the modes, gamma = {study.gamma:g}, kappa = {summary['kappa']}, "
          f"{args.realisations} realisations x {args.collisions} collisions ({study.wall_time_s:.1f} s)")
    print(f"settled = first collision with eta <= {study.threshold:g} x the finite-N equipartition mean\n")
    print("| N | Eq. 11 | finite-N mean | eta after 1 | after 5 | after 10 | settling collisions | median |")
    print("|---:|---:|---:|---:|---:|---:|---|---:|")
    for row in summary["modes"]:
        settled = ", ".join("never" if s is None else str(s) for s in row["settling"])
        median = "n/a" if row["median_settling"] is None else f"{row['median_settling']:g}"
        after = [f"{row[key]:.3f}" if key in row else "n/a" for key in ("eta_after_1", "eta_after_5", "eta_after_10")]
        print(f"| {row['modes']} | {row['eq11']:.4f} | {row['equilibrium_finite']:.4f} | {' | '.join(after)} | "
              f"{settled} | {median} |")
    if summary["settling_exponent"] is not None:
        print(f"\nmedian settling collision ~ N^{summary['settling_exponent']:.2f} (log-log fit)")
    return 0
