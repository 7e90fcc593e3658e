"""The collapse detector: a cluster of touching rods whose collisions diverge at the clock's rounding.

The fixed-restitution cells on both sides of McNamara & Young's threshold (equal rods, the set-up of
docs/gas_results.md section 2) and damped vibration-law runs that go on to millions of collisions.
Every verdict is checked against a contact criterion computed here from the final state with numpy
(gaps, cluster, collision times), not by the kernel's own cluster search.
"""

import json
import math

import numpy as np
import pytest

from wavecontact.cli import main
from wavecontact.gas import (
    EqualLengths,
    FixedRestitution,
    GasSimulation,
    UniformLengths,
    VibrationLaw,
    default_law,
    kernels,
    random_gas,
)

ROOT = 20261206  # one root seed for every cell: realisation i of cell (r, N) is SeedSequence([ROOT, N, 100 r]).spawn(12)[i]
CELLS = [(0.8, 24, False), (0.8, 32, True), (0.9, 46, False), (0.9, 69, True), (0.95, 60, False), (0.95, 120, True)]


def _gaps(sim):
    """Gaps of every neighbour pair (ring) at the simulation's time, in units of the mean free spacing."""
    t = sim.time
    x = sim.x + sim.v * (t - sim.local_time)
    following = np.roll(x, -1)
    following[-1] += sim.gas.system_length
    return (following - x - sim.reach) / (sim.gas.free_length / x.size)


def _cell_gas(restitution, rods, realisation):
    seed = np.random.SeedSequence([ROOT, rods, round(100 * restitution)]).spawn(12)[realisation]
    return random_gas(rods, seed=seed, lengths=EqualLengths(0.01), packing_fraction=0.01), seed


def _cell(restitution, rods, realisation, collisions=4_000_000, record_every=10**7, **options):
    gas, seed = _cell_gas(restitution, rods, realisation)
    sim = GasSimulation(gas, FixedRestitution(restitution), seed=seed, record_every=record_every, max_frames=0,
                        energy_floor=0.0, **options)
    return sim, sim.run(collisions)


def _time_after(restitution, rods, realisation, collisions):
    """The clock after ``collisions`` collisions of a fresh run of the same cell (stopped there by the count)."""
    sim, result = _cell(restitution, rods, realisation, collisions)
    assert result.collisions == collisions
    return sim.time


def _check_verdict(restitution, rods, realisation, sim, result):
    """A collapse has, by an independent reading of the final state, a cluster of >= 3 rods whose gaps lie below
    1e-6 of the mean free spacing and no such gap beside it, and the clock 16 collisions earlier (a second run
    stopped there) within 4 ulps of the clock at the collapse; a frozen gas has velocities or positions at their
    rounding."""
    if result.collapsed:
        gaps = _gaps(sim)
        close = np.abs(gaps) < 1e-6
        info = result.collapse
        first, last = info["first_rod"], info["last_rod"]
        members = (last - first) % sim.gas.rods + 1
        assert members == info["cluster_rods"] >= 3
        assert all(close[(first + m) % sim.gas.rods] for m in range(members - 1))  # every gap inside the cluster
        assert not close[(first - 1) % sim.gas.rods] and not close[last % sim.gas.rods]  # and none beside it
        if sim.event_times.min() < math.inf:  # (else the cluster's velocities rounded to equal first)
            earlier = _time_after(restitution, rods, realisation, result.collisions - 15)
            assert result.simulated_time - earlier <= 2.0**-50 * result.simulated_time
    elif result.status == "frozen":
        t = sim.time
        x = sim.x + sim.v * (t - sim.local_time)
        spacing = sim.gas.free_length / sim.gas.rods
        drifted = np.max(np.abs(x)) * 2.0**-48 >= 1e-6 * spacing
        rounded = np.min(np.abs(np.diff(sim.v))) <= 2.0**-50 * np.max(np.abs(sim.v))
        assert drifted or rounded, result.message
    else:
        raise AssertionError(f"a fixed-restitution cell ends collapsed or frozen with no energy floor: {result.message}")


@pytest.mark.parametrize("restitution, rods, collapses", [CELLS[0], CELLS[1]])
def test_fixed_restitution_cells_either_side_of_the_threshold(restitution, rods, collapses):
    """r = 0.8 at N = 24 (3 N_c) and 32 (4 N_c), 12 realisations each, run until collapse or numerical freeze."""
    verdicts = []
    for realisation in range(12):
        sim, result = _cell(restitution, rods, realisation)
        _check_verdict(restitution, rods, realisation, sim, result)
        verdicts.append(result.collapsed)
    assert sum(verdicts) >= 11 if collapses else sum(verdicts) == 0, verdicts


@pytest.mark.slow  # ~10 s: the six cells, 72 runs up to 2.4 million collisions each
@pytest.mark.parametrize("restitution, rods, collapses", CELLS)
def test_all_six_cells_of_the_mcnamara_young_threshold(restitution, rods, collapses):
    test_fixed_restitution_cells_either_side_of_the_threshold(restitution, rods, collapses)


def _state_with_gaps(gaps, lengths, ring):
    """Centres, reach and box length of rods at rest whose events have the given gaps (a box: N + 1 of them)."""
    rods = lengths.size
    if ring:
        reach = 0.5 * (lengths + np.roll(lengths, -1))
        x = 0.5 * lengths[0] + np.concatenate([[0.0], np.cumsum(reach[:-1] + gaps[:-1])])
        box = x[-1] + reach[-1] + gaps[-1] - x[0]
    else:
        reach = np.concatenate([[0.5 * lengths[0]], 0.5 * (lengths[1:] + lengths[:-1]), [0.5 * lengths[-1]]])
        x = np.cumsum(reach[:rods] + gaps[:rods])
        box = x[-1] + reach[rods] + gaps[rods]
    return x, reach, box


def _runs(close, ring):
    """Independent reading: the maximal runs of True (cyclic on a ring) as lists of indices."""
    count = len(close)
    if ring and all(close):
        return [list(range(count))]
    start = next((e for e in range(count) if not close[e]), 0) if ring else -1
    runs, current = [], []
    for m in range(1, count + 1):
        e = (start + m) % count if ring else m - 1
        if close[e]:
            current.append(e)
        elif current:
            runs.append(current)
            current = []
    if current:
        runs.append(current)
    return runs


def test_collapse_cluster_matches_an_independent_reading_of_the_gaps():
    rng = np.random.default_rng(7)
    floor = 1e-6
    for ring in (True, False):
        for _ in range(40):
            rods = int(rng.integers(2, 10))
            lengths = rng.uniform(0.5, 1.0, rods)
            count = rods if ring else rods + 1
            gaps = rng.choice([1e-9, 1e-4, 1.0], size=count, p=[0.6, 0.1, 0.3])  # touching, near, far
            x, reach, box = _state_with_gaps(gaps, lengths, ring)
            v, clock = np.zeros(rods), np.zeros(rods)
            runs = _runs(list(gaps < floor), ring)
            for k in range(count):
                first, last, members = kernels.collapse_cluster(k, 0.0, x, v, clock, reach, ring, box, floor)
                mine = [run for run in runs if k in run]
                if not mine:
                    assert members == 0
                    continue
                run = mine[0]
                if len(run) < count:  # (a ring closed by touching rods has no first event)
                    assert (first, last) == (run[0], run[-1])
                assert members == (rods if ring and len(run) == count else len(run) + 1)
            _, _, largest = kernels.collapse_cluster(-1, 0.0, x, v, clock, reach, ring, box, floor)
            expected = max((rods if ring and len(run) == count else len(run) + 1 for run in runs), default=0)
            assert largest == expected


def test_the_event_loops_cluster_statuses_resolve_as_the_gaps_say():
    """run_events leaves the cluster search of an accelerating run to resolve_cluster: a cluster of three bodies
    or more is a collapse; without one the pair's lost relative velocity (STATUS_CLUSTER_FROZEN) is a frozen gas,
    a run below its energy floor has cooled, and else the run goes on (STATUS_DONE: a false alarm).  A ring whose
    velocities all rounded to equal (STATUS_CLUSTER_MERGED) collapsed if its largest cluster joins three rods
    or more and their positions resolve the gap floor, else froze.  The gaps are set here, not found by the
    kernel."""
    floor = 1e-6
    lengths = np.full(6, 0.5)
    v, clock = np.zeros(6), np.zeros(6)
    collapse = np.array([1e-3, floor, 3.0, 2.0**-50, 2.0**-48, 2.0**-50])
    scalars = np.zeros(8)
    scalars[kernels.KINETIC] = 1.0
    touching = np.array([1e-9, 1e-9, 1.0, 1.0, 1.0, 1.0])  # events 0 and 1: rods 0, 1, 2 touch
    apart = np.array([1e-9, 1.0, 1.0, 1.0, 1.0, 1.0])  # event 0 alone: two rods
    for gaps, event, expected in ((touching, 1, kernels.STATUS_COLLAPSE), (apart, 0, kernels.STATUS_DONE),
                                  (touching, 3, kernels.STATUS_DONE)):
        x, reach, box = _state_with_gaps(gaps, lengths, True)
        resolved = [kernels.resolve_cluster(status, event, x, v, clock, reach, True, box, collapse, scalars)
                    for status in (kernels.STATUS_CLUSTER, kernels.STATUS_CLUSTER_FROZEN)]
        assert resolved[0] == expected
        assert resolved[1] == (kernels.STATUS_COLLAPSE if expected == kernels.STATUS_COLLAPSE else kernels.STATUS_FROZEN)
        cooled = scalars.copy()
        cooled[kernels.ENERGY_FLOOR] = 2.0  # the kinetic energy 1 lies below it
        assert kernels.resolve_cluster(kernels.STATUS_CLUSTER, event, x, v, clock, reach, True, box, collapse,
                                       cooled) == (kernels.STATUS_COLLAPSE if expected == kernels.STATUS_COLLAPSE
                                                   else kernels.STATUS_COOLED)
        merged = kernels.resolve_cluster(kernels.STATUS_CLUSTER_MERGED, -1, x, v, clock, reach, True, box, collapse,
                                         scalars)
        assert merged == (kernels.STATUS_COLLAPSE if gaps is touching else kernels.STATUS_FROZEN)
        # the rods 1e9 further out: the touching gaps still lie below the floor (their rounding is 1.2e-7), but the
        # positions' rounding 1e9 * 2^-48 = 3.6e-6 exceeds it: frozen, not collapsed
        far = x + 1e9
        if gaps is touching:
            assert kernels.collapse_cluster(-1, 0.0, far, v, clock, reach, True, box, floor)[2] == 3
        assert kernels.resolve_cluster(kernels.STATUS_CLUSTER_MERGED, -1, far, v, clock, reach, True, box,
                                       collapse, scalars) == kernels.STATUS_FROZEN
    for status in (kernels.STATUS_DONE, kernels.STATUS_NO_EVENTS, kernels.STATUS_NEED_DRAW):
        assert kernels.resolve_cluster(status, 0, x, v, clock, reach, True, box, collapse, scalars) == status


def test_a_detected_collapse_can_be_continued_and_says_where_it_was():
    _, stopped = _cell(0.8, 32, 0)
    assert stopped.collapsed and "at collision" in stopped.message and "cluster of" in stopped.message
    _, going = _cell(0.8, 32, 0, stopped.collisions + 2000, record_every=1000, continue_after_collapse=True)
    assert going.collapse == stopped.collapse  # the same detection, noted
    assert going.collisions == stopped.collisions + 2000 and going.status == "completed"
    assert f"detected at collision {stopped.collisions}" in going.message
    # up to the detection the two runs are the same, bit for bit
    _, again = _cell(0.8, 32, 0, stopped.collisions, record_every=1000, continue_after_collapse=True)
    assert again.simulated_time == stopped.simulated_time and again.collapse == stopped.collapse


def test_continue_after_collapse_is_checkpointed(tmp_path):
    seed = 5  # (a checkpoint keeps an integer root seed)
    gas = random_gas(32, seed=np.random.SeedSequence([ROOT, 32, 80]).spawn(12)[0], lengths=EqualLengths(0.01),
                     packing_fraction=0.01)
    first = GasSimulation(gas, FixedRestitution(0.8), seed=seed, record_every=1000, max_frames=0, energy_floor=0.0,
                          continue_after_collapse=True)
    first.run(40_000)  # past the detection at collision 33,790
    first.save_checkpoint(tmp_path / "gas.npz")
    resumed = GasSimulation.resume(tmp_path / "gas.npz")
    straight = GasSimulation(gas, FixedRestitution(0.8), seed=seed, record_every=1000, max_frames=0,
                             energy_floor=0.0, continue_after_collapse=True)
    a, b = resumed.run(40_000), straight.run(80_000)
    np.testing.assert_array_equal(resumed.v, straight.v)
    assert a.collapse == b.collapse and a.collapse is not None and a.collapse["collision"] < 40_000


def test_damped_vibration_runs_that_go_on_are_not_collapsed():
    """docs/gas.md section 7, tau_diss = 10, realisation 0 (seeds spawned from 40): the earlier detector (a
    thousandfold acceleration alone, the kernel of commit eab1b34) stopped it at 670,865 collisions; it goes on
    for millions (4,000,000 in the slow test below)."""
    seed = np.random.SeedSequence(40).spawn(6)[0]
    initial, dynamics = seed.spawn(2)
    gas = random_gas(200, seed=initial, lengths=UniformLengths(0.6, 1.0), packing_fraction=0.2)
    sim = GasSimulation(gas, VibrationLaw(default_law()), damping=10.0, seed=dynamics, record_every=10_000,
                        max_frames=0)
    result = sim.run(1_000_000)
    assert result.status == "completed" and result.collapse is None, result.message


@pytest.mark.slow  # ~40 s: the six tau_diss = 10 runs of docs/gas.md section 7 to 4 million collisions
def test_damped_runs_of_section_7_that_reach_four_million_collisions_are_not_collapsed():
    from wavecontact.studies.gas import gas_ensemble

    ensemble = gas_ensemble(6, rods=200, collisions=4_000_000, rule=VibrationLaw(default_law()), seed=40,
                            lengths=UniformLengths(0.6, 1.0), packing_fraction=0.2, damping=10.0,
                            record_every=10_000)
    for result in ensemble.results:
        assert result.status in ("completed", "collapsed"), result.message
        if result.collapsed:  # a collapse has its cluster
            assert result.collapse["cluster_rods"] >= 3
    assert sum(r.status == "completed" for r in ensemble.results) >= 3


def test_cli_continue_after_collapse(capsys):
    argv = ["gas", "--rods", "400", "--collisions", "20000", "--rule", "fixed", "--restitution", "0.6", "--json",
            "--no-progress"]
    assert main(argv) == 0
    stopped = json.loads(capsys.readouterr().out)
    assert stopped["collapsed"] and stopped["collapse"]["collision"] == stopped["collisions"] < 20000
    assert main([*argv, "--continue-after-collapse"]) == 0
    going = json.loads(capsys.readouterr().out)
    assert not going["collapsed"] and going["collisions"] == 20000
    assert going["collapse"] == stopped["collapse"]
