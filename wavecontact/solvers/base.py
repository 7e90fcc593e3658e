"""The solver contract: what every solver of wavecontact is and returns.

A solver is an object satisfying :class:`Solver`:

``name``
    its registry name (``"delay"``, ``"fem"``, ``"modal"``);
``Options``
    a frozen dataclass of every option it takes, each declared once with its
    default, allowed range and help text (:func:`option`); building one
    validates it, so a solver never sees an invalid option;
``resolution``
    the name of the option that sets its resolution (``"elements"``,
    ``"modes"``, ``"rtol"``), and ``refines``: whether raising it refines
    (``+1``, elements and modes) or coarsens (``-1``, a tolerance);
``expected_order(options)``
    the convergence order of the restitution in that resolution for these
    options (``None`` where no single order applies), what the contract tests
    measure against;
``solve(scene, options)``
    one collision, returned as a complete :class:`~wavecontact.result.CollisionResult`;
``capabilities``
    what else it offers (:data:`CAPABILITIES`: batches of thermal samples, the
    hard-core thermal mode, sweeps of material ratios, ring runs), as data that
    studies query through the registry (:func:`wavecontact.solvers.solvers_with`)
    instead of naming solvers; each capability's methods are declared here,
    on :class:`SolverBase`, and refused by a solver that does not offer it;
``vibration_energy_gain(fields, scene)``
    the per-rod energy split of a thermal collision, by the solver's own bookkeeping
    (the ``energy split`` capability).

:class:`SolverBase` implements ``solve`` once for all solvers: it times the
solver's own ``_collide``, recovers the paper's ``gamma`` and ``kappa`` from
the scene, measures the contact window from the force history by one rule,
and builds the result in one go from the :class:`CollisionFields` that
``_collide`` returns (with a thermal scene the per-rod energy split and the
bath's parameters included: the result is complete when ``solve`` returns).  Solvers that can run many collisions of a
ring scene also offer ``simulate(scene, options)`` (see
:class:`RepeatedCollisions`).
"""

from __future__ import annotations

import contextlib
import dataclasses
import itertools
import math
import time
from collections.abc import Callable, Mapping
from types import MappingProxyType
from typing import Any, ClassVar, Protocol, runtime_checkable

import numpy as np

from .._jit import interpreted_call_count, prepared_kernel_count
from ..errors import AccuracyError, InvalidParameterError, SolverFailure, UnsupportedSceneError
from ..limits import Cost, Limits, check_cost, check_kappa
from ..result import CONTACT_FORCE_FRACTION, CollisionResult, contact_window
from ..scene import Scene, two_rod_parameters

__all__ = [
    "CAPABILITIES",
    "ENERGY_SPLIT",
    "HARD_CORE_THERMAL",
    "MATERIAL_RATIOS",
    "RING",
    "THERMAL_BATCH",
    "Capability",
    "CollisionFields",
    "RepeatedCollisions",
    "Solver",
    "SolverBase",
    "SolverOptions",
    "Stopwatch",
    "option",
    "option_help",
    "reusing_runs",
]


# --------------------------------------------------------------------------- options
def option(default, help: str, *, kind: str = "float", low=None, high=None, choices=None,
           allow_none: bool = False, allow_inf: bool = False, check: Callable | None = None):
    """Declare one solver option: its default, type, allowed range and help text.

    Parameters
    ----------
    default
        The default value.
    help : str
        One line for ``--help`` and the docs, with units.
    kind : {'float', 'int', 'bool', 'choice', 'object'}
        Type of the value; ``'object'`` is checked by ``check`` alone.
    low, high : number, optional
        Closed bounds of a number.
    choices : tuple, optional
        Allowed values of a ``'choice'``.
    allow_none : bool
        ``None`` is allowed (meaning: chosen by the solver).
    allow_inf : bool
        ``inf`` is allowed for a float.
    check : callable, optional
        ``check(value) -> value``: extra validation (raises InvalidParameterError).
    """
    spec = {"help": help, "kind": kind, "low": low, "high": high, "choices": choices,
            "allow_none": allow_none, "allow_inf": allow_inf, "check": check}
    if isinstance(default, (list, dict, np.ndarray)):
        raise TypeError("option defaults must be immutable")
    return dataclasses.field(default=default, metadata={"option": spec})


def _range_text(spec) -> str:
    if spec["kind"] == "choice":
        text = "one of " + ", ".join(repr(c) for c in spec["choices"])
    elif spec["kind"] == "bool":
        text = "True or False"
    elif spec["kind"] in ("int", "float"):
        low = "-inf" if spec["low"] is None else f"{spec['low']:g}"
        high = ("inf" if spec["allow_inf"] or spec["high"] is None else f"{spec['high']:g}")
        noun = "an integer" if spec["kind"] == "int" else "a number"
        text = f"{noun} in [{low}, {high}]"
    else:
        text = spec["help"]
    if spec["allow_none"]:
        text += " or None"
    return text


def _validate(solver: str, name: str, spec: dict, value):
    if value is None:
        if spec["allow_none"]:
            return None
        raise InvalidParameterError(f"{solver} option {name} must be {_range_text(spec)}, got None")
    kind = spec["kind"]
    if kind == "bool":
        if not isinstance(value, (bool, np.bool_)):
            raise InvalidParameterError(f"{solver} option {name} must be True or False, got {value!r}")
        value = bool(value)
    elif kind == "choice":
        if isinstance(value, (float, np.floating)) and float(value).is_integer() and int(value) in spec["choices"]:
            value = int(value)  # order=1.0 means order=1
        if not isinstance(value, (str, int)) or isinstance(value, bool) or value not in spec["choices"]:
            raise InvalidParameterError(f"{solver} option {name} must be {_range_text(spec)}, got {value!r}")
    elif kind in ("int", "float"):
        if isinstance(value, (bool, np.bool_)):
            raise InvalidParameterError(f"{solver} option {name} must be {_range_text(spec)}, got {value!r}")
        if kind == "int":
            if isinstance(value, (float, np.floating)) and float(value).is_integer():
                value = int(value)
            if not isinstance(value, (int, np.integer)):
                raise InvalidParameterError(f"{solver} option {name} must be {_range_text(spec)}, got {value!r}")
            value = int(value)
        else:
            try:
                value = float(value)
            except (TypeError, ValueError):
                raise InvalidParameterError(
                    f"{solver} option {name} must be {_range_text(spec)}, got {value!r}") from None
            if math.isnan(value) or (math.isinf(value) and not (spec["allow_inf"] and value > 0)):
                raise InvalidParameterError(f"{solver} option {name} must be {_range_text(spec)}, got {value!r}")
        low, high = spec["low"], spec["high"]
        if (low is not None and value < low) or (high is not None and value > high and not math.isinf(value)):
            raise InvalidParameterError(f"{solver} option {name} must be {_range_text(spec)}, got {value!r}")
    if spec["check"] is not None:
        value = spec["check"](value)
    return value


@dataclasses.dataclass(frozen=True)
class SolverOptions:
    """Base of every solver's options: validated on construction, immutable.

    Subclasses declare their fields with :func:`option`.  Build them with
    ``Options(**kwargs)`` or :meth:`from_mapping` (which names the solver and
    lists the allowed names when an unknown one is given).
    """

    solver_name: ClassVar[str] = "solver"

    @classmethod
    def _declared(cls) -> tuple:
        """``(name, spec)`` of every field, ``spec`` None for an undeclared one; read once per class
        (``dataclasses.fields`` on every construction cost more than a fast solve's own work)."""
        declared = cls.__dict__.get("_declared_fields")
        if declared is None:
            declared = tuple((f.name, f.metadata.get("option")) for f in dataclasses.fields(cls))
            cls._declared_fields = declared
        return declared

    def __post_init__(self):
        solver = self.solver_name
        for name, spec in self._declared():
            if spec is not None:
                object.__setattr__(self, name, _validate(solver, name, spec, getattr(self, name)))

    @classmethod
    def from_mapping(cls, given: Mapping):
        """Options from keyword arguments, refusing unknown names."""
        allowed = {name for name, _spec in cls._declared()}
        unknown = sorted(set(given) - allowed)
        if unknown:
            raise InvalidParameterError(
                f"unknown option(s) {', '.join(map(repr, unknown))} for solver {cls.solver_name!r}; "
                f"allowed: {', '.join(sorted(allowed)) or 'none'}"
            )
        return cls(**given)

    def replace(self, **changes):
        """A copy with some options changed (validated again)."""
        return dataclasses.replace(self, **changes)

    def as_dict(self) -> dict:
        """The options as a plain dict (values as given; arrays and objects kept)."""
        return {name: getattr(self, name) for name, _spec in self._declared()}


def option_help(options_class) -> list:
    """``(name, default, allowed, help)`` of every option of an options class, for docs and ``--help``."""
    rows = []
    for f in dataclasses.fields(options_class):
        spec = f.metadata.get("option")
        if spec is not None:
            rows.append((f.name, f.default, _range_text(spec), spec["help"]))
    return rows


# --------------------------------------------------------------------------- what _collide returns
@dataclasses.dataclass(frozen=True)
class CollisionFields:
    """What a solver's ``_collide`` returns: the raw numbers of one collision, before
    :meth:`SolverBase.solve` adds the error estimate, the contact window and the timing.

    Attributes
    ----------
    restitution : float
        epsilon (dimensionless).
    time, relative_velocity : array_like
        The history: time and ``v2 - v1`` at each sample (scene units).
    contact_force : array_like or None
        The force at each sample (scene units), None if not recorded.
    force_sampling : {'point', 'interval'}
        ``'point'``: the force at ``time[i]``; ``'interval'``: its value (or mean) on
        ``(time[i-1], time[i]]`` (:func:`wavecontact.result.contact_window`).
    error_estimate : float
        The solver's own estimate of the restitution's error; NaN: Richardson decides.
    energy_drift, momentum_drift : float
        Relative drifts (NaN where not tracked).
    work : dict
        Effort counters (``steps`` at least).
    extra : dict
        Solver-specific results (see each solver's docs).
    """

    restitution: float
    time: Any
    relative_velocity: Any
    contact_force: Any = None
    force_sampling: str = "point"
    error_estimate: float = math.nan
    energy_drift: float = math.nan
    momentum_drift: float = math.nan
    work: dict = dataclasses.field(default_factory=dict)
    extra: dict = dataclasses.field(default_factory=dict)


# --------------------------------------------------------------------------- capabilities
@dataclasses.dataclass(frozen=True)
class Capability:
    """Something a solver may offer beyond ``solve``: its name and the :class:`SolverBase` methods it brings."""

    name: str
    methods: tuple
    description: str


#: Many finite-kappa thermal collisions of the paper's rods at once (an ensemble's or a Markov step's batch).
THERMAL_BATCH = "thermal batch"
#: The stochastic hard-core limit (kappa = inf with vibrations): samples, batches, grid size, per-rod split.
HARD_CORE_THERMAL = "hard-core thermal"
#: epsilon of a cold two-material collision from the ratios Z_2 / Z_1 and T_1 / T_2 alone (material maps).
MATERIAL_RATIOS = "material ratios"
#: Many collisions on a ring (``simulate``).
RING = "ring"
#: The per-rod split of the energy a thermal collision gives the rods' vibrations.
ENERGY_SPLIT = "energy split"

CAPABILITIES = {c.name: c for c in (
    Capability(THERMAL_BATCH, ("thermal_restitution", "thermal_restitutions"),
               "epsilon of many finite-kappa thermal samples without result objects"),
    Capability(HARD_CORE_THERMAL, ("hard_core_thermal_restitution", "hard_core_thermal_batch",
                                   "hard_core_grid_points", "hard_core_thermal_split"),
               "the stochastic hard-core limit: samples, batches, grid size and the per-rod split"),
    Capability(MATERIAL_RATIOS, ("check_ratios", "restitution_of_ratios"),
               "epsilon of cold two-material collisions from the impedance and round-trip ratios"),
    Capability(RING, ("simulate",), "many collisions of a ring scene"),
    Capability(ENERGY_SPLIT, ("vibration_energy_gain",),
               "each rod's vibrational energy gain in a thermal collision (extra['vibration_energy_gain'])"),
)}


def _not_offered(solver, capability: str):
    return UnsupportedSceneError(f"solver {solver.name!r} does not offer {capability!r}; solvers that do: "
                                 f"wavecontact.solvers.solvers_with({capability!r})")


# --------------------------------------------------------------------------- solvers
@runtime_checkable
class Solver(Protocol):
    """What the registry holds: one object per solver."""

    name: str
    Options: type
    resolution: str
    refines: int

    def expected_order(self, options) -> float | None: ...

    def solve(self, scene: Scene, options) -> CollisionResult: ...


@runtime_checkable
class RepeatedCollisions(Protocol):
    """A running simulation of many collisions (a ring scene), as returned by ``solver.simulate``.

    ``next_collision()`` returns a frozen :class:`~wavecontact.result.CollisionRecord`;
    ``get_state()`` / ``set_state(state)`` give and take a dict of NumPy arrays
    from which the run continues bit for bit; ``total_energy`` and
    ``reduced_mass`` are floats.
    """

    total_energy: float
    reduced_mass: float

    def next_collision(self): ...

    def get_state(self) -> dict: ...

    def set_state(self, state: dict) -> None: ...


class Stopwatch:
    """Wall-clock timer: ``with Stopwatch() as sw: ...; sw.seconds``."""

    def __enter__(self):
        self._start = time.perf_counter()
        self.seconds = 0.0
        return self

    def __exit__(self, *exc):
        self.seconds = time.perf_counter() - self._start
        return False


def scene_numbers(scene: Scene) -> tuple:
    """``(gamma, kappa)`` of a two-rod line scene of one material, else ``(nan, nan)``.

    The one rule by which every solver reports the paper's numbers.
    """
    try:
        params = two_rod_parameters(scene)
    except InvalidParameterError:
        return math.nan, math.nan
    return float(params.gamma), float(params.kappa)


#: Default safety factor of the Richardson error estimate (docs/error_estimates.md).
ERROR_SAFETY = 3.0
#: Smallest error estimate reported: the round-off a run of many steps leaves in an O(1) restitution.
ERROR_FLOOR = 1e-13


def richardson_estimate(values, order: float, ratio: float = 2.0, safety: float = ERROR_SAFETY) -> float:
    """Error of ``values[0]`` from runs at ``1/ratio``, ``1/ratio**2`` ... of its resolution.

    ``safety * D / (ratio**order - 1)`` for an error that falls like
    ``resolution**-order``, with ``D = |v0 - v1|``, or, given a third run, the larger
    of that and ``|v1 - v2| / ratio**order`` (the coarser pair's difference carried to
    the finest level: a guard against two runs that agree by accident).
    """
    differences = [abs(a - b) / ratio ** (order * i) for i, (a, b) in enumerate(itertools.pairwise(values))]
    return max(safety * max(differences) / (ratio**order - 1.0), ERROR_FLOOR)


def excess_bound(estimate: float, restitution: float, cold: bool) -> float:
    """The estimate raised to at least ``restitution - 1`` where a cold collision came out above 1
    (it cannot gain energy: the excess is error, whatever the estimate said); NaN stays NaN."""
    if restitution > 1.0 and cold and not math.isnan(estimate):
        return max(estimate, restitution - 1.0)
    return estimate


def _tolerance(value):
    if value is None:
        return None
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"tolerance must be a number in (0, 1] or None, got {value!r}") from None
    if isinstance(value, bool) or not 0.0 < number <= 1.0:
        raise InvalidParameterError(f"tolerance must be a number in (0, 1] or None, got {value!r}")
    return number


_REUSED_RUNS: list = []  # while reusing_runs() is active: one dict {(solver, scene id, options): restitution}


@contextlib.contextmanager
def reusing_runs():
    """Inside, a Richardson level whose run was made before (same solver, scene object and options, the
    recording options aside) reuses that run's restitution instead of running again: a refinement to
    twice the resolution then makes one new run, not three.  Outside, nothing is remembered."""
    _REUSED_RUNS.append({})
    try:
        yield
    finally:
        _REUSED_RUNS.pop()


def _run_key(name: str, scene: Scene, options):
    quiet = {field: False for field in ("history", "record_fields") if hasattr(options, field)}
    try:
        key = (name, id(scene), options.replace(**quiet) if quiet else options)
        hash(key)
    except TypeError:
        return None
    return key


def _remember_run(name: str, scene: Scene, options, fields: dict) -> None:
    if _REUSED_RUNS:
        key = _run_key(name, scene, options)
        if key is not None:
            _REUSED_RUNS[-1][key] = (scene, float(fields.restitution))  # the scene kept: its id stays its own


_OPTIONS_CACHE: dict = {}
_OPTIONS_CACHE_SIZE = 256


class SolverBase:
    """Shared implementation of :class:`Solver`; a solver supplies ``_collide``.

    ``_collide(scene, options)`` returns a :class:`CollisionFields`.  A solver
    lists what it offers beyond ``solve`` in :attr:`capabilities` and overrides
    that capability's methods (:data:`CAPABILITIES`); the others refuse.
    """

    name: str = "abstract"
    #: what the solver is called in help texts (``"delay solver"``)
    title: str = "solver"
    #: the options ``wavecontact collide`` exposes as flags, each with its help text (None: the option's own)
    cli_flags: Mapping = MappingProxyType({})
    #: the contact laws the solver takes by name (``contact=`` of :func:`wavecontact.two_rods`)
    contact_names: tuple = ("exponential", "hard")
    #: names of the :data:`CAPABILITIES` the solver offers
    capabilities: frozenset = frozenset()
    #: the scenes on a line the solver takes, for its refusal of the others (``solve_line``)
    line_scenes_taken: str = "the paper's two uniform rods only"
    #: options a batch of many thermal samples runs with where the caller gives none (ensembles, Markov)
    batch_defaults: Mapping = MappingProxyType({})
    #: the contract tests' order case: resolutions (coarse to fine) and options held fixed
    #: (tests/test_solver_contract.py), and the resolution and tolerance at which the
    #: solver must agree with the contract tests' reference epsilon(0.6, 20)
    order_case: Mapping = MappingProxyType({"resolutions": (), "options": {}})
    agreement_case: tuple = ({}, 0.0)
    Options: type = SolverOptions
    resolution: str = ""
    refines: int = 1
    #: safety factor of the Richardson error estimate (measured per solver, docs/error_estimates.md)
    error_safety: float = ERROR_SAFETY
    #: coarser runs of the Richardson estimate (each at half the resolution of the previous one)
    error_levels: int = 1

    def expected_order(self, options) -> float | None:
        return None

    def coarser_levels(self, options) -> int:
        """How many coarser runs the Richardson estimate of a run with ``options`` makes
        (:attr:`error_levels`; a solver may use fewer where its rule does not need them)."""
        del options
        return self.error_levels

    def options(self, given: Mapping | None = None):
        """Validated options from a mapping (or the defaults).

        Options are frozen, so the same arguments give the same object: a small cache keyed by
        each value and its type (``True`` and ``1`` stay apart) spares sweeps of fast solves
        the validation; unhashable values (arrays, noise objects) are validated every time.
        """
        if isinstance(given, self.Options):
            return given
        given = dict(given or {})
        try:
            key = (self.Options, frozenset((name, type(value), value) for name, value in given.items()))
            cached = _OPTIONS_CACHE.get(key)
        except TypeError:
            return self.Options.from_mapping(given)
        if cached is None:
            cached = self.Options.from_mapping(given)
            if len(_OPTIONS_CACHE) >= _OPTIONS_CACHE_SIZE:
                _OPTIONS_CACHE.clear()
            _OPTIONS_CACHE[key] = cached
        return cached

    # ------------------------------------------------------------ cost and error hooks
    def estimate_cost(self, scene: Scene, options) -> Cost | None:
        """The cost of ``solve(scene, options)`` estimated before any work (None: not estimated)."""
        return None

    def error_estimate_runs(self, scene: Scene, options) -> list:
        """Options of the extra runs the error estimate will make (the coarser levels), so that
        their cost is checked with the solve's before any work."""
        del scene
        runs, coarse = [], options
        for _ in range(self.coarser_levels(options)):
            coarse = self.coarser_options(coarse)
            if coarse is None:
                break
            runs.append(coarse)
        return runs

    def total_cost(self, scene: Scene, options, estimating: bool) -> Cost | None:
        """:meth:`estimate_cost` of the solve plus, when ``estimating``, of the error estimate's runs
        (their work added, the largest memory kept)."""
        cost = self.estimate_cost(scene, options)
        if cost is None or not estimating:
            return cost
        extra = [c for c in (self.estimate_cost(scene, o) for o in self.error_estimate_runs(scene, options))
                 if c is not None]
        if not extra:
            return cost
        added = sum(c.work for c in extra)
        return Cost(steps=cost.steps, work=cost.work + added, memory=max([cost.memory] + [c.memory for c in extra]),
                    detail=f"{cost.detail}; the error estimate's {len(extra)} runs add {added:.3g} updates")

    def coarser_options(self, options) -> SolverOptions | None:
        """Options at half the resolution, for the Richardson error estimate (None: no estimate)."""
        del options
        return None

    def estimate_order(self, scene: Scene, options) -> float | None:
        """Order in the resolution assumed by the error estimate (the regime's, not always the
        declared one: an unresolved contact converges more slowly)."""
        return self.expected_order(options)

    def _error_estimate(self, scene: Scene, options, fields: CollisionFields) -> tuple:
        """``(estimate, method, levels)`` of the solve's error: the solver's own, or Richardson.

        ``levels`` lists ``(resolution, restitution)`` of the requested run and of each coarser
        run the estimate used (empty for the solver's own estimate).
        """
        own = float(fields.error_estimate)
        if not math.isnan(own):
            return own, "the solver's own estimate", []
        levels, coarse_options = [(getattr(options, self.resolution, None), float(fields.restitution))], options
        failure_text = ""
        for _ in range(self.coarser_levels(options)):
            coarse_options = self.coarser_options(coarse_options)
            if coarse_options is None:
                break
            try:
                value = self._coarse_restitution(scene, coarse_options)
            except SolverFailure as failure:
                failure_text = str(failure)
                break
            levels.append((getattr(coarse_options, self.resolution), value))
        if len(levels) == 1:
            why = f"the run at half the resolution failed: {failure_text}" if failure_text else "no coarser resolution"
            return math.nan, f"none ({why})", levels
        estimate, rule = self.estimate_from_levels(scene, options, levels)
        if math.isnan(estimate):
            return estimate, f"none ({rule})", levels
        runs = "; ".join(f"{self.resolution}={n} gave {value:.12g}" for n, value in levels[1:])
        return estimate, f"Richardson: {runs}; {rule}", levels

    def _coarse_restitution(self, scene: Scene, options) -> float:
        """The restitution of a run at ``options`` (a Richardson level): remembered inside
        :func:`reusing_runs`, else run."""
        key = _run_key(self.name, scene, options) if _REUSED_RUNS else None
        if key is not None and key in _REUSED_RUNS[-1]:
            return _REUSED_RUNS[-1][key][1]
        fields = self._collide(scene, options)
        if key is not None:
            _REUSED_RUNS[-1][key] = (scene, float(fields.restitution))
        return float(fields.restitution)

    def estimate_from_levels(self, scene: Scene, options, levels: list) -> tuple:
        """``(estimate, rule)`` from ``levels``: ``(resolution, restitution)`` of the requested run
        first, then of each coarser run (at least one).

        The default: :func:`richardson_estimate` with :meth:`estimate_order` and
        :attr:`error_safety` (a solver may replace the rule).
        """
        order = self.estimate_order(scene, options)
        if order is None:
            return math.nan, "no order for this regime"
        return (richardson_estimate([value for _, value in levels], order, safety=self.error_safety),
                f"order {order:.3g}, safety {self.error_safety:g}")

    def _advice(self, options, estimate: float, tolerance: float) -> str:
        """Which resolution should bring the error estimate below ``tolerance``."""
        level = getattr(options, self.resolution, None)
        order = self.expected_order(options) or 1.0
        if level is None or math.isnan(estimate):
            return "no estimate: choose a finer resolution or another solver"
        factor = (estimate / tolerance) ** (1.0 / order)
        spec = next(f.metadata["option"] for f in dataclasses.fields(self.Options) if f.name == self.resolution)
        if self.refines > 0:
            wanted = math.ceil(1.2 * level * factor)
            if spec["high"] is not None and wanted > spec["high"]:
                return (f"{self.resolution}={wanted} would be needed, beyond this solver's range "
                        f"({spec['high']:g}); use solver='delay' for two rods of one material")
            return f"try {self.resolution}={wanted}"
        wanted = level / (1.2 * factor)
        if spec["low"] is not None and wanted < spec["low"]:
            return f"{self.resolution}={wanted:.2g} would be needed, below this solver's range ({spec['low']:g})"
        return f"try {self.resolution}={wanted:.2g}"

    def solve(self, scene: Scene, options=None, *, tolerance=None, max_work=None, max_memory=None,
              estimate_error: bool = True) -> CollisionResult:
        """One collision of ``scene`` (see the module docstring).

        Parameters
        ----------
        scene : Scene
        options : mapping or Options
        tolerance : float or None
            Largest acceptable error estimate of the restitution; a larger one
            raises :class:`~wavecontact.errors.AccuracyError` with advice.
        max_work, max_memory : float or None
            Cost limits (:class:`wavecontact.limits.Limits`), checked against
            :meth:`estimate_cost` before anything runs.
        estimate_error : bool
            Estimate the error (for FE and modal: one more run at half the
            resolution, about a quarter of the cost); False leaves NaN.
        """
        if not isinstance(scene, Scene):
            raise InvalidParameterError(f"scene must be a wavecontact.Scene, got {type(scene).__name__}")
        if scene.is_line_scene:  # piecewise rods, rigid bodies, chains, walls: an ImpactResult
            return self.solve_line(scene, options, tolerance=tolerance, max_work=max_work, max_memory=max_memory,
                                   estimate_error=estimate_error)
        options = self.options(options)
        tolerance = _tolerance(tolerance)
        limits = Limits(max_work=max_work, max_memory=max_memory)
        gamma, kappa = scene_numbers(scene)
        if "two_rods" not in scene.metadata:  # two_rods checked its kappa where it built the scene
            check_kappa(kappa)
        check_cost(self.name, self.total_cost(scene, options, estimate_error or tolerance is not None), limits)
        prepared = prepared_kernel_count()
        interpreted = interpreted_call_count()
        with Stopwatch() as watch:
            fields = self._collide(scene, options)
            _remember_run(self.name, scene, options, fields)
            with Stopwatch() as estimating:
                if estimate_error or tolerance is not None:
                    estimate, method, levels = self._error_estimate(scene, options, fields)
                else:
                    estimate, method, levels = math.nan, "not requested", []
        restitution = float(fields.restitution)
        rough = self.rough_estimate(scene, options) if levels else ""
        cold = scene.is_cold and getattr(scene, "vibrations", None) is None and getattr(options, "noise", None) is None
        estimate = excess_bound(estimate, restitution, cold)
        time_, force = np.asarray(fields.time, dtype=float), fields.contact_force
        start, duration = contact_window(time_, force, fields.force_sampling)
        result = CollisionResult(
            restitution=restitution,
            solver=self.name,
            gamma=gamma,
            kappa=kappa,
            error_estimate=float(estimate),
            wall_time_s=watch.seconds,
            time=time_,
            relative_velocity=np.asarray(fields.relative_velocity, dtype=float),
            contact_force=None if force is None else np.asarray(force, dtype=float),
            contact_start=start,
            contact_duration=duration,
            options=options.as_dict(),
            work=dict(fields.work),
            diagnostics={
                "energy_drift": float(fields.energy_drift),
                "momentum_drift": float(fields.momentum_drift),
                "includes_kernel_preparation": prepared_kernel_count() > prepared,
                "interpreted_kernels": interpreted_call_count() > interpreted,
                "error_estimate_method": method,
                "error_estimate_seconds": estimating.seconds,
                "error_estimate_levels": levels,
                "error_estimate_rough": rough,
            },
            extra=self._complete_extra(scene, fields),
        )
        if tolerance is not None and not estimate <= tolerance:
            advice = self._advice(options, estimate, tolerance)
            raise AccuracyError(
                f"{self.name}: error estimate {estimate:.2g} of epsilon = {restitution:.10g} exceeds "
                f"tolerance={tolerance:g}; {advice}", result=result, advice=advice)
        if tolerance is not None and rough:
            raise AccuracyError(
                f"{self.name}: the error estimate {estimate:.2g} of epsilon = {restitution:.10g} cannot be trusted "
                f"to meet tolerance={tolerance:g}: {rough}", result=result, advice=rough)
        return result

    def _complete_extra(self, scene: Scene, fields: CollisionFields) -> dict:
        """``fields.extra`` with, for a scene carrying vibrations drawn from a bath
        (:func:`wavecontact.bath.collide.thermal_scene`), the per-rod split
        ``vibration_energy_gain`` (where the solver gives one) and the bath's parameters ``bath``."""
        extra = dict(fields.extra)
        bath = scene.metadata.get("bath") if scene.vibrations is not None else None
        if bath is None:
            return extra
        gain = self.vibration_energy_gain(fields, scene) if self.offers(ENERGY_SPLIT) else None
        if gain is not None:
            extra["vibration_energy_gain"] = gain
        extra["bath"] = dict(bath)
        return extra

    def vibration_energy_gain(self, fields: CollisionFields, scene: Scene):
        """Energy each rod's vibrations gained in the collision of ``scene`` (units with ``E_tr = 1/4``),
        an array of two, from the solver's own bookkeeping (:data:`ENERGY_SPLIT`; None for a run
        that gives no split)."""
        raise _not_offered(self, ENERGY_SPLIT)

    # ------------------------------------------------------------ comparisons (wavecontact compare)
    def comparison_methods(self, kappa: float) -> list:
        """A few resolutions of each discretization, cheap to expensive, for the comparison of every
        solver on one collision: ``(options, label, work_unit)`` each (``work_unit``: the counter of
        ``result.work`` that measures the effort)."""
        del kappa
        return [({}, "defaults", "steps")]

    def comparison_family(self, options) -> str:
        """The series of a comparison figure that a run with ``options`` belongs to: one per
        solver and discretization."""
        del options
        return self.name

    # ------------------------------------------------------------ capabilities (see CAPABILITIES)
    def offers(self, capability: str) -> bool:
        """Whether the solver offers ``capability`` (a key of :data:`CAPABILITIES`)."""
        if capability not in CAPABILITIES:
            raise InvalidParameterError(f"capability must be one of {', '.join(map(repr, CAPABILITIES))}, "
                                        f"got {capability!r}")
        return capability in self.capabilities

    def thermal_restitution(self, scene: Scene, options=None) -> float:
        """epsilon of a finite-kappa thermal scene as :meth:`solve` gives it, without the result object
        (:data:`THERMAL_BATCH`)."""
        raise _not_offered(self, THERMAL_BATCH)

    def thermal_restitutions(self, gamma: float, kappa: float, bath, seeds, options=None) -> tuple:
        """``(epsilon, error_estimate)`` arrays of many finite-kappa thermal collisions of the paper's rods,
        one per seed (:data:`THERMAL_BATCH`)."""
        raise _not_offered(self, THERMAL_BATCH)

    def hard_core_thermal_restitution(self, gamma: float, vibrations, resolution: int = 8,
                                      tau_free: float = 0.0) -> float:
        """epsilon of one hard-core collision of the paper's rods carrying ``vibrations``
        (:data:`HARD_CORE_THERMAL`)."""
        raise _not_offered(self, HARD_CORE_THERMAL)

    def hard_core_thermal_batch(self, gamma: float, temperature, seeds, modes: int = 250, resolution: int = 8):
        """epsilon of many hard-core thermal collisions, one per seed (:data:`HARD_CORE_THERMAL`)."""
        raise _not_offered(self, HARD_CORE_THERMAL)

    def hard_core_grid_points(self, gamma: float, modes: int = 250, resolution: int = 8) -> int:
        """Grid points per short round trip of the hard-core grid at ``resolution`` (:data:`HARD_CORE_THERMAL`)."""
        raise _not_offered(self, HARD_CORE_THERMAL)

    def hard_core_thermal_split(self, gamma: float, temperature_ratio, seed, *, bath_modes: int = 250,
                                resolution: int = 8, temperatures=None) -> tuple:
        """``(epsilon^2, gain_1, gain_2)`` of one hard-core thermal collision (:data:`HARD_CORE_THERMAL`)."""
        raise _not_offered(self, HARD_CORE_THERMAL)

    def check_ratios(self, impedance_ratio: float, time_ratio: float) -> None:
        """Refuse ratios the solver cannot take (:data:`MATERIAL_RATIOS`)."""
        raise _not_offered(self, MATERIAL_RATIOS)

    def restitution_of_ratios(self, impedance_ratio: float, time_ratio: float, kappa: float,
                              rtol: float = 1e-8) -> float:
        """epsilon of a cold two-material collision from ``Z_2 / Z_1``, ``T_1 / T_2`` and ``kappa``
        (:data:`MATERIAL_RATIOS`)."""
        raise _not_offered(self, MATERIAL_RATIOS)

    def solve_line(self, scene: Scene, options=None, **limits):
        """A scene beyond the paper's two uniform rods (:attr:`Scene.is_line_scene`): refused here, the fem
        solver takes it (:mod:`wavecontact.fem.multibody`)."""
        del options, limits
        raise UnsupportedSceneError(
            f"solver {self.name!r} takes {self.line_scenes_taken}; this scene ({len(scene.rods)} bodies: "
            "piecewise rods, rigid bodies, chains or walls) needs solver='fem'")

    def rough_estimate(self, scene: Scene, options) -> str:
        """Why the error estimate of this run is only an order of magnitude, not a bound ("" if it is
        one): ``tolerance=`` then refuses the result, with this text as advice."""
        del scene, options
        return ""

    def simulate(self, scene: Scene, options=None) -> Any:
        """A running simulation of many collisions of a ring scene (:data:`RING`; a :class:`RepeatedCollisions`)."""
        raise UnsupportedSceneError(f"solver {self.name!r} runs single collisions only; use solver='modal' "
                                    "for many collisions on a ring")

    def _collide(self, scene: Scene, options) -> CollisionFields:  # pragma: no cover - abstract
        raise NotImplementedError

    def __repr__(self):
        return f"<wavecontact solver {self.name!r}>"


__all__ += ["CONTACT_FORCE_FRACTION", "scene_numbers"]
