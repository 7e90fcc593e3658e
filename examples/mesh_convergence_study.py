"""A mesh-convergence study of the finite-element restitution, from a script.

The same collision (gamma = 0.6, kappa = 20) on meshes of 25 to 200 elements,
for P1 and P2 elements with lumped and consistent mass; the error is against
the delay equation (exact for the continuum). The observed
order is the slope of log(error) against log(elements), fitted by least squares.
Central differences are second-order accurate in time and P1/P2 elements at
least second order in space, so the fit should show about 2.

    python examples/mesh_convergence_study.py [--out DIR]    # writes into DIR, default examples_output/
"""

from pathlib import Path

from wavecontact.plotting.convergence import plot_convergence
from wavecontact.studies.convergence import convergence_study

# theory of the scheme, not this package: second order
EXPECTED = {"order_p1_consistent": (2.0, 0.3, "second-order central differences and P1 elements")}


def main(out_dir="examples_output"):
    Path(out_dir).mkdir(parents=True, exist_ok=True)
    table = convergence_study(0.6, 20, orders=(1, 2), masses=("consistent", "lumped"),
                              elements=(25, 50, 100, 200), progress=False)
    for fit in table.fits:
        rows = table.rows_for(fit.order, fit.mass)
        errors = ", ".join(f"{r.elements}: {r.error:.2e}" for r in rows)
        print(f"{fit.label}: observed order {fit.observed_order:.2f}; errors {errors}")
    path = plot_convergence(table, Path(out_dir) / "mesh_convergence_study.png")
    print(f"reference epsilon = {table.reference:.10f} ({table.reference_source}); figure: {path}")
    return {"order_p1_consistent": table.fit_for(1, "consistent").observed_order,
            "order_p2_lumped": table.fit_for(2, "lumped").observed_order}


if __name__ == "__main__":
    from _output import output_folder  # examples/_output.py: the --out option

    main(output_folder(__doc__))
