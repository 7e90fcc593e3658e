"""Two rods on a ring: an endless cascade of collisions from a cold bath (paper Sec. III).

The rods move on a circle of circumference ``L``.  Going round, the right end
of rod 1 faces the left end of rod 2 (the *near* pair) and the right end of
rod 2 faces the left end of rod 1 across the seam (the *far* pair, whose
modal end displacements enter with the opposite sign pattern, Eq. 7).  Each
call of :meth:`RingSimulation.next_collision` advances through exactly one
collision of whichever pair meets next; the long flights in between are
skipped in closed form.

Units are those of :func:`wavecontact.two_rods` (``rho = c = A = 1``,
effective length ``l = 1``, first approach speed ``V = 1``, ``alpha = kappa``,
``B = mu / kappa^2``): times in ``l / c``, energies in ``mu V^2``-units with
``mu = 1/2``.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import InvalidParameterError, SolverFailure
from ..scene import two_rods
from . import kernels
from .modes import rod_modes
from .system import ModalSystem, StepControl

__all__ = ["RingSimulation"]


class RingSimulation:
    """Two rods of length ratio ``gamma`` on a ring, colliding again and again.

    Parameters
    ----------
    gamma : float
        Length ratio ``l1 / l2`` in (0, 1].
    kappa : float
        ``alpha V l / c`` in (0, inf] (``inf``: hard contact, needs the
        static correction).
    modes : int
        Modes kept per rod (the paper's ``N_mod``).
    static_correction : bool
        Add the omitted modes' static end compliance in series with the contact.
    circumference : float or None
        Ring circumference ``L`` (in ``l``); default: the two rods plus two
        free stretches, each at least 1 and at least ``100 / kappa`` long, so
        that the rods, started maximally far apart (equal free stretches on
        both sides), do not feel each other.
    seed : int or None
        Accepted for a stable interface; the cold start is deterministic and
        does not use it.
    step_accuracy, step_reach, step_order
        Contact step control (see :class:`StepControl`); the defaults keep
        the energy drift near 5e-8 of the total per collision.
    mode_source : {'analytic', 'fe'}
        Where the modes come from.

    Attributes
    ----------
    gamma, kappa, modes : the parameters.
    reduced_mass : float
        ``mu = m1 m2 / (m1 + m2) = 1/2``.
    total_energy : float
        ``mu V^2 / 2``, conserved.
    collisions : int
        Number of collisions completed.
    """

    def __init__(self, gamma, kappa, modes, static_correction=True, circumference=None, seed=None,
                 step_accuracy=StepControl.accuracy, step_reach=StepControl.reach, step_order=StepControl.order,
                 mode_source="analytic"):
        scene = two_rods(gamma, kappa)
        self.gamma = float(gamma)
        self.kappa = float(kappa)
        self.modes = int(modes)
        self.static_correction = bool(static_correction)
        self.seed = seed
        rod1, rod2 = scene.rods
        free = max(1.0, 100.0 / self.kappa) if math.isfinite(self.kappa) else 1.0
        if circumference is None:
            circumference = rod1.length + rod2.length + 2.0 * free
        circumference = float(circumference)
        if not (math.isfinite(circumference) and circumference > rod1.length + rod2.length):
            raise InvalidParameterError(
                f"circumference must be finite and exceed l1 + l2 = {rod1.length + rod2.length:g}, "
                f"got {circumference!r}"
            )
        self.circumference = circumference
        gap = 0.5 * (circumference - rod1.length - rod2.length)
        positions = (0.5 * rod1.length, rod1.length + gap + 0.5 * rod2.length)
        self.reduced_mass = rod1.mass * rod2.mass / (rod1.mass + rod2.mass)
        approach = -(scene.velocities[1] - scene.velocities[0])
        self.system = ModalSystem(
            [rod_modes(rod1, self.modes, mode_source), rod_modes(rod2, self.modes, mode_source)],
            positions,
            scene.velocities,
            [(0, 1, 0.0), (1, 0, circumference)],
            scene.contact,
            force_scale=self.reduced_mass * approach,  # mu V c / l
            static_correction=self.static_correction,
            control=StepControl(accuracy=step_accuracy, reach=step_reach, order=step_order),
        )
        if self.system.contact_range >= gap:
            raise InvalidParameterError(
                f"circumference {circumference:g} is too small: the rods would start within range of the force"
            )
        self.total_energy = self.system.total_energy()
        self.collisions = 0

    @property
    def relative_velocity(self) -> float:
        """``U2 - U1`` (in V)."""
        return float(self.system.U[1] - self.system.U[0])

    @property
    def translational_energy(self) -> float:
        """Relative translational energy ``mu v_rel^2 / 2``."""
        return 0.5 * self.reduced_mass * self.relative_velocity**2

    def next_collision(self) -> dict:
        """Advance through exactly one collision and describe it.

        Returns
        -------
        dict
            ``collision`` (index from 0), ``time`` (when the pair came within
            reach of the force, in ``l/c``), ``pair`` (``"near"`` or ``"far"``),
            ``E_tr_before``, ``E_tr_after``, ``restitution``
            (``|v_rel after| / |v_rel before|``), ``modal_energies``
            (array (2, modes) after the collision), ``E_bath`` and
            ``E_total`` (energy units), ``steps`` (integrator steps of this
            collision).
        """
        system = self.system
        before = self.relative_velocity
        if before == 0.0:
            raise SolverFailure("the rods are at rest relative to each other: no further collision")
        e_before = self.translational_energy
        steps_before = int(system.counters[0])
        system.episode[0] = -1
        while True:
            status = system.run_episode()
            system.check_status(status)
            if status == kernels.STATUS_SEPARATED:
                break
            if status == kernels.STATUS_FREE_FOREVER:
                raise SolverFailure("ring: no pair approaches any more")
        pair = int(system.episode[0])
        system.episode[0] = -1
        after = self.relative_velocity
        energies = np.array(system.modal_energies())
        e_bath = float(energies.sum())
        e_tr = self.translational_energy
        record = {
            "collision": self.collisions,
            "time": float(system.clock[1]),
            "pair": "near" if pair == 0 else "far",
            "E_tr_before": e_before,
            "E_tr_after": e_tr,
            "restitution": abs(after) / abs(before),
            "modal_energies": energies,
            "E_bath": e_bath,
            "E_total": e_tr + e_bath + system.contact_energy(),
            "steps": int(system.counters[0]) - steps_before,
        }
        self.collisions += 1
        return record

    def get_state(self) -> dict:
        """Everything needed to resume bit for bit (NumPy arrays and scalars)."""
        state = self.system.get_state()
        state["collisions"] = np.int64(self.collisions)
        state["parameters"] = np.array([self.gamma, self.kappa, self.modes, float(self.static_correction),
                                        self.circumference])
        return state

    def set_state(self, state: dict) -> None:
        """Restore a state from :meth:`get_state` (of a simulation with the same parameters)."""
        expected = np.array([self.gamma, self.kappa, self.modes, float(self.static_correction),
                             self.circumference])
        given = np.asarray(state["parameters"], dtype=float)
        if given.shape != expected.shape or not np.array_equal(given, expected):
            raise InvalidParameterError(
                f"state belongs to a ring with (gamma, kappa, modes, static_correction, L) = {given.tolist()}, "
                f"this one has {expected.tolist()}"
            )
        self.system.set_state(state)
        self.collisions = int(state["collisions"])
