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

Its options are :class:`ModalOptions`.
"""

from __future__ import annotations

import copy
import math
import threading
from collections import OrderedDict
from dataclasses import dataclass
from types import MappingProxyType

import numpy as np

from ..bath.model import _ModeSum
from ..contact_kernels import CLOSED_FORM_CODES
from ..errors import InvalidParameterError, SolverFailure, UnsupportedSceneError
from ..limits import Cost
from ..result import Outcome
from ..scene import Scene
from ..solvers.base import ENERGY_SPLIT, RING, CollisionFields, SolverBase, SolverOptions, option
from . import collocation, end_response, kernels
from .modes import rod_modes
from .system import ModalSystem, StepControl

__all__ = ["SOLVER", "ModalOptions", "ModalSolver"]


@dataclass(frozen=True)
class ModalOptions(SolverOptions):
    """Options of the modal solver."""

    solver_name = "modal"
    modes: int = option(100, "modes kept per rod", kind="int", low=1, high=20_000)
    static_correction: bool = option(True, "account for the omitted modes (needed for hard contact); False: "
                                     "plain truncation", kind="bool")
    correction: str | None = option(None, "how the omitted modes are accounted for: 'end-response' (exact end "
                                    "response of uniform rods), 'static' (static end compliance in series "
                                    "with the contact) or 'none'; None: 'end-response' for analytic modes and "
                                    "the collocation, else 'static'", kind="choice",
                                    choices=("end-response", "static", "none"), allow_none=True)
    mode_source: str = option("analytic", "closed-form modes of uniform rods, or eigenmodes of FE matrices",
                              kind="choice", choices=("analytic", "fe"))
    fe_elements: int | None = option(None, "elements per rod for mode_source='fe'; None: max(8 modes, 64)",
                                     kind="int", low=2, high=200_000, allow_none=True)
    fe_order: int = option(1, "element order for mode_source='fe'", kind="choice", choices=(1, 2))
    step_method: str = option("collocation", "exponential Radau collocation (one collision) or the ring's "
                              "kick-rotate-kick splitting", kind="choice", choices=("collocation", "splitting"))
    step_accuracy: float = option(StepControl.accuracy, "splitting: eta of the contact step (error ~ eta^2)",
                                  low=1e-6, high=10.0)
    step_reach: float = option(StepControl.reach, "splitting: largest change of alpha * gap per step in the "
                               "force's toe", low=1e-3, high=100.0)
    step_order: int = option(StepControl.order, "splitting: order of the step control", kind="choice",
                             choices=(2, 4))
    collocation_stages: int = option(6, "Radau IIA stages s of the collocation (order up to 2 s - 1)",
                                     kind="int", low=1, high=8)
    collocation_tolerance: float | None = option(None, "accepted step-to-step change of the predicted node "
                                                 "forces, relative to Z V / 2; None: 1e-3 with the "
                                                 "end-response correction, else 1e-2", low=1e-12, high=1.0,
                                                 allow_none=True)
    history: bool = option(True, "record the relative velocity and contact force at every step", kind="bool")

_CORRECTIONS = ("end-response", "static", "none")
# default collocation tolerance: the end-response correction has no series compliance to soften a stiff
# contact, and 1e-2 left up to 3e-7 at kappa = 1e4 (1e-3: below 3e-9 on a sweep, 15 % more steps)
_DEFAULT_TOLERANCE = {"end-response": 1e-3, "static": 1e-2, "none": 1e-2}
# smallest estimate of the end-response correction: the round-off its echo sums leave in epsilon
# (errors up to 2.4e-12 against the delay solver at kappa = inf, where a tolerance change moves nothing)
END_RESPONSE_FLOOR = 1e-11
# bound on the steps recorded for the echoes (about 150 MB at s = 6)
_MAX_RECORDS = 2**21
# order assumed by the error estimate where the modes do not resolve the contact time ...
UNRESOLVED_ORDER = 1.0
# ... which, with the static correction, is where alpha V l_short / (c N) exceeds this (measured:
# the best coverage/sharpness trade-off on a sample of 160 collisions, docs/error_estimates.md)
RESOLVED_BELOW = 30.0
# largest change of alpha_eff * gap per collocation step where the force matters
_EXPONENT_STEP = 2.0
# collocation tables of recent systems (filling costs ~0.1 ms per step size; repeated collisions reuse them)
_TABLE_CACHE: OrderedDict = OrderedDict()
_TABLE_CACHE_SIZE = 16  # each scene's run and its error estimate's (one mode per rod, small)
_CACHE_LOCK = threading.Lock()

# start with alpha * gap this far beyond the negligible-force range
_START_MARGIN = 5.0


def _project_field(rod, modes, field):
    """Mean and modal coordinates (mass-normalised) of a field ``f(s)``, ``s in [0, l]``.

    A field that is itself a sum of this rod's free-free modes (a bath realisation,
    :class:`wavecontact.bath.model.BathRealisation`) is read off exactly; any other is
    projected by Gauss-Legendre quadrature.
    """
    if isinstance(field, _ModeSum) and math.isclose(field.length, rod.length, rel_tol=1e-12):
        kept = min(modes.count, field.amplitudes.size)
        coords = np.zeros(modes.count)
        coords[:kept] = math.sqrt(rod.mass) * field.scale * np.asarray(field.amplitudes[:kept], dtype=float)
        return 0.0, coords
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


def _excited_modes(scene) -> int:
    """Modes per rod that a bath realisation in ``scene`` excites (0 without one)."""
    vibrations = getattr(scene, "vibrations", None)
    return 0 if vibrations is None else int(vibrations.modes)


def _warm(scene) -> bool:
    """Whether a rod of ``scene`` starts vibrating (a bath realisation or initial fields)."""
    return _excited_modes(scene) > 0 or scene.initial_displacement is not None or scene.initial_velocity is not None


def _finer_options(scene, options, tolerance):
    """Options of the end-response error estimate's run: a tenth of the collocation ``tolerance``, no
    history and, for rods that start at rest, one mode per rod.

    With the end-response correction the gap is the exact end response of the whole rods (every mode,
    :mod:`wavecontact.modal.end_response`); the kept modes only ride along, driven by the force, and
    enter the restitution nowhere but in the test that the rods have separated for good (after the
    force has fallen below ``exp(-40)`` of its scale).  The run's restitution is therefore the same
    for any number of modes (bit for bit on the sweeps of ``tests/test_modal_solver.py``), and one mode
    per rod makes it about a third cheaper than the requested hundred.  Warm rods keep the requested
    modes: their starting motion lives in them.
    """
    warm = _warm(scene)
    key = (options, float(tolerance), warm)
    finer = _FINER_OPTIONS.get(key)
    if finer is None:
        changes = {"collocation_tolerance": tolerance / 10.0, "history": False}
        if not warm:
            changes["modes"] = 1
        finer = options.replace(**changes)
        if len(_FINER_OPTIONS) >= _TABLE_CACHE_SIZE:
            _FINER_OPTIONS.clear()
        _FINER_OPTIONS[key] = finer
    return finer


# the options of recent estimate runs (validating a replace costs about as much as a short solve's overheads)
_FINER_OPTIONS: dict = {}


def _restitution_alone(scene: Scene, options: ModalOptions, exponent_step: float) -> tuple:
    """``(restitution, work)`` of a run made for its restitution alone (the error estimate's): the
    end-response collocation without the bookkeeping around it; any other run, or one whose collocation
    fails (and falls back to the splitting), through :func:`_collide`."""
    correction = _resolve_correction(options.correction, options.static_correction, options.mode_source,
                                     options.step_method)
    if correction != "end-response" or options.history:
        fields = _collide(scene, options, exponent_step, omitted_energy=False)
        return float(fields.restitution), fields.work
    tolerance = options.collocation_tolerance or _DEFAULT_TOLERANCE[correction]
    system, _ = _build(scene, options.modes, correction, options.mode_source, options.fe_elements, options.fe_order,
                       options.step_accuracy, options.step_reach, options.step_order)
    w_before = float(system.U[1] - system.U[0])
    try:
        _, work, _ = _run_collocation(system, options.collocation_stages, tolerance, np.empty((0, 3)), [],
                                      exponent_step, system.energy_at_start)
    except SolverFailure:
        fields = _collide(scene, options, exponent_step, omitted_energy=False)
        return float(fields.restitution), fields.work
    w_after = float(system.U[1] - system.U[0])
    return abs(w_after) / abs(w_before), work


def _resolve_correction(correction, static_correction, mode_source, step_method) -> str:
    """The correction actually used, from ``correction`` and the older ``static_correction`` flag."""
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
           step_reach=StepControl.reach, step_order=StepControl.order):
    """The two rods' :class:`ModalSystem` at the start of the collision, and the initial gap (length).

    Rods that start at rest are built once per scene and options and handed out as copies (a
    collision and its error estimate's run, repeated collisions); warm rods are built every time.
    The system's ``energy_at_start`` is its ``total_energy()`` at the start.
    """
    if isinstance(correction, (bool, np.bool_)):  # the older flag (benchmarks/peers pass it)
        correction = "static" if correction else "none"
    key = _system_key(scene, (modes, correction, mode_source, fe_elements, fe_order, step_accuracy, step_reach,
                              step_order))
    if key is not None:
        with _CACHE_LOCK:  # solves on a thread pool share the table
            kept = _SYSTEM_CACHE.get(key)
            if kept is not None:
                _SYSTEM_CACHE.move_to_end(key)
        if kept is not None:
            return _fresh_copy(kept[0]), kept[1]
    probe, gap = _build_system(scene, modes, correction, mode_source, fe_elements, fe_order, step_accuracy,
                               step_reach, step_order)
    probe.energy_at_start = probe.total_energy()  # its total energy, kept with the copies
    if key is not None:
        with _CACHE_LOCK:
            _SYSTEM_CACHE[key] = (_fresh_copy(probe), gap)
            while len(_SYSTEM_CACHE) > _TABLE_CACHE_SIZE:
                _SYSTEM_CACHE.popitem(last=False)
    return probe, gap


# systems of recent scenes whose rods start at rest: key -> (system at the start, initial gap)
_SYSTEM_CACHE: OrderedDict = OrderedDict()
# the parts of a ModalSystem that its runs change
_SYSTEM_STATE = ("q", "v", "X", "U", "clock", "episode", "counters")


def _system_key(scene: Scene, settings: tuple):
    """Key of a cold scene's system in :data:`_SYSTEM_CACHE` (None: warm rods, or fields that do not hash)."""
    if _warm(scene) or scene.is_ring or len(scene.rods) != 2:
        return None
    key = (scene.rods, tuple(scene.velocities), scene.contact, None if scene.gaps is None else tuple(scene.gaps),
           settings)
    try:
        hash(key)
    except TypeError:
        return None
    return key


def _fresh_copy(system: ModalSystem) -> ModalSystem:
    """A copy of ``system`` with its own state arrays (the rest, never changed by a run, is shared)."""
    copied = copy.copy(system)
    for name in _SYSTEM_STATE:
        setattr(copied, name, getattr(system, name).copy())
    return copied


def _build_system(scene: Scene, modes, correction, mode_source, fe_elements, fe_order, step_accuracy, step_reach,
                  step_order):
    if scene.is_ring:
        raise UnsupportedSceneError(
            "the modal solver's single-collision mode takes two rods on a line; for rods on a ring "
            "use wavecontact.solvers.get_solver('modal').simulate(scene)"
        )
    if len(scene.rods) != 2:
        raise UnsupportedSceneError(
            f"the modal solver computes the restitution of two rods on a line, got {len(scene.rods)} rods"
        )
    rod_a, rod_b = scene.rods
    excited = _excited_modes(scene)
    if excited > modes:
        if correction != "end-response":
            raise UnsupportedSceneError(
                f"the bath excites {excited} modes per rod and modes={modes} keeps fewer: the {correction!r} "
                f"correction would drop the rest of the thermal motion; use modes >= {excited} (the "
                "end-response correction keeps them itself)")
        # the end-response correction is exact for any number of kept modes once every warm mode is
        # among them (the omitted ones must start at rest): keep the excited ones
        modes = excited
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
    elif scene.contact.decay_rate > 0.0:
        gap = probe.contact_range + _START_MARGIN / scene.contact.decay_rate
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
    with _CACHE_LOCK:  # solves on a thread pool share the table
        tables = _TABLE_CACHE.get(key)
        if tables is None:
            tables = collocation.CollocationTables(system.omega, coupling,
                                                   1.0 / system.mass[0] + 1.0 / system.mass[1], stages, system.dt_top)
            _TABLE_CACHE[key] = tables
            while len(_TABLE_CACHE) > _TABLE_CACHE_SIZE:
                _TABLE_CACHE.popitem(last=False)
        else:
            _TABLE_CACHE.move_to_end(key)
    return tables


def _run_collocation(system, stages, tolerance, buffer, chunks, exponent_step=_EXPONENT_STEP, energy=None):
    """Advance ``system`` (two rods, one pair) through its collision by exponential collocation.

    ``energy``: ``system.total_energy()`` now, if known.  Returns the last history chunk, the work
    counters and the step records (exact ends; else empty).
    """
    first = system.rod_first.astype(np.int64)
    coupling = np.concatenate([-system.right[first[0]:first[1]], system.left[first[1]:first[2]]])
    tables = _collocation_tables(system, coupling, stages)
    counters = np.zeros(6, dtype=np.int64)
    if system.exact_ends:
        gap_0 = float(system.X[1] - system.half[1] - system.X[0] - system.half[0])
        ends = end_response.end_parameters(*system.rods, float(system.clock[0]), gap_0,
                                           float(system.U[1] - system.U[0]),
                                           system.total_energy() if energy is None else energy,
                                           float(system.omitted_compliance[0]))
        free_q, free_v = system.q.copy(), system.v.copy()
        records = np.empty((1024, 3 + stages))
    else:
        ends = np.zeros(end_response.ENDS_SIZE)
        # warm modes' starting motion: only its amplitudes are used (they bound the step, see collocation)
        free_q, free_v = system.q.copy(), system.v.copy()
        records = np.empty((0, 3 + stages))
    while True:
        status = collocation.run_collision(
            (system.q, system.v, system.omega, coupling), (system.X, system.U, system.mass, system.half),
            (int(system.law_code), float(system.alpha), float(system.strength), float(system.stiffness),
             float(system.pair_compliance[0])),
            (float(system.contact_range), float(system.force_scale), float(tolerance), float(exponent_step),
             100_000_000, False, 30.0),
            tables.arrays(), (ends, free_q, free_v, records), (system.clock, counters, buffer),
            both_ends=True,  # one compilation for every correction (compare runs the end-response and static ones)
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
        raise SolverFailure(f"modal collocation stopped with kernel status {status}", Outcome.NOT_CONVERGED)


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
    for i, (rod, energy) in enumerate(zip(system.rods, end_response.forced_energies(records, system.rods))):
        kept = float(np.sum(forced[system.rod_first[i]:system.rod_first[i + 1]]))
        total += energy - impulse**2 / (2.0 * rod.mass) - kept
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


_CORRECTION_NAMES = {"end-response": "end-response correction", "static": "static correction",
                     "none": "plain truncation"}


class ModalSolver(SolverBase):
    """The rods' free-free modes with exact free flight (Eq. 7, 14), corrected for the omitted modes."""

    name = "modal"
    Options = ModalOptions
    resolution = "modes"
    refines = 1
    title = "modal solver"
    cli_flags = MappingProxyType({"modes": None, "static_correction": (
        "plain truncation: no correction for the omitted modes (the modal solver's static_correction=False; "
        "not for hard contact). Default: corrected")})
    capabilities = frozenset({RING, ENERGY_SPLIT})
    # the static correction: the end-response default has no order in N (exact for cold rods; expected_order None)
    order_case = MappingProxyType({"resolutions": (10, 20, 40), "options": {"correction": "static"}})
    agreement_case = ({"modes": 100}, 1e-6)
    error_safety = 1.5
    error_levels = 2

    def expected_order(self, options: ModalOptions) -> float | None:
        """Order of epsilon in ``1/N``: 1 for plain truncation, 3 with the static correction (docs/modal.md);
        None with the end-response correction (exact in the modes for rods that start at rest)."""
        correction = _resolve_correction(options.correction, options.static_correction, options.mode_source,
                                         options.step_method)
        return {"none": 1.0, "static": 3.0}.get(correction)

    def _collide(self, scene: Scene, options: ModalOptions) -> CollisionFields:
        return _collide(scene, options)

    def comparison_methods(self, kappa: float) -> list:
        """Each correction for the omitted modes at 25 and 100 modes."""
        del kappa
        return [({"modes": modes, "correction": correction, "static_correction": correction != "none"},
                 f"{modes} modes, {name}", "steps")
                for correction, name in _CORRECTION_NAMES.items() for modes in (25, 100)]

    def comparison_family(self, options: ModalOptions) -> str:
        """``modal: <correction>``: end-response, static, or plain truncation."""
        correction = _resolve_correction(options.correction, options.static_correction, options.mode_source,
                                         options.step_method)
        return f"{self.name}: {_CORRECTION_NAMES[correction]}"

    def vibration_energy_gain(self, fields: CollisionFields, scene: Scene):
        """The modal energies after the collision minus the realisation's energy in the modes kept."""
        after = np.asarray(fields.extra["vibration_energy"], dtype=float)
        kept = int(fields.work["modes"])
        before = np.array([float(e[:kept].sum()) for e in scene.vibrations.modal_energies()])
        return after - before

    def _error_estimate(self, scene: Scene, options: ModalOptions, fields: CollisionFields) -> tuple:
        """Richardson in the modes; with the end-response correction, whose result does not depend on
        the modes for rods that start at rest, the change when the collocation tolerance is divided by
        ten (the integrator's error, what is left)."""
        correction = _resolve_correction(options.correction, options.static_correction, options.mode_source,
                                         options.step_method)
        work = fields.work
        if correction == "end-response" and "fallback" in work:
            # the collocation failed and the run is the splitting's with the static correction, which the
            # collocation tolerance does not enter: estimate it as such a run (Richardson in the modes)
            static = options.replace(correction="static", step_method="splitting", modes=int(work["modes"]),
                                     history=False)
            estimate, method, levels = self._richardson(scene, static, fields)
            return estimate, f"{method} (the collocation fell back to the splitting: {work['fallback']})", levels
        if correction != "end-response":
            return self._richardson(scene, options, fields)
        tolerance = options.collocation_tolerance or _DEFAULT_TOLERANCE[correction]
        finer = _finer_options(scene, options, tolerance)
        # warm modes: through the contact the step is set by how far their free motion may move the gap
        # (the exponent step, see collocation._warm_step_limit), which the tolerance does not change
        warm = _warm(scene)
        exponent_step = _EXPONENT_STEP / 2.0 if warm else _EXPONENT_STEP
        try:
            restitution, work = _restitution_alone(scene, finer, exponent_step)
            if "fallback" in work and finer.modes != options.modes:
                # the splitting it fell back to needs the modes: the run again with the requested ones
                restitution, work = _restitution_alone(scene, finer.replace(modes=options.modes), exponent_step)
        except SolverFailure as failure:
            return math.nan, f"none (the run at a tenth of the collocation tolerance failed: {failure})", []
        change = abs(restitution - float(fields.restitution))
        finer_text = f"{tolerance / 10:g}" + (f" and exponent step {exponent_step:g}" if warm else "")
        if "fallback" in work:
            finer_text += f" (which fell back to the splitting: {work['fallback']})"
        return (max(self.error_safety * change, END_RESPONSE_FLOOR),
                (f"collocation tolerance {tolerance:g} against {finer_text}: change {change:.3g}, "
                f"safety {self.error_safety:g}"), [])

    def error_estimate_runs(self, scene: Scene, options: ModalOptions) -> list:
        """With the end-response correction the run at a tenth of the collocation tolerance
        (:func:`_finer_options`), else the Richardson levels (half the modes each)."""
        correction = _resolve_correction(options.correction, options.static_correction, options.mode_source,
                                         options.step_method)
        if correction != "end-response":
            return super().error_estimate_runs(scene, options)
        tolerance = options.collocation_tolerance or _DEFAULT_TOLERANCE[correction]
        return [_finer_options(scene, options, tolerance)]

    def _richardson(self, scene: Scene, options: ModalOptions, fields: CollisionFields) -> tuple:
        """Richardson in the modes, unless a coarser run would drop modes the bath excites."""
        coarsest = options.modes // 2 ** self.coarser_levels(options)
        if _excited_modes(scene) > coarsest:
            needed = 2 ** self.coarser_levels(options) * _excited_modes(scene)
            why = f"none (the runs at fewer modes would drop modes the bath excites; keep modes >= {needed})"
            return math.nan, why, []
        return super()._error_estimate(scene, options, fields)

    def coarser_options(self, options: ModalOptions):
        """Half the modes, no histories."""
        if options.modes < 2:
            return None
        return options.replace(modes=options.modes // 2, history=False)

    def estimate_order(self, scene: Scene, options: ModalOptions) -> float:
        """The declared order where the kept modes resolve the contact time
        (``alpha V l_short / (c N) <= RESOLVED_BELOW``), else :data:`UNRESOLVED_ORDER` (the hard limit's
        slow convergence)."""
        if not options.static_correction:
            return 1.0
        contact = scene.contact
        if contact.decay_rate > 0.0 and len(scene.rods) == 2:
            shorter = min(scene.rods, key=lambda rod: rod.length)
            speed = abs(scene.velocities[0] - scene.velocities[1])
            if contact.decay_rate * speed * shorter.length / (shorter.wave_speed * options.modes) <= RESOLVED_BELOW:
                return self.expected_order(options)
        return UNRESOLVED_ORDER

    def estimate_cost(self, scene: Scene, options: ModalOptions) -> Cost | None:
        """Collocation tables, mode computation and steps of the top step size, from the options."""
        if scene.is_ring or len(scene.rods) != 2:
            return None
        kept = 2 * options.modes
        stages = options.collocation_stages
        memory = 60 * (4 * stages + 3) * kept * 8.0
        if options.mode_source == "fe":
            unknowns = options.fe_order * (options.fe_elements or max(8 * options.modes, 64)) + 1
            memory += 2 * (4 * 8.0 * unknowns**2 if unknowns <= 600 else 6 * 8.0 * unknowns * (options.modes + 1))
        shortest = min(rod.length / rod.wave_speed for rod in scene.rods)
        span = 4.0 * sum(rod.length / rod.wave_speed for rod in scene.rods)
        if scene.contact.decay_rate > 0.0:
            speed = max(abs(scene.velocities[0] - scene.velocities[1]), 1e-300)
            span += 100.0 / (scene.contact.decay_rate * speed)
        steps = 2.0 * span / (0.05 * shortest)
        memory += steps * 3 * 8.0 if options.history else 0.0
        work = steps * kept * stages
        detail = f"{kept} modes, about {steps:.3g} steps"
        correction = _resolve_correction(options.correction, options.static_correction, options.mode_source,
                                         options.step_method)
        if correction == "end-response":
            # every step sums the echoes of the force history that have come back so far: one per
            # round trip of the shorter rod, so the cost grows like the square of the round-trip ratio
            echoes = span / (2.0 * shortest)
            work += steps * stages * echoes
            detail += f" each summing up to {echoes:.3g} echoes of the end response"
        return Cost(steps=steps, work=work, memory=memory, detail=detail)

    def simulate(self, scene: Scene, options=None):
        """Many collisions of a ring scene (:class:`wavecontact.modal.ring.RingSimulation`)."""
        from .ring import RingSimulation

        options = self.options(options)
        return RingSimulation(scene, modes=options.modes, static_correction=options.static_correction,
                              step_accuracy=options.step_accuracy, step_reach=options.step_reach,
                              step_order=options.step_order, mode_source=options.mode_source,
                              step_method=options.step_method, collocation_stages=options.collocation_stages,
                              collocation_tolerance=options.collocation_tolerance)


def _check_splitting_law(scene: Scene, why: str) -> None:
    """Refuse the splitting for a law without closed-form flows (Hertz): with the generic sub-steps it
    leaves an error of about 5e-5 that neither the modes nor ``step_accuracy`` change, so no estimate
    would bound it (measured against the delay solver at rtol 1e-12)."""
    if scene.contact.code not in CLOSED_FORM_CODES:
        message = (f"{why}the modal splitting has no closed-form contact flow for {scene.contact.name} contact, "
                   "and its generic one leaves an error its estimate does not bound; use "
                   "step_method='collocation' (the default) or solver='delay'")
        raise SolverFailure(message, Outcome.NOT_CONVERGED) if why else UnsupportedSceneError(message)


def _collide(scene: Scene, options: ModalOptions, exponent_step: float = _EXPONENT_STEP,
             omitted_energy: bool = True) -> CollisionFields:
    """One collision of two rods on a line with the modal expansion (``options``: :class:`ModalOptions`).

    ``exponent_step``: the collocation's largest change of ``alpha_eff * gap`` per step;
    ``omitted_energy``: with the end-response correction, compute the energy the force left in the
    omitted modes (from the force history, about as costly as the run itself; it enters
    ``energy_drift`` only); False leaves ``energy_drift`` NaN (a run made for its restitution alone:
    the error estimate's).

    ``work``: ``modes``, ``steps``, ``step_method`` (and ``rejected_steps``,
    ``stages`` for collocation, ``free_flights`` for splitting); ``extra``:
    ``modal_energies`` (2, modes) after the collision, ``vibration_energy`` per
    rod (kept modes), ``translational_energy_before/after``, ``residual_compliance``,
    ``correction`` and, with the end-response correction, ``omitted_mode_energy``
    (what the force left in the modes above ``modes``, from its history;
    ``energy_drift`` includes it).
    """
    modes, static_correction, correction = options.modes, options.static_correction, options.correction
    mode_source, fe_elements, fe_order = options.mode_source, options.fe_elements, options.fe_order
    step_accuracy, step_reach, step_order = options.step_accuracy, options.step_reach, options.step_order
    step_method, collocation_stages = options.step_method, options.collocation_stages
    collocation_tolerance, history = options.collocation_tolerance, options.history
    correction = _resolve_correction(correction, static_correction, mode_source, step_method)
    if collocation_tolerance is None:
        collocation_tolerance = _DEFAULT_TOLERANCE[correction]
    system, gap = _build(scene, modes, correction, mode_source, fe_elements, fe_order, step_accuracy,
                         step_reach, step_order)
    energy_before = system.energy_at_start
    momentum_before = system.momentum()
    w_before = float(system.U[1] - system.U[0])
    e_tr_before = 0.5 * float(np.sum(system.mass * system.U**2))
    buffer = np.empty((4096 if history else 0, 3))
    chunks = []
    bookkeeping, omitted_energy = omitted_energy, None
    if step_method == "collocation":
        try:
            tail, work, (steps, free_q, free_v) = _run_collocation(system, collocation_stages,
                                                                   collocation_tolerance, buffer, chunks,
                                                                   exponent_step, energy_before)
            if system.exact_ends and bookkeeping:
                omitted_energy = _omitted_mode_energy(system, steps, free_q, free_v)
        except SolverFailure as failure:
            # the collocation's Newton solve can stall on a stiff contact seen by few modes; the
            # splitting takes any contact (its step follows the force), so start over with it
            _check_splitting_law(scene, f"the collocation failed ({failure}) and ")
            if correction == "end-response":
                correction = "static"  # the splitting knows only the static correction
            system, gap = _build(scene, system.rod_modes[0].count, correction, mode_source, fe_elements, fe_order,
                                 step_accuracy, step_reach, step_order)
            chunks = []
            tail, work = _run_splitting(system, buffer, chunks)
            work["fallback"] = f"splitting after: {failure}"
            step_method = "splitting"
    else:
        _check_splitting_law(scene, "")
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
    energies = system.modal_energies()
    reduced_mass = 1.0 / (1.0 / system.mass[0] + 1.0 / system.mass[1])
    return CollisionFields(
        restitution=abs(w_after) / abs(w_before),
        time=times,
        relative_velocity=velocity,
        contact_force=force if history else None,
        energy_drift=abs(energy_after - energy_before) / energy_before
        if bookkeeping or not system.exact_ends else math.nan,
        momentum_drift=abs(system.momentum() - momentum_before) / (reduced_mass * abs(w_before)),
        work={"modes": int(system.rod_modes[0].count), "mode_source": mode_source, "step_method": step_method,
              **({} if system.rod_modes[0].count == modes else {"modes_requested": int(modes)}), **work},
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


SOLVER = ModalSolver()
