"""Fig. 5 of the paper: epsilon against kappa for gamma = 0.6, delay equation
against the asymptotic formula Eq. 23.

    python examples/restitution_vs_kappa.py [OUTPUT.png]
"""

import sys

import numpy as np

from wavecontact.analytic import asymptotic_restitution
from wavecontact.studies.sweep import restitution_map


def main(path="restitution_vs_kappa.png"):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    gamma = 0.6
    kappas = np.logspace(-1, 4, 60)
    restitution = restitution_map([gamma], kappas)[0]
    asymptotic = [asymptotic_restitution(gamma, k) for k in kappas]
    fig = Figure(figsize=(6, 4), layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    ax.semilogx(kappas, restitution, "o", ms=4, label="delay equation (Eq. 16)")
    ax.semilogx(kappas, asymptotic, "k--", label="asymptotic (Eq. 23)")
    ax.axhline(gamma, color="gray", lw=0.8, label=r"hard core: $\gamma$")
    ax.set_ylim(0.5, 1.05)
    ax.set_xlabel(r"$\kappa = \alpha V l / c$")
    ax.set_ylabel(r"coefficient of restitution $\epsilon$")
    ax.legend()
    fig.savefig(path, dpi=120)
    print(f"epsilon(kappa = 100) = {restitution[np.argmin(abs(kappas - 100))]:.9f}; figure: {path}")
    return restitution


if __name__ == "__main__":
    main(*sys.argv[1:])
