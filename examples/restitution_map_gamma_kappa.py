"""epsilon over the whole (gamma, kappa) plane.

Every point is one solve of the delay equation (Eq. 16); restitution_map runs
them in threads. Along gamma = 1 the rods are equal and the collision is
elastic whatever kappa; towards large kappa epsilon approaches the hard-core
value gamma; towards small kappa it approaches 1.

    python examples/restitution_map_gamma_kappa.py [--out DIR]    # writes into DIR, default examples_output/
"""

from pathlib import Path

import numpy as np

from wavecontact.studies.sweep import restitution_map

# equal rods collide elastically for every kappa (the paper, Sec. V)
EXPECTED = {"equal_rods_min": (1.0, 1e-8, "gamma = 1: epsilon = 1 for every kappa")}


def main(out_dir="examples_output"):
    Path(out_dir).mkdir(parents=True, exist_ok=True)
    gammas = np.linspace(0.3, 1.0, 15)
    kappas = np.logspace(0, 4, 17)
    epsilon = restitution_map(gammas, kappas, progress=False)
    for gamma in (0.3, 0.6, 1.0):
        row = epsilon[np.argmin(abs(gammas - gamma))]
        print(f"gamma = {gamma:.1f}: epsilon = {row[0]:.6f} (kappa = 1) ... {row[-1]:.6f} (kappa = 1e4)")

    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(6, 4.2), layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    mesh = ax.pcolormesh(kappas, gammas, epsilon, shading="nearest", cmap="viridis", vmin=0.3, vmax=1.0)
    lines = ax.contour(kappas, gammas, epsilon, levels=[0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 0.95], colors="w",
                       linewidths=0.7)
    ax.clabel(lines, fontsize=7)
    ax.set_xscale("log")
    ax.set_xlabel(r"$\kappa = \alpha V l / c$")
    ax.set_ylabel(r"length ratio $\gamma = l_1 / l_2$")
    fig.colorbar(mesh, ax=ax, label=r"$\epsilon$ (delay equation)")
    path = Path(out_dir) / "restitution_map_gamma_kappa.png"
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    print(f"{epsilon.size} collisions; figure: {path}")
    return {"equal_rods_min": float(epsilon[-1].min()), "map": epsilon}


if __name__ == "__main__":
    from _output import output_folder  # examples/_output.py: the --out option

    main(output_folder(__doc__))
