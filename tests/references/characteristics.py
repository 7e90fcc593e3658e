"""Exact characteristic (d'Alembert) solution for rods of one wave speed on a line, hard contact.

Written without importing wavecontact.  Every rod is cut into cells of one length ``h``
(each segment a whole number of cells, ``dt = h / c``); in each cell the state is a
right-going amplitude ``a`` and a left-going amplitude ``b`` (particle velocity
``v = a + b``, axial force ``N = Z (b - a)``, tension positive, ``Z = rho c A``).  With
piecewise-constant initial data (rigid velocities) the solution stays piecewise
constant on this lattice: in one step each wave moves one cell and scatters at the
interface it crosses.  Inside a rod (a step from ``Z1`` to ``Z2``) velocity and force
are continuous::

    a2 = (2 Z1 a1 + (Z2 - Z1) b2) / (Z1 + Z2),   b1 = a2 + b2 - a1

(force transmission ``2 Z2 / (Z1 + Z2)``, reflection ``(Z2 - Z1) / (Z1 + Z2)``).  Between two
rods the same holds while the ends touch and the force is compressive; otherwise both
ends are free (``b1 = a1``, ``a2 = b2``) and the gap grows at ``2 b2 - 2 a1`` during the step.
A gap that would close inside a step is not representable on the lattice: refused.
Energy ``sum h (Z / c) (a^2 + b^2)`` and momentum ``sum h (Z / c) (a + b)`` are conserved
exactly (checked by the tests of this module).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Contact:
    """One facing pair's record: contact intervals (force > 0), impulse."""

    intervals: tuple
    impulse: float

    @property
    def first_contact(self):
        return self.intervals[0][0] if self.intervals else math.nan

    @property
    def last_contact(self):
        return self.intervals[-1][1] if self.intervals else math.nan

    @property
    def duration(self):
        return sum(b - a for a, b in self.intervals)


@dataclass(frozen=True)
class LatticeResult:
    velocities: np.ndarray  # centre-of-mass velocity of each rod after the run
    internal_energies: np.ndarray  # rod energy minus 0.5 m v^2
    contacts: tuple  # one Contact per facing pair
    forces: np.ndarray  # axial force (tension > 0) per step (rows) and cell (columns)
    cell_rod: np.ndarray  # rod index of each cell
    cell_x: np.ndarray  # cell centres along the line at rest (length)
    dt: float
    energy: float
    momentum: float


def chain(rods, velocities, wave_speed: float = 1.0, cell: float | None = None, duration: float | None = None,
          settle_round_trips: float = 2.0) -> LatticeResult:
    """Rods touching end to end (zero gaps) at ``velocities``, hard contact between them.

    Parameters
    ----------
    rods : sequence of sequences of (length, impedance)
        Each rod's segments from left to right (lengths in length units, impedances rho c A).
    velocities : sequence of float
        Initial rigid velocity of each rod (length/time).
    wave_speed : float
        The one wave speed ``c`` of every segment (length/time).
    cell : float or None
        Lattice cell; default the largest common divisor of the segment lengths (to 1e-9).
    duration : float or None
        Simulated time; default until every contact has been open for ``settle_round_trips``
        round trips of the longest rod with non-approaching neighbours.
    """
    lengths = [L for rod in rods for L, _ in rod]
    if cell is None:
        cell = _common_cell(lengths)
    impedance, rod_of, x = [], [], []
    left = 0.0
    for i, rod in enumerate(rods):
        for j, (L, Z) in enumerate(rod):
            n = round(L / cell)
            if n < 1 or abs(n * cell - L) > 1e-9 * L:
                raise ValueError(f"segment length {L} is not a whole number of cells {cell}")
            impedance += [Z] * n
            rod_of += [i] * n
            x += list(left + (np.arange(n) + 0.5) * cell)
            left += L
    Z = np.array(impedance, float)
    rod_of = np.array(rod_of)
    x = np.array(x)
    # interface k lies between cells k and k+1: a contact where the rod index changes
    contact_at = np.nonzero(np.diff(rod_of) != 0)[0]
    v0 = np.array(velocities, float)[rod_of]
    a, b = 0.5 * v0.copy(), 0.5 * v0.copy()
    dt = cell / wave_speed
    gaps = np.zeros(len(contact_at))
    impulse = np.zeros(len(contact_at))
    intervals = [[] for _ in contact_at]
    forces = []
    longest = max(sum(L for L, _ in rod) for rod in rods) * 2.0 / wave_speed
    steps = round(duration / dt) if duration is not None else None
    mass = np.bincount(rod_of, weights=Z * cell / wave_speed)
    step = 0
    quiet_since = 0.0
    while True:
        t = step * dt
        if steps is not None and step >= steps:
            break
        forces.append(Z * (b - a))
        a1, b2 = a[:-1], b[1:]
        Z1, Z2 = Z[:-1], Z[1:]
        a2_new = (2.0 * Z1 * a1 + (Z2 - Z1) * b2) / (Z1 + Z2)
        b1_new = a2_new + b2 - a1
        touching = False
        for m, k in enumerate(contact_at):
            compressive = b1_new[k] - a1[k] < 0.0 or (b1_new[k] == a1[k])
            if gaps[m] <= 1e-12 * cell and compressive:
                gaps[m] = 0.0
                force = -Z1[k] * (b1_new[k] - a1[k])
                if force > 0.0:
                    impulse[m] += force * dt
                    touching = True
                    if intervals[m] and abs(intervals[m][-1][1] - t) < 0.5 * dt:
                        intervals[m][-1][1] = t + dt
                    else:
                        intervals[m].append([t, t + dt])
            else:
                b1_new[k], a2_new[k] = a1[k], b2[k]
                new_gap = gaps[m] + dt * (2.0 * b2[k] - 2.0 * a1[k])
                if new_gap < -1e-12 * cell:
                    raise ValueError(f"a gap closes inside a step at t = {t:g}: not representable on this lattice")
                gaps[m] = max(new_gap, 0.0)
        a_new, b_new = np.empty_like(a), np.empty_like(b)
        a_new[1:] = a2_new
        b_new[:-1] = b1_new
        a_new[0] = b[0]  # free left end
        b_new[-1] = a[-1]  # free right end
        a, b = a_new, b_new
        step += 1
        if touching:
            quiet_since = step * dt
        if steps is None and step * dt - quiet_since >= settle_round_trips * longest:
            v_rod = np.bincount(rod_of, weights=Z * (a + b) * cell / wave_speed) / mass
            if np.all(np.diff(v_rod) >= -1e-12):
                break
            if step * dt > 1e4 * longest:
                raise RuntimeError("contacts did not settle")
    weights = Z * cell / wave_speed
    v_rod = np.bincount(rod_of, weights=weights * (a + b)) / mass
    energy_rod = np.bincount(rod_of, weights=weights * (a * a + b * b))
    return LatticeResult(
        velocities=v_rod, internal_energies=energy_rod - 0.5 * mass * v_rod**2,
        contacts=tuple(Contact(tuple(tuple(iv) for iv in ivs), float(imp)) for ivs, imp in zip(intervals, impulse)),
        forces=np.array(forces), cell_rod=rod_of, cell_x=x, dt=dt,
        energy=float(energy_rod.sum()), momentum=float(np.sum(weights * (a + b))),
    )


def _common_cell(lengths, tol=1e-9):
    """Largest h with every length a whole multiple of h (to ``tol``), by a Euclid on floats."""
    h = lengths[0]
    for L in lengths[1:]:
        x, y = max(h, L), min(h, L)
        while y > tol * max(lengths):
            x, y = y, math.fmod(x, y)
            if y > x - tol * max(lengths):
                y = 0.0
        h = x
    return h
