"""Rod gas runs: independent reference loop, conservation laws, checkpoints, and the physics of
inelastic collapse (McNamara & Young), Haff's law and the vibration rule."""

import math

import numpy as np
import pytest
from analytic_kick_table import analytic_kick_table
from scipy.optimize import curve_fit

from wavecontact.errors import CheckpointError, InvalidParameterError
from wavecontact.gas import (
    EqualLengths,
    FixedRestitution,
    GasSimulation,
    RodGas,
    StoppingRules,
    UniformLengths,
    VibrationSolve,
    VibrationTable,
    random_gas,
)
from wavecontact.gas.reference import heapq_ring_gas

TABLE = analytic_kick_table(levels=101)


def _state(sim):
    return {name: getattr(sim, name).copy() for name in GasSimulation._STATE}


def test_agrees_with_an_independent_heapq_event_loop():
    gas = random_gas(200, seed=3)
    sim = GasSimulation(gas, FixedRestitution(0.9), seed=1, record_every=50)
    sim.run(400)
    x, v, now, _ = heapq_ring_gas(gas.lengths, gas.positions, gas.velocities, gas.system_length, 0.9, 400)
    assert sim.time == pytest.approx(now, rel=1e-12)
    np.testing.assert_allclose(sim.v, v, rtol=0, atol=1e-12)
    np.testing.assert_allclose(sim.x + sim.v * (sim.time - sim.local_time), x, rtol=0, atol=1e-10)


def test_elastic_equal_rods_only_exchange_velocities():
    gas = random_gas(64, seed=5, lengths=EqualLengths(0.2), boundary="walls")
    sim = GasSimulation(gas, FixedRestitution(1.0), seed=0, record_every=100)
    result = sim.run(2000)
    assert result.wall_hits > 0
    # equal masses swap velocities; walls flip signs: the set of speeds is conserved (to rounding)
    np.testing.assert_allclose(np.sort(np.abs(sim.v)), np.sort(np.abs(gas.velocities)), rtol=1e-12, atol=1e-14)
    centres = sim.positions()
    assert np.all(np.diff(centres) >= 0.2 - 1e-9)
    assert centres[0] >= 0.1 - 1e-9 and centres[-1] <= gas.system_length - 0.1 + 1e-9


@pytest.mark.parametrize("damping", [None, 3.0])
def test_energy_and_momentum_are_conserved_with_the_vibration_rule(damping):
    gas = random_gas(300, seed=2, lengths=UniformLengths(0.5, 1.0), bath_temperature=1e-3)
    sim = GasSimulation(gas, VibrationTable(TABLE), seed=7, damping=damping, record_every=500)
    result = sim.run(20_000)
    history = result.history
    total = history["kinetic_energy"] + history["bath_energy"] + history["dissipated_energy"]
    # kinetic energy in the centre-of-mass frame: add the (conserved) drift energy back
    drift = np.sum(gas.masses * gas.velocities) ** 2 / (2 * gas.masses.sum())
    np.testing.assert_allclose(total + drift, total[0] + drift, rtol=1e-11)
    assert abs(result.energy_drift) < 1e-11
    assert np.sum(sim.mass * sim.v) == pytest.approx(np.sum(gas.masses * gas.velocities), abs=1e-12)
    assert history["bath_energy"][-1] > 0
    if damping:
        assert history["dissipated_energy"][-1] > 0


def test_a_solve_per_collision_rule_plugs_into_the_same_loop():
    """VibrationSolve with a constant draw moves the rods exactly like the fixed rule and fills the baths."""
    gas = random_gas(100, seed=9, lengths=UniformLengths(0.5, 1.0))
    seeds = []

    def draw(gamma, temperature_ratio, seed):
        seeds.append(seed)
        assert 0.5 <= gamma <= 1.0 and temperature_ratio >= 0.0
        return 0.8**2, 0.25

    solve = GasSimulation(gas, VibrationSolve(draw, bath_modes=10), seed=1, record_every=100)
    fixed = GasSimulation(gas, FixedRestitution(0.8), seed=1, record_every=100)
    r1, r2 = solve.run(500), fixed.run(500)
    np.testing.assert_array_equal(solve.v, fixed.v)
    assert r1.history["bath_energy"][-1] == pytest.approx(r2.history["lost_energy"][-1], rel=1e-12)
    assert len({tuple(s.spawn_key) for s in seeds}) == 500  # one independent stream per collision


def test_results_do_not_depend_on_the_chunking():
    gas = random_gas(150, seed=4, lengths=UniformLengths(0.5, 1.0))
    a = GasSimulation(gas, VibrationTable(TABLE), seed=3, record_every=1000)
    b = GasSimulation(gas, VibrationTable(TABLE), seed=3, record_every=37)
    a.run(3000)
    for _ in range(3):
        b.run(1000)
    for name, value in _state(a).items():
        if name != "window":
            np.testing.assert_array_equal(value, getattr(b, name), err_msg=name)


@pytest.mark.parametrize("rule", [FixedRestitution(0.95), VibrationTable(TABLE)])
def test_checkpoint_resumes_bit_for_bit(tmp_path, rule):
    gas = random_gas(120, seed=6, lengths=UniformLengths(0.5, 1.0), bath_temperature=0.01)
    straight = GasSimulation(gas, rule, seed=2, damping=5.0, record_every=250)
    full = straight.run(3000)
    first = GasSimulation(gas, rule, seed=2, damping=5.0, record_every=250)
    first.run(1250)
    path = first.save_checkpoint(tmp_path / "gas.npz")
    resumed = GasSimulation.resume(path)
    rest = resumed.run(1750)
    for name, value in _state(straight).items():
        np.testing.assert_array_equal(value, getattr(resumed, name), err_msg=name)
    for name in full.history:
        np.testing.assert_array_equal(full.history[name], rest.history[name], err_msg=name)
    np.testing.assert_array_equal(full.frames, rest.frames)


def test_corrupted_or_foreign_checkpoints_are_refused(tmp_path):
    sim = GasSimulation(random_gas(20, seed=1), FixedRestitution(0.9), seed=1, record_every=10)
    sim.run(100)
    path = sim.save_checkpoint(tmp_path / "gas.npz")
    data = bytearray(path.read_bytes())
    data[len(data) // 2] ^= 0xFF
    (tmp_path / "bad.npz").write_bytes(bytes(data))
    with pytest.raises(CheckpointError):
        GasSimulation.resume(tmp_path / "bad.npz")
    with pytest.raises(InvalidParameterError, match="rule"):
        GasSimulation.resume(path, rule=VibrationSolve(lambda g, r, s: (1.0, 0.5)))


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda: random_gas(1, seed=0), "rods must be an integer"),
        (lambda: random_gas(10, seed=0, packing_fraction=1.2), "packing_fraction"),
        (lambda: FixedRestitution(1.5), r"restitution must lie in \[0, 1\]"),
        (lambda: GasSimulation(random_gas(10, seed=0), FixedRestitution(0.9), damping=-1.0), "tau_diss"),
        (lambda: GasSimulation(random_gas(10, seed=0, lengths=UniformLengths(0.1, 1.0)), VibrationTable(TABLE)),
         "table covers gamma"),
        (lambda: GasSimulation(random_gas(10, seed=0), FixedRestitution(0.9)).run(0), "collisions"),
        (lambda: GasSimulation(random_gas(10, seed=0), FixedRestitution(0.9), record_every=1).run(10**8),
         "record_every must be >= collisions"),
        (lambda: RodGas([1, 1], [0.0, 0.5], [0, 0], [0, 0], 10.0), "not overlapping"),
    ],
)
def test_invalid_input_is_refused_with_a_named_option(call, message):
    with pytest.raises(InvalidParameterError, match=message):
        call()


# ----------------------------------------------------------------------------- physics


def _three_rods(restitution, middle, speed_right):
    gas = RodGas([0.01] * 3, [497.0, 500.0 + middle, 503.0], [1.0, 0.0, -speed_right], [0, 0, 0], 1000.0)
    # no energy floor: each collision here removes ~99% of the pair's energy, so even the finite
    # sequences above the threshold end far below 1e-20 of the initial energy
    return GasSimulation(gas, FixedRestitution(restitution), record_every=10**6, energy_floor=0.0).run(
        10**5, max_time=100.0)


@pytest.mark.parametrize("seed", range(4))
def test_three_rods_collapse_exactly_below_mcnamara_youngs_threshold(seed):
    critical = 7 - 4 * math.sqrt(3)  # 0.0718
    rng = np.random.default_rng(np.random.SeedSequence(seed))
    middle, speed = rng.uniform(-0.5, 0.5), rng.uniform(0.5, 1.5)
    assert _three_rods(0.9 * critical, middle, speed).collapsed
    above = _three_rods(1.05 * critical, middle, speed)
    assert not above.collapsed and above.collisions < 100  # the sequence ends after finitely many


@pytest.mark.parametrize("restitution", [0.8, 0.9])
def test_n_rods_collapse_above_the_critical_number_and_cool_below(restitution):
    critical = -math.log(1 - restitution) / (1 - restitution)  # McNamara & Young: about 8 and 23
    for seed in range(4):
        for factor, collapses in ((0.5, False), (1.5, False), (5.0, True)):
            n = int(factor * critical) + 1
            gas = random_gas(n, seed=seed, lengths=EqualLengths(0.01), packing_fraction=0.01)
            result = GasSimulation(gas, FixedRestitution(restitution), seed=seed, record_every=10**6,
                                   max_frames=0).run(10**6)
            # below: homogeneous cooling until the energy floor (1e-20), never a collapse
            assert result.status == ("collapsed" if collapses else "cooled"), (n, seed, result.message)


def test_haff_law_in_a_homogeneous_fixed_restitution_gas():
    restitution, rods, length = 0.98, 50, 0.01  # 50 rods: a quarter of the critical number (196)
    exponents, times = [], []
    for seed in range(6):
        gas = random_gas(rods, seed=seed, lengths=EqualLengths(length), packing_fraction=0.01)
        temperature = 2 * gas.kinetic_energy() / rods
        density = rods / gas.free_length
        # kinetic theory of point particles in the free length (molecular chaos):
        # dT/dt = -2 (1 - r^2) n T^1.5 / sqrt(pi m)  =>  T = T0 / (1 + t/t0)^2
        t0 = math.sqrt(math.pi * length) / ((1 - restitution**2) * density * math.sqrt(temperature))
        result = GasSimulation(gas, FixedRestitution(restitution), seed=seed, record_every=rods // 2,
                               max_frames=0).run(100 * rods)
        t = result.history["time"] / t0
        ratio = 2 * result.history["kinetic_energy"] / rods / temperature
        keep = t > 0
        (a, c), _ = curve_fit(lambda s, a, c: -a * np.log1p(s / c), t[keep], np.log(ratio[keep]), p0=(2.0, 1.0))
        exponents.append(a)
        times.append(c)
    sem_a = np.std(exponents, ddof=1) / math.sqrt(len(exponents))
    sem_t = np.std(times, ddof=1) / math.sqrt(len(times))
    assert abs(np.mean(exponents) - 2.0) < 0.1 + 3 * sem_a
    assert abs(np.mean(times) - 1.0) < 0.1 + 3 * sem_t


def test_vibration_rule_avoids_the_collapse_of_the_fixed_rule_with_the_same_mean_restitution():
    rods = 300
    for seed in range(3):
        gas = random_gas(rods, seed=seed, lengths=UniformLengths(0.6, 1.0), packing_fraction=0.2)
        vibrating = GasSimulation(gas, VibrationTable(TABLE), seed=seed, record_every=rods, max_frames=0)
        gamma = vibrating.pair_gamma
        # what the vibration rule gives on average at the start (cold baths): here eps = gamma
        restitution = float(np.mean(TABLE.mean_restitution(gamma, np.zeros_like(gamma))))
        assert 0.75 < restitution < 0.9
        fixed = GasSimulation(gas, FixedRestitution(restitution), seed=seed, record_every=rods, max_frames=0)
        # the fixed rule's collapse (a cluster whose collisions diverge at the clock's rounding) comes after
        # 62,000 to 180,000 collisions here; the vibration rule runs as long
        assert fixed.run(1000 * rods).collapsed
        result = vibrating.run(1000 * rods)
        assert result.status == "completed", result.message
        assert result.final_energy > 1e-3 * result.history["kinetic_energy"][0]


@pytest.mark.slow  # ~20 s: 18,000 collisions through Python; test_a_solve_per_collision_rule... covers the path fast
def test_per_collision_draws_agree_statistically_with_the_table_kernel():
    """The solve-per-collision path, drawing from the same table in Python with its own seed per
    collision, gives the same energy statistics as the in-kernel table rule (independent streams)."""

    def draw(gamma, temperature_ratio, seed):
        ratio = min(temperature_ratio, TABLE.temperature_ratio[-1])
        u = np.random.default_rng(seed).random()
        return float(TABLE.quantile(gamma, ratio, u)), float(TABLE.share(gamma, ratio))

    finals = {"table": [], "solve": []}
    for seed in range(6):
        gas = random_gas(60, seed=100 + seed, lengths=UniformLengths(0.6, 1.0), bath_temperature=0.02)
        for name, rule in (("table", VibrationTable(TABLE)), ("solve", VibrationSolve(draw, TABLE.bath_modes))):
            result = GasSimulation(gas, rule, seed=seed, record_every=500, max_frames=0).run(3000)
            # translational share of the total energy, averaged over the second half of the run
            h = result.history
            share = h["kinetic_energy"] / (h["kinetic_energy"] + h["bath_energy"])
            finals[name].append(np.mean(share[share.size // 2:]))
    a, b = np.array(finals["table"]), np.array(finals["solve"])
    spread = math.sqrt(np.var(a, ddof=1) / a.size + np.var(b, ddof=1) / b.size)
    assert abs(a.mean() - b.mean()) < 4 * spread + 1e-3


# ----------------------------------------------------------------------------
# Long runs through the run controller (issue 23 item 4)
# ----------------------------------------------------------------------------

_SIGNALLED_RUN = """
import sys
from wavecontact.gas import FixedRestitution, GasSimulation, random_gas
from wavecontact.gas.simulation import run_gas

def new():
    return GasSimulation(random_gas(60, seed=3), FixedRestitution(0.999), seed=4, record_every=500)

print("started", flush=True)
run_gas(new, 10**9, sys.argv[1], checkpoint_every=2000, checkpoint_seconds=None,
        log=lambda m: print(m, file=sys.stderr, flush=True))
"""


@pytest.mark.parametrize("name", ["SIGINT", "SIGTERM"])
def test_a_signalled_gas_process_leaves_a_checkpoint_that_resumes_bit_for_bit(tmp_path, name):
    import os
    import signal
    import subprocess
    import sys
    import time

    from wavecontact.gas.simulation import CHECKPOINT_NAME

    out = tmp_path / "run"
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path))
    process = subprocess.Popen([sys.executable, "-c", _SIGNALLED_RUN, str(out)], env=env, stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 300
        while not (out / CHECKPOINT_NAME).exists():  # the first cadence checkpoint: the loop is running
            assert process.poll() is None and time.monotonic() < deadline
            time.sleep(0.05)
        process.send_signal(getattr(signal, name))
        _stdout, stderr = process.communicate(timeout=120)
    finally:
        process.kill()
    assert process.returncode != 0
    assert "interrupted; the checkpoint holds collision" in stderr
    sim, segment = GasSimulation.resume(out / CHECKPOINT_NAME, with_segment=True)
    assert segment == (0, 10**9, False) and sim.collisions > 0 and sim.collisions % 500 == 0
    straight = GasSimulation(random_gas(60, seed=3), FixedRestitution(0.999), seed=4, record_every=500)
    straight.run(sim.collisions)
    for key, value in _state(straight).items():
        np.testing.assert_array_equal(value, getattr(sim, key), err_msg=key)
    assert not (out / ".wavecontact.lock").exists()


def test_a_solve_rule_run_seeded_by_a_spawned_sequence_resumes_bit_for_bit(tmp_path):
    """The per-collision seeds after a resume are those of the uninterrupted run even when the run's seed is a
    spawned child (the command line's is): the checkpoint keeps the seed's spawn key, not only its entropy."""

    def draw(gamma, temperature_ratio, seed):
        return float(np.random.default_rng(seed).uniform(0.7, 0.95)) ** 2, 0.4

    rule = VibrationSolve(draw, bath_modes=10)
    gas = random_gas(60, seed=2, lengths=UniformLengths(0.5, 1.0))
    def seed():  # a fresh object each time: spawning from a SeedSequence changes it
        return np.random.SeedSequence(5).spawn(2)[1]

    straight = GasSimulation(gas, rule, seed=seed(), record_every=50)
    straight.run(400)
    first = GasSimulation(gas, rule, seed=seed(), record_every=50)
    first.run(200)
    resumed = GasSimulation.resume(first.save_checkpoint(tmp_path / "gas.npz"), rule=rule)
    resumed.run(200)
    for name, value in _state(straight).items():
        np.testing.assert_array_equal(value, getattr(resumed, name), err_msg=name)


def test_stopping_rules_as_one_object_or_as_keywords_are_the_same_run():
    """``stopping=StoppingRules(...)`` and the same fields as keywords give the same simulation (its stored
    parameters) and the same history; a rule given both ways, an unknown keyword and a bad value are refused."""
    gas = random_gas(12, seed=3, packing_fraction=0.3)
    rule = FixedRestitution(0.5)
    whole = GasSimulation(gas, rule, seed=1, stopping=StoppingRules(collapse_window=8, energy_floor=0.0,
                                                                    collapse_gap=1e-5))
    flat = GasSimulation(gas, rule, seed=1, collapse_window=8, energy_floor=0.0, collapse_gap=1e-5)
    default = GasSimulation(gas, rule, seed=1)
    assert whole._parameters() == flat._parameters() != default._parameters()
    assert whole.stopping == flat.stopping == StoppingRules(8, 1e-3, 0.0, 1e-5, False)
    a, b = whole.run(400), flat.run(400)
    assert a.status == b.status and a.collisions == b.collisions
    np.testing.assert_array_equal(whole.v, flat.v)
    with pytest.raises(InvalidParameterError, match="energy_floor: give it in stopping=StoppingRules"):
        GasSimulation(gas, rule, stopping=StoppingRules(), energy_floor=0.0)
    with pytest.raises(TypeError, match="unexpected keyword argument 'collapse_windows'"):
        GasSimulation(gas, rule, collapse_windows=8)
    with pytest.raises(InvalidParameterError, match="collapse_window must be a power of two"):
        StoppingRules(collapse_window=12)
    with pytest.raises(InvalidParameterError, match="energy_floor must lie in"):
        GasSimulation(gas, rule, energy_floor=1.5)


def test_every_rule_calls_the_event_loop_with_the_same_argument_types(monkeypatch):
    """One compilation of the event loop serves every hard-core rule: numba specialises on array flags
    (read-only or not) and layout, so rules whose tables differ only in those would each compile the whole
    loop again.  The soft law (a contact stiffness) is the one other specialisation: its ``soft`` argument is
    the soft law's arrays where the others pass None, so that they do not compile its draw."""
    numba = pytest.importorskip("numba")
    from wavecontact.gas import VibrationLaw, default_law, default_soft_law, kernels

    seen = {}
    original = kernels.run_events

    def recording(*args):
        seen.setdefault(current, set()).add(tuple(str(numba.typeof(a)) for a in args))
        return original(*args)

    monkeypatch.setattr(kernels, "run_events", recording)
    rules = {"fixed": (FixedRestitution(0.9), None), "table": (VibrationTable(TABLE), None),
             "law": (VibrationLaw(default_law()), None),
             "soft law": (VibrationLaw(default_law(), default_soft_law()), 50.0)}
    for current, (rule, stiffness) in rules.items():
        gas = random_gas(20, seed=3, bath_temperature=0.1)
        GasSimulation(gas, rule, seed=1, contact_stiffness=stiffness, record_every=50).run(50)
    assert set(seen) == set(rules)
    assert all(len(types) == 1 for types in seen.values()), seen
    hard_core = set().union(*(seen[name] for name in ("fixed", "table", "law")))
    assert len(hard_core) == 1, {name: sorted(types) for name, types in seen.items()}
    (hard,), (soft,) = hard_core, seen["soft law"]
    assert [a for a, b in zip(hard, soft) if a != b] == ["none"]  # the soft law differs in its `soft` argument only
