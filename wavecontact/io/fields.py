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

* ``format="vtu"`` (default, the robust choice): one VTU file per sample
  time and a PVD index ``fields.pvd`` that maps times to files;
* ``format="xdmf"``: one XDMF file ``fields.xdmf`` (data inline as XML, or in
  ``fields.h5`` when :mod:`h5py` is installed).  The file is read back with
  meshio and compared with what was written; if anything differs the XDMF
  files are removed and the VTU series is written instead (with a warning).

Every element, whatever its order, is written as straight two-node segments
between neighbouring nodes (``line`` cells), so the nodal values are exact
and every reader understands the mesh.  Points get three coordinates
``(x, 0, 0)``; the rods lie on the x axis at their reference positions.
Point data per sample: ``displacement``, ``velocity``, ``stress`` (scalars,
the units of the result), ``displacement_vector`` (``(u, 0, 0)``, for
ParaView's *Warp By Vector* to show the deformed rods) and ``rod`` (1, 2, ...).
:func:`read_fields` reads either series back into the layout above.
"""

from __future__ import annotations

import os
import warnings
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import InvalidParameterError, WavecontactError

__all__ = ["FIELD_NAMES", "FieldFiles", "MissingFieldsError", "read_fields", "sampled_fields", "write_fields"]

FIELD_NAMES = ("displacement", "velocity", "stress")
FORMATS = ("vtu", "xdmf")


class MissingFieldsError(WavecontactError, ValueError):
    """The result carries no sampled fields."""


@dataclass(frozen=True)
class FieldFiles:
    """What :func:`write_fields` wrote.

    Attributes
    ----------
    format : {'vtu', 'xdmf'}
        The format actually written (``'vtu'`` after an XDMF fallback).
    index : Path
        The file to open in ParaView (``fields.pvd`` or ``fields.xdmf``).
    files : tuple of Path
        Every file written, index included.
    times : ndarray
        The sample times, as written.
    note : str
        Why the requested format was replaced, if it was ('' otherwise).
    """

    format: str
    index: Path
    files: tuple
    times: np.ndarray = field(repr=False)
    note: str = ""


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
        raw = extra.get("fields")
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
    return {"time": time, "rods": rods}


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
    """Points, segments and per-point arrays of all rods joined."""
    xs, segments, rod_ids, offset = [], [], [], 0
    for number, rod in enumerate(fields["rods"], start=1):
        xs.append(rod["x"])
        segments.append(line_segments(rod["x"], rod["cells"]) + offset)
        rod_ids.append(np.full(rod["x"].size, number, dtype=np.int64))
        offset += rod["x"].size
    x = np.concatenate(xs)
    points = np.zeros((x.size, 3))
    points[:, 0] = x
    values = {name: np.concatenate([rod[name] for rod in fields["rods"]], axis=1) for name in FIELD_NAMES}
    return points, np.concatenate(segments), np.concatenate(rod_ids), values


def _frame_data(values: dict, k: int, rod_ids: np.ndarray) -> dict:
    data = {name: values[name][k] for name in FIELD_NAMES}
    vector = np.zeros((rod_ids.size, 3))
    vector[:, 0] = values["displacement"][k]
    data["displacement_vector"] = vector
    data["rod"] = rod_ids
    return data


def write_fields(result, directory, format: str = "vtu", *, prefix: str = "fields") -> FieldFiles:
    """Write the sampled fields of a finite-element result for ParaView.

    Parameters
    ----------
    result : CollisionResult or dict
        A result of the fem solver run with ``record_fields=True`` (or its
        ``extra["fields"]`` dict).
    directory : str or Path
        Output directory, created if needed.
    format : {'vtu', 'xdmf'}
        ``'vtu'``: VTU file per sample plus a PVD index (opens in every
        ParaView).  ``'xdmf'``: one XDMF time series, verified by reading it
        back; replaced by the VTU series (with a warning) if that fails.
    prefix : str
        Base name of the files (``<prefix>.pvd``, ``<prefix>_00000.vtu``,
        ``<prefix>.xdmf``).

    Returns
    -------
    FieldFiles
        The format written, the index file to open and all files.

    Raises
    ------
    MissingFieldsError
        If the result carries no fields.
    InvalidParameterError
        For an unknown format or inconsistent field arrays.
    """
    if format not in FORMATS:
        raise InvalidParameterError(f"format must be one of {', '.join(FORMATS)}, got {format!r}")
    if not prefix or os.sep in prefix or (os.altsep and os.altsep in prefix):
        raise InvalidParameterError(f"prefix must be a plain file name stem, got {prefix!r}")
    fields = sampled_fields(result)
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    if format == "xdmf":
        try:
            written = _write_xdmf(fields, directory, prefix)
            _check_read_back(fields, written.index)
            return written
        except Exception as exc:  # noqa: BLE001 - any write or read-back failure: use the robust format
            for name in (f"{prefix}.xdmf", f"{prefix}.h5"):
                (directory / name).unlink(missing_ok=True)
            note = (
                f"XDMF series did not read back correctly ({exc}); wrote VTU files with a PVD index instead"
            )
            warnings.warn(note, UserWarning, stacklevel=2)
            written = _write_vtu_series(fields, directory, prefix)
            return FieldFiles(written.format, written.index, written.files, written.times, note)
    return _write_vtu_series(fields, directory, prefix)


def _write_vtu_series(fields: dict, directory: Path, prefix: str) -> FieldFiles:
    import meshio

    points, segments, rod_ids, values = _assemble(fields)
    time = fields["time"]
    width = max(5, len(str(time.size - 1)))
    collection = ET.Element("VTKFile", type="Collection", version="0.1", byte_order="LittleEndian")
    datasets = ET.SubElement(collection, "Collection")
    files = []
    for k, t in enumerate(time):
        name = f"{prefix}_{k:0{width}d}.vtu"
        mesh = meshio.Mesh(
            points,
            [("line", segments)],
            point_data=_frame_data(values, k, rod_ids),
            cell_data={"rod": [rod_ids[segments[:, 0]]]},
        )
        meshio.write(directory / name, mesh, file_format="vtu")
        ET.SubElement(datasets, "DataSet", timestep=repr(float(t)), group="", part="0", file=name)
        files.append(directory / name)
    index = directory / f"{prefix}.pvd"
    ET.indent(collection)
    ET.ElementTree(collection).write(index, xml_declaration=True, encoding="utf-8")
    return FieldFiles("vtu", index, (index, *files), time.copy())


def _write_xdmf(fields: dict, directory: Path, prefix: str) -> FieldFiles:
    import meshio

    try:
        import h5py  # noqa: F401

        data_format = "HDF"
    except ImportError:
        data_format = "XML"  # inline data; meshio's "Binary" writes next to the working directory
    points, segments, rod_ids, values = _assemble(fields)
    index = directory / f"{prefix}.xdmf"
    with meshio.xdmf.TimeSeriesWriter(index, data_format=data_format) as writer:
        writer.write_points_cells(points, [("line", segments.copy())])
        for k, t in enumerate(fields["time"]):
            writer.write_data(float(t), point_data=_frame_data(values, k, rod_ids))
    files = [index]
    if data_format == "HDF":
        files.append(directory / f"{prefix}.h5")
    return FieldFiles("xdmf", index, tuple(files), fields["time"].copy())


def _check_read_back(fields: dict, index: Path) -> None:
    back = read_fields(index)
    if back["time"].shape != fields["time"].shape or not np.array_equal(back["time"], fields["time"]):
        raise ValueError("sample times differ")
    if len(back["rods"]) != len(fields["rods"]):
        raise ValueError("number of rods differs")
    for rod, rod_back in zip(fields["rods"], back["rods"]):
        for name in ("x", *FIELD_NAMES):
            if not np.array_equal(rod[name], rod_back[name]):
                raise ValueError(f"{name} differs")


def read_fields(path) -> dict:
    """Read a series written by :func:`write_fields`.

    Parameters
    ----------
    path : str or Path
        The index (``.pvd`` or ``.xdmf``) or the directory holding
        ``fields.pvd`` / ``fields.xdmf``.

    Returns
    -------
    dict
        ``{"time": (nt,), "rods": [{"x", "displacement", "velocity",
        "stress", "segments"}, ...]}``; ``segments`` are the two-node cells
        with node indices local to the rod.
    """
    path = Path(path)
    if path.is_dir():
        for name in ("fields.pvd", "fields.xdmf"):
            if (path / name).exists():
                path = path / name
                break
        else:
            raise InvalidParameterError(f"no fields.pvd or fields.xdmf in {path}")
    if path.suffix == ".pvd":
        time, points, segments, frames = _read_pvd(path)
    elif path.suffix == ".xdmf":
        time, points, segments, frames = _read_xdmf(path)
    else:
        raise InvalidParameterError(f"path must be a .pvd or .xdmf file or a directory, got {path}")
    return _split_rods(time, points, segments, frames)


def _read_pvd(path: Path):
    import meshio

    root = ET.parse(path).getroot()
    entries = [(float(d.attrib["timestep"]), d.attrib["file"]) for d in root.iter("DataSet")]
    if not entries:
        raise InvalidParameterError(f"{path} lists no data sets")
    time, frames, points, segments = [], [], None, None
    for t, name in entries:
        mesh = meshio.read(path.parent / name)
        if points is None:
            points, segments = mesh.points, _line_cells(mesh.cells)
        time.append(t)
        frames.append(mesh.point_data)
    return np.array(time), points, segments, frames


def _read_xdmf(path: Path):
    import meshio

    time, frames = [], []
    with meshio.xdmf.TimeSeriesReader(path) as reader:
        points, cells = reader.read_points_cells()
        for k in range(reader.num_steps):
            t, point_data, _ = reader.read_data(k)
            time.append(t)
            frames.append(point_data)
    return np.array(time, dtype=float), points, _line_cells(cells), frames


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
