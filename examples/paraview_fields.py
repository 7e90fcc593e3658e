"""Stress and velocity fields of a collision, for ParaView and as an x-t diagram.

The finite-element solver samples displacement, velocity and stress in both
rods over the collision (record_fields=True). write_fields stores them as one
VTU file per sample and an index fields.pvd: open it in ParaView and the time
slider steps through the impact; each file's field data holds the units and the
run's parameters. read_fields reads the series back. The x-t diagram shows the
compression wave: stress -Z V / 2 (wave theory) running through the short rod
and back, then through the long rod.

    python examples/paraview_fields.py [--out DIR]    # writes into DIR, default examples_output/
"""

import math
from pathlib import Path

import wavecontact
from wavecontact.io.fields import read_fields, write_fields
from wavecontact.plotting.xt import plot_xt_diagram

# wave theory of impact: the compression wave carries the stress -Z V / 2 (units rho c V: -0.5)
EXPECTED = {"peak_compression": (-0.5, 1e-6, "wave theory: stress -Z V / 2")}


def main(out_dir="examples_output"):
    Path(out_dir).mkdir(parents=True, exist_ok=True)
    out = Path(out_dir)
    result = wavecontact.collide(0.6, math.inf, solver="fem", elements=100, record_fields=True,
                                 field_samples=60)
    written = write_fields(result, out / "paraview_fields", units="dimensionless")
    back = read_fields(written.index)
    peak = min(float(rod["stress"].min()) for rod in back["rods"])
    print(f"wrote {len(written.files)} files; open {written.index} in ParaView")
    print(f"read back: {back['time'].size} samples, rods of {[rod['x'].size for rod in back['rods']]} nodes")
    print(f"units: {back['units']}")
    print(f"parameters: gamma = {back['parameters']['gamma']:g}, restitution = "
          f"{back['parameters']['restitution']:.12f}, solver = {back['parameters']['solver']}")
    print(f"strongest compression = {peak:.9f} rho c V (wave theory: -Z V / 2 = -0.5)")
    figure = plot_xt_diagram(result, out / "paraview_fields.png")
    print(f"figure: {figure}")
    return {"peak_compression": peak, "files": len(written.files)}


if __name__ == "__main__":
    from _output import output_folder  # examples/_output.py: the --out option

    main(output_folder(__doc__))
