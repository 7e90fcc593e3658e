"""``wavecontact solve FILE``: every example scene file runs (small sizes); the output keeps momentum."""

import json
import math
from pathlib import Path

import pytest

from wavecontact import RigidBody
from wavecontact.cli import main
from wavecontact.io.scene_file import read_scene_file

SCENES = sorted((Path(__file__).resolve().parent.parent / "examples" / "scenes").glob("*.*"))


def body_mass(body):
    """Mass of a body from the file's numbers, computed here (rigid: mass; rod: sum of rho A l, tapers by the mean area)."""
    if isinstance(body, RigidBody):
        return body.mass
    if hasattr(body, "segments"):
        return sum(s.density * s.length * 0.5 * (s.area + (s.end_area if s.end_area is not None else s.area))
                   for s in body.segments)
    return body.density * body.area * body.length


@pytest.mark.parametrize("path", SCENES, ids=[p.name for p in SCENES])
def test_every_example_scene_runs(path, capsys, tmp_path):
    out = tmp_path / "result.json"
    code = main(["solve", str(path), "--elements", "16", "--json", "--out", str(out)])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    record = json.loads(captured.out)
    assert json.loads(out.read_text())["velocities"] == record["velocities"]
    scene = read_scene_file(path).scene
    masses = [body_mass(b) for b in scene.rods]
    before = sum(m * v for m, v in zip(masses, scene.velocities))
    after = sum(m * v for m, v in zip(masses, record["velocities"]))
    assert after == pytest.approx(before, rel=1e-9)
    assert len(record["contacts"]) == len(scene.rods) - 1
    assert all(c["impulse"] >= 0.0 for c in record["contacts"])


@pytest.mark.parametrize("path", SCENES, ids=[p.name for p in SCENES])
def test_every_example_scene_passes_the_default_limits_with_its_own_settings(path, capsys, monkeypatch):
    """The command each file documents, ``wavecontact solve FILE --json`` with the file's own [solve] table, gets
    past the cost check to the time loop under the default max_work and max_memory (hopkinson_bar.toml at 800
    elements was refused: about 6e11 updates estimated).  The loop itself is replaced so the test stays fast;
    the slow test below runs the files as they are."""
    from wavecontact.fem import multibody

    reached = []

    def loop_reached(*args, **kwargs):
        reached.append(kwargs.get("elements"))
        raise RuntimeError("stop: the cost check passed")

    monkeypatch.setattr(multibody, "run_line", loop_reached)
    with pytest.raises(RuntimeError, match="the cost check passed"):
        main(["solve", str(path), "--json"])
    assert reached == [read_scene_file(path).options["elements"]], capsys.readouterr().err


@pytest.mark.slow  # ~5 s warm (more on an empty cache): the four example files at their own resolutions, with estimates
@pytest.mark.parametrize("path", SCENES, ids=[p.name for p in SCENES])
def test_every_example_scene_runs_as_its_file_says(path, capsys):
    assert main(["solve", str(path), "--json"]) == 0, capsys.readouterr().err
    record = json.loads(capsys.readouterr().out)
    scene = read_scene_file(path).scene
    masses = [body_mass(b) for b in scene.rods]
    before = sum(m * v for m, v in zip(masses, scene.velocities))
    assert sum(m * v for m, v in zip(masses, record["velocities"])) == pytest.approx(before, rel=1e-9)
    assert record["error_estimate"] < 1e-2


def test_text_output_lists_bodies_and_contacts(capsys):
    code = main(["solve", str(SCENES[0]), "--elements", "16"])
    out = capsys.readouterr().out
    assert code == 0
    assert "velocity" in out and "impulse" in out


def test_a_bad_scene_file_is_one_line_and_writes_nothing(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text("[[body]]\nmass = 1.0\nvelocity = 1.0\n[[body]]\nlength = -1.0\n")
    out = tmp_path / "r.json"
    code = main(["solve", str(bad), "--out", str(out)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "bad.toml" in err[0] and "body[1]" in err[0] and "length" in err[0]
    assert not out.exists()


def test_two_uniform_rods_take_the_two_rod_path_and_agree_with_the_multi_body_loop(tmp_path, capsys):
    """Two uniform rods return the paper's CollisionResult; the command derives the velocities from
    epsilon and momentum. The same rods with the second as a one-segment piecewise rod run the
    multi-body loop: on the lattice both are exact."""
    two = tmp_path / "two.toml"
    two.write_text("[[body]]\nlength = 1.0\nvelocity = 1.0\n[[body]]\nlength = 2.0\n")
    twin = tmp_path / "twin.toml"
    twin.write_text("[[body]]\nlength = 1.0\nvelocity = 1.0\n[[body]]\n[[body.segment]]\nlength = 2.0\n")
    records = []
    for path in (two, twin):
        assert main(["solve", str(path), "--elements", "8", "--json"]) == 0
        records.append(json.loads(capsys.readouterr().out))
    assert records[0]["velocities"] == pytest.approx(records[1]["velocities"], abs=1e-9)
    assert records[0]["velocities"] == pytest.approx([0.0, 0.5], abs=1e-9)
    assert records[0]["contacts"][0]["impulse"] == pytest.approx(records[1]["contacts"][0]["impulse"], abs=1e-9)
    assert records[0]["internal_energies"] == [None, None]


def test_another_solver_ignores_the_files_solve_table(capsys):
    """hammer_on_bar.toml asks for fem with 400 elements; --solver delay runs the rigid-mass delay module
    (which takes no elements) and meets Saint-Venant's closed form V exp(-2m/M) (M = m) within its estimate."""
    path = next(p for p in SCENES if p.name == "hammer_on_bar.toml")
    assert main(["solve", str(path), "--solver", "delay", "--rtol", "1e-8", "--json"]) == 0
    record = json.loads(capsys.readouterr().out)
    assert record["solver"] == "delay"
    assert abs(record["velocities"][0] - math.exp(-2.0)) <= record["error_estimate"]


def test_without_a_solver_the_command_runs_auto_and_says_what_it_chose(tmp_path, capsys):
    """A hammer on a bar, no [solve] table, no solver options: auto takes the delay equations of a rigid mass
    and meets --tolerance against Saint-Venant's closed form V exp(-2 m / M) (M = m: V e^-2)."""
    path = tmp_path / "hammer.toml"
    path.write_text("[[body]]\nmass = 1.0\nvelocity = 1.0\n[[body]]\nlength = 1.0\n")
    assert main(["solve", str(path), "--tolerance", "1e-6", "--json"]) == 0
    record = json.loads(capsys.readouterr().out)
    assert record["solver"] == "delay" and record["auto"]["method"].startswith("delay")
    assert record["auto"]["tolerance"] == 1e-6 and record["error_estimate"] <= 1e-6
    assert record["velocities"][0] == pytest.approx(math.exp(-2.0), abs=1e-6)
    assert main(["solve", str(path), "--tolerance", "1e-6"]) == 0
    assert "auto: delay" in capsys.readouterr().out


def test_auto_refuses_an_unreachable_tolerance_in_one_line(tmp_path, capsys):
    path = tmp_path / "chain.toml"
    path.write_text("[[body]]\nlength = 0.5\nvelocity = 1.0\n[[body]]\nlength = 1.3\n[[body]]\nlength = 0.7733333\n")
    out = tmp_path / "r.json"
    assert main(["solve", str(path), "--tolerance", "1e-12", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "tolerance=1e-12" in err[0] and "elements=" in err[0]
    assert not out.exists()
