"""Solver ``delay``: the delay-differential equation for the relative velocity.

Integrating the rod modes out of the Hamiltonian leaves one scalar equation
for the scaled velocity increase ``W(tau)`` (Eq. 16), exact for infinitely
many modes.  It holds for two rods of one material and section on a line
with exponential contact, and in its hard-core limit (Eq. 26).  See
:mod:`wavecontact.delay.kernels` for the method and ``docs/theory.md``.

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
    Initial vibrations of the rods as the noise ``Q(tau)`` (Eq. 17); ``None``
    is a cold bath.  A scene with ``vibrations`` (a thermal-bath realisation,
    :mod:`wavecontact.bath`) brings its own noise instead.
noise_resolution : int
    Table nodes per period of the fastest bath mode for the noise of a scene
    with vibrations (cubic Hermite between nodes), in [4, 1024]; default 32.
hard_core_resolution : int
    Grid points per period of the fastest bath mode of the short rod in the
    stochastic hard-core mode (kappa = inf with vibrations), in [2, 4096];
    default 8.  The result comes from a grid twice as fine; its error estimate
    is the larger change from the grids at resolution/2 and resolution.
energy_split : bool
    Also compute each rod's vibrational energy gain (``extra['vibration_energy_gain']``); default True.
max_steps : int
    Safety limit on accepted steps.
"""

from __future__ import annotations

import math

import numpy as np

from ..bath.noise import NoiseTables
from ..bath.scene import scene_noise
from ..contact import Exponential, Hard
from ..delay import kernels
from ..delay.energy_split import NODES, WEIGHTS, vibration_energy_gain
from ..delay.hardcore import hard_core_history
from ..delay.noise import COLD, FourierNoise
from ..delay.stochastic_hardcore import hard_core_noise
from ..errors import InvalidParameterError, SolverFailure, UnsupportedSceneError
from ..result import CollisionResult
from ..scene import Scene, two_rod_parameters

NAME = "delay"
OPTIONS = {"rtol": 1e-11, "initial_gap": None, "end_time": None, "noise": None, "max_steps": 2_000_000,
           "noise_resolution": 32, "hard_core_resolution": 8, "energy_split": True}
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
    if not scene.is_cold and scene.vibrations is None:
        raise UnsupportedSceneError(
            "initial fields enter the delay equation as the noise Q(tau): pass noise=FourierNoise(...)"
        )
    params = two_rod_parameters(scene)
    if params.approach_speed <= 0.0:
        raise InvalidParameterError("the rods must approach each other (v1 > v2) for a collision")
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
                         tables=None):
    """Integrate Eq. 16 for length ratio ``gamma`` and softness ``kappa``.

    ``tables`` (:class:`wavecontact.bath.noise.NoiseTables`) adds tabulated
    noise to ``noise``.  Returns ``(t, W, W', error_estimate, work, a0)`` with
    ``W`` on the adaptive grid ``t`` (dimensionless time, ``tau = 0`` at the
    start, scaled gap ``a0``).
    """
    t, w, d1, _d2, error, work, a0 = _integrate(gamma, kappa, rtol, initial_gap, end_time, noise, max_steps, tables)
    return t, w, d1, error, work, a0


def _integrate(gamma, kappa, rtol, initial_gap, end_time, noise, max_steps, tables):
    rtol, a0, end_time, noise, max_steps = _check_options(rtol, initial_gap, end_time, noise, max_steps)
    tables = NoiseTables.empty() if tables is None else tables
    if a0 is None:
        a0 = GAP_MARGIN + noise.amplitude_bound
    delays = np.array([1.0 + gamma, 1.0 + 1.0 / gamma])
    free_time = a0 / kappa
    settle = float(delays.sum())
    t_end_min = free_time if end_time is None else max(free_time, end_time)
    # the collision lasts about Gamma_1 for kappa >> 1 and ~ (|ln rtol| + a0) / (kappa gamma) when soft
    t_limit = t_end_min + 50.0 * settle + 50.0 * (abs(math.log(rtol)) + a0) / (kappa * min(gamma, 0.5))
    t, w, d1, d2, status, error, rejected, evaluations = kernels.integrate_delay_equation(
        float(kappa), float(a0), delays, rtol, noise.freq, noise.cos_amp, noise.sin_amp,
        tables.periods, tables.values, tables.slopes, float(tables.slope_bound), float(tables.step_limit),
        float(t_end_min), float(t_limit), settle, max_steps,
        kernels.KRONROD_NODES, kernels.KRONROD_WEIGHTS, kernels.GAUSS_WEIGHTS,
        DIRECT_COPIES if kappa <= COMB_BELOW_KAPPA else 0,
    )
    if status != kernels.STATUS_OK:
        raise SolverFailure(f"delay solver (gamma={gamma:g}, kappa={kappa:g}): {_STATUS[status]}")
    work = {"steps": int(t.size - 1), "rejected_steps": int(rejected), "evaluations": int(evaluations)}
    return t, w, d1, d2, float(error), work, a0


def _contact_window(time, force, fraction=0.01):
    """First and last time the force exceeds ``fraction`` of its peak."""
    above = np.flatnonzero(force > fraction * force.max())
    if above.size == 0:
        return None, None
    return float(time[above[0]]), float(time[above[-1]] - time[above[0]])


def _check_resolution(name, value, low, high):
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not low <= value <= high:
        raise InvalidParameterError(f"{name} must be an integer in [{low}, {high}], got {value!r}")
    return int(value)


def solve(scene: Scene, *, rtol, initial_gap, end_time, noise, max_steps, noise_resolution=32,
          hard_core_resolution=8, energy_split=True) -> CollisionResult:
    """One collision of a two-rod scene by the delay equation (see module docstring)."""
    params = _check_scene(scene)
    noise_resolution = _check_resolution("noise_resolution", noise_resolution, 4, 1024)
    hard_core_resolution = _check_resolution("hard_core_resolution", hard_core_resolution, 2, 4096)
    gamma, kappa = params.gamma, params.kappa
    vibrations = scene.vibrations
    if vibrations is not None and noise is not None:
        raise InvalidParameterError("a scene with vibrations brings its own noise: leave the option noise=None")
    if isinstance(scene.contact, Hard) or math.isinf(kappa):
        if noise is not None:
            raise UnsupportedSceneError("the hard-core delay solver takes thermal vibrations on the scene, not noise=")
        if vibrations is not None:
            return _solve_hard_stochastic(scene, gamma, hard_core_resolution)
        return _solve_hard(gamma)
    if scene.gaps is not None and initial_gap is None:
        # a user-placed start: alpha * gap, shifted by ln(B alpha^2 / mu) for B != mu / alpha^2
        alpha = scene.contact.alpha
        reduced_mass = scene.rods[0].mass * scene.rods[1].mass / scene.total_mass
        initial_gap = alpha * scene.gaps[0] - math.log(
            scene.contact.strength * alpha**2 * params.effective_length**2 / (reduced_mass * params.wave_speed**2)
        )
    tables = None
    if vibrations is not None:
        if initial_gap is None:
            raise UnsupportedSceneError("a scene with vibrations needs its start gap (two_rods(..., vibrations=) sets it)")
        tables = scene_noise(scene, kappa, float(initial_gap), noise_resolution)
    t, w, d1, d2, error, work, a0 = _integrate(gamma, kappa, rtol, initial_gap, end_time, noise, max_steps, tables)
    restitution = w[-1] / kappa - 1.0
    force = 0.5 * d1 / kappa  # mu dv_rel/dt = W' / (2 kappa) in units of Z V = rho c A V
    start, duration = _contact_window(t, force)
    extra = {"initial_gap": a0, "free_flight_time": a0 / kappa, "velocity_increase_slope": d1}
    if energy_split and noise is None:
        tab = tables if tables is not None else NoiseTables.empty()
        gain = vibration_energy_gain(float(kappa), t, w, d1, d2, np.array([1.0 + gamma, 1.0 + 1.0 / gamma]),
                                     tab.periods, tab.values, tab.slopes, NODES, WEIGHTS, 2)
        extra["vibration_energy_gain"] = gain
    if vibrations is not None:
        extra["vibration_energy_before"] = vibrations.vibration_energy()
        extra["bath_modes"] = vibrations.modes
    return CollisionResult(
        restitution=float(restitution),
        solver=NAME,
        wall_time_s=0.0,
        time=t,
        relative_velocity=w / kappa - 1.0,
        gamma=gamma,
        kappa=kappa,
        contact_force=force,
        contact_start=start,
        contact_duration=duration,
        error_estimate=error,
        work=work,
        extra=extra,
    )


def _solve_hard_stochastic(scene, gamma, resolution):
    """The hard-core limit with the scene's vibrations (max-plus recursion on a grid)."""
    vibrations = scene.vibrations
    tau_free = float(scene.gaps[0])  # V = 1, l = 1: the gap is the free-flight time
    # the answer comes from the grid at 2 x resolution; the grid converges at first order but
    # unevenly (f often peaks at a kink of the memory terms, between nodes), so the error is
    # estimated by the larger change over the two coarser grids
    coarser = [hard_core_noise(gamma, vibrations, tau_free, r)[1][-1] for r in (max(resolution // 2, 1), resolution)]
    t, w = hard_core_noise(gamma, vibrations, tau_free, 2 * resolution)
    restitution = float(w[-1] - 1.0)
    slopes = np.diff(w) / np.diff(t)
    force = np.concatenate([0.5 * slopes, [0.0]])
    start, duration = _contact_window(t, force)
    extra = {"hard_core": True, "free_flight_time": tau_free, "bath_modes": vibrations.modes,
             "vibration_energy_before": vibrations.vibration_energy(), "grid_step": float(t[1] - t[0])}
    # the per-rod split needs W' times the noise's slope, which a grid of max-plus values
    # resolves too slowly (errors ~1e-2 of E_tr at 1e3 points per Gamma_1): only the total
    # (1 - epsilon^2) / 4 is given here; use a finite kappa for the split
    return CollisionResult(
        restitution=restitution,
        solver=NAME,
        wall_time_s=0.0,
        time=t,
        relative_velocity=w - 1.0,
        gamma=gamma,
        kappa=math.inf,
        contact_force=force,
        contact_start=start,
        contact_duration=duration,
        error_estimate=max(abs(float(coarser[1] - w[-1])), abs(float(coarser[0] - coarser[1]))),
        work={"steps": int(t.size)},
        extra=extra,
    )


def _solve_hard(gamma: float) -> CollisionResult:
    delays = (1.0 + gamma, 1.0 + 1.0 / gamma)
    knots_t, knots_w = hard_core_history(delays)
    restitution = float(knots_w[-1] - 1.0)
    slopes = np.diff(knots_w) / np.diff(knots_t)
    rising = np.flatnonzero(slopes > 0.5)
    start = float(knots_t[rising[0]])
    duration = float(knots_t[rising[-1] + 1] - start)
    # show the flat parts before and after the contact as well
    knots_t = np.concatenate([[knots_t[0] - 1.0], knots_t, [knots_t[-1] + sum(delays)]])
    knots_w = np.concatenate([[0.0], knots_w, [knots_w[-1]]])
    force = np.concatenate([[0.0], 0.5 * slopes, [0.0, 0.0]])  # constant on [knot_j, knot_j+1)
    return CollisionResult(
        restitution=restitution,
        solver=NAME,
        wall_time_s=0.0,
        time=knots_t,
        relative_velocity=knots_w - 1.0,
        gamma=gamma,
        kappa=math.inf,
        contact_force=force,
        contact_start=start,
        contact_duration=duration,
        error_estimate=1e-14,
        work={"steps": int(knots_t.size)},
        extra={"hard_core": True},
    )
