"""What the FE error estimate's orders rest on, recomputed from the stored sweeps.

Run: ``python benchmarks/estimate_tuning_figures.py [--seeds 2027 2028 2029 2030] [--update-docs]``

For each regime of docs/error_estimates.md section 1 it reads the stored sweeps
(``benchmarks/sweeps/fem_SEED.jsonl``, written by ``benchmarks/error_estimates.py --save``:
every collision's restitutions on N, N/2, N/4 elements and the delay reference) and prints:

* the ratio of the true error of the requested run to the finest difference
  ``|d0| = |eps(N) - eps(N/2)|`` (a clean power law of order p gives ``1 / (2^p - 1)``:
  1/3 for p = 2, 1.7 for p = 2/3, 1 for p = 1);
* on the characteristic lattice beyond ``x = 10``, the factor by which the error grows from N to N/2
  (2 for a first-order error).

Only collisions whose errors are above 1e-10 on every run used count (below, the delay reference's
own error and rounding blur the ratios).  ``--update-docs`` writes the table between
``<!-- tuning-figures:start -->`` and ``<!-- tuning-figures:end -->`` of docs/error_estimates.md.
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
SWEEPS = ROOT / "benchmarks" / "sweeps"
PAGE = ROOT / "docs" / "error_estimates.md"
ABOVE = 1e-10


def load(seeds) -> list:
    """The solved samples of the stored sweeps of ``seeds``."""
    rows = []
    for seed in seeds:
        with open(SWEEPS / f"fem_{seed}.jsonl", encoding="utf-8") as handle:
            rows += [r for r in map(json.loads, handle) if r["status"] == "ok"]
    return rows


def resolution(row: dict) -> float:
    """``x = alpha V h / c`` of the requested run (two-rod units: c = V = 1, alpha = kappa, shorter rod
    of length (1 + gamma) / 2); inf for hard contact."""
    return row["kappa"] * (1.0 + row["gamma"]) / (2.0 * row["options"]["elements"])


def errors(row: dict) -> list:
    """``|eps - reference|`` of the requested run, then of the coarser runs (finer runs left out)."""
    n = row["options"]["elements"]
    return [abs(eps - row["reference"]) for elements, eps in row["levels"] if elements <= n]


def error_over_difference(row: dict) -> float:
    levels = [eps for elements, eps in row["levels"] if elements <= row["options"]["elements"]]
    return abs(row["restitution"] - row["reference"]) / abs(levels[0] - levels[1])


REGIMES = (
    ("force scheme, x <= 1", "error / abs(d0)", "1/3 (order 2)",
     lambda r: r["scheme"] == "force" and resolution(r) <= 1.0, error_over_difference),
    ("x > 100 or hard contact, not the characteristic lattice", "error / abs(d0)", "1.7 (order 2/3)",
     lambda r: r["scheme"] != "characteristic" and resolution(r) > 100.0, error_over_difference),
    ("characteristic lattice, 1 < x <= 10", "error / abs(d0)", "0.55 (order 1.5)",
     lambda r: r["scheme"] == "characteristic" and 1.0 < resolution(r) <= 10.0 and math.isfinite(r["kappa"]),
     error_over_difference),
    ("characteristic lattice, x > 10", "error(N/2) / error(N)", "2 (order 1)",
     lambda r: r["scheme"] == "characteristic" and resolution(r) > 10.0 and math.isfinite(r["kappa"]),
     lambda r: errors(r)[1] / errors(r)[0]),
)


def table(seeds) -> list:
    rows = load(seeds)
    command = f"`python benchmarks/estimate_tuning_figures.py --seeds {' '.join(map(str, seeds))}`"
    lines = [f"{command} ({len(rows)} solved collisions; errors above {ABOVE:g} on the runs N, N/2, N/4)", "",
             "| regime | ratio | clean power law | n | 2.5 % | 10 % | median | 90 % | 97.5 % |",
             "|---|---|---|---|---|---|---|---|---|"]
    for name, what, clean, selects, ratio in REGIMES:
        chosen = [r for r in rows if selects(r) and min(errors(r)[:3]) > ABOVE
                  and len(errors(r)) >= 3 and errors(r)[0] != 0]
        values = np.array([ratio(r) for r in chosen if np.isfinite(ratio(r))])
        q = np.quantile(values, [0.025, 0.1, 0.5, 0.9, 0.975]) if values.size else [math.nan] * 5
        lines.append(f"| {name} | {what} | {clean} | {values.size} | " + " | ".join(f"{v:.2f}" for v in q) + " |")
    return lines


def update_docs(lines: list, page: Path = PAGE) -> None:
    start, end = "<!-- tuning-figures:start -->\n", "<!-- tuning-figures:end -->"
    text = page.read_text(encoding="utf-8")
    if start not in text or end not in text:
        raise SystemExit(f"{page} has no block {start.strip()} ... {end}")
    head, rest = text.split(start, 1)
    page.write_text(head + start + "\n".join(lines) + "\n" + end + rest.split(end, 1)[1], encoding="utf-8")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[2027, 2028, 2029, 2030])
    parser.add_argument("--update-docs", action="store_true")
    args = parser.parse_args(argv)
    lines = table(args.seeds)
    print("\n".join(lines))
    if args.update_docs:
        update_docs(lines)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
