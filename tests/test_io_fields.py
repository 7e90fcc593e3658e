"""Fields for ParaView: write VTU+PVD / XDMF series and read them back with meshio.

The fields come from the exact d'Alembert solution of the hard-core impact of
two rods of one material (wave theory of impact), sampled on P1 or P2 nodes,
so these tests do not depend on the finite-element solver.
"""

from __future__ import annotations

import importlib.util
import math
import xml.etree.ElementTree as ET

import meshio
import numpy as np
import pytest

from wavecontact.errors import InvalidParameterError
from wavecontact.io.fields import (
    FIELD_NAMES,
    UNIT_SYSTEMS,
    MissingFieldsError,
    line_segments,
    read_fields,
    sampled_fields,
    write_fields,
)
from wavecontact.result import CollisionResult


def _pulse(tau, duration):
    """Stress carried by the impact wave: -Z V / 2 = -1/2 for 0 < tau < duration."""
    return np.where((tau > 0.0) & (tau < duration), -0.5, 0.0)


def _pulse_integral(tau, duration):
    """Integral of the pulse from -inf to tau."""
    return -0.5 * np.clip(tau, 0.0, duration)


def _rod_waves(r, t, length, duration, integral=False):
    """Free-free image sums of the pulse entering a rod at r = 0 (r: distance from the contact end).

    Returns (stress, outgoing + returning pulse sum) for the velocity; with ``integral`` the
    second item is the time integral of that sum from t = 0 (for the displacement).
    """
    stress = np.zeros(np.broadcast(r, t).shape)
    moving = np.zeros_like(stress)
    for k in range(int(np.max(t) / (2 * length)) + 2):
        if integral:
            a, b = r + 2 * k * length, -r + 2 * (k + 1) * length
            away = _pulse_integral(t - a, duration) - _pulse_integral(-a, duration)
            back = _pulse_integral(t - b, duration) - _pulse_integral(-b, duration)
            moving += away + back
            continue
        away = _pulse(t - r - 2 * k * length, duration)
        back = _pulse(t + r - 2 * (k + 1) * length, duration)
        stress += away - back
        moving += away + back
    return stress, moving


def _nodes(length, elements, order, left):
    """Node coordinates and scikit-fem-like cells (vertices first, then interior nodes)."""
    vertices = np.linspace(left, left + length, elements + 1)
    if order == 1:
        return vertices, np.stack([np.arange(elements), np.arange(1, elements + 1)], axis=1)
    interior = [vertices[:-1] + (vertices[1:] - vertices[:-1]) * j / order for j in range(1, order)]
    x = np.concatenate([vertices, *interior])
    cells = [np.arange(elements), np.arange(1, elements + 1)]
    cells += [elements + 1 + j * elements + np.arange(elements) for j in range(order - 1)]
    return x, np.stack(cells, axis=1)


def hard_impact_result(gamma=0.6, elements=24, order=1, samples=60, t_end=None):
    """A CollisionResult with the exact fields of the hard-core impact (contact at t = 0).

    Units of MODEL.md section 2: rho = c = A = 1, V = 1, rod 1 on [-l1, 0], rod 2 on [0, l2].
    """
    l1, l2 = 0.5 * (1 + gamma), 0.5 * (1 + gamma) / gamma
    v1, v2 = 1 / (1 + gamma), -gamma / (1 + gamma)
    duration = 2 * l1
    t_end = 2 * l2 + 0.5 if t_end is None else t_end
    time = np.linspace(-0.3, t_end, samples)
    rods = []
    for length, left, v0, sign, n_el in (
        (l1, -l1, v1, 1.0, elements),
        (l2, 0.0, v2, -1.0, round(elements / gamma)),
    ):
        x, cells = _nodes(length, n_el, order, left)
        r = np.abs(x)[None, :]
        stress, moving = _rod_waves(r, time[:, None], length, duration)
        velocity = v0 + sign * moving
        # u = 0 at the moment of contact; the time integral of the pulses is exact
        _, swept = _rod_waves(r, time[:, None], length, duration, integral=True)
        displacement = v0 * time[:, None] + sign * swept
        rods.append(
            {"x": x, "displacement": displacement, "velocity": velocity, "stress": stress, "cells": cells}
        )
    fields = {"time": time, "rods": rods}
    relative = np.where(
        time < 0, -1.0, np.where(time < duration, -1.0 + (1 + gamma) * time / duration, gamma)
    )
    return CollisionResult(
        restitution=gamma,
        solver="analytic",
        wall_time_s=0.0,
        time=time,
        relative_velocity=relative,
        gamma=gamma,
        kappa=math.inf,
        extra={"fields": fields},
    )


def test_synthetic_fields_are_the_wave_theory_of_impact():
    # The generator itself against Saint-Venant: plateau -ZV/2 at the contact for 2 l1, then
    # rod 1 free of stress; momentum of the rods unchanged; final relative velocity gamma.
    gamma = 0.6
    result = hard_impact_result(gamma, elements=30, samples=400)
    f = result.extra["fields"]
    t = f["time"]
    rod1, rod2 = f["rods"]
    contact1 = np.argmax(rod1["x"])
    during = (t > 0.01) & (t < 1 + gamma - 0.01)
    assert np.all(rod1["stress"][during, contact1] == -0.5)
    after = t > 1 + gamma + 0.01
    assert np.all(rod1["stress"][after] == 0.0)
    mean_v1 = rod1["velocity"][after].mean(axis=1)
    assert np.allclose(mean_v1, -gamma / (1 + gamma))
    # rod 2 holds the pulse; its mean velocity follows from momentum (P1 nodes, trapezoid weights)
    l1, l2 = 0.5 * (1 + gamma), 0.5 * (1 + gamma) / gamma
    w2 = np.full(rod2["x"].size, rod2["x"][1] - rod2["x"][0])
    w2[[0, -1]] *= 0.5
    momentum2 = rod2["velocity"][-1] @ w2
    assert momentum2 == pytest.approx(-l1 * (-gamma / (1 + gamma)), abs=2e-2)
    assert momentum2 / l2 + gamma / (1 + gamma) == pytest.approx(gamma, abs=2e-2)


@pytest.mark.parametrize("order", [1, 2])
def test_vtu_series_round_trips_values_and_times(tmp_path, order):
    result = hard_impact_result(elements=10, order=order, samples=25)
    written = write_fields(result, tmp_path / "out")
    assert written.format == "vtu"
    assert written.index == tmp_path / "out" / "fields.pvd"
    assert all(p.exists() for p in written.files)
    # the PVD index lists every sample with its exact time
    datasets = list(ET.parse(written.index).getroot().iter("DataSet"))
    times = np.array([float(d.attrib["timestep"]) for d in datasets])
    expected = result.extra["fields"]
    np.testing.assert_array_equal(times, expected["time"])
    # one file read independently with meshio (which reads no text field data: drop it first):
    # 3-column points, two-node line cells, exact values
    tree = ET.parse(written.index.parent / datasets[7].attrib["file"])
    grid = tree.getroot().find("UnstructuredGrid")
    grid.remove(grid.find("FieldData"))
    tree.write(tmp_path / "plain.vtu")
    mesh = meshio.read(tmp_path / "plain.vtu")
    assert mesh.points.shape[1] == 3 and np.all(mesh.points[:, 1:] == 0)
    assert [c.type for c in mesh.cells] == ["line"]
    stress = np.concatenate([rod["stress"][7] for rod in expected["rods"]])
    np.testing.assert_array_equal(mesh.point_data["stress"], stress)
    np.testing.assert_array_equal(
        mesh.point_data["displacement_vector"][:, 0],
        np.concatenate([rod["displacement"][7] for rod in expected["rods"]]),
    )
    # the whole series back through read_fields
    back = read_fields(tmp_path / "out")
    np.testing.assert_array_equal(back["time"], expected["time"])
    for rod, rod_back in zip(expected["rods"], back["rods"]):
        for name in ("x", *FIELD_NAMES):
            np.testing.assert_array_equal(rod_back[name], rod[name])
        assert rod_back["segments"].shape == (rod["cells"].shape[0] * order, 2)


def _field_data(path):
    """The FieldData of one VTU file, decoded here without wavecontact's reader (VTK's XML layout:
    numbers in DataArray elements, text in Array elements as character codes ending in 0)."""
    root = ET.parse(path).getroot()
    (block,) = root.iter("FieldData")
    out = {}
    for element in block:
        codes = element.text.split()
        if element.tag == "Array" and element.attrib["type"] == "String":
            assert codes[-1] == "0"
            text = bytes(int(c) for c in codes[:-1]).decode()
            # VTK cannot read "inf" as an ASCII number: the writer stores non-finite values as words
            out[element.attrib["Name"]] = {"inf": math.inf, "-inf": -math.inf, "nan": math.nan}.get(text, text)
        else:
            assert element.tag == "DataArray" and element.attrib["type"] == "Float64"
            out[element.attrib["Name"]] = float(codes[0])
    return out


def test_every_file_carries_its_time_units_and_parameters(tmp_path):
    result = hard_impact_result(elements=6, samples=4)
    written = write_fields(result, tmp_path, parameters={"note": "exact d'Alembert solution", "seed": 7})
    times = result.extra["fields"]["time"]
    for k, path in enumerate(written.files[1:]):
        data = _field_data(path)
        assert data["TimeValue"] == times[k]
        assert data["gamma"] == 0.6 and data["kappa"] == math.inf and data["restitution"] == 0.6
        assert data["unit_stress"] == "rho c V" and data["unit_time"] == "l / c"
        assert data["solver"] == "analytic" and data["note"] == "exact d'Alembert solution" and data["seed"] == 7
    back = read_fields(written.index)
    assert back["units"] == UNIT_SYSTEMS["dimensionless"]
    assert back["parameters"]["note"] == "exact d'Alembert solution" and back["parameters"]["kappa"] == math.inf
    si = read_fields(write_fields(result, tmp_path / "si", units="SI").index)
    assert si["units"]["stress"] == "Pa" and si["units"]["length"] == "m"


def test_vtu_files_are_binary_and_compressed(tmp_path):
    written = write_fields(hard_impact_result(elements=200, samples=3), tmp_path)
    text = written.files[1].read_text()
    assert 'compressor="vtkZLibDataCompressor"' in text
    assert 'format="ascii"' not in text.replace('format="ascii">', "")  # only the small field data is text
    # 2 rods, 200 + 333 elements: 536 points x 7 values x 8 bytes = 30 kB raw; compressed it is smaller
    assert written.files[1].stat().st_size < 30_000


def test_bad_units_and_parameters_are_refused(tmp_path):
    result = hard_impact_result(elements=4, samples=3)
    with pytest.raises(InvalidParameterError, match="units"):
        write_fields(result, tmp_path, units="imperial")
    with pytest.raises(InvalidParameterError, match="lacks"):
        write_fields(result, tmp_path, units={"length": "m"})
    with pytest.raises(InvalidParameterError, match="parameters"):
        write_fields(result, tmp_path, parameters={"mesh": [1, 2]})
    with pytest.raises(InvalidParameterError, match="XDMF"):
        write_fields(result, tmp_path, format="xdmf")


def test_result_without_fields_is_refused_with_a_hint(tmp_path):
    result = CollisionResult(
        restitution=0.6, solver="delay", wall_time_s=0.0, time=np.zeros(2), relative_velocity=np.zeros(2)
    )
    with pytest.raises(MissingFieldsError, match="record_fields=True"):
        write_fields(result, tmp_path)
    assert not any(tmp_path.iterdir())


def test_inconsistent_fields_are_refused(tmp_path):
    result = hard_impact_result(elements=4, samples=6)
    rod = result.extra["fields"]["rods"][1]
    rod["stress"] = rod["stress"][:, :-1]
    with pytest.raises(InvalidParameterError, match=r"rods'\]\[1\]\['stress'\].*shape"):
        write_fields(result, tmp_path)
    good = hard_impact_result(elements=4, samples=6).extra["fields"]
    good["rods"][0]["cells"] = good["rods"][0]["cells"] + 100
    with pytest.raises(InvalidParameterError, match="outside"):
        sampled_fields(good)
    good = hard_impact_result(elements=4, samples=6).extra["fields"]
    good["rods"][0]["velocity"][2, 1] = np.nan
    with pytest.raises(InvalidParameterError, match="non-finite"):
        sampled_fields(good)
    with pytest.raises(InvalidParameterError, match="format"):
        write_fields(hard_impact_result(elements=4, samples=6), tmp_path, format="vtk")
    assert not any(tmp_path.iterdir())


def test_elements_of_any_order_become_sorted_two_node_segments():
    x = np.array([0.0, 1.0, 2.0, 0.5, 1.5])
    cells = np.array([[0, 1, 3], [2, 1, 4]])  # node order inside a cell is arbitrary
    segments = line_segments(x, cells)
    np.testing.assert_array_equal(segments, [[0, 3], [3, 1], [1, 4], [4, 2]])


FEM_IMPORTABLE = importlib.util.find_spec("wavecontact.fem.solver") is not None


@pytest.mark.skipif(not FEM_IMPORTABLE, reason="finite-element solver not installed")
def test_fem_fields_write_and_read_back(tmp_path):
    from wavecontact import collide

    result = collide(
        0.6, 20, solver="fem", elements=16, order=2, mass="consistent", record_fields=True, field_samples=40
    )
    written = write_fields(result, tmp_path)
    assert written.format == "vtu"
    expected = sampled_fields(result)
    back = read_fields(written.index)
    np.testing.assert_array_equal(back["time"], expected["time"])
    assert len(back["rods"]) == 2
    for rod, rod_back in zip(expected["rods"], back["rods"]):
        for name in ("x", *FIELD_NAMES):
            np.testing.assert_array_equal(rod_back[name], rod[name])
        assert rod_back["segments"].shape == (2 * rod["cells"].shape[0], 2)  # P2: two segments each
    # the stress the solver reports is the impact stress: a compression near -Z V / 2 somewhere
    assert -0.6 < min(rod["stress"].min() for rod in expected["rods"]) < -0.3


def _collision_with_fields(kappa):
    from wavecontact import collide

    return collide(0.6, kappa, solver="fem", elements=12, order=2, mass="consistent", record_fields=True,
                   field_samples=5)


@pytest.mark.skipif(not FEM_IMPORTABLE, reason="finite-element solver not installed")
def test_field_data_names_the_discretization_and_round_trips_through_meshio(tmp_path):
    """The run's discretization and units are in every file; read_fields (meshio for the mesh and point
    data; meshio 5 refuses VTK's String arrays, so it reads the field data itself) gives everything back."""
    result = _collision_with_fields(math.inf)
    written = write_fields(result, tmp_path)
    data = _field_data(written.files[1])
    assert data["order"] == 2 and data["mass"] == "consistent" and data["elements"] == 12
    assert data["kappa"] == math.inf and data["dt"] == result.work["dt"]
    back = read_fields(written.index)
    assert back["parameters"]["mass"] == "consistent" and back["parameters"]["kappa"] == math.inf
    assert back["parameters"]["restitution"] == result.restitution and back["units"] == UNIT_SYSTEMS["dimensionless"]
    expected = sampled_fields(result)
    np.testing.assert_array_equal(back["time"], expected["time"])
    for rod, rod_back in zip(expected["rods"], back["rods"]):
        for name in ("x", *FIELD_NAMES):
            np.testing.assert_array_equal(rod_back[name], rod[name])


@pytest.mark.skipif(not FEM_IMPORTABLE, reason="finite-element solver not installed")
@pytest.mark.parametrize("kappa", [100.0, math.inf])
def test_vtk_reader_gets_every_field_and_the_field_data(tmp_path, kappa):
    """ParaView reads VTU files with VTK's vtkXMLUnstructuredGridReader; it must see everything."""
    vtk = pytest.importorskip("vtk")
    from vtk.util.numpy_support import vtk_to_numpy

    result = _collision_with_fields(kappa)
    written = write_fields(result, tmp_path, units="dimensionless", parameters={"note": "vtk check"})
    expected = sampled_fields(result)
    x = np.concatenate([rod["x"] for rod in expected["rods"]])
    for k, path in enumerate(written.files[1:]):
        reader = vtk.vtkXMLUnstructuredGridReader()
        reader.SetFileName(str(path))
        reader.Update()
        assert reader.GetErrorCode() == 0, path
        grid = reader.GetOutput()
        assert grid.GetNumberOfPoints() == x.size
        np.testing.assert_array_equal(vtk_to_numpy(grid.GetPoints().GetData())[:, 0], x)
        points = grid.GetPointData()
        for name in FIELD_NAMES:
            values = np.concatenate([rod[name][k] for rod in expected["rods"]])
            np.testing.assert_array_equal(vtk_to_numpy(points.GetArray(name)), values)
        vector = vtk_to_numpy(points.GetArray("displacement_vector"))
        np.testing.assert_array_equal(vector[:, 0], np.concatenate([rod["displacement"][k] for rod in expected["rods"]]))
        assert set(vtk_to_numpy(points.GetArray("rod"))) == {1, 2}
        found = {}
        data = grid.GetFieldData()
        for i in range(data.GetNumberOfArrays()):
            array = data.GetAbstractArray(i)
            found[array.GetName()] = (array.GetValue(0) if isinstance(array, vtk.vtkStringArray)
                                      else array.GetTuple1(0))
        assert found["TimeValue"] == expected["time"][k]
        assert {f"unit_{q}": found[f"unit_{q}"] for q in UNIT_SYSTEMS["dimensionless"]} == {
            f"unit_{q}": u for q, u in UNIT_SYSTEMS["dimensionless"].items()}
        assert found["gamma"] == 0.6 and found["restitution"] == result.restitution
        assert found["kappa"] == (kappa if math.isfinite(kappa) else "inf")
        assert found["mass"] == "consistent" and found["order"] == 2 and found["note"] == "vtk check"
