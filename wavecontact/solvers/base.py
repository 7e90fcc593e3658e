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
    one collision, returned as a complete :class:`~wavecontact.result.CollisionResult`.

:class:`SolverBase` implements ``solve`` once for all solvers: it times the
solver's own ``_collide``, recovers the paper's ``gamma`` and ``kappa`` from
the scene, measures the contact window from the force history by one rule,
and builds the result in one go.  Solvers that can run many collisions of a
ring scene also offer ``simulate(scene, options)`` (see
:class:`RepeatedCollisions`).
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable, Mapping
from typing import Any, ClassVar, Protocol, runtime_checkable

import numpy as np

from .._jit import prepared_kernel_count
from ..errors import InvalidParameterError, UnsupportedSceneError
from ..result import CONTACT_FORCE_FRACTION, CollisionResult, Outcome, contact_window
from ..scene import Scene, two_rod_parameters

__all__ = [
    "RepeatedCollisions",
    "Solver",
    "SolverBase",
    "SolverOptions",
    "Stopwatch",
    "option",
    "option_help",
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

    def __post_init__(self):
        for f in dataclasses.fields(self):
            spec = f.metadata.get("option")
            if spec is not None:
                object.__setattr__(self, f.name, _validate(self.solver_name, f.name, spec, getattr(self, f.name)))

    @classmethod
    def from_mapping(cls, given: Mapping):
        """Options from keyword arguments, refusing unknown names."""
        allowed = {f.name for f in dataclasses.fields(cls)}
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
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}


def option_help(options_class) -> list:
    """``(name, default, allowed, help)`` of every option of an options class, for docs and ``--help``."""
    rows = []
    for f in dataclasses.fields(options_class):
        spec = f.metadata.get("option")
        if spec is not None:
            rows.append((f.name, f.default, _range_text(spec), spec["help"]))
    return rows


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


class SolverBase:
    """Shared implementation of :class:`Solver`; a solver supplies ``_collide``.

    ``_collide(scene, options)`` returns a dict with the keys
    ``restitution``, ``time``, ``relative_velocity``, ``contact_force``
    (or None), ``error_estimate`` (NaN if none), ``energy_drift``,
    ``momentum_drift`` (relative; NaN if not tracked), ``work`` and ``extra``.
    """

    name: str = "abstract"
    Options: type = SolverOptions
    resolution: str = ""
    refines: int = 1

    def expected_order(self, options) -> float | None:
        return None

    def options(self, given: Mapping | None = None):
        """Validated options from a mapping (or the defaults)."""
        if isinstance(given, self.Options):
            return given
        return self.Options.from_mapping(dict(given or {}))

    def solve(self, scene: Scene, options=None) -> CollisionResult:
        """One collision of ``scene`` (see the module docstring)."""
        if not isinstance(scene, Scene):
            raise InvalidParameterError(f"scene must be a wavecontact.Scene, got {type(scene).__name__}")
        options = self.options(options)
        prepared = prepared_kernel_count()
        with Stopwatch() as watch:
            fields = self._collide(scene, options)
        gamma, kappa = scene_numbers(scene)
        time_, force = np.asarray(fields["time"], dtype=float), fields.get("contact_force")
        start, duration = contact_window(time_, force, fields.get("force_sampling", "point"))
        return CollisionResult(
            restitution=float(fields["restitution"]),
            solver=self.name,
            outcome=Outcome.SEPARATED,
            gamma=gamma,
            kappa=kappa,
            error_estimate=float(fields.get("error_estimate", math.nan)),
            wall_time_s=watch.seconds,
            time=time_,
            relative_velocity=np.asarray(fields["relative_velocity"], dtype=float),
            contact_force=None if force is None else np.asarray(force, dtype=float),
            contact_start=start,
            contact_duration=duration,
            options=options.as_dict(),
            work=dict(fields.get("work", {})),
            diagnostics={
                "energy_drift": float(fields.get("energy_drift", math.nan)),
                "momentum_drift": float(fields.get("momentum_drift", math.nan)),
                "includes_kernel_preparation": prepared_kernel_count() > prepared,
            },
            extra=dict(fields.get("extra", {})),
        )

    def simulate(self, scene: Scene, options=None) -> Any:
        raise UnsupportedSceneError(f"solver {self.name!r} runs single collisions only; use solver='modal' "
                                    "for many collisions on a ring")

    def _collide(self, scene: Scene, options) -> dict:  # pragma: no cover - abstract
        raise NotImplementedError

    def __repr__(self):
        return f"<wavecontact solver {self.name!r}>"


__all__ += ["CONTACT_FORCE_FRACTION", "scene_numbers"]
