"""``solver="auto"``: the method and resolution predicted cheapest to meet a tolerance, then refined.

:func:`solve_auto` is what :func:`wavecontact.solve` runs when no solver is named:

1. **Choice.**  Every registered solver that takes the scene is a candidate at each resolution of
   its ladder; the cost model (:mod:`.cost_model`, data written by ``python
   benchmarks/cost_model.py``) predicts each candidate's error estimate and CPU time.  The
   cheapest candidate predicted to meet ``tolerance`` within the work and memory limits runs.
   Where every candidate predicted to meet it is over the limits, the call is refused before any
   work, with the cost it would need (:class:`~wavecontact.errors.LimitError`).
2. **Refinement.**  When the run's error estimate exceeds ``tolerance``, the resolution that should
   meet it is predicted from the order observed in the run's own Richardson levels (the
   solver's declared order where those do not show one), rounded up to a power-of-two multiple so
   that the earlier runs serve as the new run's coarser levels
   (:func:`~wavecontact.solvers.base.reusing_runs`), and checked against the limits before it runs.
   A solver that cannot refine (out of its range, no levels) hands over to the next candidate.
   Only when no refinement fits the limits is the call refused
   (:class:`~wavecontact.errors.AccuracyError`, with the estimate reached and the work needed).
3. **Honesty.**  ``result.diagnostics["auto"]`` says what was chosen and why, the predicted and the
   actual cost (CPU seconds, every attempt included), every attempt, and every miss of the model
   (an estimate above its prediction, a cost over twice its prediction) so that the benchmark can be
   re-calibrated.
"""

from __future__ import annotations

import dataclasses
import math
import time

from ..errors import AccuracyError, InvalidParameterError, LimitError, SolverFailure, UnsupportedSceneError
from ..limits import Limits, check_cost
from ..scene import Scene
from . import SOLVER_NAMES
from . import get_solver as _registry
from .base import _tolerance, reusing_runs
from .cost_model import Prediction, load_model, scene_class, scene_features

__all__ = ["DEFAULT_TOLERANCE", "MAX_ATTEMPTS", "choose", "run_cost", "solve_auto", "solve_refined"]

#: Tolerance on the restitution's error estimate when ``solve`` is given none (absolute).
DEFAULT_TOLERANCE = 1e-6
#: Runs (first choice and refinements, all solvers) before the call is refused.
MAX_ATTEMPTS = 5


_SOLVERS: dict = {}


def get_solver(name: str):
    """The registry's solver, remembered (a choice asks for it several times; a fast solve takes 60 us)."""
    solver = _SOLVERS.get(name)
    if solver is None:
        solver = _SOLVERS[name] = _registry(name)
    return solver


@dataclasses.dataclass
class Choice:
    """The ranked candidates for one scene and tolerance, and why the first one leads."""

    ranked: list
    reason: str
    scene_class: str
    usable: object = None
    refusal: str = ""  # the refusal a last bounded attempt precedes (its miss raises it)


def _rigid_mass_target(prediction: Prediction) -> Prediction:
    """A delay prediction on a line scene (a rigid mass on a rod) at most its ``rtol``: the delay equations double
    their steps per round trip until the estimate meets ``rtol`` (the fit, pulled up by the runs that stop at
    the finest grid, says more); where the grid's cap stops them first the run misses and is refined or handed
    over like any other."""
    if prediction.solver != "delay" or prediction.error <= prediction.resolution:
        return prediction
    return dataclasses.replace(prediction, error=prediction.resolution)


def _bounded_attempt(scene: Scene, others: list, usable):
    """The candidate of smallest predicted error among those whose work is bounded by the solver itself (no
    cost estimate: the delay equations of a rigid mass on a line), or None; two-rod scenes: None."""
    if not scene.is_line_scene:
        return None
    for prediction in others:
        if usable(prediction) and run_cost(get_solver(prediction.solver), scene, prediction.option) is None:
            return prediction
    return None


def _check_limits(solver, scene: Scene, resolution: dict, limits: Limits):
    """The solver's own cost estimate of a run with its error estimate, refused over ``limits``."""
    cost = run_cost(solver, scene, resolution)
    check_cost(solver.name, cost, limits)
    return cost


def run_cost(solver, scene: Scene, option: dict):
    """The estimated cost (:class:`~wavecontact.limits.Cost`, None: bounded) of one run of ``solver`` with
    ``option`` and its error estimate, as ``auto`` checks it against the limits."""
    options = solver.options(option)
    return _line_cost(solver, scene, options) if scene.is_line_scene else solver.total_cost(scene, options, True)


def _line_cost(solver, scene: Scene, options):
    """Cost of a line-scene run with its error estimate: the fem loop's (:func:`~wavecontact.fem.multibody.line_cost`)
    with the runs at ``elements // 2`` and ``// 4`` (work ~ elements^2: 1 + 1/4 + 1/16); the delay solver's rigid
    mass is bounded by its own step cap (None)."""
    if solver.name != "fem":
        return None
    from ..fem.multibody import line_cost
    from ..limits import Cost

    cost = line_cost(scene, options.as_dict())
    return Cost(steps=cost.steps, work=cost.work * (1.0 + 1.0 / 4.0 + 1.0 / 16.0), memory=cost.memory,
                detail=f"{cost.detail}; with the error estimate's runs at elements // 2 and // 4")


def _takes_line(solver, scene: Scene) -> bool:
    """Whether ``solver`` takes a line scene: fem every one, delay a rigid mass on one uniform rod."""
    if solver.name == "fem":
        return True
    if solver.name == "delay":
        from ..delay.rigid_mass import takes

        return takes(scene)
    return False


def _accepts(solver, scene: Scene) -> bool:
    """Whether ``solver`` takes ``scene`` (its cost estimate refuses what it cannot run)."""
    if scene.is_ring:
        return False
    if scene.is_line_scene:
        return _takes_line(solver, scene)
    try:
        solver.total_cost(scene, solver.options(), True)
    except (UnsupportedSceneError, LimitError, InvalidParameterError):
        return False
    return True


class _Usable:
    """Checks of candidates against the scene and the limits, each made once and only when needed
    (the checks cost more than a fast solve: a choice checks the candidates it reaches, not all)."""

    def __init__(self, scene: Scene, limits: Limits):
        self.scene, self.limits, self.accepted, self.refusals = scene, limits, {}, {}

    def __call__(self, prediction: Prediction) -> bool:
        name = prediction.solver
        if name not in self.accepted:
            self.accepted[name] = _accepts(get_solver(name), self.scene)
        if not self.accepted[name]:
            return False
        try:
            _check_limits(get_solver(name), self.scene, prediction.option, self.limits)
        except LimitError as error:
            self.refusals[prediction] = str(error)
            return False
        except InvalidParameterError:
            return False
        return True


def choose(scene: Scene, tolerance: float, limits: Limits, model=None) -> Choice:
    """Rank every (solver, resolution) predicted to meet ``tolerance``, cheapest first, then the others by
    predicted error; the first usable one (the solver takes the scene, within the limits) leads.

    Raises
    ------
    LimitError
        Before any work, when every candidate predicted to meet the tolerance is over the limits
        (the message names the cheapest one and its work).
    UnsupportedSceneError
        When no solver takes the scene.
    """
    model = model or load_model()
    kind = scene_class(scene)
    proxy = kind if kind in model.fits else "cold"
    try:
        features = scene_features(scene)
    except UnsupportedSceneError:
        features = {"kappa": 1.0, "time_ratio": 1.0, "vibration_energy": 0.0}
    predictions = [p for name in SOLVER_NAMES for p in model.candidates(proxy, name, features)]
    if scene.is_line_scene:
        predictions = [_rigid_mass_target(p) for p in predictions]
    meeting = sorted((p for p in predictions if p.error <= tolerance), key=lambda p: p.cpu_s)
    others = sorted((p for p in predictions if p.error > tolerance), key=lambda p: (p.error, p.cpu_s))
    usable = _Usable(scene, limits)
    lattice = None
    if scene.is_line_scene and kind in model.fits:
        lattice = _lattice_prediction(model, kind, features, scene)
        meeting = _beyond_ladders(model, kind, features, tolerance, meeting, usable)
        if lattice is not None:
            meeting = [lattice, *meeting]
    first = next((p for p in meeting if usable(p)), None)
    if first is not None and first is lattice:
        reason = (f"on the exact lattice at {first.text()} (every element one wave travel time, hard contacts "
                  f"between rod ends, the error estimate's coarser runs too): exact to round-off, "
                  f"{first.cpu_s * 1e3:.3g} ms CPU predicted")
    elif first is not None:
        reason = (f"predicted cheapest to meet tolerance={tolerance:g}: error estimate {first.error:.2g}, "
                  f"{first.cpu_s * 1e3:.3g} ms CPU")
    elif usable.refusals:
        cheapest = min(usable.refusals, key=lambda p: p.cpu_s)
        refusal = (f"tolerance={tolerance:g}: the cheapest method predicted to meet it, "
                   f"{cheapest.text()}, is over the limits: {usable.refusals[cheapest]}")
        bounded = _bounded_attempt(scene, others, usable)
        if bounded is None:
            raise LimitError(refusal)
        # the delay equations of a rigid mass stop at their own finest grid (about 0.1 s): their smallest
        # predicted error is tried before the refusal, with nothing after it
        reason = (f"no candidate within the limits is predicted to meet tolerance={tolerance:g}; {bounded.text()} "
                  f"(bounded work, predicted error estimate {bounded.error:.2g}) is tried before refusing")
        return Choice(ranked=[bounded], reason=reason, scene_class=kind, usable=usable, refusal=refusal)
    else:
        first = next((p for p in others if usable(p)), None)
        if first is None:
            raise UnsupportedSceneError(f"no solver of {', '.join(SOLVER_NAMES)} takes this scene within the limits")
        reason = (f"no candidate is predicted to meet tolerance={tolerance:g}: the smallest predicted error "
                  f"estimate, {first.error:.2g}, runs first and is refined")
    if proxy != kind:
        reason += f" (scene class {kind!r} has no calibration: the model of two cold rods stands in)"
    if scene.is_line_scene:
        # a line scene hands over only to candidates predicted to meet the tolerance: the others are the fem
        # solver's coarse rungs, whose refinement the limits refused already
        refusal = ""
        if usable.refusals:
            cheapest = min(usable.refusals, key=lambda p: p.cpu_s)
            refusal = (f"tolerance={tolerance:g}: the cheapest method predicted to meet it within the model, "
                       f"{cheapest.text()}, is over the limits: {usable.refusals[cheapest]}")
        return Choice(ranked=[first, *(p for p in meeting if p is not first)], reason=reason, scene_class=kind,
                      usable=usable, refusal=refusal)
    # a refinement that cannot proceed hands over to the next usable candidate of another solver
    return Choice(ranked=[first, *(p for p in meeting + others if p is not first)], reason=reason,
                  scene_class=kind, usable=usable)


def _lattice_prediction(model, kind: str, features: dict, scene: Scene):
    """The fem prediction at the coarsest ladder resolution whose run and error-estimate runs (``// 2``, ``// 4``)
    are all on the exact lattice (P1 lumped at Courant number 1, every element one wave travel time, only hard
    contacts between rod ends: d'Alembert's solution at the nodes, tests/test_impact_references.py), with the
    round-off floor as its error; None where the scene has a rigid body, a soft contact, a taper, or no such
    resolution.  Decided from the meshes' travel times (a set-up costs milliseconds, as much as the run); the
    run's ``diagnostics["lattice"]`` confirms it, and a run off the lattice shows in its estimate (refined,
    logged as a miss)."""
    from ..bodies import RigidBody, body_segments, pair_laws
    from .cost_model import ERROR_FLOOR

    if any(isinstance(b, RigidBody) for b in scene.rods) or not all(law.hard for law in pair_laws(scene)):
        return None
    segments = [s for b in scene.rods for s in body_segments(b)]
    if any(s.tapered for s in segments):
        return None
    shortest = min(sum(s.travel_time for s in body_segments(b)) for b in scene.rods)

    def one_travel(elements: int) -> bool:  # the multi-body set-up's meshes (_mesh): one element travel time
        travel = shortest / elements
        times = [s.travel_time / max(1, round(s.travel_time / travel)) for s in segments]
        return max(times) - min(times) <= 1e-9 * min(times)

    for elements in model.ladders.get("fem", []):
        levels = (int(elements), int(elements) // 2, int(elements) // 4)
        if levels[-1] >= 1 and all(one_travel(n) for n in levels):
            prediction = model.predict(kind, "fem", features, elements)
            return dataclasses.replace(prediction, error=ERROR_FLOOR) if prediction is not None else None
    return None


def _beyond_ladders(model, kind: str, features: dict, tolerance: float, meeting: list, usable) -> list:
    """``meeting`` of a line scene, or where no ladder resolution of a solver that takes the scene is predicted
    to meet ``tolerance``, with the resolution its error fit needs beyond the ladder (elements or modes:
    ``log10 error`` linear in ``log10 resolution``), so that a tolerance the limits cannot reach is refused
    before any work, with the work it would need (the fem solver is first order on line scenes)."""
    added = []
    for name in SOLVER_NAMES:
        fit = model.fits.get(kind, {}).get(name)
        if fit is None or any(p.solver == name for p in meeting) or not _takes_line(get_solver(name), usable.scene):
            continue
        coef = fit["error"]["coef"]
        slope = coef[2]
        if name == "delay" or slope >= 0.0:
            continue
        row = model.predict(kind, name, features, 1.0)
        needed = 10.0 ** ((math.log10(tolerance) - math.log10(row.error)) / slope)
        ladder = model.ladders.get(name, [1.0])
        resolution = float(ladder[-1] * 2.0 ** max(math.ceil(math.log2(needed / ladder[-1])), 1))
        prediction = model.predict(kind, name, features, resolution)
        if not prediction.error <= tolerance or not math.isfinite(prediction.cpu_s):
            continue
        refusal = _over_limits(name, usable.scene, resolution, usable.limits)
        if refusal:
            usable.refusals[prediction] = refusal  # beyond what the solver's options take: refused here
        else:
            added.append(prediction)
    return sorted(meeting + added, key=lambda p: p.cpu_s)


def _over_limits(name: str, scene: Scene, elements: float, limits: Limits) -> str:
    """Why a fem run of a line scene at ``elements`` (any size, not validated as an option) is over the limits
    ("" if it is within them)."""
    if name != "fem":
        return ""
    from ..fem.multibody import line_cost

    cost = line_cost(scene, {"elements": elements})
    work = cost.work * (1.0 + 1.0 / 4.0 + 1.0 / 16.0)
    if work <= limits.max_work and cost.memory <= limits.max_memory:
        return ""
    return (f"fem: this solve would take about {work:.2g} updates and {cost.memory:.2g} bytes ({cost.detail}; "
            f"with the error estimate's runs at elements // 2 and // 4), more than max_work={limits.max_work:g} or "
            f"max_memory={limits.max_memory:g}; the fem solver is first order on line scenes")


def _level_change(a, b) -> float:
    """``|a - b|`` of two levels' values: numbers (a restitution) or sequences (a line scene's velocities)."""
    if isinstance(a, (list, tuple)):
        return max((abs(x - y) for x, y in zip(a, b)), default=0.0)
    return abs(a - b)


def _observed_order(solver, options, result) -> float:
    """Order of the error in the resolution, from the run's three finest Richardson levels where they
    show one (between 0.5 and 6), else the solver's declared order (1 where it declares none)."""
    levels = sorted(result.diagnostics.get("error_estimate_levels") or [], key=lambda level: -level[0])
    if len(levels) >= 3:
        (n0, v0), (n1, v1), (_n2, v2) = levels[:3]
        d0, d1 = _level_change(v0, v1), _level_change(v1, v2)
        if d0 > 0.0 and d1 > 0.0 and n0 > n1:
            order = math.log(d1 / d0) / math.log(n0 / n1)
            if 0.5 <= order <= 6.0:
                return order
    return solver.expected_order(options) or 1.0


def refined_resolution(solver, options, result, tolerance: float):
    """The resolution predicted to bring ``result``'s error estimate to ``tolerance``, or None.

    Elements and modes: the run's resolution times ``(estimate / tolerance)^(1/order)``, rounded up to
    a power-of-two multiple (the earlier runs then are the coarser levels of the next estimate); a
    resolution whose estimate is its own (the delay solver's ``rtol``): ``rtol`` divided by the
    factor the estimate is off, and by 2.  None where the solver cannot refine (no Richardson levels,
    no estimate, the option's range exhausted).
    """
    estimate = result.error_estimate
    name = solver.resolution
    spec = next(f.metadata["option"] for f in dataclasses.fields(solver.Options) if f.name == name)
    level = getattr(options, name)
    if not math.isfinite(estimate) or level is None:
        return None
    if solver.refines < 0:
        if result.work.get("steps_per_round_trip", 0) >= _rigid_mass_steps_max():
            return None  # the rigid mass's delay equation at its finest grid: a smaller rtol changes nothing
        wanted = level * tolerance / estimate / 2.0
        if wanted >= level:
            wanted = level / 10.0
        if spec["low"] is not None and wanted < spec["low"]:
            return None
        return {name: wanted}
    if not result.diagnostics.get("error_estimate_levels"):
        return None
    order = _observed_order(solver, options, result)
    factor = max((estimate / tolerance) ** (1.0 / order), 1.0)
    wanted = int(level * 2 ** max(math.ceil(math.log2(factor)), 1))
    if spec["high"] is not None and wanted > spec["high"]:
        return None
    return {name: wanted}


def _rigid_mass_steps_max() -> int:
    from ..delay.rigid_mass import STEPS_MAX

    return STEPS_MAX


def _cpu_run(solver, scene, option: dict, limits: Limits):
    start = time.process_time()
    result = solver.solve(scene, option, tolerance=None, max_work=limits.max_work, max_memory=limits.max_memory,
                          estimate_error=True)
    return result, time.process_time() - start


def _meets(result, tolerance: float) -> bool:
    return result.error_estimate <= tolerance and not result.diagnostics.get("error_estimate_rough")


def solve_auto(scene: Scene, *, tolerance=None, max_work=None, max_memory=None, model=None, **options):
    """One collision of ``scene`` by the method predicted cheapest to meet ``tolerance`` (module docstring).

    Parameters
    ----------
    scene : Scene
    tolerance : float or None
        Largest acceptable error estimate of the restitution (absolute); None:
        :data:`DEFAULT_TOLERANCE`.
    max_work, max_memory : float or None
        Limits of every run (:class:`wavecontact.limits.Limits`).
    model : CostModel, optional
        Default: the stored one (:func:`~wavecontact.solvers.cost_model.load_model`).
    **options
        Refused: the resolution and the method are what ``auto`` chooses; name a solver to set options.

    Returns
    -------
    CollisionResult
        The accepted run; ``wall_time_s`` covers every attempt; ``diagnostics["auto"]`` holds
        ``method``, ``reason``, ``tolerance``, ``predicted_cpu_s``, ``actual_cpu_s``, ``attempts`` and
        ``misses``.
    """
    if not isinstance(scene, Scene):
        raise InvalidParameterError(f"scene must be a wavecontact.Scene, got {type(scene).__name__}")
    if options:
        raise InvalidParameterError(f"solver='auto' takes no solver options (got {', '.join(sorted(options))}); "
                                    "name a solver to set them")
    tolerance = _tolerance(DEFAULT_TOLERANCE if tolerance is None else tolerance)
    limits = Limits(max_work=max_work, max_memory=max_memory)
    choice = choose(scene, tolerance, limits, model)
    first: Prediction = choice.ranked[0]
    return _run_until_met(scene, tolerance, limits, choice, (get_solver(first.solver), first.option, first), {})


def solve_refined(scene: Scene, solver: str, *, tolerance, max_work=None, max_memory=None, **options):
    """One collision with the named ``solver`` and ``options``, refined until its error estimate meets
    ``tolerance`` (the refinement of :func:`solve_auto`, without the choice: ``converge``-style use).

    The first run is the one ``solve(scene, solver, **options)`` makes; where its estimate exceeds
    ``tolerance`` the solver's resolution option is raised (or its ``rtol`` lowered) as predicted from the
    observed order, the other options kept, each run checked against the limits before it runs.

    Raises
    ------
    AccuracyError
        When the refinement is over the limits (with the work it needs) or the solver cannot refine.
    """
    if not isinstance(scene, Scene):
        raise InvalidParameterError(f"scene must be a wavecontact.Scene, got {type(scene).__name__}")
    tolerance = _tolerance(tolerance)
    if tolerance is None:
        raise InvalidParameterError("solve_refined needs a tolerance")
    named = get_solver(solver)
    limits = Limits(max_work=max_work, max_memory=max_memory)
    resolution = {named.resolution: getattr(named.options(options), named.resolution)}
    fixed = {name: value for name, value in options.items() if name != named.resolution}
    choice = Choice(ranked=[], reason=f"named by the caller, refined to meet tolerance={tolerance:g}",
                    scene_class=scene_class(scene), usable=None)
    return _run_until_met(scene, tolerance, limits, choice, (named, resolution, None), fixed)


def _run_until_met(scene, tolerance, limits, choice, pending, fixed: dict):
    """Run ``pending`` = (solver, resolution option, prediction or None), refine or hand over until the
    estimate meets ``tolerance`` (module docstring); ``fixed``: the other options of every run."""
    attempts, misses, spent_cpu, spent_wall = [], [], 0.0, 0.0
    queue = list(choice.ranked)
    first = pending[2]
    tried: set = set()
    last = None
    with reusing_runs():
        while pending is not None and len(attempts) < MAX_ATTEMPTS:
            solver, option, prediction = pending
            tried.add(solver.name)
            pending = None
            try:
                result, cpu = _cpu_run(solver, scene, {**fixed, **option}, limits)
            except (SolverFailure, LimitError) as failure:
                attempts.append({"method": _text(solver, option), "failed": str(failure)})
                misses.append(f"{_text(solver, option)} failed: {failure}")
                pending = _next(queue, tried, choice.usable)
                continue
            spent_cpu += cpu
            spent_wall += result.wall_time_s
            last = result
            attempts.append({"method": _text(solver, option), "error_estimate": result.error_estimate,
                             "cpu_s": cpu, "predicted_error": None if prediction is None else prediction.error,
                             "predicted_cpu_s": None if prediction is None else prediction.cpu_s})
            if prediction is not None:
                if not _meets(result, tolerance) and prediction.error <= tolerance:
                    misses.append(f"{_text(solver, option)}: error estimate {result.error_estimate:.2g} above the "
                                  f"predicted {prediction.error:.2g} (tolerance {tolerance:g})")
                first_call = (result.diagnostics.get("includes_kernel_preparation")
                              or result.diagnostics.get("interpreted_kernels"))
                if cpu > 2.0 * prediction.cpu_s and not first_call:
                    misses.append(f"{_text(solver, option)}: {cpu * 1e3:.3g} ms CPU, over twice the predicted "
                                  f"{prediction.cpu_s * 1e3:.3g} ms")
            if _meets(result, tolerance):
                return _accepted(result, choice, first, attempts, misses, spent_cpu, spent_wall, tolerance)
            refined = refined_resolution(solver, solver.options({**fixed, **option}), result, tolerance)
            if refined is not None:
                try:
                    _check_limits(solver, scene, {**fixed, **refined}, limits)
                except LimitError as error:
                    raise AccuracyError(
                        f"auto: {_text(solver, option)} gave error estimate {result.error_estimate:.2g} > "
                        f"tolerance={tolerance:g}; {_text(solver, refined)} is predicted to meet it but is over "
                        f"the limits: {error}", result=result, advice=str(error)) from None
                pending = (solver, refined, None)
            elif choice.usable is not None:
                pending = _next(queue, tried, choice.usable)
    estimate = math.nan if last is None else last.error_estimate
    if choice.refusal:
        raise AccuracyError(f"auto: {', '.join(a['method'] for a in attempts)} gave error estimate {estimate:.2g}; "
                            f"{choice.refusal}", result=last, advice="raise max_work or the tolerance")
    raise AccuracyError(f"auto: no method met tolerance={tolerance:g} within {len(attempts)} runs "
                        f"(last error estimate {estimate:.2g}; tried "
                        f"{', '.join(a['method'] for a in attempts)}); raise max_work or the tolerance",
                        result=last, advice="raise max_work or the tolerance")


def _next(queue: list, tried: set, usable):
    for prediction in queue:
        if prediction.solver not in tried and usable(prediction):
            return get_solver(prediction.solver), prediction.option, prediction
    return None


def _text(solver, option: dict) -> str:
    (name, value), = option.items()
    return f"{solver.name}: {name}={value:g}"


def _accepted(result, choice: Choice, first, attempts, misses, cpu, wall, tolerance):
    final = attempts[-1]["method"]
    reason = choice.reason if len(attempts) == 1 else (
        f"{attempts[0]['method']} {choice.reason}; refined to {final} after {len(attempts) - 1} more run(s)")
    diagnostics = result.diagnostics  # the solve's own fresh dict: extended in place, not copied
    diagnostics["auto"] = {
        "method": final,
        "reason": reason,
        "tolerance": tolerance,
        "scene_class": choice.scene_class,
        "predicted_cpu_s": None if first is None else first.cpu_s,
        "predicted_error": None if first is None else first.error,
        "actual_cpu_s": cpu,
        "attempts": attempts,
        "misses": misses,
    }
    return result if len(attempts) == 1 else dataclasses.replace(result, wall_time_s=wall)
