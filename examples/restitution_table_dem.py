"""Use a thermal restitution table in a DEM or event-driven code.

Two audiences (docs/bath.md, section "Collision rules for other codes"):

* codes that take one coefficient of restitution per material pair (LIGGGHTS,
  LAMMPS, MercuryDPM, Kratos): write ``table.mean_restitution(gamma, T_B/E_tr)``
  into their input;
* codes that call user code per collision (Chrono, DEM-Engine, REBOUND): call
  ``restitution_callback`` below, which draws epsilon from the tabulated law.

Run ``python examples/restitution_table_dem.py`` (seconds): it builds a
small table (two gammas, three temperatures, 30 samples a point, kappa = 100,
20 bath modes), saves it, loads it back and uses it both ways.
"""

import math
import tempfile
from pathlib import Path

import numpy as np

from wavecontact.restitution_table import load
from wavecontact.studies.restitution_tables import restitution_table


def restitution_callback(table, rng):
    """A per-collision rule: relative normal speed and bath temperature in, epsilon out.

    ``reduced_mass * speed**2 / 2`` is the pair's translational energy E_tr;
    the table is indexed by T_B / E_tr (clipped to its grid: outside it the
    law was not computed).
    """

    def rule(gamma, reduced_mass, speed, bath_temperature):
        energy = 0.5 * reduced_mass * speed * speed
        ratio = bath_temperature / energy if energy > 0.0 else table.temperature_ratio[-1]
        ratio = min(max(ratio, table.temperature_ratio[0]), table.temperature_ratio[-1])
        return math.sqrt(table.sample(rng, gamma, ratio))

    return rule


def main():
    table = restitution_table([0.2173, 0.6173], [0.0, 0.5, 1.0], samples=30, seed=5, kappa=100.0, bath_modes=20,
                              levels=21, rtol=1e-6)
    folder = Path(tempfile.mkdtemp())
    for suffix in (".npz", ".json", ".csv"):
        table.save(folder / f"rods{suffix}")
    table = load(folder / "rods.npz")
    print("constant per pair (e.g. LIGGGHTS 'coefficientRestitution'):")
    for gamma in table.gamma:
        print(f"  gamma = {gamma}: e = {table.mean_restitution(gamma, 0.5):.4f} at T_B/E_tr = 0.5")
    rule = restitution_callback(table, np.random.default_rng(1))
    draws = [rule(0.6173, 0.5, 1.0, 0.125) for _ in range(5)]  # E_tr = 1/4, T_B/E_tr = 0.5
    print("per-collision callback draws:", " ".join(f"{e:.4f}" for e in draws))
    return table


if __name__ == "__main__":
    main()
