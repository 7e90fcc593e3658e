"""Modal-expansion solver: each rod's free-free modes plus its rigid motion (paper Eq. 7, 14).

Each rod keeps ``modes`` vibration modes (analytic for a uniform rod, or the
eigenmodes of its finite-element model); the contact acts on the two facing
ends through their modal displacements.  The omitted modes are accounted for
by the exact end response of uniform rods (``correction='end-response'``, the
default for analytic modes) or by their static end compliance in series with
the contact law (``'static'``), which turns the ~1/N truncation error into a
faster one.  The
collision is integrated by exponential Radau collocation
(:mod:`wavecontact.modal.collocation`) or, on request, by the ring's
kick-rotate-kick splitting.  See ``docs/modal.md``.

Options
-------
modes : int
    Modes kept per rod (default 100).
static_correction : bool
    Account for the omitted modes (default True; needed for hard contact);
    False: plain truncation.
correction : {None, 'end-response', 'static', 'none'}
    How the omitted modes are accounted for: 'end-response' (the exact end
    response of uniform rods, all modes; the default for analytic modes and
    the collocation), 'static' (their static end compliance in series with
    the contact; the default otherwise) or 'none' (= ``static_correction=False``).
mode_source : {'analytic', 'fe'}
    Closed-form modes of uniform rods, or eigenmodes of the FE matrices.
fe_elements : int or None
    Elements per rod for ``mode_source='fe'`` (default ``max(8 modes, 64)``).
fe_order : {1, 2}
    Element order for ``mode_source='fe'``.
step_accuracy, step_reach, step_order
    Step control of the splitting only (see ``StepControl`` and docs/modal.md):
    ``eta`` of the contact step (error ~ eta^2), the largest change of
    ``alpha * gap`` per step in the force's toe, and the order (2 or 4).
step_method : {'collocation', 'splitting'}
    'collocation': adaptive exponential Radau collocation (oscillators
    integrated exactly against a polynomial contact force; high order, the
    fast and accurate choice for one collision); 'splitting': kicks and exact
    rotations (the ring's integrator; ``step_accuracy``, ``step_reach`` and
    ``step_order`` apply to it only).
collocation_stages : int
    Radau IIA stages ``s`` of the collocation (order up to ``2 s - 1``).
collocation_tolerance : float or None
    Accepted step-to-step change of the predicted node forces, relative to
    the force scale ``Z V / 2`` (the restitution error is far smaller);
    None: 1e-3 with the end-response correction, else 1e-2.
history : bool
    Record the relative velocity and contact force at every step.
"""

from __future__ import annotations

import math
from collections import OrderedDict

import numpy as np

from ..contact import Exponential
from ..errors import InvalidParameterError, SolverFailure, UnsupportedSceneError
from ..modal import collocation, end_response, kernels
from ..modal.modes import rod_modes
from ..modal.system import ModalSystem, StepControl
from ..result import CollisionResult
from ..scene import Scene

__all__ = ["NAME", "OPTIONS", "solve"]

NAME = "modal"
OPTIONS = {
    "modes": 100,
    "static_correction": True,
    "correction": None,
    "mode_source": "analytic",
    "fe_elements": None,
    "fe_order": 1,
    "step_accuracy": StepControl.accuracy,
    "step_reach": StepControl.reach,
    "step_order": StepControl.order,
    "step_method": "collocation",
    "collocation_stages": 6,
    "collocation_tolerance": None,
    "history": True,
}
_STEP_METHODS = ("collocation", "splitting")
_CORRECTIONS = ("end-response", "static", "none")
# default collocation tolerance: the end-response correction has no series compliance to soften a stiff
# contact, and 1e-2 left up to 3e-7 at kappa = 1e4 (1e-3: below 3e-9 on a sweep, 15 % more steps)
# bound on the steps recorded for the echoes (about 150 MB at s = 6)
_MAX_RECORDS = 2**21
_DEFAULT_TOLERANCE = {"end-response": 1e-3, "static": 1e-2, "none": 1e-2}
# largest change of alpha_eff * gap per collocation step where the force matters
_EXPONENT_STEP = 2.0
# collocation tables of recent systems (filling costs ~0.1 ms per step size; repeated collisions reuse them)
_TABLE_CACHE: OrderedDict = OrderedDict()
_TABLE_CACHE_SIZE = 8

# start with alpha * gap this far beyond the negligible-force range
_START_MARGIN = 5.0


def _project_field(rod, modes, field):
    """Mean and modal coordinates (mass-normalised) of a field ``f(s)``, ``s in [0, l]``."""
    points = max(4 * modes.count, 256)
    nodes, weights = np.polynomial.legendre.leggauss(points)
    s = 0.5 * rod.length * (nodes + 1.0)
    w = 0.5 * rod.length * weights
    values = np.asarray(field(s), dtype=float)
    if values.shape != s.shape or not np.all(np.isfinite(values)):
        raise InvalidParameterError("initial fields must return one finite value per point s")
    density = rod.density * rod.area
    mean = float(np.sum(w * values)) / rod.length
    nu = np.arange(1, modes.count + 1)
    shapes = math.sqrt(2.0 / rod.mass) * np.cos(np.outer(nu, s) * math.pi / rod.length)
    return mean, density * shapes @ (w * values)


def _resolve_correction(correction, static_correction, mode_source, step_method) -> str:
    """The correction actually used, from ``correction`` and the older ``static_correction`` flag."""
    if not isinstance(static_correction, (bool, np.bool_)):
        raise InvalidParameterError(f"static_correction must be True or False, got {static_correction!r}")
    if correction is not None and correction not in _CORRECTIONS:
        raise InvalidParameterError(f"correction must be one of {_CORRECTIONS} or None, got {correction!r}")
    if not static_correction:
        if correction not in (None, "none"):
            raise InvalidParameterError(
                f"static_correction=False means no correction; it contradicts correction={correction!r}"
            )
        return "none"
    if correction is None:
        return "end-response" if mode_source == "analytic" and step_method == "collocation" else "static"
    if correction == "end-response" and (mode_source != "analytic" or step_method != "collocation"):
        raise InvalidParameterError(
            "correction='end-response' needs mode_source='analytic' (uniform rods) and "
            "step_method='collocation'; use correction='static'"
        )
    return correction


def _build(scene: Scene, modes, correction, mode_source, fe_elements, fe_order, step_accuracy,
           step_reach=OPTIONS["step_reach"], step_order=OPTIONS["step_order"]):
    if isinstance(correction, (bool, np.bool_)):  # the older flag (benchmarks/peers pass it)
        correction = "static" if correction else "none"
    if scene.is_ring:
        raise UnsupportedSceneError(
            "the modal solver's single-collision mode takes two rods on a line; for rods on a ring "
            "use wavecontact.modal.RingSimulation"
        )
    if len(scene.rods) != 2:
        raise UnsupportedSceneError(
            f"the modal solver computes the restitution of two rods on a line, got {len(scene.rods)} rods"
        )
    rod_a, rod_b = scene.rods
    basis = [rod_modes(r, modes, mode_source, elements=fe_elements, order=fe_order) for r in scene.rods]
    velocities = np.array(scene.velocities, dtype=float)
    shift = np.zeros(2)
    q0 = []
    v0 = []
    for i, (rod, m) in enumerate(zip(scene.rods, basis)):
        qi = np.zeros(m.count)
        vi = np.zeros(m.count)
        for name, target in (("initial_displacement", qi), ("initial_velocity", vi)):
            fields = getattr(scene, name)
            if fields is not None and fields[i] is not None:
                if mode_source != "analytic":
                    raise UnsupportedSceneError("initial fields need mode_source='analytic' in the modal solver")
                mean, coords = _project_field(rod, m, fields[i])
                target += coords
                if name == "initial_displacement":
                    shift[i] += mean
                else:
                    velocities[i] += mean
        q0.append(qi)
        v0.append(vi)
    approach = velocities[0] - velocities[1]
    if not approach > 0.0:
        raise UnsupportedSceneError(
            f"the rods must approach each other (v1 - v2 > 0), got v1 - v2 = {approach:g}"
        )
    z_a, z_b = rod_a.impedance, rod_b.impedance
    force_scale = z_a * z_b / (z_a + z_b) * approach  # wave-theory force plateau
    control = StepControl(accuracy=step_accuracy, reach=step_reach, order=step_order)
    probe = ModalSystem(basis, (0.0, 1.0), velocities, [(0, 1, 0.0)], scene.contact, force_scale,
                        correction == "static", control, exact_ends=correction == "end-response")
    if scene.gaps is not None:
        gap = scene.gaps[0]
    elif isinstance(scene.contact, Exponential):
        gap = probe.contact_range + _START_MARGIN / scene.contact.alpha
    else:
        gap = 0.0
    positions = (0.5 * rod_a.length + shift[0], rod_a.length + gap + 0.5 * rod_b.length + shift[1])
    probe.X[:] = positions
    probe.q[:] = np.concatenate(q0)
    probe.v[:] = np.concatenate(v0)
    return probe, gap


def _collocation_tables(system, coupling, stages):
    key = (system.omega.tobytes(), coupling.tobytes(), float(system.mass[0]), float(system.mass[1]),
           int(stages), float(system.dt_top))
    tables = _TABLE_CACHE.get(key)
    if tables is None:
        tables = collocation.CollocationTables(system.omega, coupling, 1.0 / system.mass[0] + 1.0 / system.mass[1],
                                               stages, system.dt_top)
        _TABLE_CACHE[key] = tables
        while len(_TABLE_CACHE) > _TABLE_CACHE_SIZE:
            _TABLE_CACHE.popitem(last=False)
    else:
        _TABLE_CACHE.move_to_end(key)
    return tables


def _run_collocation(system, stages, tolerance, buffer, chunks):
    """Advance ``system`` (two rods, one pair) through its collision by exponential collocation.

    Returns the last history chunk, the work counters and the step records (exact ends; else empty).
    """
    first = system.rod_first.astype(np.int64)
    coupling = np.concatenate([-system.right[first[0]:first[1]], system.left[first[1]:first[2]]])
    tables = _collocation_tables(system, coupling, stages)
    counters = np.zeros(6, dtype=np.int64)
    if system.exact_ends:
        gap_0 = float(system.X[1] - system.half[1] - system.X[0] - system.half[0])
        ends = end_response.end_parameters(*system.rods, float(system.clock[0]), gap_0,
                                           float(system.U[1] - system.U[0]), system.total_energy(),
                                           float(system.omitted_compliance[0]))
        free_q, free_v = system.q.copy(), system.v.copy()
        records = np.empty((1024, 3 + stages))
    else:
        ends = np.zeros(end_response.ENDS_SIZE)
        free_q, free_v = np.zeros_like(system.q), np.zeros_like(system.v)
        records = np.empty((0, 3 + stages))
    while True:
        status = collocation.run_collision(
            system.q, system.v, system.omega, coupling, system.X, system.U, system.mass, system.half,
            float(system.pair_compliance[0]), system.law_code, system.alpha, system.strength, system.stiffness,
            system.contact_range, system.force_scale, float(tolerance), _EXPONENT_STEP, *tables.arrays(),
            ends, free_q, free_v, records, system.clock, counters, buffer, 100_000_000,
        )
        system.check_status(status)
        if status == kernels.STATUS_BUFFER_FULL:
            chunks.append(buffer[: counters[2]].copy())
            counters[2] = 0
            buffer = np.empty((2 * buffer.shape[0], 3))
            continue
        if status == kernels.STATUS_RECORDS_FULL:
            if records.shape[0] >= _MAX_RECORDS:
                raise SolverFailure(f"modal collocation: more than {_MAX_RECORDS} steps in one collision")
            records = np.concatenate([records, np.empty_like(records)])
            continue
        if status == kernels.STATUS_SEPARATED:
            work = {"steps": int(counters[0]), "rejected_steps": int(counters[1]),
                    "newton_iterations": int(counters[4]), "stages": int(stages)}
            return buffer[: counters[2]], work, (records[: counters[5]], free_q, free_v)
        raise SolverFailure(f"modal collocation stopped with status {status}")


def _omitted_mode_energy(system, records, free_q, free_v) -> float:
    """Energy the force left in the omitted modes, from its recorded history (exact ends).

    Per rod: the energy the force puts into a rod at rest (end response, see
    :func:`~wavecontact.modal.end_response.forced_energy`) minus its rigid part ``I^2 / (2 m)``
    and minus the kept modes' forced energy (their motion less their free motion).
    """
    if records.shape[0] == 0:
        return 0.0
    last = records[-1]
    impulse = last[2] + last[1] * float(np.sum(last[3:] / np.arange(1, last.size - 2)))
    forced = 0.5 * ((system.v - free_v) ** 2 + (system.omega * (system.q - free_q)) ** 2)
    total = 0.0
    for i, rod in enumerate(system.rods):
        kept = float(np.sum(forced[system.rod_first[i]:system.rod_first[i + 1]]))
        total += end_response.forced_energy(records, rod) - impulse**2 / (2.0 * rod.mass) - kept
    return total


def _run_splitting(system, buffer, chunks):
    while True:
        status = system.run_episode(history=buffer)
        system.check_status(status)
        if status == kernels.STATUS_BUFFER_FULL:
            chunks.append(buffer[: system.counters[2]].copy())
            system.counters[2] = 0
            buffer = np.empty((2 * buffer.shape[0], 3))
            continue
        if status == kernels.STATUS_FREE_FOREVER:
            raise UnsupportedSceneError("the rods never come within range of the contact force")
        if status == kernels.STATUS_SEPARATED:
            return buffer[: system.counters[2]], {"steps": int(system.counters[0]),
                                                  "free_flights": int(system.counters[1])}


def solve(scene: Scene, *, modes=OPTIONS["modes"], static_correction=True, correction=None, mode_source="analytic",
          fe_elements=None, fe_order=1, step_accuracy=OPTIONS["step_accuracy"],
          step_reach=OPTIONS["step_reach"], step_order=OPTIONS["step_order"], step_method=OPTIONS["step_method"],
          collocation_stages=OPTIONS["collocation_stages"], collocation_tolerance=OPTIONS["collocation_tolerance"],
          history=True) -> CollisionResult:
    """One collision of two rods on a line with the modal expansion.

    Returns
    -------
    CollisionResult
        ``work``: ``modes``, ``steps``, ``step_method`` (and ``rejected_steps``,
        ``stages`` for collocation, ``free_flights`` for splitting);
        ``diagnostics``: ``energy_drift`` (relative), ``momentum_drift``;
        ``extra``: ``modal_energies`` (2, modes) after the collision,
        ``vibration_energy`` per rod (kept modes), ``translational_energy_before/after``,
        ``residual_compliance``, ``correction`` and, with the end-response
        correction, ``omitted_mode_energy`` (what the force left in the modes
        above ``modes``, from its history; ``energy_drift`` includes it).
    """
    if step_method not in _STEP_METHODS:
        raise InvalidParameterError(f"step_method must be one of {_STEP_METHODS}, got {step_method!r}")
    if step_method == "collocation":
        if isinstance(collocation_stages, bool) or not isinstance(collocation_stages, (int, np.integer)) \
                or not 1 <= collocation_stages <= 8:
            raise InvalidParameterError(f"collocation_stages must be an integer in [1, 8], got {collocation_stages!r}")
        if collocation_tolerance is not None and not (
                isinstance(collocation_tolerance, (int, float)) and 0.0 < collocation_tolerance <= 1.0):
            raise InvalidParameterError(f"collocation_tolerance must lie in (0, 1], got {collocation_tolerance!r}")
    correction = _resolve_correction(correction, static_correction, mode_source, step_method)
    if collocation_tolerance is None:
        collocation_tolerance = _DEFAULT_TOLERANCE[correction]
    system, gap = _build(scene, modes, correction, mode_source, fe_elements, fe_order, step_accuracy,
                         step_reach, step_order)
    energy_before = system.total_energy()
    momentum_before = system.momentum()
    w_before = float(system.U[1] - system.U[0])
    e_tr_before = 0.5 * float(np.sum(system.mass * system.U**2))
    buffer = np.empty((4096 if history else 0, 3))
    chunks = []
    omitted_energy = None
    if step_method == "collocation":
        try:
            tail, work, (steps, free_q, free_v) = _run_collocation(system, collocation_stages,
                                                                   collocation_tolerance, buffer, chunks)
            if system.exact_ends:
                omitted_energy = _omitted_mode_energy(system, steps, free_q, free_v)
        except SolverFailure as failure:
            # the collocation's Newton solve can stall on a stiff contact seen by few modes; the
            # splitting takes any contact (its step follows the force), so start over with it
            if correction == "end-response":
                correction = "static"  # the splitting knows only the static correction
            system, gap = _build(scene, modes, correction, mode_source, fe_elements, fe_order,
                                 step_accuracy, step_reach, step_order)
            chunks = []
            tail, work = _run_splitting(system, buffer, chunks)
            work["fallback"] = f"splitting after: {failure}"
            step_method = "splitting"
    else:
        tail, work = _run_splitting(system, buffer, chunks)
    if history:
        chunks.append(tail.copy())
        records = np.concatenate(chunks)
    else:
        records = np.empty((0, 3))
    start = np.array([[0.0, w_before, 0.0]])
    records = np.concatenate([start, records])
    w_after = float(system.U[1] - system.U[0])
    energy_after = system.total_energy() + (omitted_energy or 0.0)
    times, velocity, force = records[:, 0], records[:, 1], records[:, 2]
    contact_start = contact_duration = None
    if history and force.max() > 0.0:
        active = np.nonzero(force > 0.01 * force.max())[0]  # as the delay solver: 1 % of the peak
        contact_start = float(times[active[0]])
        contact_duration = float(times[active[-1]] - times[active[0]])
    energies = system.modal_energies()
    params = scene.metadata.get("two_rods")
    return CollisionResult(
        restitution=abs(w_after) / abs(w_before),
        solver=NAME,
        wall_time_s=0.0,
        time=times,
        relative_velocity=velocity,
        gamma=None if params is None else params.gamma,
        kappa=None if params is None else params.kappa,
        contact_force=force,
        contact_start=contact_start,
        contact_duration=contact_duration,
        work={"modes": int(modes), "mode_source": mode_source, "step_method": step_method, **work},
        diagnostics={
            "energy_drift": abs(energy_after - energy_before) / energy_before,
            "momentum_drift": abs(system.momentum() - momentum_before),
        },
        extra={
            "modal_energies": np.array(energies) if energies[0].size == energies[1].size else energies,
            "vibration_energy": [float(np.sum(e)) for e in energies],
            "translational_energy_before": e_tr_before,
            "translational_energy_after": system.translational_energy(),
            "residual_compliance": float(system.pair_compliance[0]),
            "static_correction": bool(static_correction),
            "correction": correction,
            **({} if omitted_energy is None else {"omitted_mode_energy": omitted_energy}),
            "initial_gap": float(gap),
        },
    )
