"""The delay solver for contact laws acting on overlap only (penalty, Hertz, ...): one collision.

The equation and its integration are in :mod:`wavecontact.delay.law_kernels`;
this module chooses the step, runs it twice (step ``h`` and ``2 h``) for the
error estimate, and returns the solver's result fields.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import LimitError, SolverFailure, UnsupportedSceneError
from ..limits import Cost
from ..result import Outcome
from ..solvers.base import CollisionFields
from .law_kernels import STATUS_MAX_STEPS, STATUS_OK, integrate_overlap_delay

__all__ = ["ESTIMATE_SAFETY", "STEPS_PER_SCALE_MIN", "collide_overlap_law", "contact_time_scale", "overlap_cost"]

# steps per time scale of the contact at least (rtol^(-1/4) above this: RK4 away from the force's kinks)
STEPS_PER_SCALE_MIN = 16
# the run ends once the force has been zero for this many of the longer round trips
SETTLE_ROUND_TRIPS = 4.0
# the error estimate is this times the change from twice the step: the kinks of the force at touching and
# their echoes keep the convergence irregular (Hertz, K = 5 on the paper's rods: at rtol = 1e-8 the change
# is 7.0e-10, the error against rtol = 1e-14 1.33e-9)
ESTIMATE_SAFETY = 3.0


def _deepest_rigid_overlap(law, energy: float) -> float:
    """Overlap (length) at which the law's energy equals ``energy``: the rigid bodies' turning point."""
    hi = 1e-300
    while float(law.potential(-hi)) < energy:
        hi *= 2.0
        if hi > 1e300:
            raise UnsupportedSceneError(f"the {law.name} law never stores the collision's energy")
    lo = 0.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if float(law.potential(-mid)) >= energy:
            hi = mid
        else:
            lo = mid
    return hi


def contact_time_scale(law, params) -> tuple:
    """``(shortest, rigid)``: time scales of the contact in units of ``mu / Z_s`` (dimensionless).

    ``rigid`` is the rigid bodies' approach time ``delta_max / V`` (``delta_max``: the
    overlap that stores ``mu V^2 / 2``), ``shortest`` the smaller of it and the
    relaxation time ``Z_s / k`` of a compliant end at that overlap (``k = -dF/dr`` there).
    """
    speed, mu, z_s = params.approach_speed, params.reduced_mass, params.series_impedance
    deepest = _deepest_rigid_overlap(law, 0.5 * mu * speed * speed)
    length_unit = speed * mu / z_s
    relax = float(law.stiffness_at(-deepest)) * length_unit / (z_s * speed)  # d W' / d rho at the deepest overlap
    rigid = deepest / length_unit
    return min(rigid, 1.0 / relax), rigid


def _grid(law, params, rtol) -> tuple:
    """``(h, settle, shortest, span)``: step, settling time, contact time scale and the expected run length
    (three rigid approach times, two long round trips and the settling time), all in units of ``mu / Z_s``."""
    delays = params.round_trip_times
    shortest, rigid = contact_time_scale(law, params)
    per_scale = max(STEPS_PER_SCALE_MIN, math.ceil(rtol ** -0.25))
    h = min(0.5 * min(delays), shortest / per_scale)
    settle = SETTLE_ROUND_TRIPS * max(delays)
    return h, settle, shortest, 3.0 * rigid + 2.0 * max(delays) + settle


def overlap_cost(scene, params, options) -> Cost:
    """Steps, work (delayed values interpolated) and memory of :func:`collide_overlap_law`, before any step.

    Raises
    ------
    LimitError
        If the expected run needs more than ``max_steps`` steps.
    """
    h, _settle, _shortest, span = _grid(scene.contact, params, options.rtol)
    steps = span / h
    if steps > options.max_steps:
        raise LimitError(f"delay: {scene.contact.name} contact needs about {steps:.3g} steps of {h:.3g} (the "
                         f"contact's time scale over rtol^(-1/4)), more than max_steps={options.max_steps}; raise "
                         "rtol or max_steps, or use solver='fem' or 'modal'")
    echoes = 2.0 + sum(span / delay for delay in params.round_trip_times)  # delayed values per evaluation
    return Cost(steps=1.5 * steps, work=1.5 * steps * 4.0 * echoes, memory=2 * 8.0 * (options.max_steps + 1),
                detail=f"about {1.5 * steps:.3g} steps with up to {echoes:.3g} echoes each")


def collide_overlap_law(scene, params, options) -> CollisionFields:
    """One cold collision of ``scene`` (two rods, a law acting on overlap only), as ``_collide`` returns it.

    The step is ``min(Gamma_min / 2, T_c / N)`` with ``T_c`` the shorter of :func:`contact_time_scale` and
    ``N = max(STEPS_PER_SCALE_MIN, rtol^(-1/4))``; the result comes from that step and its error
    estimate is :data:`ESTIMATE_SAFETY` times the change from twice the step.
    """
    law = scene.contact
    if options.noise is not None or scene.vibrations is not None:
        raise UnsupportedSceneError(f"the delay solver takes {law.name} contact for cold rods only; "
                                    "use solver='fem' or 'modal' for vibrating rods")
    if options.end_time is not None:
        raise UnsupportedSceneError(f"end_time applies to exponential contact; {law.name} contact runs until "
                                    "the rods have separated")
    code, alpha, strength, stiffness = law.kernel_parameters()
    speed, mu, z_s = params.approach_speed, params.reduced_mass, params.series_impedance
    length_unit = speed * mu / z_s
    force_unit = z_s * speed
    delays = np.array(params.round_trip_times, dtype=float)
    weights = np.array(params.echo_weights, dtype=float)
    a0 = 0.0 if scene.gaps is None else float(scene.gaps[0]) / length_unit
    h, settle, scale, _span = _grid(law, params, options.rtol)
    runs = []
    for step in (2.0 * h, h):
        w, d, status = integrate_overlap_delay(code, alpha, strength, float(stiffness), length_unit, force_unit,
                                               a0, delays, weights, step, settle, int(options.max_steps))
        if status != STATUS_OK:
            advice = "raise max_steps or rtol" if status == STATUS_MAX_STEPS else "report this scene"
            outcome = Outcome.STEP_LIMIT if status == STATUS_MAX_STEPS else Outcome.NON_FINITE
            raise SolverFailure(f"delay solver ({law.name} contact): {outcome.message}; {advice}", outcome)
        runs.append((w, d, step))
    (w_coarse, _, _), (w, d, step) = runs
    tau = step * np.arange(w.size)
    unit = params.time_unit
    return CollisionFields(
        restitution=float(w[-1] - 1.0),
        time=tau * unit,
        relative_velocity=speed * (w - 1.0),
        contact_force=force_unit * d,
        error_estimate=ESTIMATE_SAFETY * abs(float(w[-1] - w_coarse[-1])),
        work={"steps": int(w.size + w_coarse.size - 2)},
        extra={"grid_step": float(step * unit), "contact_time_scale": float(scale * unit),
              "delay_parameters": {"round_trip_times": params.round_trip_times,
                                   "echo_weights": params.echo_weights}},
    )
