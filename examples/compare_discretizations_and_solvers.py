"""One collision, every discretization and every solver.

gamma = 0.6, kappa = 100: the delay equation (exact for the continuum, to its
tolerance), the finite-element solver with P1/P2 elements and lumped/consistent
mass on 100 elements, and the modal solver with 40 modes per rod: with its default
correction for the omitted modes (their exact end response), with the static
correction, and plain truncation. Printed: epsilon, error against the reference
value and wall time of each.

    python examples/compare_discretizations_and_solvers.py [--out DIR]    # writes into DIR, default examples_output/
"""

from pathlib import Path

import wavecontact

MODEL_VALUE = 0.646697087  # computed independently of this package (delay equation, gamma 0.6, kappa 100)
EXPECTED = {"delay": (MODEL_VALUE, 1e-9, "independent reference value")}

RUNS = {
    "delay": {"solver": "delay"},
    "fem P1 lumped": {"solver": "fem", "elements": 100, "order": 1, "mass": "lumped"},
    "fem P1 consistent": {"solver": "fem", "elements": 100, "order": 1, "mass": "consistent"},
    "fem P2 lumped": {"solver": "fem", "elements": 100, "order": 2, "mass": "lumped"},
    "fem P2 consistent": {"solver": "fem", "elements": 100, "order": 2, "mass": "consistent"},
    "modal, end-response (default)": {"solver": "modal", "modes": 40},
    "modal, static correction": {"solver": "modal", "modes": 40, "correction": "static"},
    "modal, plain truncation": {"solver": "modal", "modes": 40, "correction": "none"},
}


def main(out_dir="examples_output"):
    Path(out_dir).mkdir(parents=True, exist_ok=True)
    results = {}
    for label, options in RUNS.items():
        wavecontact.collide(0.6, 100, **options)  # first call: numba prepares kernels; not timed
        results[label] = wavecontact.collide(0.6, 100, **options)
    print(f"{'method':30s} {'epsilon':>14s} {'error':>10s} {'time [ms]':>10s}")
    for label, result in results.items():
        print(f"{label:30s} {result.restitution:14.10f} {abs(result.restitution - MODEL_VALUE):10.1e} "
              f"{1e3 * result.wall_time_s:10.3f}")

    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(7, 3.6), layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    labels = list(results)
    errors = [max(abs(results[k].restitution - MODEL_VALUE), 1e-16) for k in labels]
    ax.barh(labels, errors, color=["C0"] + ["C1"] * 4 + ["C2"] * 3)
    ax.set_xscale("log")
    ax.invert_yaxis()
    ax.set_xlabel(r"$|\epsilon - \epsilon_{ref}|$ (reference 0.646697087)")
    ax.set_title(r"$\gamma$ = 0.6, $\kappa$ = 100: fem on 100 elements, modal with 40 modes", fontsize=9)
    path = Path(out_dir) / "compare_discretizations_and_solvers.png"
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    print(f"figure: {path}")
    return {label: result.restitution for label, result in results.items()}


if __name__ == "__main__":
    from _output import output_folder  # examples/_output.py: the --out option

    main(output_folder(__doc__))
