"""Solver ``delay``: the delay-differential equation for the relative velocity.

Integrating the rod modes out of the Hamiltonian leaves one scalar equation
for the scaled velocity increase ``W(tau)`` (Eq. 16), exact for infinitely
many modes.  It holds for two rods on a line with exponential contact, and in
its hard-core limit (Eq. 26); rods of different materials and sections only
change the round trips and give each rod's echoes the weight ``2 Z_s / Z_i``
(:mod:`wavecontact.delay.parameters`).  See :mod:`wavecontact.delay.kernels`
for the method and ``docs/theory.md``.

Results are in the scene's units (for :func:`wavecontact.two_rods` scenes those
are the paper's dimensionless ones): time ``t = tau mu / Z_s`` from the start
at the gap ``a0 / alpha``, relative velocity ``v2 - v1``, contact force.

Options
-------
rtol : float
    Target accuracy of epsilon (absolute), in [1e-14, 1e-2]; default 1e-11.
initial_gap : float or None
    Scaled initial gap ``a0 = alpha R0``; ``None`` (default) chooses
    ``40 + max|Q|`` so that the start is out of range of the force.
end_time : float or None
    Integrate at least until this dimensionless time; ``None`` lets the
    solver stop by itself once ``W`` has settled.
noise : FourierNoise or None
    Initial vibrations of the rods as the noise ``Q(tau)`` (Eq. 17), frequencies
    in units of ``Z_s / mu`` (``c / l`` for one material); ``None`` is a cold bath.
max_steps : int
    Safety limit on accepted steps.
"""

from __future__ import annotations

import math

import numpy as np

from ..contact import Exponential, Hard
from ..delay import kernels
from ..delay.hardcore import contact_intervals, hard_core_history
from ..delay.noise import COLD, FourierNoise
from ..delay.parameters import DelayParameters, delay_parameters, echoes_from_ratios
from ..errors import InvalidParameterError, SolverFailure, UnsupportedSceneError
from ..result import CollisionResult
from ..scene import Scene, two_rod_parameters

NAME = "delay"
OPTIONS = {"rtol": 1e-11, "initial_gap": None, "end_time": None, "noise": None, "max_steps": 2_000_000}
ORDER = 6  # Gauss-Kronrod (3, 7) on the smooth remainder, quintic Hermite history

GAP_MARGIN = 40.0  # exp(-40) ~ 4e-18: the force at the start is below round-off
# Soft contacts last many round trips; there W is smooth on the scale of a round trip, and the
# copies older than DIRECT_COPIES round trips are summed through running comb sums (one
# interpolation per rod instead of one per copy).  Sharp features (kappa >> 1) keep every copy.
COMB_BELOW_KAPPA = 2.0
DIRECT_COPIES = 1

_STATUS = {
    kernels.STATUS_MAX_STEPS: "the step limit (max_steps) was reached; raise max_steps or rtol",
    kernels.STATUS_NONFINITE: "a non-finite value appeared",
    kernels.STATUS_STEP_UNDERFLOW: "the step size underflowed; raise rtol",
    kernels.STATUS_TIME_LIMIT: "W did not settle before the time limit (is kappa extremely small?)",
}


def _check_scene(scene: Scene) -> DelayParameters:
    params = delay_parameters(scene)  # refuses rings, other rod counts and receding rods
    if not isinstance(scene.contact, (Exponential, Hard)):
        raise UnsupportedSceneError(
            f"the delay solver supports exponential and hard contact, not {scene.contact.name!r}; "
            "use solver='fem' (or 'modal') for penalty contact"
        )
    if not scene.is_cold:
        raise UnsupportedSceneError(
            "the delay solver takes initial vibrations only as a modal sum, the noise Q(tau): pass "
            "noise=FourierNoise(...) on a cold scene, or use solver='fem' or 'modal' for initial fields"
        )
    return params


def _check_options(rtol, initial_gap, end_time, noise, max_steps):
    try:
        rtol = float(rtol)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"rtol must be a number in [1e-14, 1e-2], got {rtol!r}") from None
    if not (1e-14 <= rtol <= 1e-2):
        raise InvalidParameterError(f"rtol must lie in [1e-14, 1e-2], got {rtol!r}")
    if initial_gap is not None:
        initial_gap = float(initial_gap)
        if not math.isfinite(initial_gap) or initial_gap < 0:
            raise InvalidParameterError(f"initial_gap (alpha R0) must be finite and >= 0, got {initial_gap!r}")
    if end_time is not None:
        end_time = float(end_time)
        if not math.isfinite(end_time) or end_time < 0:
            raise InvalidParameterError(f"end_time must be finite and >= 0, got {end_time!r}")
    if noise is None:
        noise = COLD
    if not isinstance(noise, FourierNoise):
        raise InvalidParameterError("noise must be a wavecontact.delay.noise.FourierNoise or None")
    if int(max_steps) != max_steps or max_steps < 10:
        raise InvalidParameterError(f"max_steps must be an integer >= 10, got {max_steps!r}")
    return rtol, initial_gap, end_time, noise, int(max_steps)


def solve_delay_equation(gamma, kappa, *, rtol=1e-11, initial_gap=None, end_time=None, noise=None, max_steps=2_000_000,
                         impedance_ratio=1.0):
    """Integrate the delay equation for transit-time ratio ``gamma`` and softness ``kappa``.

    ``gamma = T_1 / T_2`` is the ratio of the round-trip times ``2 l_i / c_i``
    (``l_1 / l_2`` for one material, Eq. 16) and ``impedance_ratio = Z_2 / Z_1``
    (1: one material); see :mod:`wavecontact.delay.parameters`.

    Returns ``(t, W, W', error_estimate, work, a0)`` with ``W`` on the adaptive
    grid ``t`` (dimensionless time, ``tau = 0`` at the start, scaled gap ``a0``).
    """
    rtol, a0, end_time, noise, max_steps = _check_options(rtol, initial_gap, end_time, noise, max_steps)
    if a0 is None:
        a0 = GAP_MARGIN + noise.amplitude_bound
    delays, weights = (np.array(x) for x in echoes_from_ratios(impedance_ratio, gamma))
    free_time = a0 / kappa
    settle = float(delays.sum())
    t_end_min = free_time if end_time is None else max(free_time, end_time)
    # the collision lasts about Gamma_1 for kappa >> 1 and ~ (|ln rtol| + a0) / (kappa gamma) when soft
    ratio = min(delays) / max(delays)
    t_limit = t_end_min + 50.0 * settle + 50.0 * (abs(math.log(rtol)) + a0) / (kappa * min(ratio, 0.5))
    t, w, d1, _d2, status, error, rejected, evaluations = kernels.integrate_delay_equation(
        float(kappa), float(a0), delays, weights, rtol, noise.freq, noise.cos_amp, noise.sin_amp,
        float(t_end_min), float(t_limit), settle, max_steps,
        kernels.KRONROD_NODES, kernels.KRONROD_WEIGHTS, kernels.GAUSS_WEIGHTS,
        DIRECT_COPIES if kappa <= COMB_BELOW_KAPPA else 0,
    )
    if status != kernels.STATUS_OK:
        raise SolverFailure(
            f"delay solver (gamma={gamma:g}, impedance_ratio={impedance_ratio:g}, kappa={kappa:g}): {_STATUS[status]}"
        )
    work = {"steps": int(t.size - 1), "rejected_steps": int(rejected), "evaluations": int(evaluations)}
    return t, w, d1, float(error), work, a0


def _contact_window(time, force, fraction=0.01):
    """First and last time the force exceeds ``fraction`` of its peak."""
    above = np.flatnonzero(force > fraction * force.max())
    if above.size == 0:
        return None, None
    return float(time[above[0]]), float(time[above[-1]] - time[above[0]])


def _paper_numbers(scene: Scene):
    """``(gamma, kappa)`` of the paper for rods of one material, else ``(None, None)``."""
    try:
        params = two_rod_parameters(scene)
    except InvalidParameterError:
        return None, None
    return params.gamma, params.kappa


def solve(scene: Scene, *, rtol, initial_gap, end_time, noise, max_steps) -> CollisionResult:
    """One collision of a two-rod scene by the delay equation (see module docstring)."""
    params = _check_scene(scene)
    kappa = params.kappa
    if isinstance(scene.contact, Hard) or math.isinf(kappa):
        if noise is not None:
            raise UnsupportedSceneError("the hard-core delay solver handles a cold bath only (noise=None)")
        return _solve_hard(scene, params)
    if scene.gaps is not None and initial_gap is None:
        # a user-placed start: alpha * gap, shifted by ln(B alpha^2 mu / Z_s^2) for B != Z_s^2 / (mu alpha^2)
        alpha = scene.contact.alpha
        initial_gap = alpha * scene.gaps[0] - math.log(
            scene.contact.strength * alpha**2 * params.reduced_mass / params.series_impedance**2
        )
    t, w, d1, error, work, a0 = solve_delay_equation(
        params.time_ratio, kappa, rtol=rtol, initial_gap=initial_gap, end_time=end_time, noise=noise,
        max_steps=max_steps, impedance_ratio=params.impedance_ratio,
    )
    restitution = w[-1] / kappa - 1.0
    force = d1 / kappa  # mu dv_rel/dt = Z_s V W' / kappa
    start, duration = _contact_window(t, force)
    gamma, paper_kappa = _paper_numbers(scene)
    unit = params.time_unit
    return CollisionResult(
        restitution=float(restitution),
        solver=NAME,
        wall_time_s=0.0,
        time=t * unit,
        relative_velocity=params.approach_speed * (w / kappa - 1.0),
        gamma=gamma,
        kappa=paper_kappa,
        contact_force=params.force_unit * force,
        contact_start=None if start is None else start * unit,
        contact_duration=None if duration is None else duration * unit,
        error_estimate=error,
        work=work,
        extra={
            "initial_gap": a0,
            "free_flight_time": a0 / kappa * unit,
            "velocity_increase_slope": d1,
            "delay_parameters": params,
        },
    )


def _solve_hard(scene: Scene, params: DelayParameters) -> CollisionResult:
    delays, weights = params.round_trip_times, params.echo_weights
    knots_t, knots_w = hard_core_history(delays, weights)
    restitution = float(knots_w[-1] - 1.0)
    contacts = contact_intervals(knots_t, knots_w, delays, weights)
    slopes = np.diff(knots_w) / np.diff(knots_t)
    start = contacts[0][0]
    duration = contacts[-1][1] - start
    # show the flat parts before and after the contact as well
    knots_t = np.concatenate([[knots_t[0] - 1.0], knots_t, [knots_t[-1] + sum(delays)]])
    knots_w = np.concatenate([[0.0], knots_w, [knots_w[-1]]])
    force = np.concatenate([[0.0], slopes, [0.0, 0.0]])  # constant on [knot_j, knot_j+1), units Z_s V
    unit = params.time_unit
    gamma, _kappa = _paper_numbers(scene)
    return CollisionResult(
        restitution=restitution,
        solver=NAME,
        wall_time_s=0.0,
        time=knots_t * unit,
        relative_velocity=params.approach_speed * (knots_w - 1.0),
        gamma=gamma,
        kappa=math.inf,
        contact_force=params.force_unit * force,
        contact_start=start * unit,
        contact_duration=duration * unit,
        error_estimate=1e-14,
        work={"steps": int(knots_t.size)},
        extra={
            "hard_core": True,
            "contacts": [(a * unit, b * unit) for a, b in contacts],
            "delay_parameters": params,
        },
    )
