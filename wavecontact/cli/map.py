"""``wavecontact map``: restitution of two materials over (Z2/Z1, T1/T2), figure and table."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from .common import kappa_value, positive_int


def ratio_range(text: str) -> np.ndarray:
    """``LOW:HIGH:N`` (N log-spaced values, both ends included) or a comma-separated list."""
    try:
        if ":" in text:
            low, high, count = text.split(":")
            low, high, count = float(low), float(high), int(count)
            if not (0.0 < low <= high) or count < 1:
                raise ValueError
            return np.geomspace(low, high, count)
        values = np.array([float(v) for v in text.split(",")])
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected LOW:HIGH:N with 0 < LOW <= HIGH and N >= 1, or a list a,b,c of positive numbers; got {text!r}"
        ) from None
    if not np.all(values > 0.0):
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
    p.add_argument("--rtol", type=float, default=1e-8, help="delay-solver accuracy at finite kappa")
    p.add_argument("--workers", type=positive_int, default=None, help="threads at finite kappa (default: cores)")
    p.add_argument("--out", metavar="DIR", required=True, help="output directory (created if missing)")
    p.add_argument("--no-progress", dest="progress", action="store_false", default=None,
                   help="no progress bar (it is shown on stderr only when that is a terminal)")
    p.set_defaults(run=run)
    return p


def run(args) -> int:
    from ..plotting.material_map import plot_material_map
    from ..studies.material_map import material_map

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    maps = []
    for kappa in args.kappa:
        one = material_map(args.impedance_ratio, args.time_ratio, kappa, rtol=args.rtol, workers=args.workers,
                           progress=args.progress)
        one.save(out / f"map_{'inf' if kappa == float('inf') else f'{kappa:g}'}.json")
        maps.append(one)
    plot_material_map(maps, out / "map.png")
    text = "\n\n".join(one.table() for one in maps)
    (out / "map.md").write_text(text + "\n")
    print(text)
    print(f"\nwrote {out / 'map.png'}, {out / 'map.md'} and the maps as JSON")
    return 0
