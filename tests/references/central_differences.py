"""A separately written finite-difference solver for bodies on a line with hard contact.

Written without importing wavecontact, for scenes with no closed form (tapered bars): nodes at
spacing ``h`` on every rod (velocities), cells between them (axial forces ``N = E A_mid (u_{i+1} -
u_i) / h`` with the area at the cell's middle, exact in mean for a linear taper), lumped node masses
``rho A_mid h / 2`` from each side, leapfrog in time at ``dt = courant h / c_max``.  A rigid body is
one node of its mass.  Hard contact between the facing end nodes of neighbours is the
forward-increment Lagrange multiplier: a step that would make the gap negative gets the impulse
that closes it exactly (Carpenter, Taylor and Katona 1991), which conserves momentum and loses
``O(h)`` energy per impact, so the result converges at first order; :func:`extrapolate` fits the
observed order over three meshes and returns the Richardson value with an error bound.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Outcome:
    velocities: np.ndarray  # momentum / mass of each body at the end
    energies: np.ndarray  # kinetic + strain energy of each body at the end
    impulses: np.ndarray  # per facing pair
    time: float
    last_contact: float  # time of the last step with a contact impulse


def run(bodies, velocities, cells_per_unit: int, duration: float, courant: float = 0.5) -> Outcome:
    """Bodies left to right, touching (zero gaps).

    Parameters
    ----------
    bodies : sequence
        A float: a rigid mass.  A sequence of segments ``(length, area_start, area_end, youngs_modulus,
        density)``: a rod.
    velocities : sequence of float
    cells_per_unit : int
        Cells per unit length (every segment length times it must be a whole number).
    duration : float
        Simulated time.
    """
    h = 1.0 / cells_per_unit
    masses, stiff_cells, first, last, body_of = [], [], [], [], []
    speeds = []
    for b, body in enumerate(bodies):
        first.append(len(masses))
        if isinstance(body, (int, float)):
            masses.append(float(body))
            body_of.append(b)
            last.append(len(masses) - 1)
            continue
        node_mass = [0.0]
        for length, a0, a1, modulus, density in body:
            n = round(length * cells_per_unit)
            if abs(n * h - length) > 1e-9 * length:
                raise ValueError(f"segment length {length} is not a whole number of cells")
            s = (np.arange(n) + 0.5) / n
            areas = a0 + (a1 - a0) * s
            speeds.append(np.sqrt(modulus / density))
            for area in areas:
                cell_mass = density * area * h
                node_mass[-1] += 0.5 * cell_mass
                node_mass.append(0.5 * cell_mass)
                stiff_cells.append((len(masses) + len(node_mass) - 2, modulus * area / h))
        masses += node_mass
        body_of += [b] * len(node_mass)
        last.append(len(masses) - 1)
    m = np.array(masses)
    body_of = np.array(body_of)
    left_node = np.array([c for c, _ in stiff_cells], dtype=int)
    k = np.array([s for _, s in stiff_cells])
    v = np.array(velocities, float)[body_of]
    u = np.zeros_like(v)
    dt = courant * h / max(speeds)
    steps = int(np.ceil(duration / dt))
    pairs = [(last[b], first[b + 1]) for b in range(len(bodies) - 1)]
    gaps = np.zeros(len(pairs))
    impulses = np.zeros(len(pairs))
    last_contact = 0.0
    # leapfrog: v at half steps; start v(-dt/2) = v(0) (no force at t = 0: every body unstrained)
    for step in range(steps):
        force = k * (u[left_node + 1] - u[left_node])
        f = np.zeros_like(u)
        f[left_node] += force  # each node is the left end of at most one cell, the right end of at most one
        f[left_node + 1] -= force
        v = v + dt * f / m
        for p, (i, j) in enumerate(pairs):
            trial = gaps[p] + dt * (v[j] - v[i])
            if trial < 0.0:
                impulse = -trial / dt / (1.0 / m[i] + 1.0 / m[j])
                v[i] -= impulse / m[i]
                v[j] += impulse / m[j]
                impulses[p] += impulse
                last_contact = (step + 1) * dt
                gaps[p] = 0.0
            else:
                gaps[p] = trial
        u = u + dt * v
    mass_b = np.bincount(body_of, weights=m)
    force = k * (u[left_node + 1] - u[left_node])
    strain = np.bincount(body_of[left_node], weights=0.5 * force**2 / k, minlength=len(bodies))
    kinetic = np.bincount(body_of, weights=0.5 * m * v**2)
    return Outcome(velocities=np.bincount(body_of, weights=m * v) / mass_b, energies=kinetic + strain,
                   impulses=impulses, time=steps * dt, last_contact=last_contact)


def extrapolate(values_by_level, ratio: float = 2.0):
    """Richardson from three levels (coarse to fine, refined by ``ratio``): (value, bound, order).

    The order is fitted per component from the two differences; the bound is the size of the
    correction applied, times two (the extrapolated value is then within the bound when the
    observed order holds to a factor 2 of the error; tests check it against a closed form).
    """
    a, b, c = (np.asarray(x, float) for x in values_by_level)
    d1, d2 = b - a, c - b
    with np.errstate(divide="ignore", invalid="ignore"):
        order = np.log(np.abs(d1 / d2)) / np.log(ratio)
    fallback = np.where(np.isfinite(order) & (order > 0.3), order, 1.0)
    correction = d2 / (ratio**fallback - 1.0)
    return c + correction, 2.0 * np.abs(correction) + 1e-15, order
