"""Gas kernels: the indexed heap, collision-time prediction, and the in-kernel table draw."""

import math

import numpy as np
import pytest

from wavecontact.gas import kernels, thermal_kick_table


def _heap_of(keys):
    heap = np.empty(keys.size, np.int64)
    times = np.empty(keys.size)
    slot = np.empty(keys.size, np.int64)
    kernels.build_heap(keys, heap, times, slot)
    return heap, times, slot


@pytest.mark.parametrize("jit", [True, False])
def test_heap_top_is_the_earliest_event_after_any_rekeying(jit):
    rekey = kernels._rekey if jit else kernels._rekey.py_func
    rng = np.random.default_rng(np.random.SeedSequence(4))
    keys = rng.exponential(size=257)
    keys[::17] = math.inf
    keys[5] = keys[9]  # a tie: the lower event index wins
    heap, times, slot = _heap_of(keys.copy())
    reference = keys.copy()
    for step in range(3000):
        assert heap[0] == min(range(reference.size), key=lambda k: (reference[k], k))
        assert np.array_equal(heap[slot], np.arange(reference.size))
        assert np.array_equal(times, reference[heap])
        k = int(rng.integers(reference.size))
        new = math.inf if step % 7 == 0 else float(rng.exponential())
        reference[k] = new
        rekey(heap, times, slot, k, new)


def test_collision_times_on_a_ring_and_against_walls():
    x = np.array([1.0, 3.0, 9.0])
    v = np.array([1.0, -1.0, 0.5])
    clock = np.zeros(3)
    reach = np.array([0.5, 0.5, 0.5])  # rods of length 0.5
    ring = 10.0
    assert kernels.event_time(0, 0.0, x, v, clock, reach, True, ring) == pytest.approx(0.75)  # gap 1.5, speed 2
    assert kernels.event_time(1, 0.0, x, v, clock, reach, True, ring) == math.inf  # separating
    assert kernels.event_time(2, 0.0, x, v, clock, reach, True, ring) == math.inf  # v2 = 0.5 < v0 = 1
    # walls: events 0 (left wall), 1..2 (pairs), 3 (right wall); box of length 10
    wall_reach = np.array([0.25, 0.5, 0.5, 0.25])
    v_walls = np.array([-2.0, 0.0, 1.0])
    assert kernels.event_time(0, 0.0, x, v_walls, clock, wall_reach, False, ring) == pytest.approx(0.375)
    assert kernels.event_time(3, 0.0, x, v_walls, clock, wall_reach, False, ring) == pytest.approx(0.75)
    # rods advanced lazily: the prediction from a later 'now' is the same event
    clock_later = np.array([0.0, 0.0, 0.0])
    assert kernels.event_time(0, 0.5, x, v, clock_later, reach, True, ring) == pytest.approx(0.75)


def test_kernel_draw_matches_the_table_quantile_function():
    table = thermal_kick_table(levels=101)
    ratio, probability, quantiles, share = table.arrays()[1:]
    rng = np.random.default_rng(np.random.SeedSequence(8))
    counters = np.zeros(4, np.int64)
    for _ in range(300):
        g = rng.uniform(table.gamma[0], table.gamma[-1])
        r = float(np.exp(rng.uniform(np.log(1e-3), np.log(1e3))))
        u = rng.random()
        ig = min(np.searchsorted(table.gamma, g, side="right") - 1, table.gamma.size - 2)
        wg = (g - table.gamma[ig]) / (table.gamma[ig + 1] - table.gamma[ig])
        ir, wr = kernels._lookup(ratio, r, counters)
        eps2, s = kernels._table_draw(u, ig, wg, ir, wr, probability, True, quantiles, share)
        assert eps2 == pytest.approx(float(table.quantile(g, r, u)), rel=1e-12, abs=1e-14)
        assert s == pytest.approx(table.share(g, r), rel=1e-12)
    assert counters[kernels.RATIO_CLAMPED] == 0
    kernels._lookup(ratio, 2e3, counters)
    assert counters[kernels.RATIO_CLAMPED] == 1


def test_pure_python_path_gives_the_same_run_bit_for_bit(tmp_path):
    """WAVECONTACT_PURE_PYTHON=1 (no numba) in a separate process reproduces the compiled run exactly."""
    import os
    import subprocess
    import sys

    script = (
        "import numpy as np, sys\n"
        "from wavecontact.gas import GasSimulation, VibrationTable, random_gas, thermal_kick_table\n"
        "sim = GasSimulation(random_gas(30, seed=1), VibrationTable(thermal_kick_table(levels=51)), seed=2,"
        " damping=5.0, record_every=100)\n"
        "sim.run(300)\n"
        "np.savez(sys.argv[1], v=sim.v, x=sim.x, t=sim.temperature, time=sim.time)\n"
    )
    outputs = []
    for pure in ("1", "0"):
        path = tmp_path / f"run{pure}.npz"
        env = dict(os.environ, WAVECONTACT_PURE_PYTHON=pure)
        subprocess.run([sys.executable, "-c", script, str(path)], check=True, env=env, timeout=600)
        with np.load(path) as data:
            outputs.append({k: data[k] for k in data.files})
    for name in outputs[0]:
        np.testing.assert_array_equal(outputs[0][name], outputs[1][name], err_msg=name)
