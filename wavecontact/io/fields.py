"""Write the sampled fields of a finite-element result for ParaView.

The finite-element solver, run with ``record_fields=True`` (CLI: ``--fields``),
stores in ``result.extra["fields"]``::

    {"time": (nt,),
     "rods": [{"x": (n_nodes,),                 # node coordinates on the line
               "displacement": (nt, n_nodes),
               "velocity": (nt, n_nodes),
               "stress": (nt, n_nodes),
               "cells": (n_elements, order + 1)},  # node indices per element
              ...]}

:func:`write_fields` turns this into files ParaView opens as a time series:
one VTU file per sample time (binary, zlib-compressed) and a PVD index
``fields.pvd`` that maps times to files.  (XDMF was dropped: meshio's writer
put its HDF5 file in the working directory, inline XDMF took 91.5 MB and 17 s
for one 800-element collision, and some ParaView versions fail on line-only
XDMF series.)

Every element, whatever its order, is written as straight two-node segments
between neighbouring nodes (``line`` cells), so the nodal values are exact
and every reader understands the mesh.  Points get three coordinates
``(x, 0, 0)``; the rods lie on the x axis at their reference positions.
Point data per sample: ``displacement``, ``velocity``, ``stress`` (scalars),
``displacement_vector`` (``(u, 0, 0)``, for ParaView's *Warp By Vector* to
show the deformed rods) and ``rod`` (1, 2, ...).  Field data of every file
(ParaView: Information panel, or the spreadsheet's *Field Data*): the
sample time ``TimeValue``, the parameters of the run (``gamma``, ``kappa``,
``restitution``, ``solver``, ...) and the unit of every quantity
(``unit_time``, ``unit_stress``, ...).  :func:`read_fields` reads the series
back into the layout above, with ``units`` and ``parameters``.
"""

from __future__ import annotations

import math
import os
import re
import tempfile
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np

from ..errors import InvalidParameterError, WavecontactError

__all__ = [
    "FIELD_NAMES",
    "UNIT_SYSTEMS",
    "FieldFiles",
    "MissingFieldsError",
    "read_fields",
    "run_parameters",
    "sampled_fields",
    "write_fields",
]

FIELD_NAMES = ("displacement", "velocity", "stress")
FORMATS = ("vtu",)
QUANTITIES = ("length", "time", "displacement", "velocity", "stress")
UNIT_SYSTEMS = {
    # wavecontact.collide / two_rods: rho = c = A = 1, effective length l = 1, approach speed V = 1
    "dimensionless": {
        "length": "l = 2 l1 l2 / (l1 + l2)",
        "time": "l / c",
        "displacement": "l",
        "velocity": "V (approach speed)",
        "stress": "rho c V",
    },
    # a Scene given in SI units (wavecontact.solve)
    "SI": {"length": "m", "time": "s", "displacement": "m", "velocity": "m/s", "stress": "Pa"},
    # a scene in any consistent units (wavecontact solve FILE): those of its lengths, densities and moduli
    "scene": {"length": "the scene's length unit", "time": "the scene's time unit", "displacement": "length unit",
              "velocity": "length unit / time unit", "stress": "the unit of Young's modulus"},
}


class MissingFieldsError(WavecontactError, ValueError):
    """The result carries no sampled fields."""


@dataclass(frozen=True)
class FieldFiles:
    """What :func:`write_fields` wrote.

    Attributes
    ----------
    format : {'vtu'}
        The format written.
    index : Path
        The file to open in ParaView (``fields.pvd``).
    files : tuple of Path
        Every file written, index included.
    times : ndarray
        The sample times, as written.
    """

    format: str
    index: Path
    files: tuple
    times: np.ndarray = field(repr=False)


def sampled_fields(result) -> dict:
    """Return the validated fields of ``result`` as float/int arrays.

    Parameters
    ----------
    result : CollisionResult or dict
        A result whose ``extra["fields"]`` holds the layout of the module
        docstring, or that dict itself.

    Returns
    -------
    dict
        ``{"time": (nt,), "rods": [{"x", "displacement", "velocity",
        "stress", "cells"}, ...]}`` as new NumPy arrays.

    Raises
    ------
    MissingFieldsError
        If the result has no fields (run the fem solver with
        ``record_fields=True``).
    InvalidParameterError
        If the arrays do not fit together (shapes, indices, non-finite values).
    """
    if isinstance(result, dict):
        raw = result
    else:
        extra = getattr(result, "extra", None) or {}
        raw = extra.get("fields", getattr(result, "fields", None))  # CollisionResult, or ImpactResult of a scene
        if raw is None:
            solver = getattr(result, "solver", "?")
            raise MissingFieldsError(
                f"this result (solver {solver!r}) carries no sampled fields: run the fem solver with "
                "record_fields=True (CLI: wavecontact collide --solver fem --fields DIR)"
            )
    if "time" not in raw or "rods" not in raw:
        raise InvalidParameterError("fields must be a dict with keys 'time' and 'rods'")
    time = np.asarray(raw["time"], dtype=float)
    if time.ndim != 1 or time.size == 0:
        raise InvalidParameterError(f"fields['time'] must be a non-empty 1-D array, got shape {time.shape}")
    if not np.all(np.isfinite(time)):
        raise InvalidParameterError("fields['time'] holds non-finite values")
    if np.any(np.diff(time) <= 0):
        raise InvalidParameterError("fields['time'] must be strictly increasing")
    rods_in = list(raw["rods"])
    if not rods_in:
        raise InvalidParameterError("fields['rods'] is empty")
    rods = []
    for i, rod in enumerate(rods_in):
        rods.append(_validated_rod(i, rod, time.size))
    out = {"time": time, "rods": rods}
    if "points" in raw:  # rigid bodies of a scene on a line: points with displacement and velocity
        out["points"] = [_validated_point(i, point, time.size) for i, point in enumerate(raw["points"])]
        out["walls"] = [None if w is None else float(w) for w in raw.get("walls", (None, None))]
    return out


def _validated_point(index: int, point: dict, n_times: int) -> dict:
    where = f"fields['points'][{index}]"
    out = {"body": int(point["body"]), "x": float(point["x"])}
    for name in ("displacement", "velocity"):
        values = np.asarray(point[name], dtype=float)
        if values.shape != (n_times,) or not np.all(np.isfinite(values)):
            raise InvalidParameterError(f"{where}['{name}'] must be {n_times} finite values")
        out[name] = values
    return out


def _validated_rod(index: int, rod: dict, n_times: int) -> dict:
    where = f"fields['rods'][{index}]"
    missing = [k for k in ("x", "cells", *FIELD_NAMES) if k not in rod]
    if missing:
        raise InvalidParameterError(f"{where} lacks {', '.join(missing)}")
    x = np.asarray(rod["x"], dtype=float)
    if x.ndim != 1 or x.size < 2 or not np.all(np.isfinite(x)):
        raise InvalidParameterError(f"{where}['x'] must be a finite 1-D array of >= 2 node coordinates")
    out = {"x": x}
    for name in FIELD_NAMES:
        values = np.asarray(rod[name], dtype=float)
        if values.shape != (n_times, x.size):
            raise InvalidParameterError(
                f"{where}['{name}'] must have shape (n_times, n_nodes) = ({n_times}, {x.size}), "
                f"got {values.shape}"
            )
        if not np.all(np.isfinite(values)):
            raise InvalidParameterError(f"{where}['{name}'] holds non-finite values")
        out[name] = values
    if "body" in rod:
        out["body"] = int(rod["body"])
    cells = np.asarray(rod["cells"])
    if (
        cells.ndim != 2
        or cells.shape[0] == 0
        or cells.shape[1] < 2
        or not np.issubdtype(cells.dtype, np.integer)
    ):
        raise InvalidParameterError(
            f"{where}['cells'] must be an integer array (n_elements, order + 1), "
            f"got {cells.shape} {cells.dtype}"
        )
    if cells.min() < 0 or cells.max() >= x.size:
        raise InvalidParameterError(f"{where}['cells'] refers to nodes outside 0..{x.size - 1}")
    out["cells"] = cells.astype(np.int64)
    return out


def line_segments(x: np.ndarray, cells: np.ndarray) -> np.ndarray:
    """Split elements of any order into two-node segments.

    Parameters
    ----------
    x : ndarray, shape (n_nodes,)
        Node coordinates.
    cells : ndarray, shape (n_elements, k)
        Node indices of each element, in any order.

    Returns
    -------
    ndarray, shape (n_elements * (k - 1), 2)
        Neighbouring node pairs, each element's nodes sorted along the line.
    """
    ordered = np.take_along_axis(cells, np.argsort(x[cells], axis=1), axis=1)
    return np.stack([ordered[:, :-1].ravel(), ordered[:, 1:].ravel()], axis=1)


def _assemble(fields: dict):
    """Points, segments, vertices (rigid bodies) and per-point arrays of all bodies joined.

    ``rod`` numbers the bodies from 1 (a scene's body ``i`` is ``i + 1``; rigid bodies, written as
    vertices with zero stress, count too).
    """
    xs, segments, rod_ids, offset = [], [], [], 0
    for number, rod in enumerate(fields["rods"], start=1):
        xs.append(rod["x"])
        segments.append(line_segments(rod["x"], rod["cells"]) + offset)
        rod_ids.append(np.full(rod["x"].size, rod.get("body", number - 1) + 1, dtype=np.int64))
        offset += rod["x"].size
    values = {name: [rod[name] for rod in fields["rods"]] for name in FIELD_NAMES}
    vertices = []
    for point in fields.get("points", ()):
        xs.append(np.array([point["x"]]))
        rod_ids.append(np.array([point["body"] + 1], dtype=np.int64))
        vertices.append(offset)
        offset += 1
        for name in FIELD_NAMES:
            values[name].append(point[name][:, None] if name in point else np.zeros((fields["time"].size, 1)))
    x = np.concatenate(xs)
    points = np.zeros((x.size, 3))
    points[:, 0] = x
    values = {name: np.concatenate(values[name], axis=1) for name in FIELD_NAMES}
    return points, np.concatenate(segments), np.concatenate(rod_ids), values, np.array(vertices, dtype=np.int64)


def _frame_data(values: dict, k: int, rod_ids: np.ndarray) -> dict:
    data = {name: values[name][k] for name in FIELD_NAMES}
    vector = np.zeros((rod_ids.size, 3))
    vector[:, 0] = values["displacement"][k]
    data["displacement_vector"] = vector
    data["rod"] = rod_ids
    return data


def run_parameters(result) -> dict:
    """The scalars of ``result`` worth keeping next to its fields.

    Returns
    -------
    dict
        ``gamma``, ``kappa``, ``restitution``, ``contact_start``,
        ``contact_duration`` (those that are set), ``solver``, from
        ``result.options`` the discretization (``elements``, ``order``,
        ``mass``, ``scheme``, ``gap_quadrature``), from ``result.work`` the
        time step ``dt``, plus the wavecontact ``version``.
    """
    from .._version import __version__

    out = {"solver": str(getattr(result, "solver", "?")), "version": __version__}
    for name in ("gamma", "kappa", "restitution", "contact_start", "contact_duration"):
        value = getattr(result, name, None)
        if value is not None and not math.isnan(value):  # NaN: not a two-rod scene, or no force history
            out[name] = float(value)
    # the discretization is in the solver options (elements, order, mass, scheme), the step in the work
    options = getattr(result, "options", None) or {}
    work = getattr(result, "work", None) or {}
    for source, names in ((options, ("elements", "order", "mass", "scheme", "gap_quadrature")), (work, ("dt",))):
        for name in names:
            value = source.get(name)
            if isinstance(value, str):
                out[name] = value
            elif isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool):
                out[name] = float(value)
    return out


def _units(units) -> dict:
    if isinstance(units, str):
        if units not in UNIT_SYSTEMS:
            raise InvalidParameterError(
                f"units must be one of {', '.join(map(repr, UNIT_SYSTEMS))} or a dict, got {units!r}"
            )
        return dict(UNIT_SYSTEMS[units])
    if not isinstance(units, dict) or not all(isinstance(v, str) for v in units.values()):
        raise InvalidParameterError("units must be a unit-system name or a dict of quantity -> unit text")
    missing = [q for q in QUANTITIES if q not in units]
    if missing:
        raise InvalidParameterError(f"units lacks {', '.join(missing)}")
    return dict(units)


def write_fields(result, directory, format: str = "vtu", *, prefix: str = "fields", units="dimensionless",
                 parameters: dict | None = None) -> FieldFiles:
    """Write the sampled fields of a finite-element result for ParaView.

    Parameters
    ----------
    result : CollisionResult or dict
        A result of the fem solver run with ``record_fields=True`` (or its
        ``extra["fields"]`` dict).
    directory : str or Path
        Output directory, created if needed.
    format : {'vtu'}
        One binary VTU file per sample plus a PVD index (the only format).
    prefix : str
        Base name of the files (``<prefix>.pvd``, ``<prefix>_00000.vtu``).
    units : {'dimensionless', 'SI'} or dict
        The units of the result, stored as field data: ``'dimensionless'``
        for :func:`wavecontact.collide` (lengths in ``l``, time in ``l / c``,
        velocities in ``V``, stress in ``rho c V``), ``'SI'`` for a
        :class:`~wavecontact.Scene` given in SI units, or a dict with the
        keys ``length, time, displacement, velocity, stress``.
    parameters : dict or None
        Extra scalars (numbers or strings) to store as field data, added to
        :func:`run_parameters` of the result.

    Returns
    -------
    FieldFiles
        The index file to open and all files.

    Raises
    ------
    MissingFieldsError
        If the result carries no fields.
    InvalidParameterError
        For an unknown format or unit system, inconsistent field arrays, or
        a parameter that is neither a number nor a string.
    """
    if format not in FORMATS:
        raise InvalidParameterError(
            f"format must be 'vtu' (VTU files with a PVD index; XDMF is no longer written), got {format!r}"
        )
    if not prefix or os.sep in prefix or (os.altsep and os.altsep in prefix):
        raise InvalidParameterError(f"prefix must be a plain file name stem, got {prefix!r}")
    fields = sampled_fields(result)
    metadata = {f"unit_{name}": text for name, text in _units(units).items()}
    metadata.update(run_parameters(result) if not isinstance(result, dict) else {})
    for name, value in (parameters or {}).items():
        if isinstance(value, bool) or not isinstance(value, (int, float, str, np.integer, np.floating)):
            raise InvalidParameterError(f"parameters[{name!r}] must be a number or a string, got {value!r}")
        metadata[str(name)] = value
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    return _write_vtu_series(fields, directory, prefix, metadata)


# VTK's XML reader parses ASCII numbers with C++ streams, which do not read "inf" or "nan": a file with
# one such number is refused whole (no points, no data).  Non-finite numbers are therefore written as
# String arrays holding exactly these words, and read back as floats.
_NON_FINITE = {"inf": math.inf, "-inf": -math.inf, "nan": math.nan}


def _field_data_xml(metadata: dict, time: float) -> str:
    """A VTK XML ``<FieldData>`` block: numbers as Float64 arrays, text (and inf, nan) as String arrays."""
    xml = ["<FieldData>\n",
           f'<DataArray type="Float64" Name="TimeValue" NumberOfTuples="1" format="ascii">{time!r}</DataArray>\n']
    for name, value in metadata.items():
        if not isinstance(value, str) and not math.isfinite(float(value)):
            value = repr(float(value))  # 'inf', '-inf' or 'nan'
        if isinstance(value, str):
            # VTK writes string arrays as <Array>, in ASCII as character codes, each string ended by 0
            codes = " ".join(str(byte) for byte in value.encode("utf-8") + b"\0")
            xml.append(f'<Array type="String" Name={quoteattr(name)} NumberOfTuples="1" format="ascii">'
                       f"{codes}</Array>\n")
        else:
            text = repr(float(value))
            xml.append(f'<DataArray type="Float64" Name={quoteattr(name)} NumberOfTuples="1" format="ascii">'
                       f"{text}</DataArray>\n")
    xml.append("</FieldData>\n")
    return "".join(xml)


_GRID_TAG = "<UnstructuredGrid>"
_FIELD_DATA = re.compile(r"<FieldData>.*?</FieldData>\n?", re.DOTALL)


def _write_vtu_series(fields: dict, directory: Path, prefix: str, metadata: dict) -> FieldFiles:
    import meshio

    from .files import atomic_write

    points, segments, rod_ids, values, vertices = _assemble(fields)
    cells = [("line", segments)] + ([("vertex", vertices[:, None])] if vertices.size else [])
    cell_rods = [rod_ids[segments[:, 0]]] + ([rod_ids[vertices]] if vertices.size else [])
    time = fields["time"]
    width = max(5, len(str(time.size - 1)))
    collection = ET.Element("VTKFile", type="Collection", version="0.1", byte_order="LittleEndian")
    datasets = ET.SubElement(collection, "Collection")
    files = []
    for k, t in enumerate(time):
        name = f"{prefix}_{k:0{width}d}.vtu"
        mesh = meshio.Mesh(
            points,
            cells,
            point_data=_frame_data(values, k, rod_ids),
            cell_data={"rod": cell_rods},
        )
        path = directory / name
        meshio.write(path, mesh, file_format="vtu")  # binary, zlib-compressed
        text = path.read_text()
        if text.count(_GRID_TAG) != 1:
            raise WavecontactError(f"unexpected VTU layout from meshio in {path}")
        path.write_text(text.replace(_GRID_TAG, _GRID_TAG + "\n" + _field_data_xml(metadata, float(t)), 1))
        ET.SubElement(datasets, "DataSet", timestep=repr(float(t)), group="", part="0", file=name)
        files.append(path)
    index = directory / f"{prefix}.pvd"
    ET.indent(collection)
    # the index last and atomically: a series whose index exists is complete
    atomic_write(index, lambda handle: ET.ElementTree(collection).write(handle, xml_declaration=True,
                                                                        encoding="utf-8"))
    return FieldFiles("vtu", index, (index, *files), time.copy())


def read_fields(path) -> dict:
    """Read a series written by :func:`write_fields`.

    Parameters
    ----------
    path : str or Path
        The index ``.pvd`` or the directory holding ``fields.pvd``.

    Returns
    -------
    dict
        ``{"time": (nt,), "rods": [{"x", "displacement", "velocity",
        "stress", "segments"}, ...], "units": {...}, "parameters": {...}}``;
        ``segments`` are the two-node cells with node indices local to the
        rod; ``units`` maps each quantity to its unit, ``parameters`` holds
        the other field data of the first file (numbers, and the
        words ``inf``, ``-inf``, ``nan``, as float).
    """
    path = Path(path)
    if path.is_dir():
        path = path / "fields.pvd"
        if not path.exists():
            raise InvalidParameterError(f"no fields.pvd in {path.parent}")
    if path.suffix != ".pvd":
        raise InvalidParameterError(f"path must be a .pvd file or a directory, got {path}")
    time, points, segments, frames, metadata = _read_pvd(path)
    out = _split_rods(time, points, segments, frames)
    out["units"] = {k[len("unit_"):]: v for k, v in metadata.items() if k.startswith("unit_")}
    out["parameters"] = {k: v for k, v in metadata.items() if not k.startswith("unit_") and k != "TimeValue"}
    return out


def _parse_field_data(block: str) -> dict:
    """The arrays of a ``<FieldData>`` block written by :func:`_field_data_xml`."""
    out = {}
    for element in ET.fromstring(block):
        name, text = element.attrib["Name"], (element.text or "").split()
        if element.attrib["type"] == "String":
            value = bytes(int(code) for code in text).split(b"\0")[0].decode("utf-8")
            out[name] = _NON_FINITE.get(value, value)
        else:
            out[name] = float(text[0])
    return out


def _read_pvd(path: Path):
    import meshio

    root = ET.parse(path).getroot()
    entries = [(float(d.attrib["timestep"]), d.attrib["file"]) for d in root.iter("DataSet")]
    if not entries:
        raise InvalidParameterError(f"{path} lists no data sets")
    time, frames, points, segments, metadata = [], [], None, None, {}
    with tempfile.TemporaryDirectory() as scratch:
        plain = Path(scratch) / "frame.vtu"
        for t, name in entries:
            text = (path.parent / name).read_text()
            found = _FIELD_DATA.search(text)
            if found is not None:
                if not metadata:
                    metadata = _parse_field_data(found.group(0))
                text = text[: found.start()] + text[found.end():]
            plain.write_text(text)  # meshio reads numeric field data only, and only from a file
            mesh = meshio.read(plain, file_format="vtu")
            if points is None:
                points, segments = mesh.points, _line_cells(mesh.cells)
            time.append(t)
            frames.append(mesh.point_data)
    return np.array(time), points, segments, frames, metadata


def _line_cells(cells) -> np.ndarray:
    blocks = [c.data for c in cells if c.type == "line"]
    return np.concatenate(blocks) if blocks else np.zeros((0, 2), dtype=np.int64)


def _split_rods(time, points, segments, frames) -> dict:
    rod_ids = np.asarray(frames[0]["rod"]).astype(np.int64).ravel()
    rods = []
    for number in np.unique(rod_ids):
        nodes = np.flatnonzero(rod_ids == number)
        local = np.full(rod_ids.size, -1, dtype=np.int64)
        local[nodes] = np.arange(nodes.size)
        own = segments[np.all(rod_ids[segments] == number, axis=1)]
        rod = {"x": np.asarray(points[nodes, 0], dtype=float), "segments": local[own]}
        for name in FIELD_NAMES:
            rod[name] = np.stack([np.asarray(frame[name], dtype=float).ravel()[nodes] for frame in frames])
        rods.append(rod)
    return {"time": np.asarray(time, dtype=float), "rods": rods}
