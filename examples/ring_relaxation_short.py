"""Two rods on a ring, many collisions: relaxation towards equipartition (Fig. 1-3, short).

Two rods of length ratio 0.6173 start at rest internally, maximally far apart on a
ring, and collide again and again (each collision by the modal solver with 10
modes per rod and the static correction). Translational energy flows into the
vibrations until it fluctuates around the equipartition value mu V^2 / (2 (2 N + 1))
(Eq. 8); the spectral entropy of the modes falls towards Eq. 11. The paper runs
4500 collisions with 75 modes (wavecontact ring); this is a 200-collision sketch.

    python examples/ring_relaxation_short.py [--out DIR]    # writes into DIR, default examples_output/
"""

from pathlib import Path

import numpy as np

import wavecontact
from wavecontact.analytic import equilibrium_spectral_entropy, equilibrium_translational_energy
from wavecontact.studies.ring import run_ring

GAMMA, KAPPA, MODES, COLLISIONS = 0.6173, 400.0, 10, 200
# the first collision is a cold two-rod collision: the delay equation (another solver) gives it;
# 10 modes with the static correction are accurate to a few 1e-3 there
EXPECTED = {"first_restitution": (wavecontact.collide(GAMMA, KAPPA).restitution, 1e-2,
                                  "delay solver, same collision")}


def main(out_dir="examples_output"):
    Path(out_dir).mkdir(parents=True, exist_ok=True)
    run = run_ring(GAMMA, KAPPA, MODES, COLLISIONS, progress=False)
    e_eq = equilibrium_translational_energy(MODES)
    late = run.translational_energy[COLLISIONS // 2:]
    drift = float(np.max(np.abs(run.total_energy / run.total_energy[0] - 1)))
    print(f"{run.n_collisions} collisions in {run.wall_time_s:.1f} s; energy drift {drift:.1e}")
    print(f"first collision: epsilon = {run.restitution[0]:.6f} (delay solver: "
          f"{EXPECTED['first_restitution'][0]:.6f})")
    print(f"E_tr over the second half: mean {late.mean():.4f} vs Eq. 8 {e_eq:.4f} "
          f"(started at {run.translational_energy[0]:.2f})")
    print(f"spectral entropy, last 50 collisions: {run.spectral_entropy()[-50:].mean():.3f} vs Eq. 11 "
          f"{equilibrium_spectral_entropy(MODES):.3f}")

    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(10, 3.4), layout="constrained")
    FigureCanvasAgg(fig)
    ax_e, ax_s, ax_r = fig.subplots(1, 3)
    collision = np.arange(1, run.n_collisions + 1)
    ax_e.semilogy(collision, run.translational_energy, lw=0.8)
    ax_e.axhline(e_eq, color="k", ls="--", lw=0.8, label="Eq. 8")
    ax_e.set_ylabel(r"$E_{tr}$ before the collision")
    ax_s.plot(collision, run.spectral_entropy(), lw=0.8)
    ax_s.axhline(equilibrium_spectral_entropy(MODES), color="k", ls="--", lw=0.8, label="Eq. 11")
    ax_s.set_ylabel(r"spectral entropy $\eta$")
    ax_r.plot(collision, run.restitution, ".", ms=2)
    ax_r.set_ylabel(r"$\epsilon$ of each collision")
    for ax in (ax_e, ax_s, ax_r):
        ax.set_xlabel("collision")
    ax_e.legend(fontsize=8)
    ax_s.legend(fontsize=8)
    fig.suptitle(rf"ring: $\gamma$ = {GAMMA}, $\kappa$ = {KAPPA:g}, N = {MODES} modes per rod", fontsize=9)
    path = Path(out_dir) / "ring_relaxation_short.png"
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    print(f"figure: {path}")
    return {"first_restitution": float(run.restitution[0]), "energy_drift": drift}


if __name__ == "__main__":
    from _output import output_folder  # examples/_output.py: the --out option

    main(output_folder(__doc__))
