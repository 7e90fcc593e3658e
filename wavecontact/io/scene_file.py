"""Scenes from a TOML or JSON file (the schema is in docs/usage.md, "Scene files").

A file lists the bodies from left to right, the contact law(s), the gaps and the
walls, and optionally the solver and its options::

    [solve]                      # optional; command-line options override it
    solver = "fem"
    elements = 400

    [contact]                    # one law for every facing pair ([[contact]]: one per pair)
    law = "hard"                 # hard | exponential (alpha, strength) | penalty (stiffness)

    [[body]]                     # a rigid striker
    mass = 2.0
    velocity = 1.0

    [[body]]                     # a uniform rod
    length = 1.0

    [[body]]                     # a piecewise rod: segments from left to right
    [[body.segment]]
    length = 1.0
    [[body.segment]]
    length = 1.0
    area = 2.0
    end_area = 1.0               # optional linear taper to this area

A body is rigid if it has ``mass`` and a rod otherwise.  Every problem is refused
with one line naming the file and the key (``scene.toml: body[2].segment[0].length:
...``), never a traceback.
"""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path

from ..errors import InvalidParameterError, WavecontactError

__all__ = ["SceneFile", "read_scene_file", "scene_from_mapping"]

SUFFIXES = (".toml", ".json")
_ROD_KEYS = ("length", "area", "end_area", "density", "youngs_modulus")
_BODY_KEYS = {"rigid": ("mass", "velocity", "name"), "rod": (*_ROD_KEYS, "velocity", "name", "segment")}
_WALL_KEYS = ("gap", "contact")
_TOP_KEYS = ("body", "contact", "gaps", "walls", "solve", "title", "description")


@dataclasses.dataclass(frozen=True)
class SceneFile:
    """A scene read from a file, with the solver settings the file asks for.

    Attributes
    ----------
    scene : wavecontact.Scene
        The bodies, contacts, gaps and walls.
    solver : str or None
        ``[solve] solver`` of the file (None: not given).
    options : dict
        The other keys of ``[solve]`` (solver options, e.g. ``elements``).
    names : tuple of str
        Each body's ``name`` (default ``body0``, ``body1``, ...).
    title : str
    """

    scene: object
    solver: str | None
    options: dict
    names: tuple
    title: str


class _Refusal(InvalidParameterError):
    pass


def read_scene_file(path) -> SceneFile:
    """Read a scene from a ``.toml`` or ``.json`` file.

    Raises
    ------
    InvalidParameterError
        One line naming the file and the bad key or value.
    """
    path = Path(path)
    if path.suffix.lower() not in SUFFIXES:
        raise InvalidParameterError(f"{path}: a scene file must end in .toml or .json")
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise InvalidParameterError(f"{path}: cannot read the scene file ({type(exc).__name__}: "
                                    f"{getattr(exc, 'strerror', None) or exc})") from None
    try:
        if path.suffix.lower() == ".toml":
            import tomllib

            data = tomllib.loads(text)
        else:
            data = json.loads(text)
    except ValueError as exc:  # tomllib.TOMLDecodeError and json.JSONDecodeError are ValueErrors
        raise InvalidParameterError(f"{path}: not valid {path.suffix[1:].upper()}: {' '.join(str(exc).split())}") from None
    try:
        return scene_from_mapping(data)
    except WavecontactError as exc:
        raise InvalidParameterError(f"{path}: {exc}") from None


def scene_from_mapping(data) -> SceneFile:
    """Build a :class:`SceneFile` from the parsed file (a dict, the schema of the module docstring)."""
    from ..scene import Scene

    _require_table("the file", data)
    _no_unknown("", data, _TOP_KEYS)
    bodies_data = data.get("body")
    if not isinstance(bodies_data, list) or not bodies_data:
        raise _Refusal("body: give the bodies from left to right as [[body]] tables")
    bodies, velocities, names = [], [], []
    for i, body in enumerate(bodies_data):
        where = f"body[{i}]"
        _require_table(where, body)
        built, velocity = _body(where, body)
        bodies.append(built)
        velocities.append(velocity)
        names.append(str(body.get("name", f"body{i}")))
    contact = _contacts("contact", data.get("contact", {"law": "hard"}), len(bodies) - 1)
    gaps = data.get("gaps", [0.0] * (len(bodies) - 1))
    if not isinstance(gaps, list):
        raise _Refusal(f"gaps: a list of {len(bodies) - 1} numbers (one per facing pair), got {gaps!r}")
    gaps = tuple(_number(f"gaps[{k}]", g) for k, g in enumerate(gaps))
    walls = _walls(data.get("walls"))
    solve = data.get("solve", {})
    _require_table("solve", solve)
    options = {k: v for k, v in solve.items() if k != "solver"}
    solver = solve.get("solver")
    if solver is not None and not isinstance(solver, str):
        raise _Refusal(f"solve.solver: a solver name, got {solver!r}")
    kwargs = {"rods": tuple(bodies), "velocities": tuple(velocities), "contact": contact, "gaps": gaps}
    if walls is not None:
        kwargs["walls"] = walls
    scene = _build("scene", Scene, **kwargs)
    return SceneFile(scene=scene, solver=solver, options=options, names=tuple(names),
                     title=str(data.get("title", "")))


def _body(where: str, body: dict):
    from .. import bodies
    from ..scene import Rod

    kind = "rigid" if "mass" in body else "rod"
    _no_unknown(f"{where}.", body, _BODY_KEYS[kind])
    velocity = _number(f"{where}.velocity", body.get("velocity", 0.0))
    if kind == "rigid":
        return _build(where, bodies.RigidBody, mass=_number(f"{where}.mass", body["mass"])), velocity
    segments = body.get("segment")
    if segments is None:
        if "length" not in body:
            raise _Refusal(f"{where}: a rod needs length (or [[{where.split('[')[0]}.segment]] tables), "
                           "a rigid body needs mass")
        if "end_area" not in body:
            return _build(where, Rod, **_numbers(where, body, exclude=("velocity", "name"))), velocity
        segments = [{k: v for k, v in body.items() if k in _ROD_KEYS}]
    elif any(k in body for k in _ROD_KEYS):
        raise _Refusal(f"{where}: give either the rod's length, area, ... or its [[segment]] tables, not both")
    if not isinstance(segments, list) or not segments:
        raise _Refusal(f"{where}.segment: a list of segment tables, left to right")
    built = []
    for j, segment in enumerate(segments):
        at = f"{where}.segment[{j}]"
        _require_table(at, segment)
        _no_unknown(f"{at}.", segment, _ROD_KEYS)
        if "length" not in segment:
            raise _Refusal(f"{at}.length: missing")
        built.append(_build(at, bodies.Segment, **_numbers(at, segment)))
    return _build(where, bodies.PiecewiseRod, tuple(built)), velocity


def _contacts(where: str, value, pairs: int):
    if isinstance(value, list):
        if len(value) != pairs:
            raise _Refusal(f"{where}: one [[contact]] per facing pair ({pairs}), got {len(value)}")
        return tuple(_contact(f"{where}[{k}]", v) for k, v in enumerate(value))
    return _contact(where, value)


def _contact(where: str, table):
    from .. import contact as contact_module

    _require_table(where, table)
    law = table.get("law")
    laws = {cls.name: cls for cls in _subclasses(contact_module.ContactLaw) if isinstance(getattr(cls, "name", None), str)}
    if law not in laws:
        raise _Refusal(f"{where}.law: one of {', '.join(sorted(laws))}, got {law!r}")
    cls = laws[law]
    allowed = tuple(f.name for f in dataclasses.fields(cls))
    _no_unknown(f"{where}.", table, ("law", *allowed))
    return _build(where, cls, **_numbers(where, table, exclude=("law",)))


def _walls(value):
    if value is None:
        return None
    from ..bodies import Wall

    _require_table("walls", value)
    _no_unknown("walls.", value, ("left", "right"))
    walls = []
    for side in ("left", "right"):
        table = value.get(side)
        if table is None:
            walls.append(None)
            continue
        _require_table(f"walls.{side}", table)
        _no_unknown(f"walls.{side}.", table, _WALL_KEYS)
        walls.append(_build(f"walls.{side}", Wall, gap=_number(f"walls.{side}.gap", table.get("gap", 0.0)),
                                       contact=_contact(f"walls.{side}.contact", table.get("contact", {"law": "hard"}))))
    return tuple(walls)


def _build(where: str, factory, *args, **kwargs):
    """``factory(*args, **kwargs)``, its refusal prefixed with where it is in the file."""
    try:
        return factory(*args, **kwargs)
    except _Refusal:
        raise
    except (WavecontactError, TypeError) as exc:
        raise _Refusal(f"{where}: {' '.join(str(exc).split())}") from None


def _subclasses(cls):
    for sub in cls.__subclasses__():
        yield sub
        yield from _subclasses(sub)


def _require_table(where: str, value) -> None:
    if not isinstance(value, dict):
        raise _Refusal(f"{where}: a table (key = value pairs) expected, got {value!r}")


def _no_unknown(prefix: str, table: dict, allowed) -> None:
    for key in table:
        if key not in allowed:
            raise _Refusal(f"{prefix}{key}: unknown key (allowed here: {', '.join(allowed)})")


def _number(where: str, value) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise _Refusal(f"{where}: a finite number expected, got {value!r}")
    return float(value)


def _numbers(where: str, table: dict, exclude=()) -> dict:
    return {k: _number(f"{where}.{k}", v) for k, v in table.items() if k not in exclude}
