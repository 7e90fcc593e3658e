"""``wavecontact gas``: JSON summary, outputs, resume, collapse message, refusals."""

import contextlib
import json
from pathlib import Path

import numpy as np
import pytest
from analytic_kick_table import analytic_kick_table

from wavecontact.cli import main
from wavecontact.gas import UniformLengths, random_gas
from wavecontact.gas.reference import heapq_ring_gas


def _json(capsys, argv):
    assert main(argv) == 0
    return json.loads(capsys.readouterr().out)


@contextlib.contextmanager
def _figure_not_drawn(monkeypatch):
    """For set-up runs whose figure no assertion looks at: gas.png is written empty instead of drawn (drawing it
    is most of a short run: 1.65 of 1.71 s for 300 collisions, cProfile); test_json_summary_and_outputs, the
    resumed runs and the interruption while writing draw theirs."""
    import wavecontact.plotting.gas as plotting

    with monkeypatch.context() as patch:
        patch.setattr(plotting, "plot_gas", lambda result, path, **options: Path(path).touch())
        yield


def test_json_summary_and_outputs(tmp_path, capsys):
    out = tmp_path / "run"
    table = tmp_path / "kick.npz"
    analytic_kick_table(levels=51).save(table)  # a wide analytic table: this run stays inside its grid
    summary = _json(capsys, ["gas", "--rods", "200", "--collisions", "4000", "--rule", "vibration", "--table",
                             str(table), "--damping", "30", "--seed", "2", "--out", str(out), "--json",
                             "--no-progress"])
    for key in ("collisions", "simulated_time", "collapsed", "collisions_per_second", "final_energy"):
        assert key in summary
    assert summary["collisions"] == 4000 and summary["collapsed"] is False
    assert {p.name for p in out.iterdir()} >= {"gas.png", "gas_summary.json", "gas_history.npz", "gas_checkpoint.npz"}
    with np.load(out / "gas_history.npz", allow_pickle=False) as data:
        assert data["history_kinetic_energy"][-1] == pytest.approx(summary["final_energy"])


def test_the_default_vibration_rule_is_the_hard_core_law_and_never_leaves_it(capsys):
    summary = _json(capsys, ["gas", "--rods", "100", "--collisions", "3000", "--rule", "vibration", "--seed", "2",
                             "--json", "--no-progress"])
    assert summary["rule"]["rule"] == "vibration_law" and summary["rule"]["samples_per_point"] >= 100
    assert summary["status"] == "completed" and summary["collisions"] == 3000
    assert summary["beyond_law"] >= 0


def test_contact_stiffness_is_reported_with_the_bath_limited_fraction(tmp_path, capsys, monkeypatch):
    out = tmp_path / "soft"
    base = ["gas", "--rods", "100", "--rule", "vibration", "--seed", "3", "--json", "--no-progress",
            "--contact-stiffness", "40"]
    summary = _json(capsys, [*base, "--collisions", "4000"])  # records every 10: the last one at the end
    assert summary["contact_stiffness"] == 40.0 and summary["rule"]["soft_law"]["kappa"][0] >= 3
    assert 0.0 <= summary["bath_limited_fraction"] <= 1.0 and summary["status"] == "completed"
    assert 0 <= summary["softer_than_law"] <= summary["collisions"]
    hard = _json(capsys, ["gas", "--rods", "100", "--rule", "vibration", "--seed", "3", "--json", "--no-progress",
                          "--collisions", "4000"])
    assert hard["contact_stiffness"] is None and hard["softer_than_law"] == 0
    assert hard["final_energy"] != summary["final_energy"]  # soft contacts change the run
    with _figure_not_drawn(monkeypatch):
        _json(capsys, [*base, "--collisions", "1000", "--out", str(out)])
    resumed = _json(capsys, [*base, "--collisions", "3000", "--out", str(out), "--resume"])
    assert resumed["final_energy"] == summary["final_energy"] and resumed["softer_than_law"] == summary["softer_than_law"]


def test_resume_continues_the_same_run(tmp_path, capsys, monkeypatch):
    out = tmp_path / "run"
    base = ["gas", "--rods", "100", "--rule", "fixed", "--restitution", "0.97", "--seed", "5", "--json", "--no-progress"]
    straight = _json(capsys, [*base, "--collisions", "2000"])
    with _figure_not_drawn(monkeypatch):
        _json(capsys, [*base, "--collisions", "800", "--out", str(out)])
    resumed = _json(capsys, [*base, "--collisions", "1200", "--out", str(out), "--resume"])
    assert resumed["collisions"] == 2000
    assert resumed["simulated_time"] == straight["simulated_time"]
    assert resumed["final_energy"] == straight["final_energy"]


def test_final_energy_is_the_energy_after_the_last_collision(tmp_path, capsys):
    """1,001 collisions with a record every 2: the summary's final_energy and the saved records' last row are the
    state after collision 1,001, as an independent heapq loop on the same gas finds it (not the record at 1,000)."""
    out = tmp_path / "run"
    summary = _json(capsys, ["gas", "--rods", "100", "--collisions", "1001", "--rule", "fixed", "--restitution",
                             "0.99", "--seed", "4", "--lengths", "0.5", "1.0", "--packing", "0.2", "--json",
                             "--no-progress", "--out", str(out)])
    initial = np.random.SeedSequence(4).spawn(2)[0]  # the CLI's gas: the first child of the root seed
    gas = random_gas(100, seed=initial, lengths=UniformLengths(0.5, 1.0), packing_fraction=0.2)
    _, v, now, _ = heapq_ring_gas(gas.lengths, gas.positions, gas.velocities, gas.system_length, 0.99, 1001)
    v, m = np.asarray(v), gas.lengths
    expected = 0.5 * np.sum(m * v**2) - np.sum(m * v) ** 2 / (2 * m.sum())  # centre-of-mass frame
    one_before = heapq_ring_gas(gas.lengths, gas.positions, gas.velocities, gas.system_length, 0.99, 1000)[1]
    assert abs(0.5 * np.sum(m * np.asarray(one_before) ** 2) - 0.5 * np.sum(m * v**2)) > 1e-6 * expected
    assert summary["collisions"] == 1001 and summary["simulated_time"] == pytest.approx(now, rel=1e-12)
    assert summary["final_energy"] == pytest.approx(expected, rel=1e-10)
    with np.load(out / "gas_history.npz", allow_pickle=False) as data:
        assert data["history_collisions"][-1] == 1001 and np.all(np.diff(data["history_collisions"]) > 0)
        assert data["history_kinetic_energy"][-1] == summary["final_energy"]
        assert data["history_time"][-1] == summary["simulated_time"]


def test_collapse_stops_with_a_message(capsys):
    summary = _json(capsys, ["gas", "--rods", "400", "--collisions", "1000000", "--rule", "fixed",
                             "--restitution", "0.6", "--json", "--no-progress"])
    assert summary["collapsed"] is True and summary["collisions"] < 1000000
    assert "inelastic collapse" in capsys.readouterr().err or "inelastic collapse" in summary["message"]


@pytest.mark.parametrize(
    "argv, message",
    [
        (["--rule", "fixed"], "--restitution"),
        (["--rule", "vibration", "--restitution", "0.5"], "fixed only"),
        (["--rule", "fixed", "--restitution", "1.5"], r"restitution must lie in \[0, 1\]"),
        (["--rule", "fixed", "--restitution", "0.5", "--packing", "1"], r"packing must lie in \(0, 1\)"),
        (["--rule", "vibration", "--lengths", "0.1", "1"], "table covers gamma"),
        (["--rule", "vibration", "--table", "a.npz", "--law", "b.npz"], "either --table or --law"),
        (["--rule", "vibration", "--law", "missing.npz"], "not a readable collision law"),
        (["--rule", "fixed", "--restitution", "0.5", "--contact-stiffness", "10"], "vibration only"),
        (["--rule", "vibration", "--contact-stiffness", "0"], "contact-stiffness must be a finite number > 0"),
    ],
)
def test_bad_options_end_with_one_line(argv, message, capsys):
    with pytest.raises(SystemExit) if "must lie" in message or "must be a finite" in message else _nothing():
        status = main(["gas", "--rods", "10", "--collisions", "10", *argv])
        assert status == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert __import__("re").search(message, err)


class _nothing:
    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False


# ----------------------------------------------------------------------------
# Long runs: the run controller (issue 23 items 4 and 8)
# ----------------------------------------------------------------------------

_BASE = ["gas", "--rods", "100", "--rule", "fixed", "--restitution", "0.97", "--seed", "5", "--json", "--no-progress"]


@pytest.fixture(scope="module")
def _written_run(tmp_path_factory):
    """One ``_BASE`` run of 300 collisions written by the CLI (outputs, figure and checkpoint) and its summary;
    the tests that resume or tamper with it take a copy (:func:`_copy_of_run`), so the figure is drawn once."""
    import io

    out = tmp_path_factory.mktemp("gas300") / "run"
    with contextlib.redirect_stdout(io.StringIO()) as printed, contextlib.redirect_stderr(io.StringIO()):
        assert main([*_BASE, "--collisions", "300", "--out", str(out)]) == 0
    return out, json.loads(printed.getvalue())


def _copy_of_run(written, tmp_path):
    """A copy of the module's written run in ``tmp_path/run`` (what the CLI would have written there)."""
    import shutil

    return Path(shutil.copytree(written[0], tmp_path / "run"))


def _state(out):
    from wavecontact.gas import GasSimulation

    sim = GasSimulation.resume(out / "gas_checkpoint.npz")
    return sim.collisions, sim.v.copy(), sim.time


def test_an_interrupted_resume_is_finished_by_the_same_command(tmp_path, capsys, monkeypatch):
    """Interrupted while writing its outputs (after the last collision) or in the middle of its collisions,
    the natural retry runs the interrupted run's collisions, not COLLISIONS more (issue 23: 9000 instead of 6000)."""
    import os
    import signal

    import wavecontact.plotting.gas as plotting
    from wavecontact.gas.simulation import GasSimulation

    out = tmp_path / "run"
    with _figure_not_drawn(monkeypatch):
        straight = _json(capsys, [*_BASE, "--collisions", "2000", "--out", str(tmp_path / "straight")])
        _json(capsys, [*_BASE, "--collisions", "800", "--out", str(out)])
    resume = [*_BASE, "--collisions", "1200", "--out", str(out), "--resume"]

    def interrupted_plot(*args, **kwargs):
        raise KeyboardInterrupt

    with monkeypatch.context() as patch:
        patch.setattr(plotting, "plot_gas", interrupted_plot)
        assert main(resume) == 130
    assert "interrupted" in capsys.readouterr().err
    original = GasSimulation._record

    def record_then_signal(self):
        original(self)
        if self.collisions == 1400:
            os.kill(os.getpid(), signal.SIGINT)

    with monkeypatch.context() as patch:
        patch.setattr(GasSimulation, "_record", record_then_signal)
        assert main(resume) == 130
    err = capsys.readouterr().err
    assert "the checkpoint holds collision 1400 of 2000" in err and "wavecontact: interrupted" in err
    assert _state(out)[0] == 1400
    finished = _json(capsys, resume)
    assert finished["collisions"] == 2000
    assert finished["final_energy"] == straight["final_energy"]
    assert finished["simulated_time"] == straight["simulated_time"]
    np.testing.assert_array_equal(_state(out)[1], _state(tmp_path / "straight")[1])
    again = _json(capsys, resume)  # the run finished: the same command now continues it
    assert again["collisions"] == 3200


@pytest.mark.parametrize("change, option", [
    (["--seed", "6"], "--seed"), (["--rods", "101"], "--rods"), (["--walls"], "--walls"),
    (["--damping", "3"], "--damping"), (["--lengths", "0.5", "1.0"], "--lengths"), (["--packing", "0.3"], "--packing"),
    (["--restitution", "0.9"], "fixed"),
])
def test_resume_refuses_options_that_contradict_the_checkpoint(tmp_path, capsys, change, option, _written_run):
    out = _copy_of_run(_written_run, tmp_path)
    before = (out / "gas_checkpoint.npz").read_bytes()
    argv = [*_BASE, "--collisions", "300", "--out", str(out), "--resume"]
    if change[0] in argv:  # another value of an option the run was given
        argv[argv.index(change[0]) + 1] = change[1]
    else:
        argv += change
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "--resume" in err and option in err
    assert (out / "gas_checkpoint.npz").read_bytes() == before


def test_a_folder_with_a_checkpoint_needs_resume_or_overwrite(tmp_path, capsys, _written_run):
    out = _copy_of_run(_written_run, tmp_path)
    first = _written_run[1]
    assert main([*_BASE, "--collisions", "300", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "--resume" in err and "--overwrite" in err
    again = _json(capsys, [*_BASE, "--collisions", "300", "--out", str(out), "--overwrite"])
    assert again["final_energy"] == first["final_energy"] and _state(out)[0] == 300


_GAS_TAMPERING = {
    "NaN velocity": lambda a: a["v"].__setitem__(3, np.nan),
    "infinite bath": lambda a: a["temperature"].__setitem__(0, np.inf),
    "one velocity for every rod": lambda a: a.__setitem__("v", a["v"][:1]),
    "resized positions": lambda a: a.__setitem__("x", np.concatenate([a["x"], a["x"]])),
    "missing window": lambda a: a.pop("window"),
    "history resized": lambda a: a.__setitem__("history_time", a["history_time"][:-1]),
    "negative counter": lambda a: a["counters"].__setitem__(0, -5),
    "local time ahead": lambda a: a["local_time"].__setitem__(0, 1e9),
    "unknown status": lambda a: a.__setitem__("status", np.asarray("exploded")),
    "segment ahead": lambda a: a.__setitem__("segment", np.array([10**6, 10**6, 0])),
}


@pytest.mark.parametrize("change", list(_GAS_TAMPERING), ids=list(_GAS_TAMPERING))
def test_a_crafted_gas_checkpoint_is_refused_in_one_line(tmp_path, capsys, change, _written_run):
    from test_io_run_controller import tamper

    out = _copy_of_run(_written_run, tmp_path)
    tamper(out / "gas_checkpoint.npz", _GAS_TAMPERING[change])
    assert main([*_BASE, "--collisions", "300", "--out", str(out), "--resume"]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "checkpoint" in err and "Traceback" not in err


def test_the_timing_line_tells_compiling_from_running(capsys):
    """Compile time is numba's compile events only: a fresh function compiles (seconds > 0), a compiled one
    or a kernel loaded from the cache does not; a second run in one process says neither."""
    numba = pytest.importorskip("numba")
    from wavecontact.cli.gas import _compile_timer

    fresh = numba.njit(cache=False)(lambda x: 2 * x + 1)
    with _compile_timer() as compiling:
        fresh(3)
    assert compiling[0] > 0
    with _compile_timer() as compiling:
        fresh(4)
    assert compiling[0] == 0
    argv = ["gas", "--rods", "10", "--collisions", "50", "--rule", "fixed", "--restitution", "0.9", "--no-progress"]
    main(argv)
    capsys.readouterr()
    main(argv)  # the kernels are ready in this process: nothing to prepare
    line = next(x for x in capsys.readouterr().out.splitlines() if "collisions per second" in x)
    assert "compiling" not in line and "cache" not in line, line
