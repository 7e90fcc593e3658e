"""Regenerate the tables and figures of docs/impact.md: the FE solver against the impact references.

Run from the repository root::

    python docs/impact_references.py            # print the tables
    python docs/impact_references.py --write    # also rewrite the generated block of docs/impact.md and the figures

The references are tests/references/ (written without wavecontact); the same comparisons are the
tests of tests/test_impact_references.py.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests"))

from references.central_differences import extrapolate, run
from references.characteristics import chain
from references.saint_venant import force_at, saint_venant

PAGE = ROOT / "docs" / "impact.md"
FIGURES = ROOT / "docs" / "figures"
START, END = "<!-- impact-errors:start -->", "<!-- impact-errors:end -->"


def fem(scene, elements):
    from wavecontact import solve

    return solve(scene, solver="fem", elements=elements, order=1, mass="lumped")


def lattice_error(result, reference) -> tuple:
    """(largest error of velocities, impulses, durations, first and last contact times; of internal energies).

    The FE's last_contact is the start of the last step in contact, the reference's its end (one dt apart).
    """
    errors = [np.max(np.abs(np.asarray(result.velocities) - reference.velocities))]
    dt = result.work["dt"]
    for got, want in zip(result.contacts, reference.contacts):
        if got.intervals != len(want.intervals):
            return np.inf, np.inf
        errors += [abs(got.impulse - want.impulse), abs(got.duration - want.duration),
                   abs(got.first_contact - want.first_contact), abs(got.last_contact + dt - want.last_contact)]
    energy = np.max(np.abs(np.asarray(result.internal_energies) - reference.internal_energies))
    return float(max(errors)), float(energy)


def order(elements, errors) -> float:
    errors = np.maximum(np.asarray(errors, float), 1e-300)
    return float(-np.polyfit(np.log(elements), np.log(errors), 1)[0])


def saint_venant_rows():
    from wavecontact import Hard, RigidBody, Rod, Scene

    rows, curves = [], {}
    sizes = (50, 100, 200)
    for ratio in (0.25, 1.0, 4.0):
        ref = saint_venant(mass=ratio, rod_length=1.0, impedance=1.0, wave_speed=1.0, velocity=1.0)
        want = np.array([ref.mass_velocity, ref.rod_velocity])
        scene = Scene(rods=(RigidBody(mass=ratio), Rod(1.0)), velocities=(1.0, 0.0), contact=Hard(), gaps=(0.0,))
        errors, estimates, last = [], [], None
        for n in sizes:
            last = fem(scene, n)
            errors.append(float(np.max(np.abs(np.asarray(last.velocities) - want))))
            estimates.append(float(last.error_estimate))
        curves[ratio] = (sizes, errors)
        c = last.contacts[0]
        rows.append((f"Saint-Venant, M/m = {ratio:g}", (f"e = {ref.rod_velocity - ref.mass_velocity:.10f}, "
                     f"{len(ref.intervals)} interval of {ref.duration:g}"),
                     f"P1 lumped, {sizes[-1]} el.", f"{errors[-1]:.1e}", f"{estimates[-1]:.1e}",
                     f"{order(sizes, errors):.2f}", f"{c.intervals} interval(s), duration {c.duration:.4f}"))
    for ratio in (0.25, 1.0, 4.0):
        from wavecontact import solve

        ref = saint_venant(mass=ratio, rod_length=1.0, impedance=1.0, wave_speed=1.0, velocity=1.0)
        scene = Scene(rods=(RigidBody(mass=ratio), Rod(1.0)), velocities=(1.0, 0.0), contact=Hard(), gaps=(0.0,))
        result = solve(scene, solver="delay", rtol=1e-8)
        error = float(np.max(np.abs(np.asarray(result.velocities) - [ref.mass_velocity, ref.rod_velocity])))
        rows.append((f"Saint-Venant, M/m = {ratio:g}", "(as above)",
                     f"delay solver, rtol = 1e-8 ({result.work['steps_per_round_trip']} steps per round trip)",
                     f"{error:.1e}", f"{result.error_estimate:.1e}", "2 (tests/test_delay_rigid_mass.py)",
                     f"{result.contacts[0].intervals} interval(s)"))
    return rows, curves


def lattice_rows():
    from wavecontact import Hard, PiecewiseRod, Rod, Scene, Segment

    rows = []
    for z2 in (2.0, 0.5):
        ref = chain([[(1.0, 1.0)], [(1.0, 1.0), (1.0, z2)]], [1.0, 0.0])
        bar = PiecewiseRod((Segment(length=1.0), Segment(length=1.0, youngs_modulus=z2, density=z2)))
        result = fem(Scene(rods=(Rod(1.0), bar), velocities=(1.0, 0.0), contact=Hard(), gaps=(0.0,)), 40)
        error, energy = lattice_error(result, ref)
        rows.append((f"stepped bar, Z2/Z1 = {z2:g}", f"v = ({ref.velocities[0]:.6f}, {ref.velocities[1]:.6f})",
                     "P1 lumped, 40 el., Courant 1", f"{error:.1e}", f"{result.error_estimate:.1e}",
                     "exact", f"internal energies off by {energy:.1e}"))
    for lengths in ((1.0, 1.0, 1.0), (1.0,) * 5, (0.5, 1.5, 1.0), (0.5, 1.5, 1.0, 0.75, 0.25)):
        n = len(lengths)
        ref = chain([[(L, 1.0)] for L in lengths], [1.0] + [0.0] * (n - 1))
        scene = Scene(rods=tuple(Rod(L) for L in lengths), velocities=(1.0,) + (0.0,) * (n - 1), contact=Hard(),
                      gaps=(0.0,) * (n - 1))
        elements = 8 * round(min(lengths) / 0.25)
        result = fem(scene, elements)
        error, energy = lattice_error(result, ref)
        rows.append((f"chain, lengths {', '.join(f'{L:g}' for L in lengths)}",
                     "v = (" + ", ".join(f"{v:.4g}" for v in ref.velocities) + ")",
                     f"P1 lumped, {elements} el. on the shortest, Courant 1", f"{error:.1e}",
                     f"{result.error_estimate:.1e}", "exact", f"internal energies off by {energy:.1e}"))
    return rows


def taper_rows():
    from wavecontact import Hard, PiecewiseRod, Rod, Scene, Segment

    horn = PiecewiseRod((Segment(length=1.0, area=1.0, end_area=0.25),))
    scene = Scene(rods=(Rod(0.5), horn), velocities=(1.0, 0.0), contact=Hard(), gaps=(0.0,))
    sizes = (25, 50, 100)
    fine = np.asarray(fem(scene, 4 * sizes[-1]).velocities)
    errors, estimates = [], []
    for n in sizes:
        result = fem(scene, n)
        errors.append(float(np.max(np.abs(np.asarray(result.velocities) - fine))))
        estimates.append(float(result.error_estimate))
    levels = [run([[(0.5, 1.0, 1.0, 1.0, 1.0)], [(1.0, 1.0, 0.25, 1.0, 1.0)]], [1.0, 0.0], n, 5.0)
              for n in (400, 800, 1600)]
    reference, bound, _ = extrapolate([o.velocities for o in levels])
    result = fem(scene, sizes[-1])
    independent = ("linear taper (as above)", "finite differences 400-1600 cells/l, Richardson: v = ("
                   + ", ".join(f"{v:.5f}" for v in reference) + f") +- {bound.max():.0e}",
                   f"P1 lumped, {sizes[-1]} el.", f"{np.max(np.abs(np.asarray(result.velocities) - reference)):.1e}",
                   f"{result.error_estimate:.1e}", "", "")
    row = ("linear taper 1 -> 1/4, striker l = 0.5", "v = (" + ", ".join(f"{v:.6f}" for v in fine) + f") at {4 * sizes[-1]} el.",
           f"P1 lumped, {sizes[-1]} el.", f"{errors[-1]:.1e}", f"{estimates[-1]:.1e}", f"{order(sizes, errors):.2f}", "")
    return [row, independent], (sizes, errors)


def table(rows) -> str:
    head = ("scene", "reference", "FE run", "max error", "FE error estimate", "observed order", "FE contacts")
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(lines)


def figures(sv_curves, taper_curve) -> list:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    FIGURES.mkdir(exist_ok=True)
    written = []
    fig, (left, right) = plt.subplots(1, 2, figsize=(9, 3.5))
    for ratio in (0.25, 1.0, 4.0):
        ref = saint_venant(mass=ratio, rod_length=1.0, impedance=1.0, wave_speed=1.0, velocity=1.0)
        t = np.linspace(0.0, 2.5, 1001)
        left.plot(t, [force_at(ref.pieces, ref.tau, s) for s in t], label=f"M/m = {ratio:g}")
    left.set(xlabel="time t c / l", ylabel="contact force F / (Z V)", title="Saint-Venant (reference)")
    left.legend()
    for ratio, (sizes, errors) in sv_curves.items():
        right.loglog(sizes, errors, "o-", label=f"Saint-Venant M/m = {ratio:g}")
    right.loglog(*taper_curve, "s--", label="linear taper (vs 4x run)")
    right.set(xlabel="elements", ylabel="max velocity error", title="FE convergence")
    right.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    right.legend(fontsize=7)
    fig.tight_layout()
    path = FIGURES / "impact_saint_venant.png"
    fig.savefig(path, dpi=120)
    written.append(path)
    plt.close(fig)

    fig, axes = plt.subplots(1, 2, figsize=(10, 3.8), layout="constrained")
    for ax, (rods, title) in zip(axes, (([[(1.0, 1.0)], [(1.0, 1.0), (1.0, 2.0)]], "striker on a stepped bar, Z2 = 2 Z1"),
                                        ([[(0.5, 1.0)], [(1.5, 1.0)], [(1.0, 1.0)], [(0.75, 1.0)], [(0.25, 1.0)]],
                                         "chain of unequal rods"))):
        ref = chain(rods, [1.0] + [0.0] * (len(rods) - 1), cell=0.025)
        extent = (ref.cell_x[0], ref.cell_x[-1], 0.0, ref.dt * len(ref.forces))
        image = ax.imshow(ref.forces, origin="lower", aspect="auto", extent=extent, cmap="RdBu", vmin=-1, vmax=1)
        ax.set(xlabel="x / l", ylabel="time t c / l", title=title)
    fig.colorbar(image, ax=axes, label="axial force N / (Z V)")
    path = FIGURES / "impact_characteristics.png"
    fig.savefig(path, dpi=120)
    written.append(path)
    plt.close(fig)
    return written


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--write", action="store_true", help="rewrite docs/impact.md's generated block and the figures")
    args = parser.parse_args(argv)
    sv_rows, sv_curves = saint_venant_rows()
    taper, taper_curve = taper_rows()
    text = table(sv_rows + lattice_rows() + taper)
    print(text)
    if args.write:
        page = PAGE.read_text()
        head, rest = page.split(START)
        _, tail = rest.split(END)
        PAGE.write_text(f"{head}{START}\n`python docs/impact_references.py --write`\n\n{text}\n{END}{tail}")
        for path in figures(sv_curves, taper_curve):
            print(f"wrote {path.relative_to(ROOT)}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
