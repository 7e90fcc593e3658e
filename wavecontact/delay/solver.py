"""Solver ``delay``: the delay-differential equation for the relative velocity.

Integrating the rod modes out of the Hamiltonian leaves one scalar equation
for the scaled velocity increase ``W(tau)`` (Eq. 16), exact for infinitely
many modes.  It holds for two rods of one material and section on a line
with exponential contact, and in its hard-core limit (Eq. 26).  See
:mod:`wavecontact.delay.kernels` for the method and ``docs/theory.md``.

Its options are :class:`DelayOptions`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..contact import Exponential, Hard
from ..errors import InvalidParameterError, LimitError, SolverFailure, UnsupportedSceneError
from ..limits import Cost
from ..result import Outcome
from ..scene import Scene, two_rod_parameters
from ..solvers.base import SolverBase, SolverOptions, option
from . import kernels
from .hardcore import hard_core_history
from .noise import COLD, FourierNoise

__all__ = ["ORDER", "SOLVER", "DelayOptions", "DelaySolver", "solve_delay_equation"]

ORDER = 6  # Gauss-Kronrod (3, 7) on the smooth remainder, quintic Hermite history

GAP_MARGIN = 40.0  # exp(-40) ~ 4e-18: the force at the start is below round-off
# Soft contacts last many round trips; there W is smooth on the scale of a round trip, and the
# copies older than DIRECT_COPIES round trips are summed through running comb sums (one
# interpolation per rod instead of one per copy).  Sharp features (kappa >> 1) keep every copy.
COMB_BELOW_KAPPA = 2.0
DIRECT_COPIES = 1
# Below this gamma (finite kappa) the solve is refused: W must be followed until the long rod's
# echo is back (Gamma_2 = 1 + 1/gamma) in steps shorter than Gamma_1, each summing about
# Gamma_2 / Gamma_1 delayed copies, so the cost grows like 1/gamma^2 (gamma = 1e-3: 100x gamma = 0.1)
GAMMA_MIN = 1e-2

_OUTCOMES = {
    kernels.STATUS_MAX_STEPS: (Outcome.STEP_LIMIT, "raise max_steps or rtol"),
    kernels.STATUS_NONFINITE: (Outcome.NON_FINITE, "report this scene: the equation's state left the floats"),
    kernels.STATUS_STEP_UNDERFLOW: (Outcome.STEP_UNDERFLOW, "raise rtol"),
    kernels.STATUS_TIME_LIMIT: (Outcome.TIME_LIMIT, "W did not settle (is kappa extremely small?)"),
}


def _noise(value):
    if not isinstance(value, FourierNoise):
        raise InvalidParameterError("delay option noise must be a wavecontact.delay.noise.FourierNoise or None")
    return value


@dataclass(frozen=True)
class DelayOptions(SolverOptions):
    """Options of the delay solver (every time in ``l / c``, the paper's tau)."""

    solver_name = "delay"
    rtol: float = option(1e-11, "target accuracy of epsilon (absolute)", low=1e-14, high=1e-2)
    initial_gap: float | None = option(
        None, "scaled initial gap alpha R0; None: 40 + max|Q| (out of range of the force)",
        low=0.0, allow_none=True)
    end_time: float | None = option(
        None, "integrate at least until this time tau; None: stop once W has settled", low=0.0, allow_none=True)
    noise: FourierNoise | None = option(
        None, "initial vibrations as the noise Q(tau) (Eq. 17); None: a cold bath",
        kind="object", allow_none=True, check=_noise)
    max_steps: int = option(2_000_000, "safety limit on accepted steps", kind="int", low=10, high=10**9)


def _check_scene(scene: Scene):
    if scene.is_ring or len(scene.rods) != 2:
        raise UnsupportedSceneError("the delay solver models two rods on a line; use solver='modal' or 'fem'")
    if not scene.rods[0].same_material(scene.rods[1]):
        raise UnsupportedSceneError(
            "the delay equation needs rods of one material and section; use solver='fem' for unequal impedances"
        )
    if not isinstance(scene.contact, (Exponential, Hard)):
        raise UnsupportedSceneError(
            f"the delay solver supports exponential and hard contact, not {scene.contact.name!r}; "
            "use solver='fem' for penalty contact"
        )
    if not scene.is_cold:
        raise UnsupportedSceneError(
            "initial fields enter the delay equation as the noise Q(tau): pass noise=FourierNoise(...)"
        )
    params = two_rod_parameters(scene)
    if params.approach_speed <= 0.0:
        raise InvalidParameterError("the rods must approach each other (v1 > v2) for a collision")
    return params




def solve_delay_equation(gamma, kappa, *, rtol=1e-11, initial_gap=None, end_time=None, noise=None, max_steps=2_000_000):
    """Integrate Eq. 16 for length ratio ``gamma`` and softness ``kappa``.

    Returns ``(t, W, W', error_estimate, work)`` with ``W`` on the adaptive
    grid ``t`` (dimensionless time, ``tau = 0`` at the start, scaled gap ``a0``).
    """
    options = DelayOptions(rtol=rtol, initial_gap=initial_gap, end_time=end_time, noise=noise, max_steps=max_steps)
    rtol, a0, end_time, max_steps = options.rtol, options.initial_gap, options.end_time, options.max_steps
    noise = COLD if options.noise is None else options.noise
    if a0 is None:
        a0 = GAP_MARGIN + noise.amplitude_bound
    delays = np.array([1.0 + gamma, 1.0 + 1.0 / gamma])
    free_time = a0 / kappa
    settle = float(delays.sum())
    t_end_min = free_time if end_time is None else max(free_time, end_time)
    # the collision lasts about Gamma_1 for kappa >> 1 and ~ (|ln rtol| + a0) / (kappa gamma) when soft
    t_limit = t_end_min + 50.0 * settle + 50.0 * (abs(math.log(rtol)) + a0) / (kappa * min(gamma, 0.5))
    t, w, d1, _d2, status, error, rejected, evaluations = kernels.integrate_delay_equation(
        float(kappa), float(a0), delays, rtol, noise.freq, noise.cos_amp, noise.sin_amp,
        float(t_end_min), float(t_limit), settle, max_steps,
        kernels.KRONROD_NODES, kernels.KRONROD_WEIGHTS, kernels.GAUSS_WEIGHTS,
        DIRECT_COPIES if kappa <= COMB_BELOW_KAPPA else 0,
    )
    if status != kernels.STATUS_OK:
        outcome, advice = _OUTCOMES[status]
        raise SolverFailure(f"delay solver (gamma={gamma:g}, kappa={kappa:g}): {outcome.message}; {advice}", outcome)
    work = {"steps": int(t.size - 1), "rejected_steps": int(rejected), "evaluations": int(evaluations)}
    return t, w, d1, float(error), work, a0




class DelaySolver(SolverBase):
    """The delay equation (Eq. 16) and its hard-core limit (Eq. 26): the reference solver."""

    name = "delay"
    Options = DelayOptions
    resolution = "rtol"
    refines = -1

    def expected_order(self, options) -> float:
        """1: the error is proportional to (and below) the tolerance ``rtol``."""
        return 1.0

    def estimate_cost(self, scene: Scene, options: DelayOptions) -> Cost | None:
        """Refuse, before any step, what the method of steps cannot do in bounded time:
        ``gamma < GAMMA_MIN`` at finite kappa, and an ``end_time`` beyond ``max_steps`` steps."""
        params = _check_scene(scene)
        if math.isinf(params.kappa) or isinstance(scene.contact, Hard):
            return None
        if params.gamma < GAMMA_MIN:
            raise LimitError(
                f"delay: gamma = {params.gamma:.3g} is below {GAMMA_MIN:g} at finite kappa: the equation must be "
                "followed until the long rod's echo returns (Gamma_2 = 1 + 1/gamma) in steps shorter than "
                "Gamma_1, each summing Gamma_2/Gamma_1 delayed copies, so its cost grows like 1/gamma^2; "
                "use solver='modal' or solver='fem' (or kappa=inf)")
        shortest_step = 0.95 * (1.0 + params.gamma)  # the method of steps' largest step
        if options.end_time is not None:
            steps = options.end_time / shortest_step
            if steps > options.max_steps:
                raise LimitError(
                    f"delay: end_time={options.end_time:g} needs at least {steps:.3g} steps (each at most "
                    f"0.95 Gamma_1 = {shortest_step:.3g}), more than max_steps={options.max_steps}; "
                    f"lower end_time or pass max_steps={math.ceil(steps * 1.1)}")
        return None

    def _collide(self, scene: Scene, options: DelayOptions) -> dict:
        params = _check_scene(scene)
        gamma, kappa = params.gamma, params.kappa
        if isinstance(scene.contact, Hard) or math.isinf(kappa):
            if options.noise is not None:
                raise UnsupportedSceneError("the hard-core delay solver handles a cold bath only (noise=None)")
            return _collide_hard(gamma)
        initial_gap = options.initial_gap
        if scene.gaps is not None and initial_gap is None:
            # a user-placed start: alpha * gap, shifted by ln(B alpha^2 / mu) for B != mu / alpha^2
            alpha = scene.contact.alpha
            reduced_mass = scene.rods[0].mass * scene.rods[1].mass / scene.total_mass
            initial_gap = alpha * scene.gaps[0] - math.log(
                scene.contact.strength * alpha**2 * params.effective_length**2
                / (reduced_mass * params.wave_speed**2)
            )
        t, w, d1, error, work, a0 = solve_delay_equation(
            gamma, kappa, rtol=options.rtol, initial_gap=initial_gap, end_time=options.end_time,
            noise=options.noise, max_steps=options.max_steps,
        )
        return {
            "restitution": w[-1] / kappa - 1.0,
            "time": t,
            "relative_velocity": w / kappa - 1.0,
            # mu dv_rel/dt = W' / (2 kappa) in units of Z V = rho c A V
            "contact_force": 0.5 * d1 / kappa,
            "error_estimate": error,
            "work": work,
            "extra": {"scaled_initial_gap": a0, "free_flight_time": a0 / kappa, "velocity_increase_slope": d1},
        }


def _collide_hard(gamma: float) -> dict:
    delays = (1.0 + gamma, 1.0 + 1.0 / gamma)
    knots_t, knots_w = hard_core_history(delays)
    restitution = float(knots_w[-1] - 1.0)
    slopes = np.diff(knots_w) / np.diff(knots_t)
    # show the flat parts before and after the contact as well
    knots_t = np.concatenate([[knots_t[0] - 1.0], knots_t, [knots_t[-1] + sum(delays)]])
    knots_w = np.concatenate([[0.0], knots_w, [knots_w[-1]]])
    # the force is constant between knots: force[i] is its value on (time[i-1], time[i]]
    force = np.concatenate([[0.0, 0.0], 0.5 * slopes, [0.0]])
    return {
        "restitution": restitution,
        "time": knots_t,
        "relative_velocity": knots_w - 1.0,
        "contact_force": force,
        "force_sampling": "interval",
        "error_estimate": 1e-14,
        "work": {"steps": int(knots_t.size)},
        "extra": {"hard_core": True},
    }


SOLVER = DelaySolver()
