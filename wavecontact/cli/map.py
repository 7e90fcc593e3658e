"""``wavecontact map``: restitution of two materials over (Z2/Z1, T1/T2), figure and table."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

from .common import kappa_value, positive_float, positive_int, report_written
from .guard import check_outputs


def ratio_range(text: str) -> np.ndarray:
    """``LOW:HIGH:N`` (N log-spaced values, both ends included) or a comma-separated list;
    at most :data:`~wavecontact.studies.material_map.MAX_POINTS` values, checked before they are made."""
    from ..studies.material_map import MAX_POINTS

    try:
        if ":" in text:
            low, high, count = text.split(":")
            low, high, count = float(low), float(high), int(count)
            if not (0.0 < low <= high < math.inf) or count < 1:
                raise ValueError
            if count > MAX_POINTS:
                raise argparse.ArgumentTypeError(f"a map has at most {MAX_POINTS} points, got N = {count}")
            return np.geomspace(low, high, count)
        values = np.array([float(v) for v in text.split(",")])
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected LOW:HIGH:N with 0 < LOW <= HIGH and N >= 1, or a list a,b,c of positive numbers; got {text!r}"
        ) from None
    if not np.all((values > 0.0) & np.isfinite(values)):
        raise argparse.ArgumentTypeError(f"ratios must be positive, got {text!r}")
    return values


def add_parser(subparsers):
    p = subparsers.add_parser(
        "map",
        help="restitution of two rods of different materials over (Z2/Z1, T1/T2): figure and table",
        description="Compute epsilon over a grid of the impedance ratio Z2/Z1 and the transit-time ratio "
        "T1/T2 (T = 2 l / c) with the delay solver, in the hard-core limit and/or at finite kappa "
        "(alpha V mu / Z_s), and write a figure (map.png), the maps (map_<kappa>.json) and a Markdown "
        "table (map.md) to --out; the table is also printed.",
    )
    p.add_argument("--impedance-ratio", type=ratio_range, default=ratio_range("0.01:100:101"),
                   help="Z2/Z1 values: LOW:HIGH:N (log-spaced) or a,b,c; default 0.01:100:101")
    p.add_argument("--time-ratio", type=ratio_range, default=ratio_range("0.1:10:99"),
                   help="T1/T2 values: LOW:HIGH:N (log-spaced) or a,b,c; default 0.1:10:99")
    p.add_argument("--kappa", type=kappa_value, nargs="+", default=[float("inf")],
                   help="one or more kappa = alpha V mu / Z_s in (0, inf]; 'inf' = hard core (default)")
    p.add_argument("--rtol", type=positive_float, default=1e-8, help="delay-solver accuracy at finite kappa")
    p.add_argument("--workers", type=positive_int, default=None, help="threads at finite kappa (default: cores)")
    p.add_argument("--out", metavar="DIR", required=True, help="output directory (created if missing)")
    p.add_argument("--no-progress", dest="progress", action="store_false", default=None,
                   help="no progress bar (it is shown on stderr only when that is a terminal)")
    p.set_defaults(run=run)
    return p


def _kappa_name(kappa: float) -> str:
    return "inf" if math.isinf(kappa) else f"{kappa:g}"


def run(args) -> int:
    from ..errors import InvalidParameterError
    from ..plotting.material_map import plot_material_map
    from ..studies.material_map import MAX_POINTS, material_map

    size = args.impedance_ratio.size * args.time_ratio.size
    if size * len(args.kappa) > MAX_POINTS:
        raise InvalidParameterError(f"--impedance-ratio x --time-ratio x --kappa: at most {MAX_POINTS} points in all, "
                                    f"got {args.impedance_ratio.size} x {args.time_ratio.size} x {len(args.kappa)}")
    if len({_kappa_name(k) for k in args.kappa}) != len(args.kappa):
        raise InvalidParameterError("--kappa: a value is given twice")
    names = [f"map_{_kappa_name(kappa)}.json" for kappa in args.kappa]
    check_outputs(directories=[("--out", args.out, (*names, "map.png", "map.md"))])
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    maps, written = [], []
    for kappa, name in zip(args.kappa, names):
        one = material_map(args.impedance_ratio, args.time_ratio, kappa, rtol=args.rtol, workers=args.workers,
                           progress=args.progress)
        one.save(out / name)
        written.append(out / name)
        maps.append(one)
    written.append(plot_material_map(maps, out / "map.png") or out / "map.png")
    text = "\n\n".join(one.table() for one in maps)
    from ..io.files import atomic_write

    written.append(atomic_write(out / "map.md", lambda handle: handle.write(text + "\n"), binary=False))
    print(text)
    report_written(written)
    return 0
