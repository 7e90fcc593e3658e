"""Bodies of a scene on a line beyond the uniform rod: piecewise rods, rigid bodies and walls.

A :class:`~wavecontact.scene.Scene` holds any number of bodies in order along
the line: uniform :class:`~wavecontact.scene.Rod`, :class:`PiecewiseRod`
(segments of their own length, section and material, each optionally with a
linearly tapered section) and :class:`RigidBody` (a point mass, for strikers);
each facing pair has its own contact law, and a fixed :class:`Wall` may stand
at either end.  :func:`validate_line_scene` checks such a scene; nothing here
knows about a solver.  Units are any consistent set, as for ``Rod``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from .contact import ContactLaw, Hard
from .errors import InvalidParameterError, require_finite, require_magnitude

__all__ = [
    "PiecewiseRod",
    "RigidBody",
    "Segment",
    "Wall",
    "body_segments",
    "is_line_scene",
    "pair_laws",
    "validate_line_scene",
]


@dataclass(frozen=True)
class Segment:
    """A prism (or a linearly tapered piece) of one material, part of a :class:`PiecewiseRod`.

    Parameters
    ----------
    length : float
        Length of the segment (length), > 0.
    area : float
        Cross-section at the segment's left end (length^2), > 0.
    youngs_modulus : float
        Young's modulus ``E`` (force/length^2).
    density : float
        Mass density ``rho`` (mass/length^3).
    end_area : float or None
        Cross-section at the right end (length^2), > 0; the section varies
        linearly in between.  ``None``: a prism (``end_area = area``).
    """

    length: float
    area: float = 1.0
    youngs_modulus: float = 1.0
    density: float = 1.0
    end_area: float | None = None

    def __post_init__(self):
        length = require_finite("segment length", self.length)
        if length <= 0.0:
            raise InvalidParameterError(f"segment length must be > 0 (a segment of zero length has no body), got {length!r}")
        object.__setattr__(self, "length", require_magnitude("segment length", length))
        for name in ("area", "youngs_modulus", "density"):
            value = getattr(self, name)
            if name == "area" and require_finite("segment area", value) <= 0.0:
                raise InvalidParameterError(f"segment area must be > 0, got {value!r}")
            object.__setattr__(self, name, require_magnitude(f"segment {name}", value))
        if self.end_area is not None:
            if require_finite("segment end_area", self.end_area) <= 0.0:
                raise InvalidParameterError(
                    f"segment end_area must be > 0 (a taper to zero area has an infinite stress), got {self.end_area!r}"
                )
            object.__setattr__(self, "end_area", require_magnitude("segment end_area", self.end_area))

    @property
    def right_area(self) -> float:
        """Cross-section at the right end (length^2)."""
        return self.area if self.end_area is None else self.end_area

    @property
    def tapered(self) -> bool:
        return self.end_area is not None and self.end_area != self.area

    @property
    def wave_speed(self) -> float:
        """Bar wave speed ``sqrt(E / rho)`` (length/time)."""
        return math.sqrt(self.youngs_modulus / self.density)

    @property
    def travel_time(self) -> float:
        """Time for a wave to cross the segment (time)."""
        return self.length / self.wave_speed

    @property
    def mass(self) -> float:
        """``rho (A_left + A_right) / 2 * length`` (mass)."""
        return self.density * 0.5 * (self.area + self.right_area) * self.length

    def area_at(self, s):
        """Cross-section at the segment coordinate ``s`` in ``[0, length]`` (length^2)."""
        return self.area + (self.right_area - self.area) * (s / self.length)


@dataclass(frozen=True)
class PiecewiseRod:
    """A rod made of segments joined end to end (left to right), stress-free ends.

    Parameters
    ----------
    segments : sequence of Segment
        At least one; a stepped bar has segments of different section or material.
    """

    segments: tuple

    def __post_init__(self):
        segments = tuple(self.segments) if not isinstance(self.segments, Segment) else (self.segments,)
        if not segments:
            raise InvalidParameterError("a PiecewiseRod needs at least one Segment")
        for i, segment in enumerate(segments):
            if not isinstance(segment, Segment):
                raise InvalidParameterError(f"segments[{i}] must be a wavecontact.Segment, got {type(segment).__name__}")
        object.__setattr__(self, "segments", segments)

    @property
    def length(self) -> float:
        return sum(s.length for s in self.segments)

    @property
    def mass(self) -> float:
        return sum(s.mass for s in self.segments)

    @property
    def travel_time(self) -> float:
        """Time for a wave to run from one end to the other (time)."""
        return sum(s.travel_time for s in self.segments)

    @property
    def round_trip_time(self) -> float:
        """Time for a wave to run to the far end and back (time)."""
        return 2.0 * self.travel_time


@dataclass(frozen=True)
class RigidBody:
    """A rigid body on the line: an exact point mass (length 0), e.g. a striker or a hammer.

    Parameters
    ----------
    mass : float
        Mass (mass units), > 0.
    """

    mass: float

    def __post_init__(self):
        object.__setattr__(self, "mass", require_magnitude("rigid body mass", self.mass))

    @property
    def length(self) -> float:
        return 0.0


@dataclass(frozen=True)
class Wall:
    """A fixed, immovable wall at one end of the line.

    Parameters
    ----------
    gap : float or None
        Distance (length) from the wall to the facing end of the nearest body,
        >= 0; ``None`` places the wall just out of range of the contact force.
    contact : ContactLaw
        Law between the wall and the facing body end.
    """

    gap: float | None = None
    contact: ContactLaw = field(default_factory=Hard)

    def __post_init__(self):
        if self.gap is not None:
            gap = require_finite("wall gap", self.gap)
            if gap < 0.0:
                raise InvalidParameterError(f"wall gap must be >= 0 (a wall inside a rod), got {gap:g}")
            object.__setattr__(self, "gap", gap)
        if not isinstance(self.contact, ContactLaw):
            raise InvalidParameterError("wall contact must be a wavecontact contact law (Exponential, Penalty, Hard, ...)")


def body_segments(body) -> tuple:
    """The segments of a deformable body (a uniform Rod is one segment); ``()`` for a rigid body."""
    if isinstance(body, RigidBody):
        return ()
    if isinstance(body, PiecewiseRod):
        return body.segments
    return (Segment(length=body.length, area=body.area, youngs_modulus=body.youngs_modulus, density=body.density),)


def pair_laws(scene) -> tuple:
    """One contact law per facing pair of a line scene (the scene's single law repeated, or its tuple)."""
    count = len(scene.rods) - 1
    if isinstance(scene.contact, ContactLaw):
        return (scene.contact,) * count
    return tuple(scene.contact)


def is_line_scene(scene) -> bool:
    """True for a scene beyond the paper's two uniform rods on a line: other bodies, more or
    fewer than two bodies, one law per pair, or walls.  Such a scene is taken by the fem solver's
    multi-body loop (:mod:`wavecontact.fem.multibody`); the paper's two-rod scenes are not."""
    if scene.is_ring:
        return False
    from .scene import Rod

    return (scene.walls is not None or not isinstance(scene.contact, ContactLaw) or len(scene.rods) != 2
            or not all(isinstance(body, Rod) for body in scene.rods))


def needs_line_validation(scene) -> bool:
    """True where :func:`validate_line_scene` (not the two-rod checks of Scene) validates the scene."""
    from .scene import Rod

    return (scene.walls is not None or not isinstance(scene.contact, ContactLaw)
            or not all(isinstance(body, Rod) for body in tuple(scene.rods)))


def validate_line_scene(scene) -> None:
    """Check (and normalize in place) a scene of bodies on a line with per-pair laws and walls.

    Raises InvalidParameterError with a one-line message naming the field.
    """
    from .scene import Rod

    bodies = tuple(scene.rods)
    if not bodies:
        raise InvalidParameterError("a scene needs at least one body")
    for i, body in enumerate(bodies):
        if not isinstance(body, (Rod, PiecewiseRod, RigidBody)):
            raise InvalidParameterError(
                f"rods[{i}] must be a Rod, PiecewiseRod or RigidBody, got {type(body).__name__}")
    object.__setattr__(scene, "rods", bodies)
    if scene.ring_circumference is not None:
        raise InvalidParameterError("piecewise rods, rigid bodies, per-pair laws and walls need a scene on a line "
                                    "(ring_circumference=None)")
    velocities = tuple(scene.velocities)
    if len(velocities) != len(bodies):
        raise InvalidParameterError(f"velocities must have one entry per body ({len(bodies)}), got {len(velocities)}")
    object.__setattr__(scene, "velocities", tuple(
        require_magnitude(f"velocities[{i}]", v, signed=True) for i, v in enumerate(velocities)))
    pairs = len(bodies) - 1
    if isinstance(scene.contact, ContactLaw):
        laws = None
    else:
        try:
            laws = tuple(scene.contact)
        except TypeError:
            raise InvalidParameterError("contact must be a contact law or a tuple of them, one per facing pair") from None
        if len(laws) != pairs:
            raise InvalidParameterError(f"contact must hold one law per facing pair ({pairs}), got {len(laws)}")
        for i, law in enumerate(laws):
            if not isinstance(law, ContactLaw):
                raise InvalidParameterError(f"contact[{i}] must be a wavecontact contact law, got {law!r}")
        object.__setattr__(scene, "contact", laws)
    if scene.gaps is not None:
        gaps = tuple(scene.gaps)
        if len(gaps) != pairs:
            raise InvalidParameterError(f"gaps must have {pairs} entries (one per facing pair), got {len(gaps)}")
        checked = []
        for i, gap in enumerate(gaps):
            if gap is not None:
                gap = require_finite(f"gaps[{i}]", gap)
                if gap < 0.0:
                    raise InvalidParameterError(
                        f"gaps[{i}] must be >= 0: bodies {i} and {i + 1} overlap by {-gap:g} at the start")
            checked.append(gap)
        object.__setattr__(scene, "gaps", tuple(checked))
    if scene.walls is not None:
        walls = tuple(scene.walls)
        if len(walls) != 2 or not all(w is None or isinstance(w, Wall) for w in walls):
            raise InvalidParameterError("walls must be a pair (left, right), each a wavecontact.Wall or None")
        object.__setattr__(scene, "walls", walls)
        has_wall = any(w is not None for w in walls)
    else:
        has_wall = False
    if len(bodies) < 2 and not has_wall:
        raise InvalidParameterError("a scene of one body needs a wall to hit (walls=(left, right))")
    if scene.vibrations is not None:
        raise InvalidParameterError("thermal vibrations need the paper's two rods (two_rods(..., vibrations=))")
    for name in ("initial_displacement", "initial_velocity"):
        fields = getattr(scene, name)
        if fields is not None:
            fields = tuple(fields)
            if len(fields) != len(bodies) or not all(f is None or callable(f) for f in fields):
                raise InvalidParameterError(f"{name} must hold one callable (or None) per body ({len(bodies)})")
            for i, (f, body) in enumerate(zip(fields, bodies)):
                if f is not None and isinstance(body, RigidBody):
                    raise InvalidParameterError(f"{name}[{i}] must be None: body {i} is rigid")
            object.__setattr__(scene, name, fields)
