"""Fig. 5 of the paper: epsilon against kappa for gamma = 0.6.

The delay equation (Eq. 16, exact) against the paper's asymptotic formula
Eq. 23: soft contacts (small kappa) are nearly elastic, hard ones (large kappa)
approach the wave-theory value epsilon = gamma. Eq. 23 holds from about
kappa = 20 on.

    python examples/restitution_vs_kappa.py [--out DIR]    # writes into DIR, default examples_output/
"""

from pathlib import Path

import numpy as np

from wavecontact.analytic import asymptotic_restitution
from wavecontact.studies.sweep import restitution_map

GAMMA = 0.6
# computed independently of this package (delay equation, gamma 0.6, kappa 100)
EXPECTED = {"restitution_at_100": (0.646697087, 1e-9, "independent reference value")}


def main(out_dir="examples_output"):
    Path(out_dir).mkdir(parents=True, exist_ok=True)
    kappas = np.logspace(-1, 4, 61)  # 12 points per decade: kappa = 100 is on the grid
    at_100 = int(np.argmin(abs(kappas - 100.0)))
    kappas[at_100] = 100.0  # exactly, not 100 to round-off
    restitution = restitution_map([GAMMA], kappas, progress=False)[0]
    asymptotic = [asymptotic_restitution(GAMMA, k) for k in kappas]
    for k in (0.1, 1.0, 10.0, 100.0, 1e4):
        i = int(np.argmin(abs(kappas - k)))
        print(f"kappa = {kappas[i]:8g}: epsilon = {restitution[i]:.9f}, Eq. 23: {asymptotic[i]:.9f}")

    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(6, 4), layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    ax.semilogx(kappas, restitution, "o", ms=4, label="delay equation (Eq. 16)")
    ax.semilogx(kappas, asymptotic, "k--", label="asymptotic (Eq. 23)")
    ax.axhline(GAMMA, color="gray", lw=0.8, label=r"hard core: $\gamma$")
    ax.set_ylim(0.5, 1.05)
    ax.set_xlabel(r"$\kappa = \alpha V l / c$")
    ax.set_ylabel(r"coefficient of restitution $\epsilon$")
    ax.set_title(r"$\gamma$ = 0.6", fontsize=9)
    ax.legend()
    path = Path(out_dir) / "restitution_vs_kappa.png"
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    print(f"figure: {path}")
    return {"restitution_at_100": float(restitution[at_100]), "kappas": kappas, "restitution": restitution}


if __name__ == "__main__":
    from _output import output_folder  # examples/_output.py: the --out option

    main(output_folder(__doc__))
