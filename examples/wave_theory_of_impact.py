"""The wave theory of impact, checked with the finite-element solver.

Two rods of one material, length ratio gamma = 0.6, hard contact. Saint-Venant's
wave theory says: the contact force is a plateau Z V / 2 while a compression
wave runs once up and down the short rod, so contact lasts 2 l1 / c; the short
rod leaves at rest internally and epsilon = gamma; the long rod keeps
(1 - gamma^2) of the translational energy, split over its modes as Eq. 25 of
the paper. Units: rho = c = A = 1, effective length l = 1, approach speed V = 1
(so Z V / 2 = 0.5 and 2 l1 / c = 1 + gamma).

    python examples/wave_theory_of_impact.py [--out DIR]    # writes into DIR, default examples_output/
"""

import math
from pathlib import Path

import numpy as np

import wavecontact
from wavecontact.analytic import hard_core_modal_energies

GAMMA = 0.6
# the one number tests/test_examples.py checks, against the wave theory (not this package)
EXPECTED = {"restitution": (GAMMA, 1e-12, "wave theory: epsilon = gamma for hard contact")}


def long_rod_modal_energies(result, modes):
    """Energy of the first ``modes`` free-free modes of the long rod after the impact.

    Projects the last field sample onto the mass-normalized modes
    phi_nu(s) = sqrt(2 / l2) cos(nu pi s / l2) (rho A = 1): E_nu = (p^2 + omega^2 q^2) / 2.
    """
    rod = result.extra["fields"]["rods"][1]
    s = rod["x"] - rod["x"].min()
    order = np.argsort(s)
    s, u, v = s[order], rod["displacement"][-1][order], rod["velocity"][-1][order]
    length = s[-1]
    energies = []
    for nu in range(1, modes + 1):
        phi = math.sqrt(2.0 / length) * np.cos(nu * math.pi * s / length)
        q, p = np.trapezoid(u * phi, s), np.trapezoid(v * phi, s)
        omega = nu * math.pi / length
        energies.append(0.5 * (p * p + omega * omega * q * q))
    return np.array(energies)


def main(out_dir="examples_output"):
    Path(out_dir).mkdir(parents=True, exist_ok=True)
    # P1 elements with lumped mass at the stable step are exact for hard contact (docs/fem.md)
    result = wavecontact.collide(GAMMA, math.inf, solver="fem", elements=400, record_fields=True)
    plateau = float(np.median(result.contact_force[result.contact_force > 0.01]))
    translational = 0.25  # mu V^2 / 2 with mu = 1/2
    fem_modes = long_rod_modal_energies(result, 4) / translational
    eq25 = hard_core_modal_energies(GAMMA, 4)[1]  # row 1: the long rod (row 0, the short rod, is zero)
    print(f"epsilon          = {result.restitution:.15f}   (wave theory: gamma = {GAMMA})")
    print(f"contact duration = {result.contact_duration:.6f}            (2 l1 / c = {1 + GAMMA})")
    print(f"force plateau    = {plateau:.6f}            (Z V / 2 = 0.5)")
    print(f"vibration energy = {1 - result.restitution ** 2:.6f} E_tr       (1 - gamma^2 = {1 - GAMMA ** 2:.2f})")
    print("modal split of the long rod, E_nu / E_tr (FE fields projected on the modes vs Eq. 25):")
    for nu, (fe, exact) in enumerate(zip(fem_modes, eq25), start=1):
        print(f"  mode {nu}: {fe:.5f}  Eq. 25: {exact:.5f}")

    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(9, 3.6), layout="constrained")
    FigureCanvasAgg(fig)
    ax_f, ax_m = fig.subplots(1, 2)
    ax_f.plot(result.time, result.contact_force, lw=1.2, label="finite elements, 400 elements")
    ax_f.axhline(0.5, color="k", ls="--", lw=0.8, label="wave theory: Z V / 2")
    ax_f.set_xlabel(r"time $t\,c/l$")
    ax_f.set_ylabel(r"contact force / $(Z V)$")
    ax_f.legend(fontsize=8)
    nu = np.arange(1, 5)
    ax_m.bar(nu - 0.2, fem_modes, width=0.4, label="FE fields, projected")
    ax_m.bar(nu + 0.2, eq25, width=0.4, label="Eq. 25")
    ax_m.set_xticks(nu)
    ax_m.set_xlabel(r"mode $\nu$ of the long rod")
    ax_m.set_ylabel(r"$E_\nu / E_{tr}$")
    ax_m.legend(fontsize=8)
    path = Path(out_dir) / "wave_theory_of_impact.png"
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    print(f"figure: {path}")
    return {"restitution": result.restitution, "contact_duration": result.contact_duration,
            "plateau": plateau, "modal_split": fem_modes}


if __name__ == "__main__":
    from _output import output_folder  # examples/_output.py: the --out option

    main(output_folder(__doc__))
