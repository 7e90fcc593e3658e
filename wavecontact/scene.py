"""What is simulated: rods, their placement and motion, and the contact law.

Nothing here knows about a solver.  Units are whatever the user chooses, as
long as they are consistent; :func:`two_rods` builds the paper's setting in
the dimensionless units of docs/theory.md (Dimensionless numbers) (``rho = c = A = 1``, effective
length ``l = 1``, approach speed ``V = 1``, hence ``alpha = kappa``).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from .bodies import is_line_scene, needs_line_validation, validate_line_scene
from .contact import LAW_PENALTY, ContactLaw, Penalty, contact_from_name
from .errors import InvalidParameterError, require_finite, require_magnitude, require_positive
from .limits import check_kappa

__all__ = ["Rod", "Scene", "TwoRodParameters", "penalty_stiffness", "two_rod_parameters", "two_rods", "two_rods_on_a_ring"]

FieldFunction = Callable[[np.ndarray], np.ndarray]


@dataclass(frozen=True)
class Rod:
    """A uniform, linearly elastic rod with stress-free ends.

    Parameters
    ----------
    length : float
        Length ``l`` (length units), in [1e-30, 1e30].
    density : float
        Mass density ``rho`` (mass/length^3), in [1e-30, 1e30].
    youngs_modulus : float
        Young's modulus ``E`` (force/length^2), in [1e-30, 1e30].
    area : float
        Cross-section ``A`` (length^2), in [1e-30, 1e30].

    Notes
    -----
    The range covers any consistent unit system (SI spans 1e-9 m to 1e12 Pa);
    it keeps the products the solvers form (``c^2 / h^2``, ``rho A l``, ...)
    inside double precision, where values near 1e300 would overflow.
    """

    length: float
    density: float = 1.0
    youngs_modulus: float = 1.0
    area: float = 1.0

    def __post_init__(self):
        for name in ("length", "density", "youngs_modulus", "area"):
            object.__setattr__(self, name, require_magnitude(f"rod {name}", getattr(self, name)))

    @property
    def wave_speed(self) -> float:
        """Bar wave speed ``c = sqrt(E / rho)`` (length/time)."""
        return math.sqrt(self.youngs_modulus / self.density)

    @property
    def impedance(self) -> float:
        """Mechanical impedance ``Z = rho c A`` (mass/time)."""
        return self.density * self.wave_speed * self.area

    @property
    def mass(self) -> float:
        """Total mass ``rho A l`` (mass)."""
        return self.density * self.area * self.length

    @property
    def round_trip_time(self) -> float:
        """Time ``2 l / c`` for a wave to run to the far end and back (time)."""
        return 2.0 * self.length / self.wave_speed

    def same_material(self, other: Rod, rtol: float = 1e-12) -> bool:
        """True if both rods share density, modulus and cross-section."""
        return all(
            math.isclose(getattr(self, n), getattr(other, n), rel_tol=rtol)
            for n in ("density", "youngs_modulus", "area")
        )


@dataclass(frozen=True)
class Scene:
    """Rods on a line (left to right) or on a ring, with a contact law.

    Parameters
    ----------
    rods : sequence of Rod
        The rods in order along the line (or around the ring).
    velocities : sequence of float
        Rigid-body velocity of each rod (length/time).
    contact : ContactLaw
        Law acting between every pair of facing ends.
    gaps : sequence of float or None
        End-to-end gaps (length) between rod ``i`` and ``i + 1`` (on a ring
        also between the last and the first).  ``None`` lets the solver place
        the rods just out of range of the contact force.
    ring_circumference : float or None
        Circumference ``L`` of the ring (length); ``None`` for a line.
    initial_displacement, initial_velocity : sequence of callables or None
        Optional fields ``u_i(s)`` (length) and ``du_i/dt(s)`` (length/time)
        of the rod coordinate ``s`` in ``[0, l_i]``, added to the rigid motion.
    vibrations : wavecontact.bath.BathRealisation or None
        A thermal-bath realisation (modal amplitudes at the nominal contact
        time).  The fields above are then that realisation's mode sums at the
        start; solvers that work with modes or with the noise ``Q(tau)`` use
        the amplitudes directly (see :func:`two_rods`).
    walls : pair of (Wall or None), or None
        Fixed walls at the left and right end of a line (:class:`wavecontact.bodies.Wall`).

    Notes
    -----
    On a line, ``rods`` may also hold :class:`~wavecontact.bodies.PiecewiseRod`
    and :class:`~wavecontact.bodies.RigidBody` bodies, ``contact`` may be a
    tuple of laws (one per facing pair) and ``gaps`` entries may be ``None``;
    such scenes (and any number of bodies other than two) are checked by
    :func:`wavecontact.bodies.validate_line_scene` and solved by
    ``solver='fem'`` only (docs/multibody.md).
    """

    rods: tuple
    velocities: tuple
    contact: ContactLaw
    gaps: tuple | None = None
    ring_circumference: float | None = None
    initial_displacement: tuple | None = None
    initial_velocity: tuple | None = None
    metadata: dict = field(default_factory=dict, compare=False)
    vibrations: object = None
    walls: tuple | None = None

    def __post_init__(self):
        if needs_line_validation(self):  # piecewise rods, rigid bodies, per-pair laws or walls (bodies.py)
            validate_line_scene(self)
            return
        rods = tuple(self.rods)
        if len(rods) < 2:
            raise InvalidParameterError(f"a scene needs at least 2 rods, got {len(rods)}")
        if not all(isinstance(r, Rod) for r in rods):
            raise InvalidParameterError("rods must be wavecontact.Rod instances")
        object.__setattr__(self, "rods", rods)
        velocities = tuple(self.velocities)
        if len(velocities) != len(rods):
            raise InvalidParameterError(
                f"velocities must have one entry per rod ({len(rods)}), got {len(velocities)}"
            )
        object.__setattr__(
            self, "velocities", tuple(require_magnitude(f"velocities[{i}]", v, signed=True) for i, v in enumerate(velocities))
        )
        if not isinstance(self.contact, ContactLaw):
            raise InvalidParameterError("contact must be a wavecontact contact law (Exponential, Penalty, Hertz, Hard)")
        n_pairs = len(rods) if self.ring_circumference is not None else len(rods) - 1
        if self.ring_circumference is not None:
            circumference = require_positive("ring_circumference", self.ring_circumference)
            total = sum(r.length for r in rods)
            if circumference <= total:
                raise InvalidParameterError(
                    f"ring_circumference must exceed the total rod length {total:g}, got {circumference:g}"
                )
            object.__setattr__(self, "ring_circumference", circumference)
        if self.gaps is not None:
            gaps = tuple(require_finite(f"gaps[{i}]", g) for i, g in enumerate(self.gaps))
            if len(gaps) != n_pairs:
                raise InvalidParameterError(f"gaps must have {n_pairs} entries, got {len(gaps)}")
            for i, g in enumerate(gaps):
                if g < 0.0:
                    raise InvalidParameterError(
                        f"gaps[{i}] must be >= 0 (rods may not overlap at the start), got {g:g}"
                    )
            if self.ring_circumference is not None:
                free = self.ring_circumference - sum(r.length for r in rods)
                if not math.isclose(sum(gaps), free, rel_tol=1e-9, abs_tol=1e-12):
                    raise InvalidParameterError(
                        f"gaps on a ring must add up to L - sum(l_i) = {free:g}, got {sum(gaps):g}"
                    )
            object.__setattr__(self, "gaps", gaps)
        for name in ("initial_displacement", "initial_velocity"):
            fields = getattr(self, name)
            if fields is not None:
                fields = tuple(fields)
                if len(fields) != len(rods) or not all(f is None or callable(f) for f in fields):
                    raise InvalidParameterError(
                        f"{name} must hold one callable (or None) per rod ({len(rods)})"
                    )
                object.__setattr__(self, name, fields)

    @property
    def is_line_scene(self) -> bool:
        """True for a scene beyond the paper's two uniform rods on a line (:func:`wavecontact.bodies.is_line_scene`)."""
        return is_line_scene(self)

    @property
    def is_ring(self) -> bool:
        return self.ring_circumference is not None

    @property
    def is_cold(self) -> bool:
        """True when no rod carries an initial internal field."""
        fields = (self.initial_displacement or ()) + (self.initial_velocity or ())
        return all(f is None for f in fields)

    @property
    def total_mass(self) -> float:
        return sum(r.mass for r in self.rods)

    def momentum(self) -> float:
        """Total rigid-body momentum (mass * length/time)."""
        return sum(r.mass * v for r, v in zip(self.rods, self.velocities))

    def kinetic_energy(self) -> float:
        """Rigid-body kinetic energy (energy)."""
        return sum(0.5 * r.mass * v * v for r, v in zip(self.rods, self.velocities))


@dataclass(frozen=True)
class TwoRodParameters:
    """The paper's dimensionless numbers of a two-rod collision (docs/theory.md, Dimensionless numbers)."""

    gamma: float  # l1 / l2 in (0, 1]
    kappa: float  # alpha V l / c in (0, inf]
    effective_length: float  # l = 2 l1 l2 / (l1 + l2)
    approach_speed: float  # V
    wave_speed: float  # c

    @property
    def round_trip_times(self) -> tuple:
        """Dimensionless round-trip times ``(Gamma_1, Gamma_2) = (1 + gamma, 1 + 1/gamma)``."""
        return (1.0 + self.gamma, 1.0 + 1.0 / self.gamma)

    @property
    def time_unit(self) -> float:
        """``l / c``: the unit of the dimensionless time tau (time)."""
        return self.effective_length / self.wave_speed


def validate_gamma_kappa(gamma, kappa) -> tuple:
    """Check the paper's two numbers and return them as floats.

    ``gamma`` must lie in (0, 1]; ``kappa`` in (0, inf] (``inf``: hard core).
    """
    try:
        g = float(gamma)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"gamma must be a number in (0, 1], got {gamma!r}") from None
    if not (0.0 < g <= 1.0):
        raise InvalidParameterError(f"gamma must lie in (0, 1] (gamma = l1/l2, l1 <= l2), got {g!r}")
    k = require_positive("kappa", kappa, allow_inf=True)
    return g, k


def two_rods(
    gamma: float,
    kappa: float,
    *,
    contact: str | ContactLaw = "exponential",
    gap: float | None = None,
    initial_displacement: Sequence | None = None,
    initial_velocity: Sequence | None = None,
    vibrations=None,
) -> Scene:
    """The paper's head-on collision of two rods of one material, dimensionless.

    Units (docs/theory.md, Dimensionless numbers): ``rho = c = A = 1``, effective length
    ``l = 2 l1 l2 / (l1 + l2) = 1`` and approach speed ``V = 1``; so
    ``l1 = (1 + gamma) / 2``, ``l2 = (1 + gamma) / (2 gamma)``, the reduced
    mass is ``mu = 1/2`` and ``alpha = kappa``.  The short rod is on the
    left.  Velocities are in the centre-of-mass frame (zero momentum), the
    relative velocity ``v2 - v1`` is ``-V``.

    Parameters
    ----------
    gamma : float
        Length ratio ``l1 / l2`` in (0, 1].
    kappa : float
        ``alpha V l / c`` in [1e-2, 1e7] or ``inf`` (selects hard contact;
        :data:`wavecontact.limits.KAPPA_MIN`, :data:`~wavecontact.limits.KAPPA_MAX`).
    contact : {'exponential', 'penalty', 'hard'} or ContactLaw
        The contact law.  The exponential law gets ``B = mu c^2 / (alpha l)^2``,
        the value for which the delay equation (Eq. 16) holds without a shift.
        The penalty law gets the stiffness ``k = kappa Z_eff c / l``
        (:func:`penalty_stiffness`, here ``kappa / 2``): the spring whose
        contact relaxes at the rate ``alpha V`` of the exponential law at its
        plateau, so that both resolve the same collision time; with ``kappa =
        inf`` the stiffness is left to the solver (the FE solver ties it to
        the mesh, so the run tends to hard contact as the mesh is refined).
        A ``Penalty`` passed in must have the rule's stiffness or ``None``
        (then it is set).
    gap : float or None
        Initial end-to-end gap (length); ``None`` lets the solver choose.
    initial_displacement, initial_velocity : sequences of two callables or None
        Optional internal fields, see :class:`Scene`.
    vibrations : wavecontact.bath.BathRealisation or None
        Thermal vibrations (for example ``ThermalBath(...).draw(...)``), given
        at the nominal contact time ``t_c = gap / V``.  ``gap=None`` then
        chooses a gap beyond the vibrations' reach
        (:func:`wavecontact.bath.scene.start_gap`), and the initial fields
        are the realisation evolved back to ``t = 0``.

    Returns
    -------
    Scene
        With ``metadata['two_rods']`` holding the :class:`TwoRodParameters`.
    """
    g, k, rods = _validated_two_rods(gamma, kappa)
    return _assemble_two_rods(g, k, rods, contact=contact, gap=gap, initial_displacement=initial_displacement,
                              initial_velocity=initial_velocity, vibrations=vibrations)


def _validated_two_rods(gamma, kappa) -> tuple:
    """``(gamma, kappa, (rod1, rod2))`` of :func:`two_rods`, checked: the one validation of the two numbers
    along a solve (the solvers trust ``metadata['two_rods']``; :func:`wavecontact.bath.collide.thermal_scene`
    needs the rods' lengths before it can draw their vibrations, and checks nothing again)."""
    g, k = validate_gamma_kappa(gamma, kappa)
    check_kappa(k)
    l1 = 0.5 * (1.0 + g)
    l2 = 0.5 * (1.0 + g) / g
    # the lengths are the only numbers of the rods that gamma sets: checked here, once (l2 leaves the
    # magnitude range for gamma below about 1e-30), the unit material taken as it is
    return g, k, (_unit_rod(require_magnitude("rod length", l1)), _unit_rod(require_magnitude("rod length", l2)))


def _assemble_two_rods(g: float, k: float, rods: tuple, *, contact="exponential", gap=None,
                       initial_displacement=None, initial_velocity=None, vibrations=None) -> Scene:
    """:func:`two_rods` from the values :func:`_validated_two_rods` checked."""
    reduced_mass = 0.5
    if isinstance(contact, ContactLaw):
        law = contact
        if law.decay_rate > 0.0 and not math.isclose(law.decay_rate, k) and math.isfinite(k):
            raise InvalidParameterError(
                f"contact alpha ({law.decay_rate:g}) must equal kappa ({k:g}) in the units of two_rods"
            )
        if law.code == LAW_PENALTY and math.isfinite(k):
            stiffness = penalty_stiffness(k, 0.5, 1.0, 1.0)
            if law.stiffness is None:
                law = Penalty(stiffness)
            elif not math.isclose(law.stiffness, stiffness):
                raise InvalidParameterError(
                    f"penalty stiffness ({law.stiffness:g}) must be kappa / 2 = {stiffness:g} in the units of "
                    "two_rods (or None); for another stiffness build the Scene directly"
                )
    elif contact == "penalty":
        # finite kappa: the rule's stiffness; kappa = inf: the solver ties it to the mesh (hard limit)
        law = Penalty(penalty_stiffness(k, 0.5, 1.0, 1.0)) if math.isfinite(k) else Penalty()
    else:
        law = contact_from_name(contact, k, reduced_mass / (k * k) if math.isfinite(k) else 1.0)
    if law.hard and math.isfinite(k) and contact == "hard":
        k = math.inf
    m1, m2 = rods[0].mass, rods[1].mass
    velocities = (m2 / (m1 + m2), -m1 / (m1 + m2))
    params = TwoRodParameters(gamma=g, kappa=k, effective_length=1.0, approach_speed=1.0, wave_speed=1.0)
    if vibrations is not None:
        from .bath.scene import vibration_fields

        if initial_displacement is not None or initial_velocity is not None:
            raise InvalidParameterError("give either vibrations or initial fields, not both")
        gap, initial_displacement, initial_velocity = vibration_fields(vibrations, rods, law, gap)
    if gap is None and initial_displacement is None and initial_velocity is None and vibrations is None:
        # everything in it was derived and checked above: validated once, here, not again by Scene
        # the short rod's speed m1 / (m1 + m2) < 1/2 leaves the magnitude range first (gamma below about 1e-30):
        # the Scene's check of it kept, the long rod's m2 / (m1 + m2) lies in [1/2, 1)
        require_magnitude("velocities[1]", velocities[1], signed=True)
        return _checked_scene(rods, velocities, law, {"two_rods": params})
    return Scene(
        rods=rods,
        velocities=velocities,
        contact=law,
        gaps=None if gap is None else (gap,),
        initial_displacement=initial_displacement,
        initial_velocity=initial_velocity,
        metadata={"two_rods": params},
        vibrations=vibrations,
    )


def _unit_rod(length: float) -> Rod:
    """``Rod(length)`` (unit density, modulus and section) of a length already checked by the caller."""
    rod = object.__new__(Rod)
    for name, value in (("length", length), ("density", 1.0), ("youngs_modulus", 1.0), ("area", 1.0)):
        object.__setattr__(rod, name, value)
    return rod


def _checked_scene(rods: tuple, velocities: tuple, law: ContactLaw, metadata: dict) -> Scene:
    """A cold two-rod :class:`Scene` on a line (no gaps, fields, vibrations or walls) from values the caller
    derived and checked (:func:`two_rods`): the same object ``Scene(...)`` builds, without its checks."""
    scene = object.__new__(Scene)
    values = {"rods": rods, "velocities": velocities, "contact": law, "gaps": None, "ring_circumference": None,
              "initial_displacement": None, "initial_velocity": None, "metadata": metadata, "vibrations": None,
              "walls": None}
    for name, value in values.items():
        object.__setattr__(scene, name, value)
    return scene


def two_rods_on_a_ring(gamma: float, kappa: float, circumference: float | None = None) -> Scene:
    """The paper's two rods on a ring (Sec. III), started maximally far apart with a cold bath.

    Units and contact law as :func:`two_rods`.  Going round the ring, rod 1's
    right end faces rod 2's left end (the *near* pair, gap ``gaps[0]``) and
    rod 2's right end faces rod 1's left end across the seam (the *far* pair,
    ``gaps[1]``); both gaps are equal.

    Parameters
    ----------
    gamma, kappa : float
        As :func:`two_rods`.
    circumference : float or None
        Ring circumference ``L`` (in ``l``); default: the two rods plus two free
        stretches, each at least 1 and at least ``100 / kappa`` long, so that the
        rods start out of range of the force.
    """
    line = two_rods(gamma, kappa)
    rod1, rod2 = line.rods
    total = rod1.length + rod2.length
    if circumference is None:
        k = line.metadata["two_rods"].kappa
        free = max(1.0, 100.0 / k) if math.isfinite(k) else 1.0
        circumference = total + 2.0 * free
    circumference = require_positive("circumference", circumference)
    if circumference <= total:
        raise InvalidParameterError(f"circumference must exceed l1 + l2 = {total:g}, got {circumference:g}")
    gap = 0.5 * (circumference - total)
    return Scene(rods=line.rods, velocities=line.velocities, contact=line.contact, gaps=(gap, gap),
                 ring_circumference=circumference, metadata=dict(line.metadata))


def penalty_stiffness(kappa: float, impedance: float, wave_speed: float, length: float) -> float:
    """Penalty stiffness ``k = kappa Z_eff c / l`` (force/length) that stands for ``kappa``.

    At the plateau of the exponential law (force ``Z_eff V``) the gap of two
    massless ends relaxes at the rate ``alpha V``; a spring ``k`` relaxes it at
    ``k / Z_eff``.  Equal rates give ``k = alpha V Z_eff = kappa Z_eff c / l``.

    Parameters
    ----------
    kappa : float
        ``alpha V l / c`` (dimensionless), finite.
    impedance : float
        ``Z_eff = 1 / (1/Z_1 + 1/Z_2)`` (mass/time).
    wave_speed, length : float
        ``c`` (length/time) and the effective length ``l`` (length).
    """
    return kappa * impedance * wave_speed / length


def two_rod_parameters(scene: Scene) -> TwoRodParameters:
    """Recover ``(gamma, kappa, ...)`` of a two-rod scene on a line.

    Works for scenes built by :func:`two_rods` (or :func:`two_rods_on_a_ring`)
    and for any line scene of two rods of one material; the contact law fixes
    ``kappa`` (``inf`` for hard contact; for a penalty law the inverse of
    :func:`penalty_stiffness`, NaN if the solver is to choose the stiffness).
    """
    if "two_rods" in scene.metadata:
        return scene.metadata["two_rods"]
    if len(scene.rods) != 2 or scene.is_ring or scene.is_line_scene:
        raise InvalidParameterError("two_rod_parameters needs two rods on a line")
    r1, r2 = scene.rods
    if not r1.same_material(r2):
        raise InvalidParameterError("two_rod_parameters needs rods of one material and section")
    l1, l2 = r1.length, r2.length
    gamma = min(l1, l2) / max(l1, l2)
    ell = 2.0 * l1 * l2 / (l1 + l2)
    speed = -(scene.velocities[1] - scene.velocities[0])
    c = r1.wave_speed
    law = scene.contact
    if law.decay_rate > 0.0:
        kappa = law.decay_rate * speed * ell / c
    elif law.hard:
        kappa = math.inf
    elif law.code == LAW_PENALTY:  # the stiffness that corresponds to kappa (penalty_stiffness)
        stiffness = law.stiffness
        kappa = math.nan if stiffness is None else stiffness / penalty_stiffness(1.0, 0.5 * r1.impedance, c, ell)
    else:  # another law has numbers of its own (docs/theory.md)
        kappa = math.nan
    return TwoRodParameters(gamma=gamma, kappa=kappa, effective_length=ell, approach_speed=speed, wave_speed=c)

