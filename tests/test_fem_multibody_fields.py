"""Sampled fields of the fem multi-body loop: recording, ParaView files, x-t diagram, CLI.

References are independent of the loop: a chain of equal rods hit with hard contact leaves every rod at
rest but the last, which flies off at the striker's speed (Newton's cradle of rods); a hard impact of a
striker on a bar of one impedance sends a plateau of stress ``-rho c V / 2`` (``-Z V / 2`` per unit area,
``Z = rho c A``) into both (wave theory of impact).
"""

import json
import re
from pathlib import Path

import meshio
import numpy as np
import pytest

from wavecontact import Hard, ImpactResult, RigidBody, Rod, Scene, Wall, solve
from wavecontact.cli import main
from wavecontact.errors import LimitError
from wavecontact.io.fields import read_fields, write_fields
from wavecontact.plotting.xt import xt_figure

CHAIN = Scene(rods=(Rod(1.0), Rod(1.0), Rod(1.0)), velocities=(1.0, 0.0, 0.0), contact=Hard(), gaps=(0.0, 0.0))


@pytest.fixture(scope="module")
def chain():
    plain = solve(CHAIN, solver="fem", elements=40, estimate_error=False)
    recorded = solve(CHAIN, solver="fem", elements=40, estimate_error=False, record_fields=True, field_samples=40)
    return plain, recorded


def test_recording_changes_no_result(chain):
    plain, recorded = chain
    assert plain.fields is None
    assert recorded.velocities == plain.velocities
    assert recorded.internal_energies == plain.internal_energies
    assert recorded.contacts == plain.contacts
    assert recorded.end_time == plain.end_time


def test_chain_fields_end_in_the_final_velocities(chain):
    _, result = chain
    fields = result.fields
    assert fields["time"][0] == 0.0 and fields["time"][-1] == pytest.approx(result.end_time, rel=1e-12)
    assert [rod["body"] for rod in fields["rods"]] == [0, 1, 2] and fields["points"] == []
    for rod, velocity, expected in zip(fields["rods"], result.velocities, (0.0, 0.0, 1.0)):
        v = rod["velocity"][-1]
        weights = np.full(v.size, 1.0)
        weights[[0, -1]] = 0.5  # lumped P1 masses of a uniform rod
        mean = float(weights @ v / weights.sum())
        assert mean == pytest.approx(velocity, abs=1e-12)
        assert mean == pytest.approx(expected, abs=1e-9)  # Newton's cradle of equal rods, exact lattice
        assert rod["x"][0] == pytest.approx(rod["body"] * 1.0)  # each rod at its place on the line


def test_incident_stress_is_minus_z_v_over_two():
    # striker and bar of one material and area: c = 2, Z = rho c A = 6, V = 1.5 -> stress -Z V / (2 A) = -1.5
    rod = {"density": 1.0, "youngs_modulus": 4.0, "area": 3.0}
    scene = Scene(rods=(Rod(0.5, **rod), Rod(2.0, **rod)), velocities=(1.5, 0.0), contact=Hard(), gaps=(0.0,),
                  walls=(None, None))
    result = solve(scene, solver="fem", elements=100, estimate_error=False, record_fields=True, field_samples=60)
    expected = -(1.0 * 2.0 * 3.0) * 1.5 / 2.0 / 3.0
    bar = result.fields["rods"][1]
    checked = 0
    for k, t in enumerate(result.fields["time"]):
        if not 0.1 < t < 0.45:  # the front runs at c = 2 from x = 0.5; the striker's pulse lasts 2 l1 / c = 0.5
            continue
        inside = (bar["x"] > 0.5 + 0.2 * t) & (bar["x"] < 0.5 + 2.0 * t - 0.1)
        assert np.all(np.abs(bar["stress"][k][inside] - expected) < 1e-9)
        ahead = bar["x"] > 0.5 + 2.0 * t + 0.1
        assert np.all(np.abs(bar["stress"][k][ahead]) < 1e-9)
        checked += inside.sum()
    assert checked > 100


def test_paraview_files_load_back(tmp_path):
    scene = Scene(rods=(RigidBody(0.5), Rod(1.0)), velocities=(1.0, 0.0), contact=Hard(), walls=(None, Wall(gap=0.1)))
    result = solve(scene, solver="fem", elements=30, estimate_error=False, record_fields=True, field_samples=12)
    files = write_fields(result, tmp_path / "f", units="scene")
    # meshio reads numeric field data only: the units (text) are read by read_fields below
    text = re.sub(r"<FieldData>.*?</FieldData>\n?", "", files.files[1].read_text(), flags=re.DOTALL)
    (tmp_path / "plain.vtu").write_text(text)
    mesh = meshio.read(tmp_path / "plain.vtu")
    nodes = result.fields["rods"][0]["x"].size
    assert mesh.points.shape[0] == nodes + 1  # the rod's nodes and the rigid body's point
    assert {c.type for c in mesh.cells} == {"line", "vertex"}
    back = read_fields(files.index)
    assert np.allclose(back["time"], result.fields["time"], rtol=1e-15)
    assert back["units"]["stress"] == "the unit of Young's modulus"
    rigid = [rod for rod in back["rods"] if rod["x"].size == 1]
    assert len(rigid) == 1 and rigid[0]["velocity"][0, 0] == 1.0
    assert np.array_equal(back["rods"][1]["stress"], result.fields["rods"][0]["stress"])


def test_xt_figure_of_a_scene_has_labelled_axes(chain):
    fig = xt_figure(chain[1], names=("striker", "middle", "last"), title="cradle", units="SI")
    ax = fig.axes[0]
    assert ax.get_xlabel().startswith("position x [m]")
    assert ax.get_ylabel() == "time t [s]"
    assert "cradle" in ax.get_title() and "3 bodies" in ax.get_title()
    assert "Pa" in fig.axes[1].get_ylabel()  # the colour bar
    texts = {t.get_text() for t in ax.texts}
    assert {"striker", "middle", "last"} <= texts
    assert ax.get_legend() is not None  # the contacts


@pytest.mark.parametrize("suffix", [".json", ".npz"])
def test_fields_survive_save_and_load(chain, tmp_path, suffix):
    result = chain[1]
    back = ImpactResult.load(result.save(tmp_path / f"r{suffix}"))
    assert back.velocities == result.velocities
    for a, b in zip(back.fields["rods"], result.fields["rods"]):
        for name in ("x", "displacement", "velocity", "stress", "cells"):
            assert np.array_equal(a[name], b[name])
    assert np.array_equal(back.fields["time"], result.fields["time"])


def test_memory_is_refused_before_the_run():
    with pytest.raises(LimitError, match="field samples") as refused:
        solve(CHAIN, solver="fem", elements=2000, record_fields=True, field_samples=100_000, max_memory=1e8)
    assert "max_memory=" in str(refused.value)
    solve(CHAIN, solver="fem", elements=20, estimate_error=False, max_memory=1e8)  # without fields it fits


def test_cli_writes_and_lists_fields_and_xt(tmp_path, capsys):
    scene = Path(__file__).resolve().parent.parent / "examples" / "scenes" / "hammer_on_bar.toml"
    code = main(["solve", str(scene), "--elements", "16", "--json", "--fields", str(tmp_path / "f"),
                 "--xt-plot", str(tmp_path / "xt.png")])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    written = json.loads(captured.out)["files_written"]
    assert written[0].endswith("fields.pvd") and written[-1].endswith("xt.png")
    assert "fields_*.vtu" in written[1]
    assert (tmp_path / "xt.png").stat().st_size > 0
    assert captured.err.count("xt.png") == 1
    assert len(read_fields(tmp_path / "f")["time"]) == len(list((tmp_path / "f").glob("fields_*.vtu")))


def test_cli_refuses_fields_of_another_solver_before_work(tmp_path, capsys):
    scene = Path(__file__).resolve().parent.parent / "examples" / "scenes" / "hammer_on_bar.toml"
    code = main(["solve", str(scene), "--solver", "delay", "--fields", str(tmp_path / "f"), "--xt-plot",
                 str(tmp_path / "xt.png")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "--fields" in err[0] and "fem" in err[0]
    assert not (tmp_path / "f").exists() and not (tmp_path / "xt.png").exists()
