"""The delay equation of a rigid mass striking one free-free uniform rod (Saint-Venant's scene).

The rod's end answers a compressive force ``F`` with the displacement (d'Alembert, free far end)::

    u_end(t) = (G(t) + 2 sum_{n >= 1} G(t - n T)) / Z,   G(t) = int_0^t F,   T = 2 l / c,   Z = rho c A,

so the whole rod is this delayed end response and the collision is an equation for the impulse
alone.  It is integrated on a grid of ``steps_per_round_trip`` steps per round trip (the echoes
``G(t - nT)`` fall on grid points): per step the impulse ``J`` moves the mass's velocity by ``-J/M``
exactly and its position by the step's mean velocity; hard contact takes the ``J >= 0`` that closes
the gap at the step's end (zero if the gap stays open), a force law ``F(r)`` the ``J`` of the
trapezoidal rule, ``J = dt (F(r_k) + F(r_{k+1})) / 2`` (a monotone scalar equation).  Second order
in the step (docs/impact.md); the error estimate is Richardson's from the run at half the steps.

Works in the rod's rest frame (the rod's rigid velocity added back at the end).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

__all__ = ["RigidMassOutcome", "rigid_mass_on_rod"]


@dataclass(frozen=True)
class RigidMassOutcome:
    """Velocities after the last separation, the rod's internal energy, the contact's record.

    Attributes
    ----------
    mass_velocity, rod_velocity : float
        Final velocity of the mass and the rod's centre of mass (length/time).
    rod_internal_energy : float
        Rod energy minus its rigid kinetic energy (energy).
    impulse : float
        Total contact impulse (force time).
    intervals : tuple of (float, float)
        Contact intervals (time), grid resolution.
    steps : int
    """

    mass_velocity: float
    rod_velocity: float
    rod_internal_energy: float
    impulse: float
    intervals: tuple
    steps: int


def rigid_mass_on_rod(mass: float, length: float, impedance: float, wave_speed: float, mass_velocity: float,
                      rod_velocity: float = 0.0, gap: float = 0.0, law=None, steps_per_round_trip: int = 400,
                      max_round_trips: int = 200) -> RigidMassOutcome:
    """A rigid ``mass`` (left) at ``mass_velocity`` against the left end of a free-free rod.

    Parameters
    ----------
    mass : float
        The rigid body's mass (mass).
    length, impedance, wave_speed : float
        The rod's length (length), ``Z = rho c A`` (mass/time) and ``c`` (length/time).
    mass_velocity, rod_velocity : float
        Initial velocities (length/time); the mass must approach.
    gap : float
        Initial gap (length), >= 0.
    law : ContactLaw or None
        None or a law named ``hard``: the unilateral constraint; otherwise a law with ``force(gap)``.
    steps_per_round_trip : int
        Grid steps per round trip ``2 l / c``.
    max_round_trips : int
        Give up (RuntimeError) if the bodies have not parted for good by then.
    """
    M, Z, K = float(mass), float(impedance), int(steps_per_round_trip)
    T = 2.0 * length / wave_speed
    dt = T / K
    m_rod = Z * length / wave_speed
    hard = law is None or getattr(law, "name", "") == "hard"
    approach = float(mass_velocity) - float(rod_velocity)
    G = np.zeros(K * max_round_trips + 1)
    x, v = -float(gap), approach  # mass's front in the rod's rest frame; the rod's end starts at 0
    force_prev = 0.0 if hard else float(law.force(gap))
    intervals, open_since, quiet = [], None, 0
    k = 0
    for k in range(K * max_round_trips):
        echoes = 2.0 * sum(G[k + 1 - n * K] for n in range(1, (k + 1) // K + 1))
        base = (G[k] + echoes) / Z - x - dt * v  # gap at the step's end without an impulse
        slope = 1.0 / Z + dt / (2.0 * M)  # how the impulse opens it
        if hard:
            J = max(0.0, -base / slope)
        else:
            def residual(j, base=base, force_prev=force_prev, slope=slope):
                return j - 0.5 * dt * (force_prev + float(law.force(base + slope * j)))

            J = 0.0
            if residual(0.0) < 0.0:
                high = max(dt * force_prev, 1e-300)
                while residual(high) < 0.0:
                    high *= 2.0
                J = brentq(residual, 0.0, high, xtol=1e-15 * high, rtol=1e-15, maxiter=300)
            force_prev = float(law.force(base + slope * J))
        G[k + 1] = G[k] + J
        x += dt * v - dt * J / (2.0 * M)
        v -= J / M
        touching = J > 0.0 if hard else force_prev > 1e-12 * M * abs(approach) / dt
        if touching and open_since is None:
            open_since = k * dt
        if not touching and open_since is not None:
            intervals.append((open_since, k * dt))
            open_since = None
        quiet = 0 if touching else quiet + 1
        if quiet >= 2 * K and v <= G[k + 1] / m_rod:
            break  # the end repeats its motion every T with mean I/m above the mass's velocity
    else:
        raise RuntimeError(f"the mass and the rod did not part for good within {max_round_trips} round trips "
                           "(raise max_round_trips)")
    impulse = float(G[k + 1])
    rod_v = impulse / m_rod
    internal = 0.5 * M * approach**2 - 0.5 * M * v**2 - 0.5 * m_rod * rod_v**2
    return RigidMassOutcome(mass_velocity=v + rod_velocity, rod_velocity=rod_v + rod_velocity,
                            rod_internal_energy=internal, impulse=impulse, intervals=tuple(intervals), steps=k + 1)


def richardson(fine: float, coarse: float, order: float = 2.0) -> float:
    """Error estimate of ``fine`` from the run at half the steps: ``|fine - coarse| / (2^order - 1)``."""
    return abs(fine - coarse) / (2.0**order - 1.0) if math.isfinite(coarse) else math.nan
