"""Closed-form results: the wave theory of impact and the paper's formulas.

Unless said otherwise, quantities are dimensionless in the units of
:func:`wavecontact.two_rods`: time ``tau = t c / l``, velocities in units of
the approach speed ``V``, energies in units of the initial translational
energy ``E_tr = mu V^2 / 2``, ``Gamma_1 = 1 + gamma``, ``Gamma_2 = 1 + 1/gamma``.
Equation numbers refer to Giese & Zippelius, Phys. Rev. E 54, 4828 (1996).
"""

from __future__ import annotations

import math

import numpy as np

from .errors import require_integer, require_positive
from .scene import validate_gamma_kappa

__all__ = [
    "ENTROPY_CONSTANT",
    "asymptotic_restitution",
    "asymptotic_velocity_increase",
    "boltzmann_density",
    "equilibrium_spectral_entropy",
    "equilibrium_spectral_entropy_finite",
    "equilibrium_translational_energy",
    "force_plateau",
    "hard_core_contact_duration",
    "hard_core_modal_energies",
    "hard_core_relative_velocity",
    "hard_core_restitution",
    "noise_covariance",
    "round_trip_times",
    "two_material_impact",
]


def round_trip_times(gamma: float) -> tuple:
    """``(Gamma_1, Gamma_2) = (1 + gamma, 1 + 1/gamma)``: round trips of a wave
    on the short and the long rod, in units of ``l / c``."""
    g, _ = validate_gamma_kappa(gamma, 1.0)
    return 1.0 + g, 1.0 + 1.0 / g


def hard_core_restitution(gamma: float) -> float:
    """``epsilon = min(gamma, 1/gamma)`` of the cold hard-core collision."""
    if not (math.isfinite(gamma) and gamma > 0):
        raise ValueError(f"gamma must be positive and finite, got {gamma!r}")
    return min(gamma, 1.0 / gamma)


def hard_core_contact_duration(length_short: float, wave_speed: float = 1.0) -> float:
    """Contact time ``2 l1 / c`` of the hard-core impact (time units): the
    round trip of the stress wave on the shorter rod."""
    return 2.0 * length_short / wave_speed


def force_plateau(impedance: float, approach_speed: float) -> float:
    """Contact force ``Z V / 2`` during a hard impact of equal impedances (force units)."""
    return 0.5 * impedance * approach_speed


def two_material_impact(rod_left, rod_right, approach_speed: float, max_steps: int = 10_000) -> dict:
    """Wave theory of the hard impact of two free rods of different materials.

    At first contact the interface takes the velocity that balances the two
    stress waves it launches: with impedances ``Z1, Z2`` the force is
    ``F0 = Z1 Z2 V / (Z1 + Z2)``.  Call ``a`` the rod with the shorter round
    trip ``T = 2 l / c`` and ``b`` the other.  Rod a's wave comes back from
    its free end at ``T_a`` as an unloading wave that leaves the force
    ``R F0`` with ``R = (Z_a - Z_b) / (Z_a + Z_b)``:

    * ``Z_a <= Z_b`` (``R <= 0``): the ends separate at ``T_a``; rod a leaves
      without vibration;
    * ``Z_a > Z_b``: the force steps down to ``R^k F0`` at every return
      ``k T_a`` and the contact ends when rod b's wave returns, at ``T_b``.

    In both cases the ends never meet again (docs/theory.md, "Two materials").

    Parameters
    ----------
    rod_left, rod_right : Rod
        The rods (any order; the left one moves towards the right one).
    approach_speed : float
        ``V = v_left - v_right`` (velocity units), > 0.
    max_steps : int
        At most this many force steps are listed (the impulse is summed in closed form).

    Returns
    -------
    dict
        ``force`` (the first plateau ``F0``, force), ``duration`` (time),
        ``impulse`` (momentum), ``restitution`` (``(J (1/m1 + 1/m2) - V) / V``),
        ``reflection`` ``R``, ``steps`` (list of ``(start, end, force)``),
        ``velocity_change`` (``(-J / m_left, +J / m_right)``, velocity units)
        and ``vibration_energy`` (per rod, energy; they add up to the
        translational energy lost).
    """
    z1, z2 = rod_left.impedance, rod_right.impedance
    fast, slow = sorted((rod_left, rod_right), key=lambda rod: rod.round_trip_time)
    t_a, t_b = fast.round_trip_time, slow.round_trip_time
    force = z1 * z2 * approach_speed / (z1 + z2)
    reflection = (fast.impedance - slow.impedance) / (fast.impedance + slow.impedance)
    if reflection <= 1e-12:
        steps = [(0.0, t_a, force)]
        impulse, duration = force * t_a, t_a
    else:
        whole = math.floor(t_b / t_a)  # full steps of length T_a before rod b's wave returns
        rest = t_b - whole * t_a
        impulse = force * (t_a * (1.0 - reflection**whole) / (1.0 - reflection) + rest * reflection**whole)
        duration = t_b
        steps = [(k * t_a, min((k + 1) * t_a, t_b), force * reflection**k) for k in range(min(whole + 1, max_steps))]
        steps = [step for step in steps if step[1] > step[0]]
    after = impulse * (1.0 / rod_left.mass + 1.0 / rod_right.mass) - approach_speed
    # a constant force held for whole round trips leaves rod a rigid; only the last, shorter step
    # (length d, force F) leaves it vibrating, with the work F^2 d / Z less the rigid part (F d)^2 / (2 m)
    last_force = steps[-1][2] if reflection > 1e-12 else 0.0
    last_length = steps[-1][1] - steps[-1][0]
    vibration_fast = last_force**2 * last_length / fast.impedance * (1.0 - last_length / t_a)
    lost = 0.5 * rod_left.mass * rod_right.mass / (rod_left.mass + rod_right.mass) * (
        approach_speed**2 - after**2
    )
    vibration = (vibration_fast, lost - vibration_fast) if fast is rod_left else (lost - vibration_fast, vibration_fast)
    return {
        "force": force,
        "duration": duration,
        "impulse": impulse,
        "restitution": after / approach_speed,
        "reflection": reflection,
        "steps": steps,
        "velocity_change": (-impulse / rod_left.mass, impulse / rod_right.mass),
        "vibration_energy": vibration,
    }


def hard_core_relative_velocity(tau, gamma: float, tau_contact: float = 0.0):
    """Eq. 24: relative velocity ``v2 - v1`` (units of V) of the hard impact.

    ``-1`` before contact (``tau_contact``), rising linearly with slope 1 for
    ``Gamma_1``, then ``+gamma`` for ``0 < gamma <= 1``.
    """
    g1, _ = round_trip_times(gamma)
    tau = np.asarray(tau, dtype=float)
    return -1.0 + np.clip(tau - tau_contact, 0.0, g1)


def hard_core_modal_energies(gamma: float, modes: int) -> np.ndarray:
    """Eq. 25: energy of each mode after the hard impact, in units of ``E_tr``.

    Returns an array ``(2, modes)``; row 0 (short rod) is zero, row 1 sums
    to ``1 - gamma^2`` as ``modes -> inf``.
    """
    modes = require_integer("modes", modes, 1, allowed="a positive integer")
    g1, g2 = round_trip_times(gamma)
    nu = np.arange(1, int(modes) + 1, dtype=float)
    out = np.empty((2, nu.size))
    for row, gi in enumerate((g1, g2)):
        out[row] = 2.0 * gi / (math.pi**2 * nu**2) * np.sin(nu * math.pi * g1 / gi) ** 2
    out[0] = np.where(np.abs(out[0]) < 1e-15, 0.0, out[0])
    return out


def _softplus(x):
    return np.logaddexp(0.0, x)


def asymptotic_velocity_increase(tau, gamma: float, kappa: float, tau_free: float = 0.0):
    """Eq. 21 (``gamma = 1``) and Eq. 22 (``0.5 <= gamma < 1``): ``W(tau)`` for
    large ``kappa``, up to exponentially small terms.

    For ``gamma < 0.5`` ``Gamma_2`` is replaced by ``2 Gamma_1`` (App. B).
    Evaluated with logarithms throughout, so it does not overflow.
    """
    g, k = validate_gamma_kappa(gamma, kappa)
    if math.isinf(k):
        raise ValueError("the asymptotic W(tau) needs a finite kappa")
    tau = np.asarray(tau, dtype=float)
    x = k * (tau - tau_free)
    if g == 1.0:
        return np.logaddexp(0.0, x - np.logaddexp(math.log(k), x - 2.0 * k))
    g1, g2 = round_trip_times(g)
    if g < 0.5:
        g2 = 2.0 * g1
    x1 = x - k * g1 - math.log(k)
    x2 = x - k * g2 - math.log(k)
    # log of L = softplus(x1) - softplus(x2) > 0, accurate when both are tiny
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        tiny = x1 < -30.0
        log_l_tiny = x1 + np.log(-np.expm1(x2 - x1))
        log_l_big = np.log(_softplus(x1) - _softplus(x2))
        log_l = np.where(tiny, log_l_tiny, log_l_big)
    return np.logaddexp(0.0, k * g1 + log_l)


def asymptotic_restitution(gamma: float, kappa: float) -> float:
    """Eq. 23: ``epsilon ~ gamma + ln(kappa (Gamma_2 - Gamma_1)) / kappa`` for
    ``0.5 <= gamma < 1`` (1 for ``gamma = 1``; ``Gamma_2 -> 2 Gamma_1`` for
    ``gamma < 0.5``, App. B)."""
    g, k = validate_gamma_kappa(gamma, kappa)
    if g == 1.0:
        return 1.0
    if math.isinf(k):
        return g
    g1, g2 = round_trip_times(g)
    if g < 0.5:
        g2 = 2.0 * g1
    return g + math.log(k * (g2 - g1)) / k


def noise_covariance(tau, gamma: float, kappa: float, bath_temperature: float, translational_energy: float = 0.25):
    """Eq. 19: covariance ``C_Q(tau) = <Q(t) Q(t + tau)>`` of the thermal noise.

    Parameters
    ----------
    tau : array_like
        Lag (dimensionless time); the covariance is even in ``tau``.
    gamma, kappa : float
        Length ratio and softness.
    bath_temperature : float
        ``T_B`` (energy units, Boltzmann constant 1).
    translational_energy : float
        ``E_tr = mu V^2 / 2`` (1/4 in the units of :func:`two_rods`).
    """
    g, k = validate_gamma_kappa(gamma, kappa)
    sigma2 = k * k * bath_temperature / (2.0 * translational_energy)
    g1, g2 = round_trip_times(g)
    tau = np.abs(np.asarray(tau, dtype=float))
    total = -g1 * g2 / 24.0
    for gi in (g1, g2):
        phase = np.mod(tau, gi)  # tau - Gamma_i * sum_n theta(tau - n Gamma_i)
        total = total + (phase - 0.5 * gi) ** 2 / (2.0 * gi)
    return sigma2 * total


def equilibrium_translational_energy(modes: int, reduced_mass: float = 0.5, approach_speed: float = 1.0) -> float:
    """Mean translational energy at equipartition, Eq. 8.

    ``<E_tr> = mu V^2 / (2 (2 N + 1))``: the initial energy ``mu V^2 / 2``
    shared equally among the relative motion and the ``2 N`` oscillators.

    Parameters
    ----------
    modes : int
        Modes per rod ``N`` (>= 1).
    reduced_mass : float
        ``mu`` (mass); ``1/2`` in the units of ``two_rods``.
    approach_speed : float
        Initial approach speed ``V`` (velocity); 1 in those units.

    Returns
    -------
    float
        Energy (units of ``mu V^2`` when ``mu = V = 1``).
    """
    n = _require_modes(modes)
    mu = require_positive("reduced_mass", reduced_mass)
    v = require_positive("approach_speed", approach_speed)
    return mu * v * v / (2.0 * (2 * n + 1))


def boltzmann_density(energy, mean_energy: float):
    """Eq. 9: ``p(E_tr) = exp(-E_tr / <E_tr>) / <E_tr>``."""
    energy = np.asarray(energy, dtype=float)
    return np.where(energy >= 0, np.exp(-energy / mean_energy) / mean_energy, 0.0)


#: ``1 - Euler's gamma``: the mean of ``x ln x`` for an exponential variable of mean 1, where
#: the paper's 0.423 in Eq. 11 comes from.
ENTROPY_CONSTANT = 1.0 - 0.5772156649015329


def equilibrium_spectral_entropy(modes: int) -> float:
    """Mean normalised spectral entropy at equipartition, Eq. 11: ``0.423 / ln(2 N)``.

    ``0.423 = 1 - C_Euler`` is the large-``N`` value for modal energies that
    are independent and exponentially (Boltzmann) distributed.

    Parameters
    ----------
    modes : int
        Modes per rod ``N`` (>= 1).
    """
    n = _require_modes(modes)
    return 0.423 / math.log(2 * n)


def equilibrium_spectral_entropy_finite(modes: int) -> float:
    """Exact mean of ``eta`` for ``2 N`` independent exponential modal energies.

    Then ``w`` is uniform on the simplex and the mean of ``h`` is
    ``psi(2N + 1) - psi(2) = H_(2N) - 1`` (``psi`` the digamma function,
    ``H`` the harmonic number), so ``<eta> = 1 - (H_(2N) - 1) / ln(2N)
    = (1 - C_Euler - 1/(4N) + O(N^-2)) / ln(2N)``; Eq. 11 is its leading term.

    Parameters
    ----------
    modes : int
        Modes per rod ``N`` (>= 1).
    """
    from scipy.special import digamma

    n = _require_modes(modes)
    return 1.0 - float(digamma(2 * n + 1) - digamma(2)) / math.log(2 * n)


def _require_modes(modes) -> int:
    return require_integer("modes", modes, 1)
