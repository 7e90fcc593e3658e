"""The result of a scene of many bodies on a line: per-body velocities and energies, per-contact records.

The paper's two-rod scenes keep :class:`~wavecontact.result.CollisionResult`;
every other line scene (piecewise rods, rigid bodies, chains, walls) returns an
:class:`ImpactResult`.  Times, velocities and energies are in the scene's own
units.  :meth:`ImpactResult.save` writes JSON, or NumPy's npz for a ``.npz`` path (no pickle either
way); :meth:`ImpactResult.load` reads both back, sampled fields included.
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

import numpy as np

from .errors import InvalidParameterError

__all__ = ["ContactRecord", "ImpactResult"]

_FORMAT = "wavecontact-impact-result"
_VERSION = 1


@dataclass(frozen=True)
class ContactRecord:
    """What happened at one contact (a facing pair of bodies, or a body and a wall).

    Attributes
    ----------
    name : str
        ``"0-1"`` for the pair of bodies 0 and 1, ``"left wall"``, ``"right wall"``.
    impulse : float
        Total impulse transmitted (mass * length/time), >= 0.
    duration : float
        Total time in contact (time): steps in which the contact acted, times the step.
    first_contact, last_contact : float
        Time of the first and the last step in which it acted (time); NaN if never.
    intervals : int
        Number of separate contact intervals (0 if the sides never met).
    """

    name: str
    impulse: float
    duration: float
    first_contact: float
    last_contact: float
    intervals: int


@dataclass(frozen=True)
class ImpactResult:
    """Outcome of one line scene after the last separation.

    Attributes
    ----------
    velocities : tuple of float
        Each body's centre-of-mass velocity after the last separation (length/time).
    internal_energies : tuple of float
        Each body's internal (vibration) energy then (energy); 0 for rigid bodies.
    contacts : tuple of ContactRecord
        One per facing pair (left to right), then one per wall present (left, right).
    error_estimate : float
        Bound on ``max |velocity error| / max |initial velocity|`` (Richardson from coarser runs;
        NaN if not estimated).
    solver : str
    end_time : float
        Time at which the run stopped (time).
    initial_velocities : tuple of float
    masses : tuple of float
        Each body's mass (mass).
    bodies : tuple of str
        A short description of each body.
    wall_time_s : float
    options : dict
    work : dict
        ``steps``, ``nodes``, ``element_steps``, ...
    diagnostics : dict
        ``energy_drift`` (relative, the contact losses of hard contact included), ``momentum_drift``,
        ``error_estimate_method``, ``error_estimate_levels``, ``includes_kernel_preparation``, ...
    fields : dict or None
        The sampled fields when run with ``record_fields=True`` (layout:
        :func:`wavecontact.fem.multibody.replay_fields`; written for ParaView by
        :func:`wavecontact.io.fields.write_fields`), else None.
    """

    velocities: tuple
    internal_energies: tuple
    contacts: tuple
    error_estimate: float
    solver: str = "fem"
    end_time: float = math.nan
    initial_velocities: tuple = ()
    masses: tuple = ()
    bodies: tuple = ()
    wall_time_s: float = math.nan
    options: dict = field(default_factory=dict)
    work: dict = field(default_factory=dict)
    diagnostics: dict = field(default_factory=dict)
    fields: dict | None = field(default=None, repr=False, compare=False)

    @property
    def momentum(self) -> float:
        """Total momentum after the last separation (mass * length/time)."""
        return sum(m * v for m, v in zip(self.masses, self.velocities))

    @property
    def kinetic_energies(self) -> tuple:
        """Each body's centre-of-mass kinetic energy after the last separation (energy)."""
        return tuple(0.5 * m * v * v for m, v in zip(self.masses, self.velocities))

    def summary(self) -> str:
        """A few lines for a terminal."""
        lines = [(f"{self.solver}: {len(self.velocities)} bodies, stopped at t = {self.end_time:.6g}, "
                  f"error estimate {self.error_estimate:.2g} (of max |v0|), wall time {self.wall_time_s:.3g} s")]
        for i, (name, v0, v, e) in enumerate(zip(self.bodies, self.initial_velocities, self.velocities,
                                                  self.internal_energies)):
            lines.append(f"  body {i} ({name}): v {v0:.6g} -> {v:.10g}, internal energy {e:.6g}")
        for record in self.contacts:
            lines.append(f"  contact {record.name}: impulse {record.impulse:.10g}, {record.intervals} interval(s), "
                         f"duration {record.duration:.6g}, first {record.first_contact:.6g}, "
                         f"last {record.last_contact:.6g}")
        return "\n".join(lines)

    def to_dict(self) -> dict:
        """Plain JSON-ready values (NaN as null); the sampled fields, if any, are left out."""
        data = asdict(replace(self, fields=None))
        del data["fields"]
        data["contacts"] = [asdict(c) for c in self.contacts]
        return _json_safe(data)

    def save(self, path) -> Path:
        """Write the result to ``path``; return the path.

        A ``.npz`` path gets NumPy's npz (the scalars as a JSON text entry, the fields as arrays; read with
        ``allow_pickle=False``), any other path JSON (the fields, if any, as lists of numbers).
        """
        path = Path(path)
        payload = {"format": _FORMAT, "version": _VERSION, "result": self.to_dict()}
        if path.suffix == ".npz":
            arrays = _flat_fields(self.fields) if self.fields is not None else {}
            with open(path, "wb") as stream:
                np.savez_compressed(stream, result=np.array(json.dumps(payload, allow_nan=False)), **arrays)
            return path
        if self.fields is not None:
            payload["fields"] = _json_safe(_listed(self.fields))
        path.write_text(json.dumps(payload, indent=1, allow_nan=False) + "\n")
        return path

    @classmethod
    def load(cls, path) -> ImpactResult:
        """Read a result written by :meth:`save` (JSON, or npz for a ``.npz`` path)."""
        fields = None
        try:
            if Path(path).suffix == ".npz":
                with np.load(path, allow_pickle=False) as archive:
                    payload = json.loads(str(archive["result"]))
                    arrays = {name: archive[name] for name in archive.files if name != "result"}
                fields = _nested_fields(arrays) if arrays else None
            else:
                payload = json.loads(Path(path).read_text())
        except (OSError, ValueError, KeyError) as error:
            raise InvalidParameterError(f"cannot read an impact result from {str(path)!r}: {error}") from None
        if not isinstance(payload, dict) or payload.get("format") != _FORMAT:
            raise InvalidParameterError(f"{str(path)!r} is not a wavecontact impact result (JSON of ImpactResult.save)")
        if "fields" in payload:
            fields = _arrays(payload["fields"])
        data = payload["result"]
        data["fields"] = fields
        records = tuple(ContactRecord(**{k: _number(v) if k != "name" else v for k, v in c.items()})
                        for c in data.pop("contacts"))
        records = tuple(ContactRecord(r.name, r.impulse, r.duration, r.first_contact, r.last_contact,
                                      int(r.intervals)) for r in records)
        for name in ("velocities", "internal_energies", "initial_velocities", "masses"):
            data[name] = tuple(_number(v) for v in data[name])
        data["bodies"] = tuple(data["bodies"])
        for name in ("error_estimate", "end_time", "wall_time_s"):
            data[name] = _number(data[name])
        return cls(contacts=records, **data)


def _listed(fields: dict) -> dict:
    """The fields with every array as (nested) lists."""
    def convert(value):
        if isinstance(value, np.ndarray):
            return value.tolist()
        if isinstance(value, dict):
            return {k: convert(v) for k, v in value.items()}
        if isinstance(value, (list, tuple)):
            return [convert(v) for v in value]
        return value
    return convert(fields)


def _arrays(fields: dict) -> dict:
    """Fields read from JSON: the lists of numbers back to arrays (cells as integers)."""
    out = {"time": np.asarray(fields["time"], dtype=float), "walls": list(fields.get("walls", [None, None])),
           "rods": [], "points": []}
    for rod in fields["rods"]:
        out["rods"].append({k: (int(v) if k == "body" else np.asarray(v, dtype=np.int64 if k == "cells" else float))
                            for k, v in rod.items()})
    for point in fields.get("points", []):
        out["points"].append({k: (int(v) if k == "body" else float(v) if k == "x" else np.asarray(v, dtype=float))
                              for k, v in point.items()})
    return out


def _flat_fields(fields: dict) -> dict:
    """The fields as named arrays for npz: ``time``, ``walls`` (NaN: none), ``rod3_x``, ``point0_velocity``, ..."""
    arrays = {"time": fields["time"], "walls": np.array([math.nan if w is None else w for w in fields["walls"]])}
    for kind, items in (("rod", fields["rods"]), ("point", fields.get("points", []))):
        for item in items:
            for name, value in item.items():
                if name != "body":
                    arrays[f"{kind}{item['body']}_{name}"] = np.asarray(value)
    return arrays


def _nested_fields(arrays: dict) -> dict:
    """The inverse of :func:`_flat_fields`."""
    fields = {"time": arrays["time"], "walls": [None if math.isnan(w) else float(w) for w in arrays["walls"]],
              "rods": [], "points": []}
    grouped = {}
    for key, value in arrays.items():
        if key in ("time", "walls"):
            continue
        head, name = key.split("_", 1)
        kind = "rods" if head.startswith("rod") else "points"
        body = int(head[3:] if kind == "rods" else head[5:])
        grouped.setdefault((kind, body), {"body": body})[name] = float(value) if name == "x" and kind == "points" \
            else value
    for (kind, _), item in sorted(grouped.items(), key=lambda entry: entry[1]["body"]):
        fields[kind].append(item)
    return fields


def _number(value):
    return math.nan if value is None else value


def _json_safe(value):
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {str(k): _json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_json_safe(v) for v in value]
    if hasattr(value, "item"):  # numpy scalars
        return _json_safe(value.item())
    return value
