"""Use a thermal restitution table in a DEM or event-driven code.

Two audiences (docs/bath.md, section "Collision rules for other codes"):

* codes that take one coefficient of restitution per material pair (LIGGGHTS,
  LAMMPS, MercuryDPM, Kratos): write ``table.mean_restitution(gamma, T_B/E_tr)``
  into their input;
* codes that call user code per collision (Chrono, DEM-Engine, REBOUND): call
  ``restitution_callback`` below, which draws epsilon from the tabulated law.

It builds a small table (two gammas, three temperatures, 30 samples a point,
kappa = 100, 20 bath modes), saves it as NPZ, JSON and CSV, loads it back,
uses it both ways and plots the tabulated quantile functions.

    python examples/restitution_table_dem.py [--out DIR]    # writes into DIR, default examples_output/
"""

import math
from pathlib import Path

import numpy as np

from wavecontact.errors import InvalidParameterError
from wavecontact.restitution_table import load
from wavecontact.studies.restitution_tables import restitution_table

GAMMAS = (0.2173, 0.6)
TEMPERATURES = (0.0, 0.5, 1.0)  # T_B / E_tr
# a cold bath makes the collision deterministic: the table's law at T_B = 0 is a point mass at the
# cold restitution, computed independently of this package for gamma = 0.6, kappa = 100
EXPECTED = {"cold_mean_restitution_0.6": (0.646697087, 1e-6, "independent reference value (cold bath)")}


def restitution_callback(table, rng):
    """A per-collision rule: length ratio, reduced mass, relative normal speed and bath temperature in,
    epsilon out.  ``reduced_mass * speed**2 / 2`` is the pair's translational energy E_tr; a state
    outside the table's grid is refused (the law was not computed there), never clipped."""

    def rule(gamma, reduced_mass, speed, bath_temperature):
        energy = 0.5 * reduced_mass * speed * speed
        if energy <= 0.0:
            raise InvalidParameterError("the pair does not approach: no collision")
        return math.sqrt(table.sample(rng, gamma, bath_temperature / energy))

    return rule


def main(out_dir="examples_output"):
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    table = restitution_table(list(GAMMAS), list(TEMPERATURES), samples=30, seed=5, kappa=100.0, bath_modes=20,
                              levels=21, rtol=1e-6)
    for suffix in (".npz", ".json", ".csv"):
        table.save(out / f"rods{suffix}")
    table = load(out / "rods.npz")
    print("constant per pair (e.g. LIGGGHTS 'coefficientRestitution'):")
    numbers = {}
    for gamma in table.gamma:
        for ratio in table.temperature_ratio:
            mean = table.mean_restitution(gamma, ratio)
            numbers[f"mean_restitution_{gamma:g}_{ratio:g}"] = mean
            print(f"  gamma = {gamma:g}, T_B/E_tr = {ratio:g}: e = {mean:.6f}")
    numbers["cold_mean_restitution_0.6"] = table.mean_restitution(0.6, 0.0)
    rule = restitution_callback(table, np.random.default_rng(1))
    draws = [rule(0.6, 0.5, 1.0, 0.125) for _ in range(5)]  # E_tr = 1/4, T_B/E_tr = 0.5
    print("per-collision callback draws at gamma = 0.6, T_B/E_tr = 0.5:", " ".join(f"{e:.4f}" for e in draws))

    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(6, 4), layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    for g, gamma in enumerate(table.gamma):
        for r, ratio in enumerate(table.temperature_ratio):
            ax.plot(table.eps2_quantiles[g, r], table.probability, ls="-" if g else "--",
                    label=rf"$\gamma$ = {gamma:g}, $T_B/E_{{tr}}$ = {ratio:g}")
    ax.set_xlabel(r"$\epsilon^2$")
    ax.set_ylabel(r"$D(\epsilon^2)$ (tabulated distribution)")
    ax.set_title(r"restitution table, $\kappa$ = 100, 20 bath modes, 30 samples a point", fontsize=9)
    ax.legend(fontsize=7)
    path = out / "restitution_table.png"
    fig.savefig(path, dpi=110)
    print(f"wrote {path}")
    return numbers


if __name__ == "__main__":
    from _output import output_folder  # examples/_output.py: the --out option

    main(output_folder(__doc__))
