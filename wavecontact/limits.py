"""Limits on what a run may cost, checked before a solver allocates or runs anything.

Every solver estimates, from the scene and its options alone, how many time
steps it will take, how much work they are (steps times the unknowns each
step touches: ``work`` is a count of elementary updates, a few nanoseconds
each in the compiled kernels) and how much memory it will hold
(:class:`Cost`).  :func:`check_cost` compares the estimate with the limits
of the call and refuses, with the estimate and the option that raises the
limit, before any work is done.

Limits and their defaults (``docs/error_estimates.md`` lists them too):

``max_work`` (default :data:`DEFAULT_MAX_WORK` = 2e11 updates: under a minute on the FE lattice, tens of minutes for the general schemes)
    estimated updates (FE: time steps x nodes; modal: steps x modes x stages;
    delay: steps x delayed copies summed per step);
``max_memory`` (default: half of the memory available now, :func:`available_memory`)
    estimated bytes held at once;
``kappa`` in [:data:`KAPPA_MIN`, :data:`KAPPA_MAX`] or ``inf``
    the supported softness of the paper's two rods (outside it the delay
    reference takes minutes or stops at its step limit, and the modal and FE
    contact steps shrink like 1/kappa);
the solvers' own option ranges (``elements``, ``modes``, ``courant`` ...),
    declared with their options.

Studies of many solves are checked as a whole by :func:`check_study_cost`
(the command line's ``--max-work``); :func:`ring_cost` bounds a run of ring
collisions (steps per collision :func:`ring_steps`, records held in memory).
"""

from __future__ import annotations

import math
import os
import time
from dataclasses import dataclass

from .errors import InvalidParameterError, LimitError

__all__ = [
    "DEFAULT_MAX_WORK",
    "KAPPA_MAX",
    "KAPPA_MIN",
    "Cost",
    "Limits",
    "available_memory",
    "check_cost",
    "check_kappa",
    "check_study_cost",
    "format_bytes",
    "ring_cost",
    "ring_steps",
]

#: Supported softness of the paper's two rods (besides ``inf``, the hard core).
KAPPA_MIN = 1e-2
KAPPA_MAX = 1e7
#: Default bound on the estimated work of one solve (elementary updates; a few ns each).
DEFAULT_MAX_WORK = 2e11
#: Share of the available memory one solve may take by default.
MEMORY_SHARE = 0.5


#: Steps per collision of the ring integrator are at most ``N (RING_STEPS_PER_MODE + RING_SOFT_STEPS_PER_MODE / kappa)``
#: (measured with the counter ``next_collision().steps``, gamma 0.2-1: the kick-rotate-kick splitting takes up to
#: 746 N for stiff contacts and 2212 N at kappa = 0.01 (N = 8-1000); the exponential collocation, the ring's default
#: integrator, up to 175 N at kappa >= 1, 670 N at kappa = 0.1 and 6299 N at kappa = 0.01 (N = 8 and 40);
#: tests/test_cli_costs.py checks the bound).
RING_STEPS_PER_MODE, RING_SOFT_STEPS_PER_MODE = 800, 70
#: Bytes held per recorded ring collision and mode (modal energies in lists, then one array) and the rest.
RING_BYTES_PER_MODE, RING_BYTES_PER_COLLISION = 32, 400

_MEMORY_READ = [-math.inf, 0]  # (when, bytes): /proc/meminfo read at most once a second


def available_memory() -> int:
    """Memory available to a new allocation now (bytes).

    ``MemAvailable`` of ``/proc/meminfo`` where it exists (Linux), else the
    free physical pages from ``os.sysconf``, else 4 GiB.  Read at most once a
    second (a solve of a fraction of a millisecond should not pay for the read).
    """
    now = time.monotonic()
    if now - _MEMORY_READ[0] < 1.0:
        return _MEMORY_READ[1]
    _MEMORY_READ[:] = [now, _read_available_memory()]
    return _MEMORY_READ[1]


def _read_available_memory() -> int:
    try:
        with open("/proc/meminfo", encoding="ascii") as handle:
            for line in handle:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return int(os.sysconf("SC_AVPHYS_PAGES")) * int(os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):
        return 4 * 2**30


def format_bytes(size: float) -> str:
    """``1.5 GiB`` style text of a byte count."""
    for unit, scale in (("TiB", 2**40), ("GiB", 2**30), ("MiB", 2**20), ("KiB", 2**10)):
        if size >= scale:
            return f"{size / scale:.3g} {unit}"
    return f"{size:.0f} B"


def _limit_value(name: str, value, default: float) -> float:
    if value is None:
        return default
    if isinstance(value, bool):
        raise InvalidParameterError(f"{name} must be a positive number, got {value!r}")
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"{name} must be a positive number, got {value!r}") from None
    if not number > 0.0 or math.isnan(number):
        raise InvalidParameterError(f"{name} must be a positive number (or inf for no limit), got {value!r}")
    return number


@dataclass(frozen=True)
class Limits:
    """The cost limits of one solve (validated; ``None`` means the default).

    Parameters
    ----------
    max_work : float or None
        Largest estimated work (elementary updates); default :data:`DEFAULT_MAX_WORK`.
    max_memory : float or None
        Largest estimated memory (bytes); default half of :func:`available_memory`.
    """

    max_work: float | None = None
    max_memory: float | None = None

    def __post_init__(self):
        object.__setattr__(self, "max_work", _limit_value("max_work", self.max_work, DEFAULT_MAX_WORK))
        memory = self.max_memory
        if memory is None:
            memory = MEMORY_SHARE * available_memory()
            object.__setattr__(self, "_memory_default", True)
        else:
            object.__setattr__(self, "_memory_default", False)
        object.__setattr__(self, "max_memory", _limit_value("max_memory", memory, 0.0))


@dataclass(frozen=True)
class Cost:
    """What a solve is estimated to cost, from its scene and options alone.

    Attributes
    ----------
    steps : float
        Time steps (or accepted steps of an adaptive integrator).
    work : float
        Elementary updates (``steps`` times the unknowns touched per step).
    memory : float
        Bytes held at once.
    detail : str
        What the estimate counts, for the message (``"2.7e6 nodes, 6.3e6 steps"``).
    """

    steps: float
    work: float
    memory: float
    detail: str = ""


def check_cost(solver: str, cost: Cost | None, limits: Limits) -> None:
    """Refuse a solve whose estimated cost exceeds ``limits`` (:class:`~wavecontact.errors.LimitError`)."""
    if cost is None:
        return
    detail = f" ({cost.detail})" if cost.detail else ""
    if not cost.memory <= limits.max_memory:
        source = "half the available memory" if limits._memory_default else "max_memory"
        raise LimitError(
            f"{solver}: this solve would need about {format_bytes(cost.memory)}{detail}, more than "
            f"{format_bytes(limits.max_memory)} ({source}); use a coarser resolution or pass "
            f"max_memory={math.ceil(cost.memory):d} (bytes) to allow it"
        )
    if not cost.work <= limits.max_work:
        raise LimitError(
            f"{solver}: this solve would take about {cost.work:.2g} updates{detail}, more than "
            f"max_work={limits.max_work:.3g}; use a coarser resolution or pass max_work={cost.work:.2g} "
            "to allow it"
        )


def check_study_cost(what: str, cost: Cost, limits: Limits, advice: str) -> None:
    """Refuse a study (many solves) whose estimated total cost exceeds ``limits``.

    Parameters
    ----------
    what : str
        The run, for the message (``"ring: 5 collisions at N = 20000"``).
    cost : Cost
        Its estimated total work (updates) and memory (bytes held at once).
    limits : Limits
        The bounds (``max_work`` default :data:`DEFAULT_MAX_WORK`).
    advice : str
        How to make the run smaller (``"use fewer --collisions"``); the message
        adds how to raise the bound.

    Raises
    ------
    LimitError
        With the estimate, the bound and how to proceed.
    """
    detail = f" ({cost.detail})" if cost.detail else ""
    if not cost.memory <= limits.max_memory:
        source = "half the available memory" if limits._memory_default else "max_memory"
        raise LimitError(f"{what} would hold about {format_bytes(cost.memory)}{detail}, more than "
                         f"{format_bytes(limits.max_memory)} ({source}); {advice}")
    if not cost.work <= limits.max_work:
        raise LimitError(f"{what} would take about {cost.work:.2g} updates{detail}, more than "
                         f"max_work = {limits.max_work:.3g} (a few ns each); {advice}, or pass "
                         f"--max-work {cost.work:.2g} to allow it")


def check_kappa(kappa, name: str = "kappa") -> None:
    """Refuse a finite ``kappa`` outside the supported range [:data:`KAPPA_MIN`, :data:`KAPPA_MAX`]
    (``name``: how the message calls it, e.g. ``--kappa``)."""
    if math.isfinite(kappa) and not KAPPA_MIN <= kappa <= KAPPA_MAX:
        raise InvalidParameterError(
            f"{name} must lie in [{KAPPA_MIN:g}, {KAPPA_MAX:g}] or be inf (hard contact), got {kappa:g}: "
            "softer contacts last longer than the solvers' step limits allow; stiffer ones differ from "
            "the hard limit by about ln(kappa)/kappa < 2e-6 (use kappa=inf)"
        )


def ring_steps(kappa: float, modes: int) -> float:
    """Bound on the steps of one ring collision with ``modes`` modes per rod at softness ``kappa``."""
    return float(modes) * (RING_STEPS_PER_MODE + RING_SOFT_STEPS_PER_MODE / kappa)


def ring_cost(kappa: float, modes, collisions: int, copies: int = 1) -> Cost:
    """``copies`` runs of ``collisions`` ring collisions at each mode count in ``modes``."""
    modes = [int(n) for n in modes]
    steps = sum(ring_steps(kappa, n) * collisions * copies for n in modes)
    work = sum(ring_steps(kappa, n) * 2.0 * n * collisions * copies for n in modes)
    memory = max(float(collisions) * (RING_BYTES_PER_MODE * 2 * n + RING_BYTES_PER_COLLISION) for n in modes)
    return Cost(steps=steps, work=work, memory=memory,
                detail=f"at most {ring_steps(kappa, max(modes)):.3g} steps per collision over 2N modes, "
                       f"{format_bytes(memory)} of records")
