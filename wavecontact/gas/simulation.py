"""Running a rod gas: the event loop in chunks, histories, collapse detection, checkpoints.

>>> from wavecontact.gas import FixedRestitution, GasSimulation, random_gas
>>> sim = GasSimulation(random_gas(50, seed=1), FixedRestitution(0.95), seed=2, record_every=100)
>>> result = sim.run(1000)
>>> result.collisions, result.collapsed
(1000, False)
"""

from __future__ import annotations

import json
import math
import time
from dataclasses import dataclass, field

import numpy as np

from ..errors import CheckpointError, InvalidParameterError, require_integer, require_positive
from ..io.checkpoint import read_checkpoint, write_checkpoint
from ..io.run_controller import KeywordGroup, RunController
from ..restitution_table import RestitutionTable
from . import kernels
from .collision_law import LAW_ARRAYS, law_from_arrays
from .model import RodGas
from .rules import FixedRestitution, VibrationLaw, VibrationSolve, VibrationTable, rule_from_description

__all__ = ["CHECKPOINT_NAME", "MAX_COLLISIONS", "GasResult", "GasSimulation", "StoppingRules", "run_gas"]

MAX_COLLISIONS = 10**11
MAX_RECORDS = 10**7  # history rows one run may add (6 floats each)
CHECKPOINT_SCHEMA = "wavecontact.gas"
CHECKPOINT_VERSION = 3  # 2: the event times (leaves of a tournament tree) instead of a heap; 3: law v2, stiffness
_HISTORY = ("time", "collisions", "kinetic_energy", "bath_energy", "lost_energy", "dissipated_energy")
_STATUS = {
    kernels.STATUS_DONE: "completed",
    kernels.STATUS_TIME_LIMIT: "time_limit",
    kernels.STATUS_COLLAPSE: "collapsed",
    kernels.STATUS_NO_EVENTS: "no_events",
    kernels.STATUS_COOLED: "cooled",
    kernels.STATUS_OFF_TABLE: "off_table",
    kernels.STATUS_FROZEN: "frozen",
}
COLLAPSE_RODS = 3  # bodies a collapsing cluster joins at least (McNamara & Young's smallest collapse: three rods)
FROZEN_SPEED = 2.0**-50  # a relative velocity below this fraction of the pair's speed is rounding (4 ulps)
FROZEN_POSITION = 2.0**-48  # a gap below this fraction of the centres' magnitude is rounding (16 ulps)
COLLAPSE_CLOCK = 2.0**-50  # collisions within this fraction of the clock happen at one time (4 ulps)


@dataclass
class GasResult:
    """What a run of :meth:`GasSimulation.run` produced (energies in mass x velocity^2).

    Attributes
    ----------
    status : str
        ``completed``, ``collapsed``, ``cooled`` (below ``energy_floor``), ``frozen`` (the relative
        velocities were lost in the rounding: not a collapse), ``time_limit``, ``no_events``
        or ``off_table`` (a pair met at a temperature ratio outside the restitution table; the run stops
        there rather than extrapolate or clip the table).
    message : str
        One line for a human (says why a run stopped early).
    collisions, wall_hits : int
        Rod-rod collisions and wall reflections since the simulation began.
    simulated_time : float
        Time of the last event.
    wall_time_s : float
        Wall-clock time of this call.
    collisions_per_second : float
        Collisions of this call per wall-clock second.
    history : dict of ndarray
        At every ``record_every`` collisions, and at the end of the run: ``time``, ``collisions``,
        ``kinetic_energy`` (in the centre-of-mass frame on a ring),
        ``bath_energy``, ``lost_energy`` (fixed rule), ``dissipated_energy``
        (bath damping).
    frame_times, frames : ndarray
        Space-time picture: rod centres (centre-of-mass frame, wrapped into
        the ring) at ``frame_times``; shape (F, rods shown).
    velocities, bath_temperatures : ndarray
        The final state.
    bath_limited : int
        Draws capped so that no bath went below zero.
    beyond_law : int
        Law rule: draws for pairs below the law's last row (``E_tr / (E_tr + T_pair) < 10^log_x[0]``),
        which took that row's law.
    softer_than_law : int
        Law rule with a contact stiffness: draws at a ``kappa`` below the soft law's softest row, which took
        that row's law.
    soft_floored : int
        Law rule with a contact stiffness: draws whose soft-corrected ``eps^2`` came out negative (hard-core
        draw plus an interpolated correction) and was set to 0.
    contact_stiffness : float or None
        ``alpha`` of the run (None: hard core).
    energy_drift : float
        Relative change of kinetic + bath + lost + dissipated energy since the start.
    collapse : dict or None
        Where the collapse detector fired (``collision``, ``time``, ``cluster_rods``, ``first_rod``,
        ``last_rod``; in a box -1 and N stand for the left and right wall), also when the run went on
        (``continue_after_collapse``); None if it never did.
    """

    status: str
    message: str
    collisions: int
    wall_hits: int
    simulated_time: float
    wall_time_s: float
    collisions_per_second: float
    history: dict
    frame_times: np.ndarray
    frames: np.ndarray
    velocities: np.ndarray
    bath_temperatures: np.ndarray
    bath_limited: int
    energy_drift: float
    rule: dict = field(default_factory=dict)
    beyond_law: int = 0
    softer_than_law: int = 0
    soft_floored: int = 0
    contact_stiffness: float | None = None
    collapse: dict | None = None

    @property
    def collapsed(self) -> bool:
        return self.status == "collapsed"

    @property
    def final_energy(self) -> float:
        """Translational (centre-of-mass frame) kinetic energy at the end."""
        return float(self.history["kinetic_energy"][-1]) if self.history["kinetic_energy"].size else math.nan

    def collision_rate(self):
        """``(time, collisions per unit time)`` between successive records."""
        t, c = self.history["time"], self.history["collisions"]
        dt = np.diff(t)
        with np.errstate(divide="ignore", invalid="ignore"):
            rate = np.where(dt > 0, np.diff(c) / np.where(dt > 0, dt, 1.0), np.inf)
        return 0.5 * (t[1:] + t[:-1]), rate

    def summary(self) -> dict:
        """JSON-ready numbers of the run."""
        return {
            "status": self.status,
            "message": self.message,
            "collapsed": self.collapsed,
            "collisions": self.collisions,
            "wall_hits": self.wall_hits,
            "simulated_time": self.simulated_time,
            "wall_time_s": self.wall_time_s,
            "collisions_per_second": self.collisions_per_second,
            "final_energy": self.final_energy,
            "final_bath_energy": float(self.history["bath_energy"][-1]) if self.history["bath_energy"].size else 0.0,
            "energy_drift": self.energy_drift,
            "bath_limited": self.bath_limited,
            "bath_limited_fraction": self.bath_limited / self.collisions if self.collisions else 0.0,
            "beyond_law": self.beyond_law,
            "softer_than_law": self.softer_than_law,
            "soft_floored": self.soft_floored,
            "contact_stiffness": self.contact_stiffness,
            "collapse": self.collapse,
            "rule": self.rule,
        }

    def save(self, directory):
        """Write ``gas_history.npz`` (histories, frames, final state) and ``gas_summary.json`` into ``directory``."""
        from pathlib import Path

        from ..io.files import atomic_write
        from ..io.run_controller import write_summary

        directory = Path(directory)
        arrays = {f"history_{k}": v for k, v in self.history.items()}
        arrays.update(frame_times=self.frame_times, frames=self.frames, velocities=self.velocities,
                      bath_temperatures=self.bath_temperatures)
        atomic_write(directory / "gas_history.npz", lambda h: np.savez(h, **arrays))
        write_summary(directory / "gas_summary.json", self.summary())
        return directory


@dataclass(frozen=True)
class StoppingRules(KeywordGroup):
    """When a gas run stops before its collisions are done (docs/gas.md, "Stopping rules").

    :class:`GasSimulation` also takes these fields one by one as keywords
    (``GasSimulation(gas, rule, energy_floor=0.0)``), the same as ``stopping=StoppingRules(energy_floor=0.0)``.

    Parameters
    ----------
    collapse_window, collapse_factor, collapse_gap : int, float, float
        (``collapse_window`` a power of two.)  Inelastic collapse: infinitely many collisions in a
        finite time, seen in floating point as collisions that accelerate (the last ``collapse_window``
        took less than ``collapse_factor`` times as long as the ``collapse_window`` before them) until all
        of the last ``collapse_window`` fall within the rounding of the clock (``2^-50 t``), in a cluster
        of at least three bodies (rods, or a wall) around the colliding pair whose gaps all lie below
        ``collapse_gap`` times the mean free spacing (the free length over the number of gaps).  A
        collapse whose cluster's velocities round to equal first (no events left on a ring) counts too.
        Acceleration without such a cluster goes on (a false alarm), unless the relative motion was lost
        in the rounding (a pair's relative velocity within 4 ulps of its speed, or centres so far out that
        their rounding reaches the gap floor): then the gas froze numerically (status ``frozen``).
    energy_floor : float
        Stop (status ``cooled``) once the kinetic energy in the centre-of-mass frame falls below this
        fraction of its initial value: velocities then differ by less than their rounding (0: never).
    continue_after_collapse : bool
        Do not stop at a detected collapse: note it (:attr:`GasResult.collapse`), switch the detector
        off and go on, to see what happens next.
    """

    collapse_window: int = 16
    collapse_factor: float = 1e-3
    energy_floor: float = 1e-20
    collapse_gap: float = 1e-6
    continue_after_collapse: bool = False

    def __post_init__(self):
        window = require_integer("collapse_window", self.collapse_window, 2, 2**20)
        if window & (window - 1):
            raise InvalidParameterError(f"collapse_window must be a power of two, got {window}")
        object.__setattr__(self, "collapse_window", window)
        object.__setattr__(self, "collapse_factor", require_positive("collapse_factor", self.collapse_factor))
        gap = require_positive("collapse_gap", self.collapse_gap)
        if not gap < 1.0:
            raise InvalidParameterError(f"collapse_gap must lie in (0, 1) (of the mean free spacing), got "
                                        f"{self.collapse_gap!r}")
        object.__setattr__(self, "collapse_gap", gap)
        object.__setattr__(self, "continue_after_collapse", bool(self.continue_after_collapse))
        floor = float(self.energy_floor)
        if not 0.0 <= floor < 1.0:
            raise InvalidParameterError(f"energy_floor must lie in [0, 1), got {self.energy_floor!r}")
        object.__setattr__(self, "energy_floor", floor)


class GasSimulation:
    """An event-driven rod gas with a collision rule; run it in pieces, checkpoint, resume.

    Parameters
    ----------
    gas : RodGas
        Initial state.
    rule : FixedRestitution, VibrationLaw, VibrationTable or VibrationSolve
        The collision rule.
    damping : float, optional
        Relaxation time ``tau_diss`` of every bath (time unit of the gas; the
        baths cool as ``exp(-t / tau_diss)`` between collisions).  None: no
        dissipation.
    contact_stiffness : float, optional
        ``alpha`` of the exponential contact ``V(r) = B exp(-alpha r)`` (an inverse length, in the gas's
        length unit).  Each collision then has its own softness ``kappa = alpha V l / c`` (docs/theory.md)
        with ``V`` the approach speed, ``c = 1`` and ``l = 2 l_i l_j / (l_i + l_j)``, the pair's effective
        length (twice the reduced mass, rods of unit density and section).  The vibration law blends its
        soft (finite-kappa) law with the hard-core law at that kappa; a :class:`VibrationSolve` draw is
        called with ``kappa=``.  None (default): every collision in the hard-core limit.
    seed : int or numpy.random.SeedSequence
        Root of the collision draws: ``SeedSequence(seed).spawn(2)`` gives the stream of the
        table's probability levels and the parent of the per-collision seeds of :class:`VibrationSolve`.
    record_every : int
        Collisions between records of the energies (and chunk size of the kernel calls).
    frame_every : int, optional
        Records between frames of the space-time picture (default: every record).
    max_frames : int
        Frames kept (later ones are dropped).
    frame_rods : int
        At most this many rods (evenly chosen) in each frame.
    stopping : StoppingRules, optional
        Inelastic collapse and cooling (default ``StoppingRules()``).
    **rules
        The fields of :class:`StoppingRules` one by one (``collapse_window``, ``collapse_factor``,
        ``collapse_gap``, ``continue_after_collapse``, ``energy_floor``), instead of ``stopping``.
    """

    def __init__(self, gas: RodGas, rule, *, damping=None, contact_stiffness=None, seed=0, record_every=1000,
                 frame_every=1, max_frames=400, frame_rods=2000, stopping: StoppingRules | None = None, **rules):
        if not isinstance(gas, RodGas):
            raise InvalidParameterError("gas must be a RodGas (see wavecontact.gas.random_gas)")
        if not isinstance(rule, (FixedRestitution, VibrationLaw, VibrationTable, VibrationSolve)):
            raise InvalidParameterError("rule must be FixedRestitution, VibrationLaw, VibrationTable or VibrationSolve")
        self.gas = gas
        self.rule = rule
        self.damping = None if damping is None else require_positive("damping time tau_diss", damping, allow_inf=True)
        self.contact_stiffness = None
        if contact_stiffness is not None:
            alpha = require_positive("contact_stiffness alpha", contact_stiffness)
            if not 1e-6 <= alpha <= 1e12:
                raise InvalidParameterError(f"contact_stiffness alpha must lie in [1e-6, 1e12], got {alpha!r}")
            if rule.code not in (kernels.RULE_LAW, kernels.RULE_EXTERNAL):
                raise InvalidParameterError("contact_stiffness applies to the vibration law and the solve rule only")
            if rule.code == kernels.RULE_LAW and rule.soft_law is None:
                raise InvalidParameterError("contact_stiffness needs VibrationLaw(default_law(), default_soft_law()): "
                                            "the rule has no soft (finite-kappa) law")
            self.contact_stiffness = alpha
        self.record_every = require_integer("record_every", record_every, 1, MAX_COLLISIONS)
        self.frame_every = require_integer("frame_every", frame_every, 1, MAX_COLLISIONS)
        self.max_frames = require_integer("max_frames", max_frames, 0, 100_000)
        self.frame_rods = require_integer("frame_rods", frame_rods, 1, 100_000)
        rules = dict(rules)
        stopping = StoppingRules.gather(stopping, rules, "stopping")
        if rules:
            raise TypeError(f"GasSimulation() got an unexpected keyword argument {next(iter(rules))!r}")
        self.stopping = stopping
        window = stopping.collapse_window
        self.collapse_factor = stopping.collapse_factor
        self.collapse_gap = stopping.collapse_gap
        self.continue_after_collapse = stopping.continue_after_collapse
        self.collapse_detected = None  # where the detector fired (a dict, see GasResult.collapse)
        self.energy_floor = stopping.energy_floor
        sequence = seed if isinstance(seed, np.random.SeedSequence) else np.random.SeedSequence(seed)
        self.seed_entropy = sequence.entropy
        self.seed_spawn_key = tuple(sequence.spawn_key)
        levels, self._solve_seeds = sequence.spawn(2)  # table levels; parent of the per-collision seeds
        self._rng = np.random.Generator(np.random.PCG64(levels))
        n = gas.rods
        ring = gas.boundary == "ring"
        self.ring = ring
        lengths = gas.lengths
        # state
        self.x = gas.positions.copy()
        self.v = gas.velocities.copy()
        self.local_time = np.zeros(n)
        self.temperature = gas.bath_temperatures.copy()
        self.mass = lengths.copy()
        # per event
        if ring:  # every event a pair of rods (k, k + 1 mod N)
            l_left, l_right = lengths, np.roll(lengths, -1)
            self.reach = 0.5 * (l_left + l_right)
            inner = slice(None)
        else:  # the walls (events 0 and N) count as partners of length 1
            self.reach = np.concatenate([[0.5 * lengths[0]], 0.5 * (lengths[1:] + lengths[:-1]), [0.5 * lengths[-1]]])
            left, right = np.arange(-1, n), np.arange(0, n + 1)
            inner = (left >= 0) & (right < n)
            l_left = np.where(inner, lengths[np.clip(left, 0, n - 1)], 1.0)
            l_right = np.where(inner, lengths[np.clip(right, 0, n - 1)], 1.0)
        self.left_is_short = l_left <= l_right
        self.pair_gamma = np.minimum(l_left, l_right) / np.maximum(l_left, l_right)
        grid = rule.gamma_grid()
        grids = [grid]
        if self.contact_stiffness is not None and rule.code == kernels.RULE_LAW:
            grids.append(rule.soft_law.gamma)
        if rule.code in (kernels.RULE_TABLE, kernels.RULE_LAW):
            low, high = self.pair_gamma[inner].min(), self.pair_gamma[inner].max()
            for covered in grids:
                if low < covered[0] or high > covered[-1]:
                    raise InvalidParameterError(
                        f"the gas has length ratios {low:.4g}..{high:.4g} but the table covers gamma in "
                        f"[{covered[0]:g}, {covered[-1]:g}]: choose lengths inside it or a wider table")
        if grid.size == 1:
            self.gamma_index, self.gamma_weight = np.zeros(self.reach.size, np.int64), np.zeros(self.reach.size)
        else:
            g = np.clip(self.pair_gamma, grid[0], grid[-1])
            self.gamma_index = np.clip(np.searchsorted(grid, g, side="right") - 1, 0, grid.size - 2).astype(np.int64)
            self.gamma_weight = (g - grid[self.gamma_index]) / (grid[self.gamma_index + 1] - grid[self.gamma_index])
        key = np.empty(self.reach.size)
        kernels.event_times(0.0, self.x, self.v, self.local_time, self.reach, ring, gas.system_length, key)
        self.tree_time = np.empty(kernels.tree_size(self.reach.size))
        self.tree_event = np.empty(self.tree_time.size, np.int32)
        kernels.build_tree(key, self.tree_time, self.tree_event)
        self.window = np.zeros(2 * window)
        spacing = gas.free_length / (n if ring else n + 1)  # mean free spacing: the free length over the gaps
        self.collapse = np.array([self.collapse_factor, self.collapse_gap * spacing, COLLAPSE_RODS, FROZEN_SPEED,
                                  FROZEN_POSITION, COLLAPSE_CLOCK])
        momentum = float(np.sum(self.mass * self.v))
        total_mass = float(self.mass.sum())
        self.scalars = np.zeros(8)
        self.scalars[kernels.KINETIC] = self.scalars[kernels.KINETIC_REFERENCE] = gas.kinetic_energy()
        self.scalars[kernels.MOMENTUM_ENERGY] = momentum**2 / (2 * total_mass) if ring else 0.0
        self.total_mass = total_mass
        self.counters = np.zeros(kernels.COUNTERS, np.int64)
        self.pending = np.zeros(3)
        energies = self._energies()
        self.initial_energy = energies[4]
        self.scalars[kernels.ENERGY_FLOOR] = self.energy_floor * energies[0]
        self.history = {name: [] for name in _HISTORY}
        self.frame_times, self.frames = [], []
        self.records = 0
        self.status = "completed"
        self.off_table = None  # (gamma, T_B/E_tr) of the pair the table refused
        self.drawn = 0  # collision seeds spawned (external rule)

    # ---------------------------------------------------------------- helpers
    @property
    def time(self) -> float:
        return float(self.scalars[kernels.T_NOW])

    @property
    def event_times(self) -> np.ndarray:
        """Predicted time of every event (a view of the tree's leaves; the tree above them follows from it)."""
        leaves = self.tree_time.size // 2
        return self.tree_time[leaves:leaves + self.reach.size]

    @property
    def collisions(self) -> int:
        return int(self.counters[kernels.COLLISIONS])

    def _decay_rate(self):
        return 0.0 if self.damping is None or math.isinf(self.damping) else 1.0 / self.damping

    def _synced_temperatures(self, now):
        rate = self._decay_rate()
        return self.temperature * np.exp(-rate * (now - self.local_time)) if rate > 0 else self.temperature

    def _energies(self):
        """(kinetic in the COM frame, bath, lost, dissipated, total) at the current time."""
        translational = float(0.5 * np.sum(self.mass * self.v**2))
        kinetic = translational
        if self.ring:
            kinetic -= float(np.sum(self.mass * self.v)) ** 2 / (2.0 * self.total_mass)
        bath = 0.0
        dissipated = float(self.scalars[kernels.DISSIPATED])
        if self.rule.code != kernels.RULE_FIXED:  # the fixed rule has no baths
            temperatures = self._synced_temperatures(self.time)
            modes = float(self.rule.bath_modes)
            bath = modes * float(temperatures.sum())
            dissipated += modes * float(np.sum(self.temperature - temperatures))
        lost = float(self.scalars[kernels.LOST])
        total = translational + bath + lost + dissipated
        return kinetic, bath, lost, dissipated, total

    def positions(self):
        """Rod centres now (centre-of-mass frame, wrapped into [0, L) on a ring)."""
        now = self.time
        x = self.x + self.v * (now - self.local_time)
        if self.ring:
            drift = float(np.sum(self.mass * self.v)) / self.total_mass
            x = np.mod(x - drift * now, self.gas.system_length)
        return x

    def _record_row(self, energies=None):
        """The values of one history record now, in the order of ``_HISTORY`` (``energies``: those of
        :meth:`_energies`, if the caller already has them)."""
        kinetic, bath, lost, dissipated, _ = self._energies() if energies is None else energies
        return self.time, self.collisions, kinetic, bath, lost, dissipated

    def _record(self):
        for name, value in zip(_HISTORY, self._record_row()):
            self.history[name].append(value)
        if self.records % self.frame_every == 0 and len(self.frames) < self.max_frames:
            stride = max(1, math.ceil(self.gas.rods / self.frame_rods))
            self.frame_times.append(self.time)
            self.frames.append(self.positions()[::stride].astype(np.float32))
        self.records += 1

    def _pair_state(self, event):
        """``(gamma, T_B/E_tr)`` of the pair of ``event`` at its collision time (mean bath temperature)."""
        n = self.gas.rods
        i, j = (event, (event + 1) % n) if self.ring else (event - 1, event)
        now = float(self.event_times[event])
        temperatures = self._synced_temperatures(now)
        reduced = self.mass[i] * self.mass[j] / (self.mass[i] + self.mass[j])
        e_tr = 0.5 * reduced * (self.v[i] - self.v[j]) ** 2
        ratio = 0.5 * (temperatures[i] + temperatures[j]) / e_tr if e_tr > 0 else math.inf
        if self.rule.code == kernels.RULE_EXTERNAL and self.rule.per_rod:
            short, long = (i, j) if self.left_is_short[event] else (j, i)
            ratio = (temperatures[short] / e_tr, temperatures[long] / e_tr) if e_tr > 0 else (math.inf, math.inf)
        return float(self.pair_gamma[event]), ratio

    def collision_kappa(self, event):
        """``kappa = alpha V l`` of the pair of ``event`` now (``inf`` without a contact stiffness)."""
        if self.contact_stiffness is None:
            return math.inf
        n = self.gas.rods
        i, j = (event, (event + 1) % n) if self.ring else (event - 1, event)
        reduced = self.mass[i] * self.mass[j] / (self.mass[i] + self.mass[j])
        return self.contact_stiffness * float(self.v[i] - self.v[j]) * 2.0 * reduced

    def _draw_external(self, event):
        gamma, ratio = self._pair_state(event)
        # the drawn-th child of _solve_seeds, as _solve_seeds.spawn() would give it (but stateless)
        parent = self._solve_seeds
        seed = np.random.SeedSequence(parent.entropy, spawn_key=parent.spawn_key + (self.drawn,))
        self.drawn += 1
        if self.contact_stiffness is None:
            eps2, share = self.rule.draw(gamma, ratio, seed)
        else:
            eps2, share = self.rule.draw(gamma, ratio, seed, kappa=self.collision_kappa(event))
        eps2, share = float(eps2), float(share)
        if not (math.isfinite(eps2) and eps2 >= 0 and math.isfinite(share)):
            raise InvalidParameterError(f"the rule's draw must return a finite eps2 >= 0 and a finite share, "
                                        f"got ({eps2!r}, {share!r})")
        self.pending[:] = (1.0, eps2, share)

    # ------------------------------------------------------------------- run
    def run(self, collisions, *, max_time=math.inf, progress=False, controller=None) -> GasResult:
        """Advance by ``collisions`` rod-rod collisions, or until ``max_time``, a collapse, or no events left.

        Parameters
        ----------
        collisions : int
            Collisions to add (1 ... 10^11).
        max_time : float
            Absolute simulated time at which to stop.
        progress : bool
            Show a tqdm bar (ignored with ``controller``).
        controller : RunController, optional
            Told of every chunk of ``record_every`` collisions at the consistent point after it
            (:class:`~wavecontact.io.run_controller.RunController`: progress, checkpoints, interrupts);
            None: a progress bar only.
        """
        collisions = require_integer("collisions", collisions, 1, MAX_COLLISIONS)
        if math.isnan(float(max_time)) or float(max_time) < 0:
            raise InvalidParameterError(f"max_time must be >= 0, got {max_time!r}")
        if collisions // self.record_every > MAX_RECORDS:
            raise InvalidParameterError(
                f"record_every must be >= collisions / {MAX_RECORDS:.0e} (= {math.ceil(collisions / MAX_RECORDS)}) "
                f"so that the history stays bounded, got {self.record_every}")
        if self.status not in ("completed", "time_limit"):
            raise InvalidParameterError(f"this simulation ended ({self.status}); it cannot be continued")
        if self.records == 0:
            self._record()
        target = self.collisions + collisions
        if controller is None:
            with RunController(collisions, "gas", unit="collision", progress=bool(progress)) as bar_only:
                return self._run_chunks(target, max_time, bar_only)
        return self._run_chunks(target, max_time, controller)

    def _run_chunks(self, target, max_time, controller) -> GasResult:
        rule = self.rule
        table = _read_only(rule.kernel_arrays())
        probability = table[2]
        soft_law = self.contact_stiffness is not None and rule.code == kernels.RULE_LAW
        soft = _read_only(rule.soft_arrays()) if soft_law else None
        stiffness = self.contact_stiffness if soft_law else 0.0
        uniform = bool(np.array_equal(probability, np.linspace(0.0, 1.0, probability.size)))
        restitution2 = rule.restitution**2 if rule.code == kernels.RULE_FIXED else 0.0
        # the kernel's argument groups (kernels.run_events): the ones that stay the same for the whole run
        rods = (self.x, self.v, self.local_time, self.temperature, self.mass)
        pairs = (self.reach, self.pair_gamma, self.gamma_index, self.gamma_weight, self.left_is_short)
        tree = (self.tree_time, self.tree_event)
        constants = (rule.code, restitution2, float(rule.bath_modes), self._decay_rate(), stiffness, uniform)
        monitor = (self.window, self.collapse, self.scalars, self.counters)
        no_uniforms = np.zeros(0)
        status = kernels.STATUS_DONE
        start = time.perf_counter()
        first = self.collisions
        while self.collisions < target:
            boundary = (self.collisions // self.record_every + 1) * self.record_every
            chunk = min(boundary, target) - self.collisions
            uniforms = no_uniforms
            if rule.code in (kernels.RULE_TABLE, kernels.RULE_LAW):
                state = self._rng.bit_generator.state
                uniforms = self._rng.random(chunk)
            before = self.collisions
            while True:
                status, event, _done = kernels.run_events(
                    rods, pairs, tree, self.ring, self.gas.system_length, constants, table, soft,
                    (uniforms[self.collisions - before:], self.pending),
                    (chunk - (self.collisions - before), float(max_time)), monitor)
                status = kernels.resolve_cluster(status, event, self.x, self.v, self.local_time, self.reach, self.ring,
                                                 self.gas.system_length, self.collapse, self.scalars)
                if status == kernels.STATUS_DONE and self.collisions - before < chunk:
                    continue  # a false alarm of the collapse detector: the loop goes on
                if status == kernels.STATUS_OFF_TABLE:
                    self.off_table = self._pair_state(event)
                if status == kernels.STATUS_COLLAPSE and self.collapse_detected is None:
                    self.collapse_detected = self._cluster(event)
                    if self.continue_after_collapse:
                        self.collapse[kernels.COLLAPSE_FACTOR] = 0.0  # noted; the detector is off from here
                        continue
                if status != kernels.STATUS_NEED_DRAW:
                    break
                self._draw_external(event)
            used = self.collisions - before
            if rule.code in (kernels.RULE_TABLE, kernels.RULE_LAW) and used < chunk:
                self._rng.bit_generator.state = state  # rewind: only the used levels are consumed
                self._rng.bit_generator.advance(used)
            if status == kernels.STATUS_DONE and self.collisions % self.record_every == 0:
                self._record()
            controller.advance(used, consistent=status == kernels.STATUS_DONE)
            if status != kernels.STATUS_DONE:
                if status in (kernels.STATUS_COLLAPSE, kernels.STATUS_NO_EVENTS, kernels.STATUS_COOLED,
                              kernels.STATUS_OFF_TABLE, kernels.STATUS_FROZEN):
                    self._record()  # the final state of a run that cannot continue
                break
        wall = time.perf_counter() - start
        self.status = _STATUS[status]
        return self._result(wall, self.collisions - first)

    def _cluster(self, event):
        """Where the detector fired: the collision, its time and the cluster of ``event`` (-1: the largest)."""
        n = self.gas.rods
        first, last, members = kernels.collapse_cluster(
            int(event), self.time, self.x, self.v, self.local_time, self.reach, self.ring, self.gas.system_length,
            float(self.collapse[kernels.COLLAPSE_GAP]))
        # event e joins rods (e, e + 1 mod N) on a ring and (e - 1, e) in a box (a wall at either end)
        first_rod, last_rod = (int(first), int(last + 1) % n) if self.ring else (int(first) - 1, int(last))
        return {"collision": self.collisions, "time": self.time, "cluster_rods": int(members),
                "first_rod": first_rod, "last_rod": last_rod}

    def _message(self):
        noted = self.collapse_detected
        if noted is not None and self.status != "collapsed":
            return (f"{self._status_message()}; an inelastic collapse was detected at collision {noted['collision']} "
                    f"(t = {noted['time']:.6g}, a cluster of {noted['cluster_rods']} rods) and the run went on "
                    f"(continue_after_collapse) with the detector off")
        return self._status_message()

    def _status_message(self):
        t, c = self.time, self.collisions
        if self.status == "frozen":
            return (f"the gas froze numerically after {c} collisions (t = {t:.6g}): its collisions accelerated, but its "
                    f"relative motion was lost in the rounding (a relative velocity below {FROZEN_SPEED:.2g} of the "
                    f"speed, or rod centres drifted so far that their rounding reaches the gap floor); not a collapse")
        if self.status == "cooled":
            return (f"the gas cooled below {self.energy_floor:g} of its initial kinetic energy after {c} collisions "
                    f"(t = {t:.6g}); further collisions would be lost in the rounding of the velocities")
        if self.status == "collapsed":
            w = self.window.size // 2
            cluster = self.collapse_detected
            return (f"inelastic collapse at collision {c} (t = {t:.6g}): a cluster of {cluster['cluster_rods']} "
                    f"rods ({cluster['first_rod']} to {cluster['last_rod']}) closer than {self.collapse_gap:g} of "
                    f"the mean free spacing, whose collisions accelerated (the last {w} took less than "
                    f"{self.collapse_factor:g} times as long as the {w} before them) until {w} of them fell within "
                    f"the clock's rounding: infinitely many collisions in a finite time; the run was stopped "
                    f"(continue_after_collapse goes on)")
        if self.status == "off_table":
            gamma, ratio = self.off_table
            grid = self.rule.table.temperature_ratio
            return (f"stopped at collision {c + 1} (t = {t:.6g}): a pair with gamma = {gamma:.4g} met at "
                    f"T_B/E_tr = {ratio:.6g}, outside the restitution table's range [{grid[0]:g}, {grid[-1]:g}]; "
                    f"the table is not extrapolated: pass a table covering this ratio (wavecontact restitution-table)")
        if self.status == "time_limit":
            return f"stopped at the time limit after {c} collisions (t = {t:.6g})"
        if self.status == "no_events":
            return f"no further collisions after {c} (all neighbours separate), t = {t:.6g}"
        return f"{c} collisions, t = {t:.6g}"

    def _result(self, wall, done) -> GasResult:
        history = {name: list(values) for name, values in self.history.items()}
        energies = self._energies()
        if not history["collisions"] or history["collisions"][-1] != self.collisions:
            # a run that ends between records: the result's history ends with the final state (the
            # simulation's own records keep their cadence, so that a run in pieces records what one run does)
            for name, value in zip(_HISTORY, self._record_row(energies)):
                history[name].append(value)
        history = {name: np.asarray(values, dtype=np.int64 if name == "collisions" else float)
                   for name, values in history.items()}
        total = energies[4]
        frames = np.array(self.frames) if self.frames else np.zeros((0, 0), np.float32)
        return GasResult(
            status=self.status, message=self._message(), collisions=self.collisions,
            wall_hits=int(self.counters[kernels.WALL_HITS]), simulated_time=self.time, wall_time_s=wall,
            collisions_per_second=done / wall if wall > 0 else math.inf, history=history,
            frame_times=np.asarray(self.frame_times), frames=frames, velocities=self.v.copy(),
            bath_temperatures=self._synced_temperatures(self.time).copy(),
            bath_limited=int(self.counters[kernels.BATH_LIMITED]),
            energy_drift=(total - self.initial_energy) / self.initial_energy if self.initial_energy > 0 else 0.0,
            rule=self.rule.describe(),
            beyond_law=int(self.counters[kernels.OFF_TABLE]) if self.rule.code == kernels.RULE_LAW else 0,
            softer_than_law=int(self.counters[kernels.SOFTER]), soft_floored=int(self.counters[kernels.FLOORED]),
            contact_stiffness=self.contact_stiffness, collapse=self.collapse_detected,
        )

    # ------------------------------------------------------------ checkpoint
    _STATE = ("x", "v", "local_time", "temperature", "event_times", "window", "scalars", "counters",
              "pending")

    def _parameters(self) -> dict:
        return {
            "rule": self.rule.describe(),
            "damping": self.damping,
            "contact_stiffness": self.contact_stiffness,
            "record_every": self.record_every,
            "frame_every": self.frame_every,
            "max_frames": self.max_frames,
            "frame_rods": self.frame_rods,
            "collapse_window": int(self.window.size // 2),
            "collapse_factor": self.collapse_factor,
            "energy_floor": self.energy_floor,
            "collapse_gap": self.collapse_gap,
            "continue_after_collapse": self.continue_after_collapse,
            "collapse_detected": self.collapse_detected,
            "seed_entropy": str(self.seed_entropy),
            "seed_spawn_key": [int(k) for k in self.seed_spawn_key],
            "boundary": self.gas.boundary,
            "system_length": self.gas.system_length,
        }

    def save_checkpoint(self, path, segment=None):
        """Write the whole state (npz + JSON, checksummed) so that :meth:`resume` continues bit for bit.

        Parameters
        ----------
        path : path-like
            The checkpoint file.
        segment : (int, int, bool), optional
            ``(first, target, finished)`` of the run in progress (:func:`run_gas`): the collision count
            it started from, the count it runs to, and whether its outputs are written.
        """
        arrays = {name: getattr(self, name) for name in self._STATE}
        arrays.update(gas_lengths=self.gas.lengths, gas_positions=self.gas.positions,
                      gas_velocities=self.gas.velocities, gas_bath_temperatures=self.gas.bath_temperatures)
        arrays.update({f"history_{k}": np.asarray(v, dtype=float) for k, v in self.history.items()})
        arrays["frame_times"] = np.asarray(self.frame_times, dtype=float)
        arrays["frames"] = np.array(self.frames) if self.frames else np.zeros((0, 0), np.float32)
        arrays["rng_state"] = np.asarray(json.dumps(self._rng.bit_generator.state))
        arrays["progress"] = np.array([self.records, self.drawn], np.int64)
        arrays["status"] = np.asarray(self.status)
        if segment is not None:
            arrays["segment"] = np.array([int(segment[0]), int(segment[1]), int(bool(segment[2]))], np.int64)
        if isinstance(self.rule, VibrationLaw):
            for prefix, law in (("law", self.rule.law), ("soft_law", self.rule.soft_law)):
                if law is not None:
                    arrays.update({f"{prefix}_{n}": a for n, a in zip(LAW_ARRAYS, law.arrays()) if n != "kappa"})
                    arrays[f"{prefix}_metadata"] = np.asarray(json.dumps(law.metadata()))
        if isinstance(self.rule, VibrationTable):
            arrays.update({f"table_{n}": a for n, a in zip(
                ("gamma", "temperature_ratio", "probability", "eps2_quantiles", "rod1_share"), self.rule.table.arrays())})
            arrays["table_metadata"] = np.asarray(json.dumps(self.rule.table.metadata()))
        return write_checkpoint(path, CHECKPOINT_SCHEMA, CHECKPOINT_VERSION, self._parameters(), arrays)

    @classmethod
    def resume(cls, path, rule=None, *, with_segment=False):
        """Rebuild a simulation from :meth:`save_checkpoint` (pass ``rule`` for a :class:`VibrationSolve`).

        The checkpoint's contents are checked as strictly as user input (shapes, finiteness, ranges,
        consistency with its parameters), whatever its checksum says; a failed check raises
        :class:`~wavecontact.errors.CheckpointError` with one line.  ``with_segment``: return
        ``(simulation, segment)`` with the ``segment`` given to :meth:`save_checkpoint` (None if none).
        """
        arrays, meta = read_checkpoint(path, CHECKPOINT_SCHEMA, CHECKPOINT_VERSION)
        try:
            sim, segment = cls._from_checkpoint(path, arrays, meta["parameters"], rule)
        except CheckpointError:
            raise
        except (KeyError, ValueError, TypeError, IndexError, AttributeError, OverflowError) as exc:
            reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
            if isinstance(exc, KeyError):
                reason = f"missing {reason}"
            raise CheckpointError(f"checkpoint {path} is incomplete or invalid ({reason}); delete it or pass "
                                  "--overwrite to start afresh") from None
        return (sim, segment) if with_segment else sim

    @classmethod
    def _from_checkpoint(cls, path, arrays, params, rule):
        if rule is None:
            table = None
            soft_law = None
            if "law_gamma" in arrays:
                table, soft_law = (
                    law_from_arrays({n: arrays[f"{prefix}_{n}"] for n in LAW_ARRAYS if n != "kappa"},
                                    json.loads(str(arrays[f"{prefix}_metadata"])), f"checkpoint {path}")
                    if f"{prefix}_gamma" in arrays else None for prefix in ("law", "soft_law"))
            if "table_gamma" in arrays:
                info = json.loads(str(arrays["table_metadata"]))
                table = RestitutionTable(
                    arrays["table_gamma"], arrays["table_temperature_ratio"], arrays["table_probability"],
                    arrays["table_eps2_quantiles"], arrays["table_rod1_share"],
                    kappa=math.inf if info["kappa"] == "inf" else info["kappa"], bath_modes=info["bath_modes"],
                    samples_per_point=info["samples_per_point"], solver=info["solver"], seed=info["seed"])
            rule = rule_from_description(params["rule"], table, soft_law)
        elif json.loads(json.dumps(rule.describe())) != params["rule"]:
            raise InvalidParameterError(f"checkpoint {path} was written with the rule {params['rule']}, "
                                        f"not {rule.describe()}")
        gas = RodGas(arrays["gas_lengths"], arrays["gas_positions"], arrays["gas_velocities"],
                     arrays["gas_bath_temperatures"], params["system_length"], params["boundary"])
        seed = np.random.SeedSequence(int(params["seed_entropy"]),
                                      spawn_key=tuple(int(k) for k in params.get("seed_spawn_key", ())))
        sim = cls(gas, rule, damping=params["damping"], contact_stiffness=params["contact_stiffness"], seed=seed,
                  record_every=params["record_every"], frame_every=params["frame_every"],
                  max_frames=params["max_frames"], frame_rods=params["frame_rods"],
                  stopping=StoppingRules(params["collapse_window"], params["collapse_factor"], params["energy_floor"],
                                         params.get("collapse_gap", 1e-6),
                                         params.get("continue_after_collapse", False)))
        sim.collapse_detected = params.get("collapse_detected")
        if sim.collapse_detected is not None:
            sim.collapse[kernels.COLLAPSE_FACTOR] = 0.0
        segment = _check_checkpoint_arrays(path, sim, arrays)
        for name in cls._STATE:
            getattr(sim, name)[...] = arrays[name]
        kernels.build_tree(sim.event_times.copy(), sim.tree_time, sim.tree_event)
        sim._rng.bit_generator.state = json.loads(str(arrays["rng_state"]))
        sim.history = {k: arrays[f"history_{k}"].tolist() for k in _HISTORY}
        sim.history["collisions"] = [int(c) for c in sim.history["collisions"]]
        sim.frame_times = arrays["frame_times"].tolist()
        sim.frames = list(arrays["frames"])
        sim.records, sim.drawn = (int(a) for a in arrays["progress"])
        sim.status = str(arrays["status"])
        return sim, segment


def _check_checkpoint_arrays(path, sim: GasSimulation, arrays: dict):
    """Refuse a gas checkpoint whose state no run can reach (the same checks as user input); return its segment."""

    def refuse(what):
        raise CheckpointError(f"checkpoint {path}: {what}; delete it or pass --overwrite to start afresh")

    for name in GasSimulation._STATE:
        value, target = np.asarray(arrays[name]), getattr(sim, name)
        if value.shape != target.shape:
            refuse(f"{name} has shape {value.shape}, this gas needs {target.shape}")
        if value.dtype.kind not in ("iu" if target.dtype.kind in "iu" else "iuf"):
            refuse(f"{name} has dtype {value.dtype}, expected {target.dtype}")
        if name == "event_times":
            if np.any(np.isnan(value)) or np.any(value == -np.inf):
                refuse("event_times holds NaN or -inf")
        elif not np.all(np.isfinite(value)):
            refuse(f"{name} holds NaN or infinite values")
    if np.any(arrays["temperature"] < 0.0):
        refuse("bath temperatures must be >= 0")
    if np.any(arrays["counters"] < 0):
        refuse("counters must be >= 0")
    now = float(arrays["scalars"][kernels.T_NOW])
    if now < 0.0 or np.any(arrays["local_time"] < 0.0) or np.any(arrays["local_time"] > now):
        refuse("local times must lie in [0, t] with t the simulation time")
    collisions = int(arrays["counters"][kernels.COLLISIONS])
    names = [f"history_{k}" for k in _HISTORY]
    rows = np.asarray(arrays[names[0]]).shape
    for name in names:
        value = np.asarray(arrays[name])
        if value.ndim != 1 or value.shape != rows or value.dtype.kind != "f" or not np.all(np.isfinite(value)):
            refuse(f"{name} must be a finite 1-d array as long as history_time")
    counts = np.asarray(arrays["history_collisions"])
    if np.any(np.diff(counts) < 0) or (counts.size and (counts[0] < 0 or counts[-1] > collisions)):
        refuse("history_collisions must be non-decreasing and at most the collision count")
    progress = np.asarray(arrays["progress"])
    if progress.shape != (2,) or progress.dtype.kind not in "iu" or progress[0] != rows[0] or progress[1] < 0:
        refuse("progress must be [records, draws] with one record per history row")
    frames, frame_times = np.asarray(arrays["frames"]), np.asarray(arrays["frame_times"])
    if (frames.ndim != 2 or frame_times.ndim != 1 or (frames.size and frames.shape[0] != frame_times.size)
            or frames.shape[0] > sim.max_frames or not np.all(np.isfinite(frames))
            or not np.all(np.isfinite(frame_times))):
        refuse("frames and frame_times do not match")
    if str(arrays["status"]) not in _STATUS.values():
        refuse(f"unknown status {str(arrays['status'])!r}")
    state = json.loads(str(arrays["rng_state"]))
    if not isinstance(state, dict) or state.get("bit_generator") != "PCG64":
        refuse("rng_state is not a PCG64 state")
    segment = None
    if "segment" in arrays:
        value = np.asarray(arrays["segment"])
        if value.shape != (3,) or value.dtype.kind not in "iu":
            refuse("segment must be [first, target, finished]")
        first, target, finished = (int(v) for v in value)
        if not (0 <= first <= collisions and first <= target and finished in (0, 1)):
            refuse(f"segment {value.tolist()} is inconsistent with {collisions} collisions")
        segment = (first, target, bool(finished))
    return segment


CHECKPOINT_NAME = "gas_checkpoint.npz"


def run_gas(new_simulation, collisions: int, out_dir=None, *, resume: bool = False, overwrite: bool = False,
            check_resumed=None, write_outputs=None, progress: bool | None = False, checkpoint_seconds=60.0,
            checkpoint_every: int | None = None, log=None):
    """Run a gas as a long run: checkpoints at a cadence and on SIGINT/SIGTERM, resume, one writer per folder.

    Parameters
    ----------
    new_simulation : callable
        ``new_simulation() -> GasSimulation`` for a fresh run.
    collisions : int
        Collisions of this run: a fresh run goes from 0 to ``collisions``; ``resume`` continues the
        checkpoint by ``collisions`` more, counted from where its run began if that run was interrupted
        (so that the same command run again finishes the interrupted run, not a longer one).
    out_dir : path-like or None
        Folder of the checkpoint (``gas_checkpoint.npz``) and of ``write_outputs``' files; None: nothing
        is written.
    resume, overwrite : bool
        Continue the checkpoint in ``out_dir``, or replace it; neither: a folder holding one is refused.
    check_resumed : callable, optional
        ``check_resumed(simulation)`` refuses (raises) a resumed simulation that contradicts the caller's options.
    write_outputs : callable, optional
        ``write_outputs(simulation, result)`` writes the run's files; the checkpoint that marks the run as
        finished is written after it returns.
    progress : bool or None
        Progress bar on stderr.
    checkpoint_seconds : float or None
        Wall time between checkpoints (s).
    checkpoint_every : int or None
        Also checkpoint whenever the collision count (of this run) crosses a multiple of this.
    log : callable, optional
        Receives one-line messages (what an interrupt left).

    Returns
    -------
    (GasSimulation, GasResult)
    """
    from pathlib import Path

    from ..io.run_controller import OutputLock, claim_folder

    collisions = require_integer("collisions", collisions, 1, MAX_COLLISIONS)
    if out_dir is None:
        if resume:
            raise InvalidParameterError("--resume needs --out DIR")
        sim = new_simulation()
        return sim, sim.run(collisions, progress=progress)
    out_dir = Path(out_dir)
    path = out_dir / CHECKPOINT_NAME
    with OutputLock(out_dir):
        if claim_folder(out_dir, [CHECKPOINT_NAME], resume=resume, overwrite=overwrite):
            sim, segment = GasSimulation.resume(path, with_segment=True)
            if check_resumed is not None:
                check_resumed(sim)
            first = sim.collisions if segment is None or segment[2] else segment[0]
            if first + collisions < sim.collisions:
                raise InvalidParameterError(
                    f"--collisions: the checkpoint holds collision {sim.collisions} of an interrupted run that "
                    f"began at {first}; give at least {sim.collisions - first} to finish it")
        else:
            sim, first = new_simulation(), 0
        target = first + collisions
        segment = (first, target, False)

        def describe(done):
            return (f"interrupted; the checkpoint holds collision {first + done} of {target}: run the same "
                    "command with --resume to finish the run")

        run = RunController(collisions, "gas", unit="collision", save=lambda: sim.save_checkpoint(path, segment),
                            every=checkpoint_every, seconds=checkpoint_seconds, progress=progress, log=log,
                            describe_resume=describe)
        with run:
            if sim.collisions > first:
                run.resumed(sim.collisions - first)
            remaining = target - sim.collisions
            result = sim.run(remaining, controller=run) if remaining else sim._result(0.0, 0)
            if write_outputs is not None:
                write_outputs(sim, result)
            sim.save_checkpoint(path, (first, target, True))  # after the outputs it records are durable
    return sim, result


def _read_only(arrays: tuple) -> tuple:
    """Read-only C-contiguous views of the rule's table arrays, whatever flags the rule's own arrays carry.

    numba compiles one specialisation of :func:`~wavecontact.gas.kernels.run_events` per combination of
    writable and read-only arguments: a stored law's arrays are read-only, the placeholders of
    :func:`~wavecontact.gas.kernels.empty_table` are not, so without one convention every rule compiled the
    whole event loop again (four compilations of the same code in one process).  The values are untouched.
    """
    views = []
    for array in arrays:
        view = np.ascontiguousarray(array).view()
        view.flags.writeable = False
        views.append(view)
    return tuple(views)
