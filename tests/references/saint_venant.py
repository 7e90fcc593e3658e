"""Saint-Venant's problem: a rigid mass hits the free end of a free-free uniform rod (hard contact).

Written without importing wavecontact.  Method of steps on the end response of the
rod: with the contact force ``F(t) >= 0`` (compressive) acting on the end ``x = 0`` of a
rod at rest, d'Alembert's solution ``u = f(t - x/c) + g(t + x/c)`` with the free far end
(stress zero at ``x = l``: ``g'(s) = f'(s - T)``, ``T = 2 l / c``) and the loaded end
(``f' - g' = F / Z``) gives the end velocity::

    v_end(t) = F(t) / Z + (2 / Z) sum_{n >= 1} F(t - n T)          (Z = rho c A)

(the far end reflects a compressive wave as a tensile one whose particle velocity has
the same sign, hence ``+2``; the mean of ``v_end`` over a round trip after the force
has ended is ``2 I / (Z T) = I / m``, the rod's momentum per mass, checked below).
While in contact the mass moves with the end: ``M v' = -F``, ``F = Z (v - h(t))`` with the
known history ``h(t) = (2/Z) sum_{n>=1} F(t - nT)``: a linear ODE whose forcing, window by
window, is ``exp(-(t - t0)/tau)`` times a polynomial (``tau = M / Z``), so every piece of the
force is such a product and is integrated in closed form.  Separation when ``F`` would turn
negative; re-contact when the gap ``int (v_end - v_mass) dt`` closes again.

The energy of the rod is ``Z int_{t-T}^{t} f'(s)^2 ds`` with ``f'(t) = sum_{n>=0} F(t - nT)/Z``
(energy density ``rho A (f'^2 + g'^2)``), an independent check of the solution.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np
from numpy.polynomial import Polynomial
from scipy.integrate import quad
from scipy.optimize import brentq


@dataclass(frozen=True)
class Piece:
    """The force ``exp(-(t - start)/tau) * poly(t - start)`` on ``[start, stop)``."""

    start: float
    stop: float
    poly: Polynomial


@dataclass(frozen=True)
class SaintVenantResult:
    mass_velocity: float  # final velocity of the rigid mass
    rod_velocity: float  # final centre-of-mass velocity of the rod
    rod_internal_energy: float  # rod energy minus 0.5 m v_rod^2
    impulse: float
    intervals: tuple  # ((start, stop), ...) of contact
    pieces: tuple
    round_trip: float
    rod_energy: float
    tau: float
    impedance: float

    @property
    def duration(self) -> float:
        return sum(b - a for a, b in self.intervals)

    @property
    def first_contact(self) -> float:
        return self.intervals[0][0]

    @property
    def last_contact(self) -> float:
        return self.intervals[-1][1]


def _shift(poly: Polynomial, a: float) -> Polynomial:
    """p(u + a)."""
    return poly(Polynomial([a, 1.0]))


def _first_root(func, length: float, samples: int = 4001) -> float | None:
    """First zero crossing from positive to non-positive of ``func`` on ``(0, length]``."""
    u = np.linspace(0.0, length, samples)
    values = np.array([func(x) for x in u])
    for k in range(1, samples):
        if values[k] <= 0.0 < values[k - 1] or (k == 1 and values[0] <= 0.0 and values[1] < 0.0):
            if values[k] == 0.0:
                return float(u[k])
            return float(brentq(func, u[k - 1], u[k], xtol=1e-15, rtol=4e-16))
    return None


def saint_venant(mass: float, rod_length: float, impedance: float, wave_speed: float, velocity: float,
                 max_round_trips: int = 60) -> SaintVenantResult:
    """Hard impact of a rigid ``mass`` at ``velocity`` on the end of a free-free rod at rest.

    Parameters in any consistent units: ``impedance = rho c A`` (mass/time), ``wave_speed = c``.
    """
    M, Z, V = float(mass), float(impedance), float(velocity)
    T = 2.0 * rod_length / wave_speed
    tau = M / Z
    m_rod = Z * rod_length / wave_speed
    pieces: list[Piece] = []
    intervals: list[list[float]] = []

    def breakpoints_after(t):
        times = [p.start + n * T for p in pieces for n in range(1, max_round_trips + 2)]
        times += [p.stop + n * T for p in pieces for n in range(1, max_round_trips + 2)]
        later = [s for s in times if s > t * (1 + 1e-14) + 1e-300]
        return min(later) if later else math.inf

    def history(t):
        """h(t + u) = exp(-u/tau) q(u) on the window starting at t (no breakpoint inside)."""
        q = Polynomial([0.0])
        for p in pieces:
            for n in range(1, max_round_trips + 2):
                s = t - n * T
                if p.start <= s * (1 + 1e-15) and s < p.stop * (1 - 1e-15):
                    lag = s - p.start
                    q = q + (2.0 / Z) * math.exp(-lag / tau) * _shift(p.poly, lag)
        return q

    t, v, contact, gap = 0.0, V, True, 0.0
    intervals.append([0.0, None])
    impulse = 0.0
    end_time = max_round_trips * T
    while t < end_time:
        stop = min(breakpoints_after(t), end_time) if pieces else T
        q = history(t)
        length = stop - t
        if contact:
            w = Polynomial([v]) + q.integ() / tau
            force = Z * (w - q)
            if force(0.0) < -1e-13 * Z * abs(V):  # the arriving wave pulls the end away
                contact, gap = False, 0.0
                intervals[-1][1] = t
                continue
            root = _first_root(force, length)
            stop_here = t + root if root is not None and root > 0 else stop
            pieces.append(Piece(t, stop_here, force))
            u = stop_here - t
            impulse += quad(lambda x, force=force: math.exp(-x / tau) * force(x), 0.0, u, epsabs=0, epsrel=1e-13, limit=200)[0]
            v = math.exp(-u / tau) * w(u)
            t = stop_here
            if root is not None and root > 0:
                contact, gap = False, 0.0
                intervals[-1][1] = t
        else:
            # gap(u) = gap + int_0^u (exp(-s/tau) q(s) - v) ds, with d/ds[exp(-s/tau) r] = exp(-s/tau) q
            r = Polynomial([0.0])
            term = q
            for _ in range(q.degree() + 1):
                r = r - tau * term
                term = tau * term.deriv()
            g0 = gap

            def gap_at(u, r=r, g0=g0, v=v):
                return g0 + math.exp(-u / tau) * r(u) - r(0.0) - v * u

            opening = q(0.0) - v
            if g0 <= 1e-14 * V * T and opening < 0.0:
                contact = True
                intervals.append([t, None])
                continue
            root = _first_root(lambda u, g0=g0, gap_at=gap_at: gap_at(u) if u > 0 else max(g0, 1e-300), length)
            if root is not None:
                t = t + root
                contact = True
                intervals.append([t, None])
                continue
            gap = gap_at(length)
            t = stop
            last = intervals[-1][1]
            if v <= impulse / m_rod and t >= last + 2.0 * T:
                break  # h is T-periodic with mean I/m >= v and the gap stayed open a whole period
    else:
        raise RuntimeError(f"contact not over after {max_round_trips} round trips")
    rod_energy = _rod_energy(pieces, Z, T, tau, t)
    rod_velocity = impulse / m_rod
    return SaintVenantResult(
        mass_velocity=v, rod_velocity=rod_velocity,
        rod_internal_energy=rod_energy - 0.5 * m_rod * rod_velocity**2, impulse=impulse,
        intervals=tuple((a, b) for a, b in intervals), pieces=tuple(pieces), round_trip=T, rod_energy=rod_energy,
        tau=tau, impedance=Z,
    )


def force_at(pieces, tau: float, t: float) -> float:
    for p in pieces:
        if p.start <= t < p.stop:
            return math.exp(-(t - p.start) / tau) * p.poly(t - p.start)
    return 0.0


def _rod_energy(pieces, Z, T, tau, t):
    """Z int_{t-T}^{t} f'(s)^2 ds, f'(s) = sum_{n>=0} F(s - nT) / Z, by quadrature between breakpoints."""
    def fprime(s):
        return sum(force_at(pieces, tau, s - n * T) for n in range(int(s // T) + 2)) / Z

    cuts = sorted({t - T, t} | {p.start + n * T for p in pieces for n in range(int(t // T) + 2)}
                  | {p.stop + n * T for p in pieces for n in range(int(t // T) + 2)})
    cuts = [c for c in cuts if t - T <= c <= t]
    total = 0.0
    for a, b in itertools.pairwise(cuts):
        if b > a:
            total += quad(lambda s: fprime(s) ** 2, a, b, epsabs=0, epsrel=1e-13, limit=200)[0]
    return Z * total


def end_velocity_mean(result: SaintVenantResult, t0: float) -> float:
    """Mean of ``v_end = (2/Z) sum_{n>=1} F(t - nT)`` over one round trip from ``t0`` (no force after t0).

    Equals the rod's momentum per mass ``I / m`` if the far-end reflection sign is right.
    """
    T, tau, Z = result.round_trip, result.tau, result.impedance

    def v_end(s):
        return 2.0 * sum(force_at(result.pieces, tau, s - n * T) for n in range(1, int(s // T) + 2)) / Z

    cuts = sorted({t0, t0 + T} | {p.start + n * T for p in result.pieces for n in range(1, int(t0 // T) + 3)}
                  | {p.stop + n * T for p in result.pieces for n in range(1, int(t0 // T) + 3)})
    cuts = [c for c in cuts if t0 <= c <= t0 + T]
    total = sum(quad(v_end, a, b, epsabs=0, epsrel=1e-13, limit=200)[0] for a, b in itertools.pairwise(cuts) if b > a)
    return total / T
