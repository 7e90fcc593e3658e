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


# -- the delay solver's entry for Saint-Venant's scene (solve(scene, solver="delay")) ---------------------------

#: Grid steps per round trip: doubled from the first until Richardson's estimate meets the target, at most the last
STEPS_START, STEPS_MAX = 64, 8192
#: Richardson's estimate of a second-order result, times this safety (the fit 1.9-2.1 of tests/test_delay_rigid_mass.py)
SAFETY = 1.5
#: Start gap where the scene leaves it to the solver: this many ranges of the law (exp(-40) of the force)
START_RANGES = 40.0


def _uniform_rod(body):
    """``(length, impedance, wave speed)`` of a uniform rod (a Rod, or a piecewise rod of one prism), else None."""
    from ..bodies import PiecewiseRod, RigidBody
    from ..scene import Rod

    if isinstance(body, Rod):
        return body.length, body.impedance, body.wave_speed
    if isinstance(body, PiecewiseRod) and len(body.segments) == 1 and not isinstance(body, RigidBody):
        (s,) = body.segments
        if s.end_area is None or s.end_area == s.area:
            speed = math.sqrt(s.youngs_modulus / s.density)
            return s.length, s.density * speed * s.area, speed
    return None


def takes(scene) -> bool:
    """True for a rigid body and one uniform rod on a line, no walls, hard or force-law contact (not a
    penalty law left to the solver)."""
    from ..bodies import RigidBody, pair_laws

    if scene.is_ring or scene.walls is not None or len(scene.rods) != 2:
        return False
    rigid = [isinstance(b, RigidBody) for b in scene.rods]
    if sum(rigid) != 1 or _uniform_rod(scene.rods[rigid.index(False)]) is None:
        return False
    (law,) = pair_laws(scene)
    return law.name == "hard" or (law.name != "penalty" or getattr(law, "stiffness", None) is not None)


def solve_scene(scene, options, *, tolerance=None, max_work=None, max_memory=None, estimate_error=True):
    """The ImpactResult of a rigid body against one uniform rod (:func:`takes`), by the delay equation.

    The steps per round trip double from 64 until Richardson's estimate (times 1.5) meets the target
    ``max(options.rtol, tolerance)`` or reach 8192; the error estimate is relative to the largest
    initial speed, as the fem solver's.
    """
    from ..bodies import RigidBody, pair_laws
    from ..errors import AccuracyError
    from ..impact_result import ContactRecord, ImpactResult
    from ..solvers.base import Stopwatch

    del max_work, max_memory  # at most STEPS_MAX steps per round trip: bounded, milliseconds to seconds
    left_rigid = isinstance(scene.rods[0], RigidBody)
    body, rod = (scene.rods[0], scene.rods[1]) if left_rigid else (scene.rods[1], scene.rods[0])
    length, impedance, speed = _uniform_rod(rod)
    (law,) = pair_laws(scene)
    sign = 1.0 if left_rigid else -1.0  # mirrored: the mass on the right approaching leftwards
    v_mass, v_rod = (sign * v for v in ((scene.velocities[0], scene.velocities[1]) if left_rigid
                                        else (scene.velocities[1], scene.velocities[0])))
    gap = scene.gaps[0] if scene.gaps is not None else (0.0 if law.name == "hard" else START_RANGES * law.range)
    scale = max(abs(v) for v in scene.velocities) or 1.0
    target = max(options.rtol, tolerance or 0.0)
    with Stopwatch() as watch:
        steps, previous, outcome, estimate = STEPS_START, None, None, math.nan
        while True:
            outcome = rigid_mass_on_rod(body.mass, length, impedance, speed, v_mass, v_rod, gap,
                                        None if law.name == "hard" else law, steps_per_round_trip=steps)
            if previous is not None:
                estimate = SAFETY * max(richardson(outcome.mass_velocity, previous.mass_velocity),
                                        richardson(outcome.rod_velocity, previous.rod_velocity)) / scale
                if estimate <= target or steps >= STEPS_MAX or not (estimate_error or tolerance):
                    break
            previous, steps = outcome, 2 * steps
    if tolerance is not None and estimate > tolerance:
        raise AccuracyError(f"delay (rigid mass): error estimate {estimate:.2g} above tolerance={tolerance:g} at "
                            f"{STEPS_MAX} steps per round trip; use solver='fem' with more elements")
    velocities = (sign * outcome.mass_velocity, sign * outcome.rod_velocity)
    energies = (0.0, outcome.rod_internal_energy)
    if not left_rigid:
        velocities, energies = velocities[::-1], energies[::-1]
    dt = 2.0 * length / speed / steps
    intervals = outcome.intervals
    record = ContactRecord(
        name="0-1", impulse=outcome.impulse, duration=sum(b - a for a, b in intervals),
        first_contact=intervals[0][0] if intervals else math.nan,
        last_contact=intervals[-1][1] - dt if intervals else math.nan, intervals=len(intervals))
    masses = tuple(b.mass if isinstance(b, RigidBody) else impedance * length / speed for b in scene.rods)
    return ImpactResult(
        velocities=velocities, internal_energies=energies, contacts=(record,), error_estimate=float(estimate),
        solver="delay", end_time=outcome.steps * dt, initial_velocities=tuple(float(v) for v in scene.velocities),
        masses=masses, bodies=tuple("rigid" if isinstance(b, RigidBody) else "rod" for b in scene.rods),
        wall_time_s=watch.seconds, options={"rtol": options.rtol, "steps_per_round_trip": steps},
        work={"steps": outcome.steps, "steps_per_round_trip": steps, "dt": dt},
        diagnostics={"error_estimate_method": "Richardson from half the steps per round trip (order 2, x1.5)",
                     "includes_kernel_preparation": False})
