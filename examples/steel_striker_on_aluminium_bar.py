"""A steel striker hits an aluminium bar (SI units): three solvers, the stress x-t
diagram and the restitution against the impact velocity.

    python examples/steel_striker_on_aluminium_bar.py [--out DIR]    # writes into DIR, default examples_output/

Both rods have a 20 mm diameter.  The striker is the stiffer rod (impedance
about 2.95 times the bar's) and has the shorter round trip, so the contact
force steps down by R = (Z_s - Z_b)/(Z_s + Z_b) at every return of the
striker's wave and the contact ends when the bar's wave returns
(docs/theory.md, "Two materials").  The contact is the exponential law with a
range 1/alpha of 1 micrometre; the softness kappa = alpha V mu / Z_s grows with
the impact speed V, so epsilon approaches the hard-core value as V grows.
"""

import math
from pathlib import Path

import numpy as np

import wavecontact
from wavecontact.analytic import two_material_impact
from wavecontact.delay.parameters import delay_parameters
from wavecontact.plotting.xt import plot_xt_diagram

AREA = math.pi * 0.010**2  # m^2, 20 mm diameter
STEEL = {"density": 7850.0, "youngs_modulus": 210e9, "area": AREA}  # kg/m^3, Pa
ALUMINIUM = {"density": 2700.0, "youngs_modulus": 70e9, "area": AREA}
BAR_LENGTH = 1.0  # m
ALPHA = 1e6  # 1/m: the contact force decays over 1 micrometre
SPEED = 5.0  # m/s


def rods():
    """The striker's transit time l/c is one fifth of the bar's (about 0.203 m of steel),
    so a finite-element mesh with equal element transit times fits both rods exactly."""
    bar = wavecontact.Rod(BAR_LENGTH, **ALUMINIUM)
    striker_length = math.sqrt(STEEL["youngs_modulus"] / STEEL["density"]) * bar.round_trip_time / 2.0 / 5.0
    return wavecontact.Rod(striker_length, **STEEL), bar


def impact(speed, contact=None):
    """The striker at ``speed`` (m/s) hits the bar at rest."""
    return wavecontact.Scene(rods=rods(), velocities=(speed, 0.0), contact=contact or wavecontact.Exponential(ALPHA))


def characteristic_restitution(striker, bar, speed):
    """Hard-contact epsilon from the rods' end responses, written out here as a check.

    A force F(t) pressed on the end of a free rod moves that end at (1/Z) [F(t) + 2 sum_n F(t - n 2T)]
    (its echoes return every round trip 2T = 2 l / c). The two ends move together while F > 0; the bar's
    round trip is five of the striker's, so F is constant over each striker round trip and the contact
    opens at the first one whose F would not be positive. Then momentum gives the rods' velocities.
    """
    z1, z2, step = striker.impedance, bar.impedance, striker.round_trip_time  # kg/s, kg/s, s
    ratio = round(bar.round_trip_time / step)
    forces = []  # N, one per striker round trip
    while True:
        k = len(forces)
        echoes_striker = sum(forces[k - n] for n in range(1, k + 1))
        echoes_bar = sum(forces[k - n * ratio] for n in range(1, k // ratio + 1))
        force = (speed - 2 * echoes_striker / z1 - 2 * echoes_bar / z2) / (1 / z1 + 1 / z2)
        if force <= 0:
            break
        forces.append(force)
    impulse = sum(forces) * step  # N s
    striker_mass, bar_mass = (r.density * r.area * r.length for r in (striker, bar))  # kg
    return (impulse / bar_mass - (speed - impulse / striker_mass)) / speed


# the one number tests/test_examples.py checks for every example: the solvers' hard contact
# (docs/theory.md "Two materials") against the end-response solution written out above
EXPECTED = {"hard": (characteristic_restitution(*rods(), SPEED), 1e-12, "end responses of the two rods")}


def main(out_dir="examples_output"):
    Path(out_dir).mkdir(parents=True, exist_ok=True)
    out = Path(out_dir)
    striker, bar = rods()
    speed = SPEED
    scene = impact(speed)
    params = delay_parameters(scene)
    theory = two_material_impact(striker, bar, speed)
    print(f"striker {striker.length:.4f} m steel, bar {bar.length:.1f} m aluminium, V = {speed} m/s, "
          f"Z_striker/Z_bar = {striker.impedance / bar.impedance:.3f}, kappa = {params.kappa:.1f}")
    print(f"hard-contact wave theory: epsilon = {theory['restitution']:.6f}, plateau {theory['force'] / 1e3:.2f} kN, "
          f"{len(theory['steps'])} force steps (R = {theory['reflection']:.3f}), "
          f"contact {1e6 * theory['duration']:.1f} us; end responses written out here: "
          f"epsilon = {characteristic_restitution(striker, bar, speed):.6f}")

    delay = wavecontact.solve(scene, "delay")
    fem = wavecontact.solve(scene, "fem", elements=120, record_fields=True)
    modal = wavecontact.solve(scene, "modal", modes=200)
    for result in (delay, fem, modal):
        first = " (first call: includes loading the compiled kernels)" if result.diagnostics[
            "includes_kernel_preparation"] else ""
        print(f"  {result.solver:<5}: epsilon = {result.restitution:.8f} (delay - this: "
              f"{delay.restitution - result.restitution:+.1e}), peak force {result.contact_force.max() / 1e3:.2f} kN, "
              f"contact {1e6 * result.contact_duration:.1f} us, {1e3 * result.wall_time_s:.0f} ms{first}")
    plot_xt_diagram(fem, out / "striker_xt.png", units="SI")

    speeds = np.geomspace(0.1, 20.0, 25)
    restitution = np.array([wavecontact.solve(impact(v), "delay", rtol=1e-8).restitution for v in speeds])
    hard = wavecontact.solve(impact(1.0, wavecontact.Hard()), "delay").restitution
    _plot_restitution(speeds, restitution, hard, out / "striker_restitution.png")
    print(f"epsilon from {restitution[0]:.4f} at {speeds[0]:g} m/s to {restitution[-1]:.4f} at {speeds[-1]:g} m/s; "
          f"hard contact {hard:.6f}; figures in {out}")
    return {"delay": delay, "fem": fem, "modal": modal, "theory": theory, "speeds": speeds,
            "restitution": restitution, "hard": hard}


def _plot_restitution(speeds, restitution, hard, path):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(6, 4), layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    ax.semilogx(speeds, restitution, "o-", ms=4, label=r"delay equation, $1/\alpha$ = 1 $\mu$m")
    ax.axhline(hard, color="gray", ls="--", label="hard contact (wave theory)")
    ax.set_xlabel("impact speed V (m/s)")
    ax.set_ylabel(r"coefficient of restitution $\epsilon$")
    ax.set_title("steel striker on aluminium bar", fontsize=9)
    ax.legend()
    fig.savefig(path, dpi=120)


if __name__ == "__main__":
    from _output import output_folder  # examples/_output.py: the --out option

    main(output_folder(__doc__))
