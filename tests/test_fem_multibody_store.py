"""The multi-body loop's store: views made inside compiled kernels, and the layout of every body's arrays."""

import itertools

import numpy as np
import pytest

from wavecontact import Exponential, RigidBody, Rod, Scene
from wavecontact._jit import kernel
from wavecontact.fem import multibody_store as ms
from wavecontact.fem.interleaved_step import L_SHAPE, L_U, L_V
from wavecontact.fem.multibody_setup import build_line_setup, mass_solves


def _scale_parts(store, factor):
    """Scale a 1-D segment, a 2-D block and a whole (borrowed) array of ``store`` through views."""
    part = ms.segment(store, np.int64(3), np.int64(4))
    for i in range(part.size):
        part[i] *= factor
    table = ms.block(store, np.int64(8), np.int64(2), np.int64(3))
    for i in range(table.shape[0]):
        table[i, 2] *= factor
    whole = ms.borrowed(store)
    whole[whole.size - 1] *= factor
    return part.size + 10 * table.shape[0] + 100 * table.shape[1] + 1000 * whole.size


def _scale_parts_python(store, factor):
    part = ms._segment_python(store, 3, 4)
    part *= factor
    table = ms._block_python(store, 8, 2, 3)
    table[:, 2] *= factor
    ms._borrowed_python(store)[-1] *= factor
    return part.size + 10 * table.shape[0] + 100 * table.shape[1] + 1000 * store.size


@pytest.mark.parametrize("function", [kernel(_scale_parts), _scale_parts_python], ids=["compiled", "python"])
def test_views_are_the_store_entries_they_name(function):
    store = np.arange(20.0)
    expected = store.copy()
    expected[3:7] *= 2.0
    expected[8:14].reshape(2, 3)[:, 2] *= 2.0  # entries 10 and 13
    expected[-1] *= 2.0
    assert function(store, 2.0) == 4 + 10 * 2 + 100 * 3 + 1000 * 20
    np.testing.assert_array_equal(store, expected)


def test_store_holds_every_array_at_its_offsets_each_rod_on_a_cache_line():
    scene = Scene(rods=(Rod(1.0), RigidBody(0.5), Rod(0.5)), velocities=(1.0, 0.0, -1.0),
                  contact=Exponential(20.0, 0.01))
    setup = build_line_setup(scene, 200, 1, "consistent")
    solves = mass_solves(setup)
    assert int(solves[0][1][L_SHAPE, 0]) > 0  # the first rod runs in the interleaved layout
    rng = np.random.default_rng(np.random.SeedSequence(7).spawn(1)[0])
    us = [rng.standard_normal(d.n_nodes) for d in setup.rods]
    vs = [rng.standard_normal(d.n_nodes) for d in setup.rods]
    ru, rv = np.array([0.25]), np.array([-0.5])
    store, layout, (rigid_u, rigid_v, zero) = ms.build_store(setup.rods, us, vs, solves, ru, rv)
    assert store.ctypes.data % 64 == 0
    for row, d, u, v, (kind, table) in zip(layout, setup.rods, us, vs, solves):
        n = d.n_nodes
        for column in (ms.G_FLAT_U, ms.G_FLAT_V, ms.G_SCRATCH, ms.G_WEIGHTS, ms.G_BANDS, ms.G_TABLE):
            assert row[column] % 8 == 0
        np.testing.assert_array_equal(store[row[ms.G_FLAT_U]:][:n], u)
        np.testing.assert_array_equal(store[row[ms.G_FLAT_V]:][:n], v)
        np.testing.assert_array_equal(store[row[ms.G_WEIGHTS]:][:n], d.lumped_mass)
        np.testing.assert_array_equal(store[row[ms.G_BANDS]:][:d.stiffness_bands.size].reshape(row[ms.G_BAND_ROWS], n),
                                      d.stiffness_bands)
        rows, cols = row[ms.G_TABLE_ROWS], row[ms.G_TABLE_COLS]
        np.testing.assert_array_equal(store[row[ms.G_TABLE]:][:rows * cols].reshape(rows, cols), table)
        assert row[ms.G_KIND] == kind and row[ms.G_CHUNK_ROWS] == int(table[L_SHAPE, 0])
        if row[ms.G_CHUNK_ROWS]:  # the loop steps the table's rows
            assert (row[ms.G_STEPPED_U], row[ms.G_STEPPED_V], row[ms.G_STEPPED_SIZE]) == (
                row[ms.G_TABLE] + L_U * cols, row[ms.G_TABLE] + L_V * cols, cols)
        else:
            assert (row[ms.G_STEPPED_U], row[ms.G_STEPPED_V], row[ms.G_STEPPED_SIZE]) == (
                row[ms.G_FLAT_U], row[ms.G_FLAT_V], n)
    assert (store[rigid_u], store[rigid_v], store[zero]) == (0.25, -0.5, 0.0)
    # no two arrays overlap
    spans = sorted([(r[c], r[c] + size) for r in layout for c, size in (
        (ms.G_FLAT_U, r[ms.G_NODES]), (ms.G_FLAT_V, r[ms.G_NODES]), (ms.G_SCRATCH, r[ms.G_NODES]),
        (ms.G_WEIGHTS, r[ms.G_NODES]), (ms.G_BANDS, r[ms.G_BAND_ROWS] * r[ms.G_NODES]),
        (ms.G_TABLE, r[ms.G_TABLE_ROWS] * r[ms.G_TABLE_COLS]))] + [(rigid_u, rigid_u + 1), (rigid_v, rigid_v + 1),
                                                                  (zero, zero + 1)])
    assert all(a[1] <= b[0] for a, b in itertools.pairwise(spans)) and spans[-1][1] <= store.size
