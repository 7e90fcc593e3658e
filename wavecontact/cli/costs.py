"""What a command's run will cost, estimated from its options before any work, and refused above the bounds.

Every study command states its total work in the units of
:mod:`wavecontact.limits` (elementary updates, a few ns each) and the memory
it holds, and refuses (:func:`wavecontact.limits.check_study_cost`) above
``--max-work`` (default :data:`wavecontact.limits.DEFAULT_MAX_WORK`) or half
the available memory, saying which option makes the run smaller.

The work of one solve is the solver's own estimate
(:meth:`~wavecontact.solvers.base.SolverBase.total_cost`) where it gives one (FE
and modal solvers).  Where none exists, the bounds below are stated from
counts measured on this package (the commands that measured them are named):

* :func:`ring_steps`: the modal ring integrator takes at most
  ``N (RING_STEPS_PER_MODE + RING_SOFT_STEPS_PER_MODE / kappa)`` steps per
  collision (``tests/test_cli_costs.py`` checks it), each touching the ``2 N`` modes;
* :data:`THERMAL_SAMPLE_UPDATES_PER_MODE`, :data:`HARD_CORE_SAMPLE_UPDATES`,
  :data:`COVARIANCE_REALISATION_UPDATES`: the delay solver's thermal samples
  and Fig. 4's realisations, as updates of 4 ns (their CPU time on a 2-core
  machine: 1.1 ms per finite-kappa sample at nu_max = 250, 3.9 ms at 1000;
  4.7 ms per hard-core sample; 7 ms per Fig. 4 realisation: ``ensemble`` of 32-64 samples
  timed with ``time.process_time``).
"""

from __future__ import annotations

import math

from ..limits import (  # noqa: F401 - the ring bound lives with the limits (run_ring checks it too)
    DEFAULT_MAX_WORK,
    RING_SOFT_STEPS_PER_MODE,
    RING_STEPS_PER_MODE,
    Cost,
    Limits,
    check_study_cost,
    ring_cost,
    ring_steps,
)

__all__ = [
    "COVARIANCE_REALISATION_UPDATES",
    "HARD_CORE_SAMPLE_UPDATES",
    "RING_STEPS_PER_MODE",
    "THERMAL_SAMPLE_UPDATES_PER_MODE",
    "add_work_option",
    "check_run",
    "compare_cost",
    "covariance_cost",
    "methods_cost",
    "ring_cost",
    "ring_steps",
    "thermal_samples_cost",
]

#: Updates (4 ns) of one finite-kappa thermal delay sample, per bath mode nu_max.
THERMAL_SAMPLE_UPDATES_PER_MODE = 1500
#: Updates (4 ns) of one hard-core thermal sample (the stochastic hard-core mode of the delay solver).
HARD_CORE_SAMPLE_UPDATES = 2e6
#: Updates (4 ns) of one realisation of Fig. 4's noise covariance, plus per bath mode.
COVARIANCE_REALISATION_UPDATES, COVARIANCE_UPDATES_PER_MODE = 1.5e6, 2e3
#: Bytes kept per thermal sample (restitution, two gains, error estimate, seed bookkeeping).
SAMPLE_BYTES = 64


def add_work_option(parser) -> None:
    """``--max-work``: the bound on the estimated work of the whole run."""
    from .common import positive_float

    parser.add_argument("--max-work", type=positive_float, metavar="UPDATES",
                        help=f"refuse before starting a run estimated to take more updates (a few ns each) "
                             f"(default: {DEFAULT_MAX_WORK:.0e}, tens of minutes)")


def check_run(args, what: str, cost: Cost, advice: str) -> None:
    """Refuse the run (LimitError) if ``cost`` exceeds ``--max-work`` or half the available memory."""
    check_study_cost(what, cost, Limits(max_work=getattr(args, "max_work", None)), advice)


def methods_cost(gamma: float, kappa: float, methods, repeats: int = 1) -> Cost:
    """Solves of one collision by ``methods`` (pairs ``(solver, options)``), ``repeats`` times each."""
    from ..scene import two_rods
    from ..solvers import get_solver

    scene = two_rods(gamma, kappa)
    work, memory, unknown = 0.0, 0.0, 0
    for solver, options in methods:
        engine = get_solver(solver)
        cost = engine.total_cost(scene, engine.options(dict(options)), True)
        if cost is None:
            unknown += 1
            continue
        work += cost.work
        memory = max(memory, cost.memory)
    detail = f"{repeats} x the solvers' own estimates" if repeats != 1 else "the solvers' own estimates"
    if unknown:
        detail += f"; {unknown} delay solves not counted"
    return Cost(steps=0.0, work=work * repeats, memory=memory, detail=detail)


def compare_cost(gamma: float, kappa: float, repeats: int) -> Cost:
    """Every method of :func:`~wavecontact.studies.compare.default_methods`, ``repeats`` times each."""
    from ..studies.compare import default_methods

    return methods_cost(gamma, kappa, [(m.solver, m.options) for m in default_methods(kappa)], repeats)


def thermal_samples_cost(samples: int, kappa: float, bath_modes: int, solver: str = "delay",
                         gamma: float = 0.6, options: dict | None = None) -> Cost:
    """``samples`` thermal collisions at ``(gamma, kappa)`` with ``bath_modes`` modes per rod."""
    from ..solvers import get_solver
    from ..solvers.base import HARD_CORE_THERMAL, THERMAL_BATCH

    samples = int(samples)
    engine = get_solver(solver)
    if engine.offers(HARD_CORE_THERMAL if math.isinf(kappa) else THERMAL_BATCH):  # the batched samplers
        each = HARD_CORE_SAMPLE_UPDATES if math.isinf(kappa) else THERMAL_SAMPLE_UPDATES_PER_MODE * bath_modes
        detail = f"{samples} samples x {each:.2g} updates each"
    else:
        from ..scene import two_rods

        cost = engine.total_cost(two_rods(gamma, kappa), engine.options(dict(options or {})), True)
        each = (0.0 if cost is None else cost.work) + THERMAL_SAMPLE_UPDATES_PER_MODE * bath_modes
        detail = f"{samples} samples x {each:.2g} updates each ({solver} solver's estimate and the bath)"
    return Cost(steps=0.0, work=samples * each, memory=samples * float(SAMPLE_BYTES), detail=detail)


def covariance_cost(realisations: int, bath_modes: int) -> Cost:
    """Fig. 4: ``realisations`` draws of the noise, each tabulated and correlated."""
    each = COVARIANCE_REALISATION_UPDATES + COVARIANCE_UPDATES_PER_MODE * bath_modes
    return Cost(steps=0.0, work=realisations * each, memory=realisations * 241 * 8.0,
                detail=f"{realisations} realisations x {each:.2g} updates each")
