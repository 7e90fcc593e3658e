"""Save a result to disk and read it back.

CollisionResult.save_npz writes every array (time, relative velocity, contact
force, solver extras) into a NumPy .npz archive with the scalars, options and
diagnostics as JSON inside; CollisionResult.load_npz reads it back, without
pickle. to_json() gives the scalars alone, for logs and tables.

    python examples/saving_and_loading_results.py [--out DIR]    # writes into DIR, default examples_output/
"""

import json
from pathlib import Path

import numpy as np

import wavecontact
from wavecontact import CollisionResult

# computed independently of this package (delay equation, gamma 0.6, kappa 20); the fem
# error on 200 elements is about 1e-8 (docs/convergence.md)
EXPECTED = {"loaded_restitution": (0.7530132413, 5e-8, "independent reference; fem error on 200 elements ~1e-8")}


def main(out_dir="examples_output"):
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    result = wavecontact.collide(0.6, 20, solver="fem", elements=200)
    path = out / "saving_and_loading_results.npz"
    result.save_npz(path)
    loaded = CollisionResult.load_npz(path)
    same = (loaded.restitution == result.restitution and np.array_equal(loaded.time, result.time)
            and np.array_equal(loaded.contact_force, result.contact_force))
    print(f"saved {path} ({path.stat().st_size / 1e3:.0f} kB); read back identical: {same}")
    print("scalars:", json.dumps({k: v for k, v in json.loads(loaded.to_json()).items()
                                  if k in ("restitution", "solver", "gamma", "kappa", "contact_duration")}))

    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(6, 3.6), layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    ax.plot(loaded.time, loaded.relative_velocity, label="relative velocity / V (loaded from .npz)")
    ax.plot(loaded.time, loaded.contact_force, label="contact force / (Z V)")
    ax.set_xlabel(r"time $t\,c/l$")
    ax.set_title(rf"fem, 200 elements: $\epsilon$ = {loaded.restitution:.8f}", fontsize=9)
    ax.legend(fontsize=8)
    figure = out / "saving_and_loading_results.png"
    fig.savefig(figure, dpi=110)
    print(f"figure: {figure}")
    return {"loaded_restitution": loaded.restitution, "identical": same}


if __name__ == "__main__":
    from _output import output_folder  # examples/_output.py: the --out option

    main(output_folder(__doc__))
