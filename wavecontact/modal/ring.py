"""Two rods on a ring: an endless cascade of collisions from a cold bath (paper Sec. III).

The rods move on a circle of circumference ``L``.  Going round, the right end
of rod 1 faces the left end of rod 2 (the *near* pair) and the right end of
rod 2 faces the left end of rod 1 across the seam (the *far* pair, whose
modal end displacements enter with the opposite sign pattern, Eq. 7).  Each
call of :meth:`RingSimulation.next_collision` advances through exactly one
collision of whichever pair meets next; the long flights in between are
skipped in closed form.

The simulation is built from a ring :class:`~wavecontact.scene.Scene`
(:func:`wavecontact.scene.two_rods_on_a_ring` for the paper's setting, whose
units are those of :func:`wavecontact.two_rods`: times in ``l / c``,
energies in ``mu V^2``-units with ``mu = 1/2``).  Studies reach it through the
solver contract, ``get_solver("modal").simulate(scene, options)``.
"""

from __future__ import annotations

import numpy as np

from ..errors import InvalidParameterError, SolverFailure, UnsupportedSceneError, require_integer
from ..result import CollisionRecord, Outcome
from ..scene import Scene
from . import collocation, end_response, kernels
from .modes import rod_modes
from .system import ModalSystem, StepControl

__all__ = ["RingSimulation"]


class RingSimulation:
    """Two rods on a ring, colliding again and again.

    Parameters
    ----------
    scene : Scene
        Two rods on a ring (``scene.ring_circumference`` set), cold, with
        ``gaps`` placing them; the contact law acts on both pairs of facing ends.
    modes : int
        Modes kept per rod (the paper's ``N_mod``).
    static_correction : bool
        Add the omitted modes' static end compliance in series with the contact
        (needed for hard contact).
    step_accuracy, step_reach, step_order
        Contact step control (see :class:`StepControl`); the defaults keep
        the energy drift near 5e-8 of the total per collision.
    mode_source : {'analytic', 'fe'}
        Where the modes come from.
    step_method : {'collocation', 'splitting'}
        How each collision is integrated: exponential Radau collocation of the pair in contact
        (:func:`wavecontact.modal.collocation.run_collision`), or the kick-rotate-kick splitting of
        the whole episode (the ring's integrator before; ``step_accuracy`` ... apply to it). The free
        flights between collisions are exact either way.
    collocation_stages : int
        Radau IIA stages ``s`` of the collocation.
    collocation_tolerance : float or None
        Accepted change of the predicted node forces relative to the collision's own force scale
        ``mu |w|`` (``w`` its approach speed); ``None``: :data:`COLLOCATION_TOLERANCE`.

    Attributes
    ----------
    scene : Scene
    modes : int
    reduced_mass : float
        ``mu = m1 m2 / (m1 + m2)`` (mass).
    total_energy : float
        Energy at the start, conserved (energy).
    circumference : float
        ``L`` (length).
    collisions : int
        Number of collisions completed.
    """

    def __init__(self, scene: Scene, modes: int = 100, static_correction: bool = True,
                 step_accuracy=StepControl.accuracy, step_reach=StepControl.reach, step_order=StepControl.order,
                 mode_source: str = "analytic", step_method: str = "collocation", collocation_stages: int = 6,
                 collocation_tolerance: float | None = None):
        if not isinstance(scene, Scene) or not scene.is_ring or len(scene.rods) != 2:
            raise UnsupportedSceneError("a ring simulation needs a Scene of two rods on a ring "
                                        "(wavecontact.scene.two_rods_on_a_ring); use solve() for a line")
        if not scene.is_cold:
            raise UnsupportedSceneError("a ring simulation starts from cold rods (no initial fields)")
        require_integer("modes", modes, 1)
        self.scene = scene
        self.modes = int(modes)
        self.static_correction = bool(static_correction)
        rod1, rod2 = scene.rods
        self.circumference = float(scene.ring_circumference)
        gaps = scene.gaps if scene.gaps is not None else (0.5 * (self.circumference - rod1.length - rod2.length),) * 2
        positions = (0.5 * rod1.length, rod1.length + gaps[0] + 0.5 * rod2.length)
        self.reduced_mass = rod1.mass * rod2.mass / (rod1.mass + rod2.mass)
        approach = abs(scene.velocities[1] - scene.velocities[0])
        if approach == 0.0:
            raise InvalidParameterError("the rods of a ring scene must move relative to each other")
        self.system = ModalSystem(
            [rod_modes(rod1, self.modes, mode_source), rod_modes(rod2, self.modes, mode_source)],
            positions,
            scene.velocities,
            [(0, 1, 0.0), (1, 0, self.circumference)],
            scene.contact,
            force_scale=self.reduced_mass * approach,  # mu V c / l
            static_correction=self.static_correction,
            control=StepControl(accuracy=step_accuracy, reach=step_reach, order=step_order),
        )
        if self.system.contact_range >= min(gaps):
            raise InvalidParameterError(
                f"circumference {self.circumference:g} is too small: the rods would start within range of the force"
            )
        self.total_energy = self.system.total_energy()
        self.collisions = 0
        if step_method not in ("collocation", "splitting"):
            raise InvalidParameterError(f"step_method must be 'collocation' or 'splitting', got {step_method!r}")
        self.step_method = step_method
        if step_method == "collocation":
            self._pairs = [_CollocationPair(self.system, k, collocation_stages) for k in range(2)]
            self.collocation_tolerance = float(COLLOCATION_TOLERANCE if collocation_tolerance is None
                                               else collocation_tolerance)

    @property
    def relative_velocity(self) -> float:
        """``U2 - U1`` (velocity units)."""
        return float(self.system.U[1] - self.system.U[0])

    @property
    def translational_energy(self) -> float:
        """Relative translational energy ``mu v_rel^2 / 2`` (energy)."""
        return 0.5 * self.reduced_mass * self.relative_velocity**2

    def next_collision(self) -> CollisionRecord:
        """Advance through exactly one collision and describe it.

        Returns
        -------
        CollisionRecord
            ``pair`` 0 for the near ends, 1 for the far ends across the seam.
        """
        system = self.system
        before = self.relative_velocity
        if before == 0.0:
            raise SolverFailure("the rods are at rest relative to each other: no further collision",
                                Outcome.NEVER_MEET)
        e_before = self.translational_energy
        steps_before = int(system.counters[0])
        system.episode[0] = -1
        if self.step_method == "collocation":
            self._collide_by_collocation()
        else:
            self._run_until(None)
        pair = int(system.episode[0])
        system.episode[0] = -1
        after = self.relative_velocity
        energies = np.array(system.modal_energies())
        e_bath = float(energies.sum())
        e_tr = self.translational_energy
        record = CollisionRecord(
            index=self.collisions,
            time=float(system.clock[1]),
            pair=pair,
            translational_energy_before=e_before,
            translational_energy_after=e_tr,
            restitution=abs(after) / abs(before),
            modal_energies=energies,
            bath_energy=e_bath,
            total_energy=e_tr + e_bath + system.contact_energy(),
            steps=int(system.counters[0]) - steps_before,
        )
        self.collisions += 1
        return record

    def _run_until(self, max_steps):
        """Splitting (and free flight) until the episode's pair separated; with ``max_steps`` return
        after so many steps (0: only the free flight to the next contact)."""
        system = self.system
        while True:
            if max_steps is None:
                status = system.run_episode()
            else:
                status = system.run_episode(max_steps=max_steps)
            system.check_status(status)
            if status == kernels.STATUS_SEPARATED:
                return status
            if status == kernels.STATUS_FREE_FOREVER:
                raise SolverFailure("ring: no pair approaches any more", Outcome.NEVER_MEET)
            if max_steps is not None and status == kernels.STATUS_RUNNING:
                return status

    def _collide_by_collocation(self):
        system = self.system
        # free flight to where a pair can no longer be proven out of range (no step taken)
        self._run_until(0)
        while system.episode[0] < 0:
            # no closing pair yet (a pair that has just opened is still close): splitting steps
            if self._run_until(1) == kernels.STATUS_SEPARATED:
                return
        pair = self._pairs[int(system.episode[0])]
        pair.collide(self.collocation_tolerance)

    def _signature(self) -> np.ndarray:
        rod1, rod2 = self.scene.rods
        return np.array([rod1.length, rod2.length, self.modes, float(self.static_correction), self.circumference])

    def get_state(self) -> dict:
        """Everything needed to resume bit for bit (NumPy arrays)."""
        state = self.system.get_state()
        state["collisions"] = np.int64(self.collisions)
        state["parameters"] = self._signature()
        return state

    def set_state(self, state: dict) -> None:
        """Restore a state from :meth:`get_state` (of a simulation with the same parameters)."""
        expected = self._signature()
        given = np.asarray(state["parameters"], dtype=float)
        if given.shape != expected.shape or not np.array_equal(given, expected):
            raise InvalidParameterError(
                f"state belongs to a ring with (l1, l2, modes, static_correction, L) = {given.tolist()}, "
                f"this one has {expected.tolist()}"
            )
        self.system.set_state(state)
        self.collisions = int(state["collisions"])


# largest collocation step in radians of the fastest kept mode: the nodes (up to 0.28 of a step apart
# for s = 6) sample the gap, whose fastest part swings with that mode; at twice this phase a light
# touch between two nodes was missed about once in a thousand thermalised collisions (error 6e-3)
TOP_STEP_PHASE = 6.0
# rungs of the step ladder (ratio sqrt 2 each) above TOP_STEP_PHASE, for steps over which the gap provably
# stays more than 28 e-folds of the force out of range (collocation._sampled_step): before and after the
# contact, where half the steps fell otherwise; 0 takes every step at most TOP_STEP_PHASE (the rule before)
FREE_STEP_RUNGS = 10
# largest change of alpha_eff * gap per step where the force matters (as in the single collisions; 4 left a
# collision with an error of 8e-5 among 200 in a development run)
EXPONENT_STEP = 2.0
# collocation tolerance of the ring's collisions (static correction; see docs/ring.md)
COLLOCATION_TOLERANCE = 1e-2
# Newton on the node forces stops once its quadratic convergence puts the next change below round-off (one
# iteration fewer than confirming it; the results differ in the last bits): False is the rule before
QUICK_NEWTON = True
# the step changes alpha_eff * gap by at most EXPONENT_STEP once the force is within this many e-folds of the
# collision's force scale, by that much more below; 20 or 25 took 7 % or no less time and left a few collisions
# 5-20 times less accurate than 30 on a set of 99 thermalised states (another set: more accurate; see docs/ring.md)
ONSET_EFOLDS = 30.0


class _CollocationPair:
    """One pair of facing ends of the ring, integrated through a collision by exponential collocation.

    The collocation kernel integrates rod 0 (left) against rod 1 (right); for the far pair the
    left rod is the ring's rod 1 and the right one rod 0, one circumference further on, which is
    put into the half length (the kernel uses half lengths in the rigid gap only).
    """

    def __init__(self, system: ModalSystem, pair: int, stages: int):
        a = int(system.pair_a[pair])
        b = int(system.pair_b[pair])
        first = system.rod_first.astype(np.int64)
        coupling = np.zeros(system.omega.size)
        coupling[first[a]:first[a + 1]] = -system.right[first[a]:first[a + 1]]
        coupling[first[b]:first[b + 1]] = system.left[first[b]:first[b + 1]]
        self.system = system
        self.order = np.array([a, b])
        self.coupling = coupling
        self.X = np.empty(2)
        self.U = np.empty(2)
        self.mass = system.mass[self.order].copy()
        self.reduced_mass = self.mass[0] * self.mass[1] / (self.mass[0] + self.mass[1])
        self.half = np.array([system.half[a], system.half[b] - system.pair_offset[pair]])
        self.compliance = float(system.pair_compliance[pair])
        self.tables = collocation.CollocationTables(system.omega, coupling, 1.0 / self.mass[0] + 1.0 / self.mass[1],
                                                    stages, min(system.dt_top, TOP_STEP_PHASE / float(np.max(system.omega))),
                                                    free_rungs=FREE_STEP_RUNGS)
        self.ends = np.zeros(end_response.ENDS_SIZE)  # no exact ends: the static correction is the compliance
        self.free = np.zeros(system.omega.size)  # free-running copy of the modes (exact ends only)
        self.records = np.empty((0, 3 + stages))
        self.counters = np.zeros(6, dtype=np.int64)

    def collide(self, tolerance):
        system = self.system
        self.X[:] = system.X[self.order]
        self.U[:] = system.U[self.order]
        self.counters[:] = 0
        # this collision's own force scale (the wave-theory plateau at its approach speed): the ring's
        # collisions slow down by an order of magnitude as the translation thermalises, and a tolerance
        # relative to the first collision's force would leave the slow ones under-resolved
        force_scale = max(self.reduced_mass * abs(self.U[1] - self.U[0]), 1e-9 * system.force_scale)
        status = collocation.run_collision(
            (system.q, system.v, system.omega, self.coupling), (self.X, self.U, self.mass, self.half),
            (int(system.law_code), float(system.alpha), float(system.strength), float(system.stiffness),
             self.compliance),
            (float(system.contact_range), float(force_scale), float(tolerance), float(EXPONENT_STEP), 1 << 62,
             bool(QUICK_NEWTON), float(ONSET_EFOLDS)),
            self.tables.arrays(), (self.ends, self.free, self.free, self.records),
            (system.clock, self.counters, None),  # no history: the kernel compiled without the recording
        )
        system.check_status(status)
        if status != kernels.STATUS_SEPARATED:
            raise SolverFailure(f"ring collocation stopped with kernel status {status}", Outcome.NOT_CONVERGED)
        system.X[self.order] = self.X
        system.U[self.order] = self.U
        system.counters[0] += self.counters[0]
