"""Restitution against impact velocity for two steel rods with a soft contact layer.

epsilon depends on the impact speed V only through kappa = alpha V l / c: a slow
impact sees a soft contact (kappa small, epsilon near 1), a fast one a hard
contact (epsilon towards gamma). Two steel rods of 60 mm and 100 mm (gamma = 0.6),
10 cm^2 section, and an exponential contact law whose force decays over
1 / alpha = 1 micrometre. The scene is given in SI units and solved by the delay
equation directly.

    python examples/restitution_vs_impact_velocity.py [--out DIR]    # writes into DIR, default examples_output/
"""

import math
from pathlib import Path

import numpy as np

from wavecontact import Exponential, Rod, Scene, solve
from wavecontact.analytic import asymptotic_restitution

STEEL = {"density": 7850.0, "youngs_modulus": 2.1e11, "area": 1e-3}  # kg/m^3, Pa, m^2
LENGTHS = (0.06, 0.10)  # m
ALPHA = 1e6  # 1/m: the contact force falls by e over one micrometre
FAST = 10.0  # m/s
# checked against the paper's asymptotic formula Eq. 23, written out here: epsilon ~ gamma +
# ln(kappa (Gamma_2 - Gamma_1)) / kappa with the round trips Gamma_1 = 1 + gamma, Gamma_2 = 1 + 1/gamma
# (units l / c; for 0.5 <= gamma < 1), accurate below 1e-12 from kappa = 100 on
_KAPPA_FAST = ALPHA * FAST * (2 * 0.06 * 0.10 / 0.16) / math.sqrt(2.1e11 / 7850.0)  # alpha V l / c, l = 75 mm
EXPECTED = {"restitution_at_10_m_per_s": (0.6 + math.log(_KAPPA_FAST * ((1 + 1 / 0.6) - (1 + 0.6))) / _KAPPA_FAST,
                                          1e-9, "Eq. 23 (asymptotic formula of the paper)")}


def restitution_at(speed):
    """epsilon of the two rods hitting at ``speed`` (m/s); the long rod at rest."""
    scene = Scene(rods=tuple(Rod(length=length, **STEEL) for length in LENGTHS),
                  velocities=(speed, 0.0), contact=Exponential(alpha=ALPHA))
    return solve(scene, "delay")


def main(out_dir="examples_output"):
    Path(out_dir).mkdir(parents=True, exist_ok=True)
    wave_speed = math.sqrt(STEEL["youngs_modulus"] / STEEL["density"])
    effective_length = 2 * LENGTHS[0] * LENGTHS[1] / sum(LENGTHS)
    speeds = np.logspace(-3, 1.5, 40)
    results = [restitution_at(v) for v in speeds]
    fast = restitution_at(FAST)
    print(f"steel: c = {wave_speed:.1f} m/s; l = {1e3 * effective_length:.1f} mm; "
          f"kappa = alpha V l / c = {ALPHA * effective_length / wave_speed:.4f} x V[m/s]")
    for v in (1e-3, 1e-2, 0.1, 1.0, FAST):
        r = fast if v == FAST else restitution_at(v)
        print(f"V = {v:7.3f} m/s: kappa = {r.kappa:9.4f}, epsilon = {r.restitution:.9f}")

    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(6, 4), layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    ax.semilogx(speeds, [r.restitution for r in results], "o-", ms=3, label="delay equation")
    ax.semilogx(speeds, [asymptotic_restitution(0.6, r.kappa) for r in results], "k--", lw=0.8,
                label="Eq. 23 (large kappa)")
    ax.axhline(0.6, color="0.5", lw=0.8, label=r"hard contact: $\gamma$")
    ax.set_ylim(0.55, 1.02)
    ax.set_xlabel("impact speed V (m/s)")
    ax.set_ylabel(r"coefficient of restitution $\epsilon$")
    ax.set_title(r"steel rods 60 mm + 100 mm, contact range $1/\alpha$ = 1 $\mu$m", fontsize=9)
    ax.legend(fontsize=8)
    path = Path(out_dir) / "restitution_vs_impact_velocity.png"
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    print(f"figure: {path}")
    return {"restitution_at_10_m_per_s": fast.restitution, "speeds": speeds,
            "restitution": np.array([r.restitution for r in results])}


if __name__ == "__main__":
    from _output import output_folder  # examples/_output.py: the --out option

    main(output_folder(__doc__))
