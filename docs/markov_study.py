"""Regenerates the numbers and figures of docs/markov.md: ``python docs/markov_study.py [--workers 2]``.

Writes docs/figures/markov_fig10.png, docs/figures/markov_cooling.png and
docs/markov_study.json, and prints the tables that docs/markov.md shows.
``--update-docs`` also writes those tables into docs/markov.md (blocks
markov-fig10, markov-balance, markov-samples, markov-cooling, markov-defect, markov-nu-max);
``--tables-only`` renders them from the stored docs/markov_study.json without running the study;
``--parts nu-max fig10`` runs only those parts and keeps the others' stored results.

The nu_max study (issue 24): per nu_max in NU_MAX, SEEDS_PER_MODES runs of NU_CHAINS chains x
NU_STEPS solved collisions (gamma = 0.6, hard core, fixed bath, started from Eq. 30), run seeds
drawn from ROOT_SEED; the stationary mean of E_tr / T_B^0 with its autocorrelation-aware standard
error, and a weighted least-squares fit ``mean = m_inf + a / nu_max``.  About 10 minutes of CPU.
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
# the nu_max study: SEEDS_PER_MODES runs of NU_CHAINS chains x NU_STEPS steps per nu_max, seeds from ROOT_SEED
ROOT_SEED = 24
NU_MAX = (125, 250, 500, 1000, 2000)
SEEDS_PER_MODES = 5
NU_CHAINS = 8
NU_STEPS = 8000
NU_BURN_IN = 100  # the chains start from Eq. 30; 100 steps are about 10 autocorrelation times


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
        f"{pooled['mean_energy_standard_error']:.3f} from the autocorrelation time; "
        f"{pooled['mean_energy_standard_error_between_chains']:.3f} from the {pooled['chains']} chains' spread) | "
        f"{first['mean_energy']:.3f} ({first['mean_energy_standard_error']:.3f}) | 1 |"),
        (f"| fraction below `T_B^0` | {pooled['fraction_below_bath_temperature']:.3f} | "
        f"{first['fraction_below_bath_temperature']:.3f} | {pooled['boltzmann_fraction_below']:.3f} |"),
        (f"| KS p-value (thinned, every {pooled['ks_stride']}th state) | {pooled['ks_pvalue']:.2f} "
        f"({pooled['ks_samples']} states) | {first['ks_pvalue']:.2f} ({first['ks_samples']} states) | |"),
        "",
        (f"Means of the single chains: {means}. Burn-in: {pooled['burn_in']} steps per chain. The integrated "
        f"autocorrelation time of the energy is {pooled['integrated_autocorrelation_time']:.1f} steps (window "
        f"{pooled['autocorrelation_window']}), so error bars that count every state as independent are too small "
        f"by sqrt({pooled['integrated_autocorrelation_time']:.1f}) = "
        f"{math.sqrt(pooled['integrated_autocorrelation_time']):.1f}; states {pooled['ks_stride']} collisions apart "
        "have an autocorrelation below 0.1 (the KS test's thinning)."),
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
            "markov-defect": defect, "markov-nu-max": nu_max_table(out)}


def nu_max_table(out):
    """The stationary mean against nu_max, its fit in 1/nu_max and the deficit at the paper's 250 modes."""
    study = out["nu_max_study"]
    rows, fit = study["rows"], study["fit"]
    lines = [
        (f"`gamma = {GAMMA}`, hard core, fixed bath; per `nu_max` {SEEDS_PER_MODES} runs of {study['chains']} chains x "
         f"{study['steps']:,} steps, started from Eq. 30, burn-in {study['burn_in']} steps; run seeds from root seed "
         f"{study['root_seed']} (`SeedSequence({study['root_seed']}).generate_state`, listed in "
         "docs/markov_study.json). Standard errors (SE) from the integrated autocorrelation time `tau` of the "
         "pooled chains; the last columns check them against the spread of the runs' means."),
        "",
        ("| nu_max | mean `E_tr / T_B^0` (SE) | (mean - 1) / SE | `tau` (steps) | fraction below `T_B^0` (SE) | "
         f"SE from the spread of the {SEEDS_PER_MODES} runs | runs' means |"),
        "|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['bath_modes']} | {r['mean_energy']:.4f} ({r['standard_error']:.4f}) | "
            f"{(r['mean_energy'] - 1.0) / r['standard_error']:+.1f} | {r['tau']:.2f} | "
            f"{r['fraction_below']:.4f} ({r['fraction_below_standard_error']:.4f}) | "
            f"{r['seed_spread_standard_error']:.4f} | {', '.join(f'{m:.3f}' for m in r['seed_means'])} |")
    at = {r["bath_modes"]: r for r in rows}
    r250 = at[250]
    fitted_250 = fit["limit"] + fit["slope"] / 250.0
    lines += [
        "",
        (f"Fit `mean = m_inf + a / nu_max` (weighted least squares, all {len(rows)} points): `m_inf = "
         f"{fit['limit']:.4f} +- {fit['limit_standard_error']:.4f}` "
         f"({(fit['limit'] - 1.0) / fit['limit_standard_error']:+.1f} SE from Eq. 30's 1), `a = "
         f"{fit['slope']:.2f} +- {fit['slope_standard_error']:.2f}`, chi^2 = {fit['chi2']:.1f} for {fit['dof']} "
         "degrees of freedom."),
        (f"Deficit at the paper's 250 modes: `1 - mean = {1.0 - r250['mean_energy']:.4f} +- "
         f"{r250['standard_error']:.4f}` measured ({(1.0 - r250['mean_energy']) / r250['standard_error']:.1f} SE), "
         f"`{1.0 - fitted_250:.4f}` on the fit; P(E < T_B^0) = {r250['fraction_below']:.4f} +- "
         f"{r250['fraction_below_standard_error']:.4f} against 0.6321."),
    ]
    if "boltzmann_defect_250" in out:
        defect = out["boltzmann_defect_250"]
        rho = r250["lag1_autocorrelation"]
        lines.append(
            f"The per-collision defect of Eq. 32 at 250 modes (the `markov-defect` block, "
            f"{defect['mean_of_independent_sets']:+.4f} +- {defect['standard_error']:.4f}) divided by `1 - rho_1` "
            f"(`rho_1 = {rho:.3f}`, the lag-1 autocorrelation of these chains) predicts a stationary mean of "
            f"{1.0 + defect['mean_of_independent_sets'] / (1.0 - rho):.3f} +- "
            f"{defect['standard_error'] / (1.0 - rho):.3f}.")
    return "\n".join(lines)


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
    parser.add_argument("--parts", nargs="+", choices=("fig10", "balance", "cooling", "nu-max"),
                        default=["fig10", "balance", "cooling", "nu-max"],
                        help="run only these parts (the others stay as stored in docs/markov_study.json)")
    args = parser.parse_args()
    if not args.tables_only:
        run_study(args)
    out = json.loads((HERE / "markov_study.json").read_text())
    for name, table in tables(out).items():
        print(f"\n{table}")
        if args.update_docs:
            write_block("markov.md", name, f"`python docs/markov_study.py` (docs/markov_study.json):\n\n{table}")


def run_study(args):
    """Run the chains of the parts asked for, update docs/markov_study.json and the figures."""
    path = HERE / "markov_study.json"
    out = json.loads(path.read_text()) if path.exists() and set(args.parts) != set(PARTS) else {}
    with concurrent.futures.ProcessPoolExecutor(args.workers) as pool:
        for part in args.parts:
            PARTS[part](args, pool, out)
    path.write_text(json.dumps(out, indent=1))
    print(json.dumps(out, indent=1))


def run_fig10(args, pool, out):
    """Fig. 10: four chains of 10,000 solved collisions (gamma = 0.6, hard core, nu_max = 250)."""
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


def run_balance(args, pool, out):
    """Detailed balance and the Eq. 32 defect from independent transitions."""
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


def run_cooling(args, pool, out):
    """Cooling from a cold bath with the vibration rule and Glauber's."""
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


def nu_max_seeds(root: int = ROOT_SEED) -> dict:
    """The run seeds of the nu_max study: SEEDS_PER_MODES independent ones per nu_max, from one root seed
    (``SeedSequence(root).generate_state``, distinct across nu_max so that the points of the fit are independent)."""
    words = np.random.SeedSequence(root).generate_state(SEEDS_PER_MODES * len(NU_MAX), np.uint32)
    return {modes: [int(w) for w in words[i * SEEDS_PER_MODES:(i + 1) * SEEDS_PER_MODES]]
            for i, modes in enumerate(NU_MAX)}


def fit_inverse_modes(modes, means, errors) -> dict:
    """Weighted least squares of ``mean = limit + slope / nu_max``: limit and slope with standard errors, chi^2."""
    x = 1.0 / np.asarray(modes, dtype=float)
    y, sigma = np.asarray(means, dtype=float), np.asarray(errors, dtype=float)
    design = np.stack([np.ones_like(x), x], axis=1) / sigma[:, None]
    covariance = np.linalg.inv(design.T @ design)
    limit, slope = covariance @ design.T @ (y / sigma)
    chi2 = float(np.sum(((y - limit - slope * x) / sigma) ** 2))
    return {"limit": float(limit), "limit_standard_error": float(math.sqrt(covariance[0, 0])),
            "slope": float(slope), "slope_standard_error": float(math.sqrt(covariance[1, 1])),
            "chi2": chi2, "dof": int(x.size - 2)}


def run_nu_max(args, pool, out):
    """The stationary mean of E_tr / T_B^0 against the number of bath modes (issue 24 item 2)."""
    from wavecontact.studies.autocorrelation import autocorrelation, integrated_autocorrelation_time

    rows = []
    start = time.perf_counter()
    for modes, seeds in nu_max_seeds().items():
        runs = [markov_chains(GAMMA, rule="solve", chains=NU_CHAINS, steps=NU_STEPS, seed=seed, bath_modes=modes,
                              initial_energy="boltzmann", executor=pool, batch_size=NU_CHAINS // 2)
                for seed in seeds]
        states = np.concatenate([run.stationary(NU_BURN_IN) for run in runs])
        pooled = integrated_autocorrelation_time(states)
        below = integrated_autocorrelation_time((states < 1.0).astype(float))
        seed_means = [float(run.stationary(NU_BURN_IN).mean()) for run in runs]
        rows.append({"bath_modes": modes, "seeds": seeds, "mean_energy": pooled.mean,
                     "standard_error": pooled.standard_error, "tau": pooled.tau, "window": pooled.window,
                     "lag1_autocorrelation": float(autocorrelation(states)[1]),
                     "fraction_below": below.mean, "fraction_below_standard_error": below.standard_error,
                     "seed_means": seed_means,
                     "seed_spread_standard_error": float(np.std(seed_means, ddof=1) / math.sqrt(len(seed_means)))})
        print(f"nu_max {modes}: {pooled.mean:.4f} +- {pooled.standard_error:.4f} (tau {pooled.tau:.2f})", flush=True)
    fit = fit_inverse_modes([r["bath_modes"] for r in rows], [r["mean_energy"] for r in rows],
                            [r["standard_error"] for r in rows])
    out["nu_max_study"] = {"root_seed": ROOT_SEED, "chains": NU_CHAINS, "steps": NU_STEPS, "burn_in": NU_BURN_IN,
                           "rows": rows, "fit": fit, "wall_s": time.perf_counter() - start}


PARTS = {"fig10": run_fig10, "balance": run_balance, "cooling": run_cooling, "nu-max": run_nu_max}


if __name__ == "__main__":
    main()
