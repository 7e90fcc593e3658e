"""Regenerates the numbers and figures of docs/markov.md: ``python docs/markov_study.py [--workers 2]``.

Writes docs/figures/markov_fig10.png, docs/figures/markov_cooling.png and
docs/markov_study.json, and prints the tables that docs/markov.md shows.
``--update-docs`` also writes those tables into docs/markov.md (blocks
markov-fig10, markov-balance, markov-samples, markov-cooling, markov-defect);
``--tables-only``
renders them from the stored docs/markov_study.json without running the study.
"""

from __future__ import annotations

import argparse
import concurrent.futures
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the checkout this script lives in
sys.path.insert(1, str(Path(__file__).resolve().parents[1] / "benchmarks"))

from docs_block import write_block

from wavecontact.plotting.markov import plot_cooling, plot_stationary_distribution
from wavecontact.studies.markov import markov_chains, symmetry_samples_needed, symmetry_test

HERE = Path(__file__).resolve().parent
GAMMA = 0.6


def _relaxed_at(energy):
    """First collision whose chain-mean E_tr lies within 3 standard errors above T_B^0."""
    mean = energy.mean(axis=0)
    error = energy.std(axis=0, ddof=1) / math.sqrt(energy.shape[0])
    return int(np.nonzero(mean <= 1.0 + 3.0 * error)[0][0])


def _glauber_contrast(scale, bins=6):
    edges = -np.log(1.0 - np.arange(bins) / bins)
    p_start = np.diff(np.append(1.0 - np.exp(-edges), 1.0))
    p_end = np.diff(np.append(1.0 - np.exp(-edges / scale), 1.0))
    return symmetry_samples_needed(np.outer(p_start, p_end), alpha=1e-3)


def tables(out):
    """The three Markdown tables of docs/markov.md from the study's results ``out``, by block name."""
    pooled, first = out["fig10_pooled"], out["fig10_first_chain"]
    means = ", ".join(f"{chain['mean_energy']:.3f}" for chain in out["fig10_per_chain"])
    fig10 = "\n".join([
        "| | chains pooled | first chain alone (the paper's Fig. 10 size) | Eq. 30 |",
        "|---|---|---|---|",
        (f"| mean `E_tr / T_B^0` | {pooled['mean_energy']:.3f} (standard error "
        f"{pooled['mean_energy_standard_error']:.3f} from the {pooled['chains']} chains' spread) | "
        f"{first['mean_energy']:.3f} | 1 |"),
        (f"| fraction below `T_B^0` | {pooled['fraction_below_bath_temperature']:.3f} | "
        f"{first['fraction_below_bath_temperature']:.3f} | {pooled['boltzmann_fraction_below']:.3f} |"),
        (f"| KS p-value (thinned, every {pooled['ks_stride']}th state) | {pooled['ks_pvalue']:.2f} "
        f"({pooled['ks_samples']} states) | {first['ks_pvalue']:.2f} ({first['ks_samples']} states) | |"),
        "",
        (f"Means of the single chains: {means}. Burn-in: {pooled['burn_in']} steps per chain. States "
        f"{pooled['ks_stride']} collisions apart are nearly independent (autocorrelation below 0.1), so error "
        f"bars that count every state as independent are too small by about sqrt({pooled['ks_stride']}) = "
        f"{math.sqrt(pooled['ks_stride']):.1f}."),
    ])
    solve, glauber = out["detailed_balance_solve"], out["detailed_balance_glauber"]
    balance = "\n".join([
        "| rule | transitions | Bowker statistic | p-value | KS p-value of `E'` (Eq. 32) |",
        "|---|---|---|---|---|",
        (f"| solve (`nu_max = 250`) | {solve['transitions']:,} | {solve['statistic']:.1f} | {solve['pvalue']:.2g} | "
        f"{solve['stationarity_pvalue']:.2g} |"),
        f"| Glauber | {glauber['transitions']:,} | {glauber['statistic']:.1f} | {glauber['pvalue']:.2g} | |",
        "",
        _asymmetry_line(solve),
    ])
    needed = {float(key.split("_")[2]): value for key, value in out["samples_needed"].items()}
    samples = "\n".join([
        "| temperature error `s` | " + " | ".join(f"{s:g}" for s in needed) + " |",
        "|---|" + "---|" * len(needed),
        "| transitions needed (0.1 % level, on average) | "
        + " | ".join(f"{float(f'{n:.3g}'):,.0f}" for n in needed.values()) + " |",
    ])
    cold = out["cooling"]
    first = cold["vibration_mean_energy"][1], cold["glauber_mean_energy"][1]
    cooling = "\n".join([
        (f"{cold['chains']} chains, conserving bath (`N_mod = {cold['modes_per_rod']}`), "
         f"`E_tr(0) = {cold['initial_energy']:g} T_B^0`, cold bath:"),
        "",
        "| | vibration rule (solve) | Glauber, Eq. 35 |",
        "|---|---|---|",
        (f"| mean `E_tr(1) / T_B^0` | {first[0]:.4f} (`gamma^2 E_tr(0)` = {GAMMA**2 * cold['initial_energy']:.4f}) | "
         f"{first[1]:.4f} |"),
        (f"| first collision whose chain mean lies within 3 standard errors of `T_B^0` | "
         f"{cold['vibration_relaxed_at']} | {cold['glauber_relaxed_at']} |"),
        f"| mean `E_tr / T_B^0` over collisions 20-40 | {cold['vibration_late_mean']:.3f} | {cold['glauber_late_mean']:.3f} |",
    ])
    sets = out["boltzmann_defect_250"]
    few = out["boltzmann_defect"][0]
    defect = (f"Mean of `E' - E` for `E` from Eq. 30 (`nu_max = 250`, three independent sets of "
              f"{solve['transitions']:,} transitions): {sets['mean_of_independent_sets']:+.4f} +- "
              f"{sets['standard_error']:.4f}; at `nu_max = {few['bath_modes']}`: {few['mean_change']:+.4f} +- "
              f"{few['standard_error']:.4f}.")
    return {"markov-fig10": fig10, "markov-balance": balance, "markov-samples": samples, "markov-cooling": cooling,
            "markov-defect": defect}


def _glauber_asymmetry(scale, bins=6, alpha=1e-3):
    """lambda (per transition) of Glauber's rule at a bath temperature off by ``scale``."""
    from scipy import stats

    dof = bins * (bins - 1) // 2
    return (float(stats.chi2.isf(alpha, dof)) - dof) / _glauber_contrast(scale, bins)


def _temperature_error_with(asymmetry):
    """The temperature error ``s - 1`` whose Glauber rule has this ``lambda`` (bisection on s in (1, 2))."""
    low, high = 1.0 + 1e-9, 2.0
    if asymmetry <= _glauber_asymmetry(low):
        return 0.0
    for _ in range(60):
        middle = 0.5 * (low + high)
        low, high = (middle, high) if _glauber_asymmetry(middle) < asymmetry else (low, middle)
    return 0.5 * (low + high) - 1.0


def _asymmetry_line(solve):
    """The solved transitions' asymmetry, and the temperature error of a Glauber rule as asymmetric."""
    value, error = solve["asymmetry"], solve["asymmetry_standard_error"]
    upper = value + error
    return (f"Asymmetry of the solved transitions: `lambda = ({1e4 * value:.1f} +- {1e4 * error:.1f}) x 10^-4` per "
            f"transition. A Glauber rule at a bath temperature off by {100 * _temperature_error_with(value):.1f} % "
            f"has the central value, one off by {100 * _temperature_error_with(upper):.1f} % the central value plus "
            "one standard error.")


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--transitions", type=int, default=20_000)
    parser.add_argument("--update-docs", action="store_true", help="write the tables into docs/markov.md")
    parser.add_argument("--tables-only", action="store_true",
                        help="do not run the study: render the tables from docs/markov_study.json")
    args = parser.parse_args()
    if not args.tables_only:
        run_study(args)
    out = json.loads((HERE / "markov_study.json").read_text())
    for name, table in tables(out).items():
        print(f"\n{table}")
        if args.update_docs:
            write_block("markov.md", name, f"`python docs/markov_study.py` (docs/markov_study.json):\n\n{table}")


def run_study(args):
    """Run the chains, write docs/markov_study.json and the figures."""
    out = {}
    with concurrent.futures.ProcessPoolExecutor(args.workers) as pool:
        # Fig. 10: four chains of 10,000 solved collisions (gamma = 0.6, hard core, nu_max = 250)
        start = time.perf_counter()
        fig10 = markov_chains(GAMMA, rule="solve", chains=4, steps=10_000, seed=2026, executor=pool, batch_size=1)
        out["fig10_wall_s"] = time.perf_counter() - start
        summary = fig10.summary()
        per_chain = [
            {"mean_energy": float(row.mean()), "fraction_below": float(np.mean(row < 1.0))}
            for row in fig10.stationary(summary["burn_in"])
        ]
        first = type(fig10)(fig10.spec, fig10.energy[:1], fig10.temperature[:1], fig10.eps2[:1]).summary()
        out["fig10_pooled"] = summary
        out["fig10_first_chain"] = first
        out["fig10_per_chain"] = per_chain
        plot_stationary_distribution(fig10, HERE / "figures" / "markov_fig10.png")

        # detailed balance: independent transitions from the Boltzmann law
        n = args.transitions
        start = time.perf_counter()
        pairs = markov_chains(GAMMA, rule="solve", chains=n, steps=1, seed=77, initial_energy="boltzmann",
                              executor=pool, batch_size=max(1, n // 32))
        out["transitions_wall_s"] = time.perf_counter() - start
        test = symmetry_test(pairs.energy[:, 0], pairs.energy[:, 1])
        pairs_change_250 = pairs.energy[:, 1] - pairs.energy[:, 0]
        out["detailed_balance_solve"] = {
            "transitions": n, "statistic": test.statistic, "dof": test.dof, "pvalue": test.pvalue,
            "asymmetry": test.asymmetry, "asymmetry_standard_error": math.sqrt(2 * test.dof) / n,
            "stationarity_pvalue": test.stationarity_pvalue, "mean_final_energy": float(pairs.energy[:, 1].mean()),
            "mean_final_energy_standard_error": float(pairs.energy[:, 1].std(ddof=1) / math.sqrt(n)),
        }
        glauber_pairs = markov_chains(GAMMA, rule="glauber", chains=n, steps=1, seed=77, initial_energy="boltzmann")
        gtest = symmetry_test(glauber_pairs.energy[:, 0], glauber_pairs.energy[:, 1])
        out["detailed_balance_glauber"] = {"transitions": n, "statistic": gtest.statistic, "dof": gtest.dof,
                                           "pvalue": gtest.pvalue}
        out["samples_needed"] = {f"glauber_at_{s:g}_T": _glauber_contrast(s) for s in (1.02, 1.05, 1.1, 1.2, 1.5)}

        # Eq. 32 against the number of bath modes: mean of E' - E for E ~ exp(-E)
        defects = []
        for modes in (8, 16, 32, 64, 128):
            pairs = markov_chains(GAMMA, rule="solve", chains=n, steps=1, seed=78, initial_energy="boltzmann",
                                  bath_modes=modes, executor=pool, batch_size=max(1, n // 32))
            change = pairs.energy[:, 1] - pairs.energy[:, 0]
            defects.append({"bath_modes": modes, "mean_change": float(change.mean()),
                            "standard_error": float(change.std(ddof=1) / math.sqrt(n))})
        change = pairs_change_250
        defects.append({"bath_modes": 250, "mean_change": float(change.mean()),
                        "standard_error": float(change.std(ddof=1) / math.sqrt(n))})
        out["boltzmann_defect"] = defects
        # at 250 modes: two more independent sets, and the first set again on a grid twice as fine
        repeats = [defects[-1]]
        for seed, resolution in ((79, 8), (80, 8), (77, 16)):
            pairs = markov_chains(GAMMA, rule="solve", chains=n, steps=1, seed=seed, initial_energy="boltzmann",
                                  executor=pool, batch_size=max(1, n // 32), hard_core_resolution=resolution)
            change = pairs.energy[:, 1] - pairs.energy[:, 0]
            repeats.append({"seed": seed, "hard_core_resolution": resolution, "mean_change": float(change.mean()),
                            "standard_error": float(change.std(ddof=1) / math.sqrt(n))})
        independent = np.array([r["mean_change"] for r in repeats[:3]])
        out["boltzmann_defect_250"] = {"sets": repeats, "mean_of_independent_sets": float(independent.mean()),
                                       "standard_error": float(np.hypot.reduce([r["standard_error"] for r in repeats[:3]]) / 3)}

        # cooling from a cold bath (Eq. 28, N_mod = 10, all energy translational at the start)
        cold = {"chains": 400, "steps": 40, "seed": 31, "bath": "conserved", "modes_per_rod": 10, "initial_energy": 21.0}
        vibration = markov_chains(GAMMA, rule="solve", executor=pool, batch_size=25, **cold)
        glauber = markov_chains(GAMMA, rule="glauber", **cold)
        out["cooling"] = {
            "chains": 400, "modes_per_rod": 10, "initial_energy": 21.0,
            "vibration_relaxed_at": _relaxed_at(vibration.energy),
            "glauber_relaxed_at": _relaxed_at(glauber.energy),
            "vibration_mean_energy": [float(x) for x in vibration.energy.mean(axis=0)[:12]],
            "glauber_mean_energy": [float(x) for x in glauber.energy.mean(axis=0)[:12]],
            "vibration_late_mean": float(vibration.energy[:, 20:].mean()),
            "glauber_late_mean": float(glauber.energy[:, 20:].mean()),
        }
        plot_cooling({"vibration rule (solve)": vibration, "Glauber, Eq. 35": glauber},
                     HERE / "figures" / "markov_cooling.png")
    (HERE / "markov_study.json").write_text(json.dumps(out, indent=1))
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
