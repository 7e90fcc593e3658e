"""Assembled modal system: rods, their modes, contact pairs; state, energy, stepping.

:class:`ModalSystem` packs everything the compiled integrator needs into flat
arrays once, and offers the bookkeeping around it (energies, modal energies,
state snapshots).  Both the single-collision solver
(:mod:`wavecontact.modal.solver`) and the ring (:mod:`wavecontact.modal.ring`) are built on it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..contact import ContactLaw
from ..contact_kernels import CLOSED_FORM_CODES
from ..errors import InvalidParameterError, SolverFailure, UnsupportedSceneError
from ..result import Outcome
from . import kernels

__all__ = ["ModalSystem", "StepControl", "contact_parameters"]

# a force below force_scale * exp(-NEGLIGIBLE_EXPONENT) is treated as zero
NEGLIGIBLE_EXPONENT = 40.0


@dataclass(frozen=True)
class StepControl:
    """Step-size control of the contact integrator (all dimensionless).

    Attributes
    ----------
    accuracy : float
        ``eta``: the step is at most ``eta`` over the linearised contact
        frequency, and ``eta sqrt(F_scale / F)`` over the rate
        ``alpha_eff |d gap/dt|`` at which the force changes.  The error in
        epsilon falls like ``eta^2`` (Strang splitting).
    reach : float
        Largest change of ``alpha * gap`` in one step while the force is small.
    ladder_ratio : float
        Steps are ``dt_top * ladder_ratio**-j`` (rotations tabulated once).
    levels : int
        Number of ladder rungs (smallest step ``dt_top * ladder_ratio**-(levels-1)``).
    order : {2, 4}
        Strang splitting (2) or its symmetric triple-jump composition (4).
    """

    accuracy: float = 0.0125
    reach: float = 0.25
    ladder_ratio: float = 2.0**0.25
    levels: int = 140
    order: int = 2

    def __post_init__(self):
        for name in ("accuracy", "reach"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and 0.0 < value <= 10.0):
                raise InvalidParameterError(f"step {name} must lie in (0, 10], got {value!r}")
        if self.order not in (2, 4):
            raise InvalidParameterError(f"step order must be 2 or 4, got {self.order!r}")
        if not (1.0 < self.ladder_ratio <= 2.0):
            raise InvalidParameterError(f"ladder_ratio must lie in (1, 2], got {self.ladder_ratio!r}")


def contact_parameters(law: ContactLaw, force_scale: float, static_correction: bool):
    """Kernel encoding ``(code, alpha, strength, stiffness, contact_range)`` of a contact law.

    The first four numbers are the law's own :meth:`~wavecontact.contact.ContactLaw.kernel_parameters`
    (a hard law is a penalty spring of infinite stiffness to these kernels).
    """
    code, alpha, strength, stiffness = law.kernel_parameters()
    if law.decay_rate > 0.0:
        shift = max(0.0, math.log(law.decay_rate * law.strength / force_scale))
        return code, alpha, strength, stiffness, (NEGLIGIBLE_EXPONENT + shift) / law.decay_rate
    if law.hard:
        if not static_correction:
            raise UnsupportedSceneError(
                "hard contact (kappa = inf) needs static_correction=True in the modal solver: without the "
                "omitted modes a truncated rod end has a finite mass and a hard impact on it is "
                "instantaneous and undefined (correction='end-response' or 'static' account for them)"
            )
        return kernels.LAW_LINEAR, 1.0, 0.0, stiffness, 0.0
    if law.stiffness_from_solver:
        raise UnsupportedSceneError(
            f"the modal solver needs an explicit {law.name} stiffness (Penalty(stiffness=k)); "
            "it has no mesh to choose one from"
        )
    return code, 1.0, 0.0, stiffness, 0.0


class ModalSystem:
    """Rods (centre of mass + kept modes) joined by contact pairs.

    Parameters
    ----------
    rod_modes : sequence of RodModes
        Modes of each rod, in order.
    positions, velocities : sequence of float
        Centre-of-mass positions (length) and velocities (length/time).
    pairs : sequence of (int, int, float)
        ``(a, b, offset)``: the right end of rod ``a`` faces the left end of
        rod ``b``, whose position is shifted by ``offset`` (the circumference
        for the pair across a ring's seam, else 0).
    law : ContactLaw
        The contact law of every pair.
    force_scale : float
        Typical contact force (force units), the yardstick of "negligible".
    static_correction : bool
        Add the omitted modes' end compliance in series with the contact.
    control : StepControl
        Step-size control.
    exact_ends : bool
        The omitted modes are accounted for by the exact end response of
        uniform rods (collocation of two rods only, see
        :func:`wavecontact.modal.collocation.run_collision`): no series
        compliance, and hard contact is allowed without it.

    Notes
    -----
    The residual compliance joins the two ends of one pair (the diagonal
    terms); the cross-compliance between two pairs sharing a rod is left
    out, which is exact as long as no rod is pushed at both ends at once
    (always true on a ring much longer than the force's range).
    """

    def __init__(self, rod_modes, positions, velocities, pairs, law, force_scale,
                 static_correction=True, control=StepControl(), exact_ends=False):
        self.rod_modes = tuple(rod_modes)
        self.rods = tuple(m.rod for m in self.rod_modes)
        self.law = law
        self.exact_ends = bool(exact_ends)
        self.static_correction = bool(static_correction) and not self.exact_ends
        self.control = control
        counts = [m.count for m in self.rod_modes]
        # unsigned offsets let the compiler drop negative-index handling and vectorise the mode loops
        self.rod_first = np.concatenate([[0], np.cumsum(counts)]).astype(np.uint64)
        self.omega = np.concatenate([m.omega for m in self.rod_modes]).astype(float)
        self.left = np.concatenate([m.left for m in self.rod_modes]).astype(float)
        self.right = np.concatenate([m.right for m in self.rod_modes]).astype(float)
        self.mass = np.array([r.mass for r in self.rods], dtype=float)
        self.half = np.array([0.5 * r.length for r in self.rods], dtype=float)
        self.q = np.zeros(self.omega.size)
        self.v = np.zeros(self.omega.size)
        self.X = np.array(positions, dtype=float)
        self.U = np.array(velocities, dtype=float)
        pairs = list(pairs)
        self.pair_a = np.array([p[0] for p in pairs], dtype=np.int64)
        self.pair_b = np.array([p[1] for p in pairs], dtype=np.int64)
        self.pair_offset = np.array([p[2] for p in pairs], dtype=float)
        compliance = []
        omitted = []
        inverse_mass = []
        for a, b, _ in pairs:
            ma, mb = self.rod_modes[a], self.rod_modes[b]
            c = ma.residual_compliance[1, 1] + mb.residual_compliance[0, 0]
            omitted.append(c)
            compliance.append(c if self.static_correction else 0.0)
            inverse_mass.append(1.0 / self.mass[a] + 1.0 / self.mass[b]
                                + float(np.sum(ma.right**2)) + float(np.sum(mb.left**2)))
        self.pair_compliance = np.array(compliance, dtype=float)
        self.omitted_compliance = np.array(omitted, dtype=float)  # of the omitted modes, used or not
        self.pair_inverse_mass = np.array(inverse_mass, dtype=float)
        self.force_scale = float(force_scale)
        (self.law_code, self.alpha, self.strength, self.stiffness,
         self.contact_range) = contact_parameters(law, self.force_scale, self.static_correction or self.exact_ends)
        # the kernels' flag for a law without closed forms (None: compiled without the generic solve)
        self.generic_law = None if self.law_code in CLOSED_FORM_CODES else True
        self.dt_top = 0.05 * min(r.length / r.wave_speed for r in self.rods)
        if self.law_code == kernels.LAW_EXPONENTIAL:
            self.dt_top = max(self.dt_top, 0.05 / (self.alpha * max(1e-300, np.max(np.abs(self.U)))))
        self._fractions, self.sub_index, self.sub_weight = kernels.composition(control.order)
        self._rotation_tables = None  # filled on the first splitting step (the collocation path needs none)
        self.clock = np.zeros(2)
        self.episode = np.full(1, -1, dtype=np.int64)
        self.counters = np.zeros(4, dtype=np.int64)

    # ---------------------------------------------------------------- stepping
    def rotation_tables(self):
        """``(cos, sin / omega, omega sin)`` of every substep fraction on every ladder rung (cached)."""
        if self._rotation_tables is None:
            self._rotation_tables = kernels.rotation_tables(
                self.omega, self.dt_top, self.control.ladder_ratio, self.control.levels, self._fractions
            )
        return self._rotation_tables

    def run_episode(self, history=None, max_steps=10_000_000):
        """Integrate until the current collision is over; return the kernel status."""
        if self.exact_ends:
            raise UnsupportedSceneError("exact ends are integrated by collocation only (two rods); "
                                        "use correction='static' with the splitting")
        if history is not None and history.shape[0] == 0:
            history = None  # records nothing: the kernel compiled without the recording
        # max_steps 0 (the ring's free flights): no step, and the kernel compiled without the stepping
        tables = self.rotation_tables() if max_steps > 0 else None
        return kernels.run_episode(
            (self.q, self.v, self.omega, self.left, self.right, self.rod_first), (self.X, self.U, self.mass, self.half),
            (self.pair_a, self.pair_b, self.pair_offset, self.pair_compliance, self.pair_inverse_mass),
            (int(self.law_code), float(self.alpha), float(self.strength), float(self.stiffness),
             float(self.contact_range)),
            (float(self.control.accuracy), float(self.control.reach), float(self.force_scale), float(self.dt_top),
             float(self.control.ladder_ratio), self.sub_index, self.sub_weight),
            tables, (self.clock, self.episode, self.counters), history, int(max_steps), self.generic_law,
        )

    @staticmethod
    def check_status(status):
        """Raise :class:`SolverFailure` for a failed kernel status."""
        if status == kernels.STATUS_STEP_UNDERFLOW:
            raise SolverFailure(
                "modal integrator: the contact step fell below the smallest ladder step; the contact is "
                "too stiff for this resolution (try more modes, static_correction=True or step_method='splitting')",
                Outcome.STEP_UNDERFLOW,
            )
        if status == kernels.STATUS_NOT_FINITE:
            raise SolverFailure("modal integrator: the contact force overflowed (overlap far beyond the "
                                "force's range); reduce step_accuracy", Outcome.NON_FINITE)

    # ------------------------------------------------------------- bookkeeping
    def gaps(self) -> np.ndarray:
        """Modal gap of each pair (length), without the residual spring."""
        sums = np.empty((self.X.size, 4))
        kernels.end_sums(self.q, self.v, self.left, self.right, self.rod_first, sums)
        a, b = self.pair_a, self.pair_b
        return (self.X[b] - self.half[b] + self.pair_offset + sums[b, 0]) - (self.X[a] + self.half[a] + sums[a, 1])

    def contact_energy(self) -> float:
        total = 0.0
        for k, g in enumerate(self.gaps()):
            # the response the compiled kernels use (no kernel of its own to compile for this call)
            if self.law_code == kernels.LAW_EXPONENTIAL:
                _, energy, _, _ = kernels.exponential_response(float(g), float(self.alpha), float(self.strength),
                                                               float(self.pair_compliance[k]), math.nan)
            else:
                _, energy, _, _ = kernels.contact_response_from(
                    float(g), int(self.law_code), float(self.alpha), float(self.strength), float(self.stiffness),
                    float(self.pair_compliance[k]), math.nan, self.generic_law,
                )
            total += energy
        return total

    def modal_energies(self) -> list:
        """Energy of every kept mode, one array per rod (energy units)."""
        e = 0.5 * (self.v**2 + (self.omega * self.q) ** 2)
        return [e[self.rod_first[i]:self.rod_first[i + 1]].copy() for i in range(self.X.size)]

    def translational_energy(self) -> float:
        return float(0.5 * np.sum(self.mass * self.U**2))

    def total_energy(self) -> float:
        """Centres of mass, kept modes and contact (energy units); the same sums as
        :meth:`translational_energy`, :meth:`modal_energies` and :meth:`contact_energy`, without their copies."""
        e = 0.5 * (self.v**2 + (self.omega * self.q) ** 2)
        first = self.rod_first
        vibration = 0
        for i in range(self.X.size):
            vibration += np.sum(e[first[i]:first[i + 1]])
        return self.translational_energy() + float(vibration) + self.contact_energy()

    def momentum(self) -> float:
        return float(np.sum(self.mass * self.U))

    def get_state(self) -> dict:
        return {
            "q": self.q.copy(), "v": self.v.copy(), "X": self.X.copy(), "U": self.U.copy(),
            "clock": self.clock.copy(), "episode": self.episode.copy(), "counters": self.counters.copy(),
        }

    def set_state(self, state: dict) -> None:
        for name in ("q", "v", "X", "U", "clock", "episode", "counters"):
            value = np.asarray(state[name])
            target = getattr(self, name)
            if value.shape != target.shape:
                raise InvalidParameterError(f"state[{name!r}] has shape {value.shape}, expected {target.shape}")
            target[...] = value
