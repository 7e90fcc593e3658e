"""Gas kernels: the tournament tree of event times, collision-time prediction, and the in-kernel table draw."""

import math
from pathlib import Path

import numpy as np
import pytest
from analytic_kick_table import analytic_kick_table
from pure_python_runs import pure_and_compiled_outputs

from wavecontact.gas import kernels


def _tree_of(keys):
    times = np.empty(kernels.tree_size(keys.size))
    events = np.empty(times.size, np.int64)
    kernels.build_tree(keys, times, events)
    return times, events


def _assert_every_node_holds_its_earliest_child(times, events):
    """Every node of the four-ary tree holds the earliest of its four children, ties to the leftmost (written
    here as a sort by (time, position), independently of the kernel's selects)."""
    level = times.size // 2
    while level > 1:
        level //= 4
        for p in range(level, 2 * level):
            children = range(4 * p, 4 * p + 4)
            best = min(children, key=lambda c: (times[c], c))
            assert times[p] == times[best] and events[p] == events[best]


@pytest.mark.parametrize("jit", [True, False])
@pytest.mark.parametrize("size", [1, 2, 3, 5, 17, 257, 1100])
def test_tree_root_is_the_earliest_event_after_any_change(jit, size):
    """After re-timing single events, or a neighbour triple (the ring's seam included, and triples straddling
    the tree's blocks of 4 and 16 leaves), the root is the earliest event, ties going to the lower index, and
    every node holds the earliest of its children."""
    pull_range = kernels._pull_range if jit else kernels._pull_range.py_func
    pull_triple = kernels._pull_triple if jit else kernels._pull_triple.py_func
    rng = np.random.default_rng(np.random.SeedSequence([4, size]))
    keys = rng.exponential(size=size)
    keys[::17] = math.inf
    if size > 9:
        keys[5] = keys[9]  # a tie: the lower event index wins
    times, events = _tree_of(keys.copy())
    leaves = times.size // 2
    reference = keys.copy()
    steps = 3000 if size < 1000 else 600
    for step in range(steps):
        earliest = min(range(size), key=lambda k: (reference[k], k))
        assert events[1] == earliest and times[1] == reference[earliest]
        assert np.array_equal(times[leaves:leaves + size], reference)
        if step % 50 == 0 or size < 20:
            _assert_every_node_holds_its_earliest_child(times, events)
        k = int(rng.integers(size))
        changed = [k] if step % 2 else sorted({(k - 1) % size, k, (k + 1) % size})
        for c in changed:
            reference[c] = math.inf if rng.random() < 0.3 else float(rng.exponential())
            if rng.random() < 0.1:
                reference[c] = reference[earliest]  # ties with the current root
            times[leaves + c] = reference[c]
        if len(changed) == 3 and changed == list(range(changed[0], changed[0] + 3)):
            root = pull_triple(times, events, leaves + changed[1])  # the kernel's interior case
            assert root == (times[1], events[1])
        elif changed == list(range(changed[0], changed[-1] + 1)):
            pull_range(times, events, changed[0], changed[-1])
        else:
            for c in changed:
                pull_range(times, events, c, c)
    _assert_every_node_holds_its_earliest_child(times, events)


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
    table = analytic_kick_table(levels=101)
    ratio, probability, quantiles, share = table.arrays()[1:]
    rng = np.random.default_rng(np.random.SeedSequence(8))
    for _ in range(300):
        g = rng.uniform(table.gamma[0], table.gamma[-1])
        r = float(np.exp(rng.uniform(np.log(1e-3), np.log(1e3))))
        u = rng.random()
        ig = min(np.searchsorted(table.gamma, g, side="right") - 1, table.gamma.size - 2)
        wg = (g - table.gamma[ig]) / (table.gamma[ig + 1] - table.gamma[ig])
        ir, wr = kernels._lookup(ratio, r)
        eps2, s = kernels._table_draw(u, ig, wg, ir, wr, 0, 0.0, probability, True, quantiles[:, :, None, :],
                                      share[:, :, None, None], False)
        assert eps2 == pytest.approx(float(table.quantile(g, r, u)), rel=1e-12, abs=1e-14)
        assert s == pytest.approx(table.share(g, r), rel=1e-12)
    assert kernels._lookup(ratio, 2 * ratio[-1])[0] == -1  # beyond the grid: refused, never clipped
    assert kernels._lookup(ratio[1:], 0.5 * ratio[1])[0] == -1  # below a grid that starts above 0


def test_pure_python_path_gives_the_same_run_bit_for_bit(tmp_path):
    """WAVECONTACT_PURE_PYTHON=1 (no numba) in a separate process reproduces the compiled runs exactly (a ring
    with the table rule and damping, a box with walls and the fixed rule)."""

    script = (
        "import numpy as np, sys\n"
        "sys.path.insert(0, sys.argv[2])\n"
        "from analytic_kick_table import analytic_kick_table\n"
        "from wavecontact.gas import GasSimulation, VibrationTable, random_gas\n"
        "sim = GasSimulation(random_gas(30, seed=1), VibrationTable(analytic_kick_table(levels=51)), seed=2,"
        " damping=5.0, record_every=100)\n"
        "sim.run(300)\n"
        "from wavecontact.gas import FixedRestitution\n"
        "walls = GasSimulation(random_gas(20, seed=3, boundary='walls'), FixedRestitution(0.9), seed=0,"
        " record_every=50)\n"
        "walls.run(300)\n"
        "np.savez(sys.argv[1], v=sim.v, x=sim.x, t=sim.temperature, time=sim.time, walls_v=walls.v,"
        " walls_x=walls.x, walls_time=walls.time, walls_hits=walls.counters)\n"
    )
    outputs = pure_and_compiled_outputs(script, tmp_path, Path(__file__).parent)
    for name in outputs[0]:
        np.testing.assert_array_equal(outputs[0][name], outputs[1][name], err_msg=name)


@pytest.mark.parametrize("jit", [True, False])
def test_branch_free_bracket_agrees_with_searchsorted(jit):
    """The select-based binary search finds the grid interval np.searchsorted finds (grid points, edges, outside)."""
    bracket = kernels._bracket if jit else kernels._bracket.py_func
    rng = np.random.default_rng(np.random.SeedSequence(11))
    for size in (2, 3, 5, 32, 201):
        grid = np.cumsum(rng.exponential(size=size))
        values = np.concatenate([grid, rng.uniform(grid[0] - 1.0, grid[-1] + 1.0, 200), [grid[0] - 5.0]])
        for value in values:
            expected = int(np.clip(np.searchsorted(grid, value, side="right") - 1, 0, size - 2))
            assert bracket(grid, value) == expected
