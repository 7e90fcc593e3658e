"""The interleaved layout of large consistent masses (fem/interleaved_step.py): layout, solve, time loop."""

import numpy as np
import pytest
from scipy.linalg import solve_banded
from test_fem_explicit_step import (
    _banded_mass,
    _graded_nodes,
    assert_steps_equal_a_banded_solve,
    highest_eigenvalue,
)

import wavecontact
from wavecontact import Rod
from wavecontact.fem import interleaved_step
from wavecontact.fem.discretization import discretize_rod, matched_nodes
from wavecontact.fem.explicit_step import T_CHAIN_INVERSE, prepare_mass, step_rod
from wavecontact.fem.interleaved_step import (
    L_SHAPE,
    LANES,
    ORIGIN,
    lanes_width,
    midpoint_origin,
    node_position,
    pack_nodes,
    table_width,
    unpack_nodes,
)
from wavecontact.fem.simulation import _Run, build_setup, run_collision


@pytest.mark.parametrize("order", [1, 2])
@pytest.mark.parametrize("elements", [63, 64, 100, 1301])
def test_packing_places_every_node_where_node_position_says(order, elements):
    nodes = order * elements + 1
    unknowns = elements + 1  # P1 nodes, or P2 vertices
    rows = -(-unknowns // LANES)
    x = np.arange(nodes, dtype=float) + 1.0
    packed = np.zeros(order * lanes_width(unknowns))
    pack_nodes(x, packed, rows, order)
    for node in range(nodes):
        assert packed[node_position(node, rows, order)] == x[node]
    assert np.count_nonzero(packed) == nodes  # the ghost rows and the padding stay zero
    assert np.all(packed[:ORIGIN] == 0.0) and np.all(packed[ORIGIN + rows * LANES : ORIGIN + (rows + 1) * LANES] == 0)
    back = np.zeros(nodes)
    unpack_nodes(packed, back, rows, order)
    np.testing.assert_array_equal(back, x)


@pytest.mark.parametrize("order", [1, 2])
def test_interleaved_tables_start_every_row_on_a_cache_line(order):
    disc = discretize_rod(Rod(1.0), np.linspace(0.0, 1.0, 1500), order, "consistent")
    _, table = prepare_mass(disc)
    assert table[L_SHAPE, 0] > 0
    assert table.ctypes.data % 64 == 0 and table.strides[0] % 64 == 0 and table.flags.c_contiguous
    with pytest.raises(ValueError, match="multiple of 8"):
        interleaved_step.aligned_table(2, 12)


def test_table_rows_do_not_start_a_multiple_of_4_kib_apart():
    for minimum in (10, 1000, 10752, 43008):
        width = table_width(minimum)
        assert width >= minimum and (width * 8) % 4096 == 192


@pytest.mark.parametrize("order", [1, 2])
@pytest.mark.parametrize("rows_per_chunk", [2, 11])  # fewer rows than the corrections span
def test_short_chunks_equal_a_reference_step_with_a_banded_solve(monkeypatch, order, rows_per_chunk):
    """Chunks shorter than the rows their neighbour's correction reaches (the corrections then cross whole
    chunks): 400 steps near the stability limit against a step with LAPACK's banded solver."""
    monkeypatch.setattr(interleaved_step, "LANE_MIN_UNKNOWNS", 0)
    monkeypatch.setattr(interleaved_step, "LANE_MIN_VERTICES", 0)
    elements = rows_per_chunk * LANES - 1
    rng = np.random.default_rng(elements + order)
    disc = discretize_rod(Rod(1.1, 2.0, 3.0, 0.5), _graded_nodes(rng, elements, 1.1, 3.0), order, "consistent")
    kind, table = prepare_mass(disc)
    rows, forward_rows, backward_rows = table[L_SHAPE, :3]
    assert rows == rows_per_chunk <= min(forward_rows, backward_rows)  # every row of a chunk is corrected
    assert table[L_SHAPE, 3] == table[L_SHAPE, 4] == 1.0  # the chunks' boundary values chained (sequential)
    assert_steps_equal_a_banded_solve(disc, kind, table, rng)


@pytest.mark.parametrize("order", [1, 2])
def test_collision_in_the_interleaved_layout_equals_the_flat_one_to_rounding(monkeypatch, order):
    """A whole collision (contact on the packed ends, energy checks on the unpacked state) in both layouts."""
    scene = wavecontact.two_rods(0.6, 100)
    results = []
    for threshold in (10**9, 0):
        monkeypatch.setattr(interleaved_step, "LANE_MIN_UNKNOWNS", threshold)
        monkeypatch.setattr(interleaved_step, "LANE_MIN_VERTICES", threshold)
        setup = build_setup(scene, elements=300, order=order, mass="consistent")
        run = _Run(setup, 0.05)
        assert [int(table[L_SHAPE, 0]) > 0 for _, table in run.mass_solves] == [threshold == 0] * 2
        results.append(run_collision(setup))
    flat, packed = results
    assert flat["steps"] == packed["steps"]
    scale = np.abs(flat["contact_force"]).max()
    np.testing.assert_allclose(packed["contact_force"], flat["contact_force"], rtol=0, atol=1e-11 * scale)
    np.testing.assert_allclose(packed["relative_velocity"], flat["relative_velocity"], rtol=0, atol=1e-12)
    for name in ("kinetic", "strain"):  # the packed rods take the force scheme's contact force in their mass
        # solve, the flat ones along the column M^-1 e_end: the velocities (order 1) round differently, which
        # the first checks' energies of 1e-25 .. 1e-11 (first contact) show relative to the peak, not to themselves
        np.testing.assert_allclose(packed[name], flat[name], rtol=1e-11, atol=1e-16 * np.abs(flat[name]).max())
    for flat_u, packed_u in zip(flat["run"].u, packed["run"].u):  # the final fields, unpacked
        np.testing.assert_allclose(packed_u, flat_u, rtol=0, atol=1e-11 * np.abs(flat_u).max())
    momentum = packed["run"].momentum()
    assert abs(momentum - packed["run"].momentum0) <= 1e-12 * packed["run"].momentum_scale


def _last_chunk_rows(table, unknowns):
    """Rows of the last chunk that hold unknowns (the rest is padding)."""
    return unknowns - (LANES - 1) * int(table[L_SHAPE, 0])


def _uniform_rows(table):
    lo, hi = table[interleaved_step.L_UNIFORM, :2]
    return int(lo), int(hi)


@pytest.mark.parametrize("order", [1, 2])
def test_uniform_rows_cover_a_uniform_mesh_between_its_ends_and_nothing_of_a_graded_one(order):
    """Equal elements (rounded node coordinates): every row but a few dozen at the ends runs with constants;
    a mesh graded by at most 1 % from one element to the next: none."""
    elements = 3000
    disc = discretize_rod(Rod(1.1, 2.0, 3.0, 0.5), np.linspace(0.0, 1.1, elements + 1), order, "consistent")
    _, table = prepare_mass(disc)
    rows = int(table[L_SHAPE, 0])
    lo, hi = _uniform_rows(table)
    # the factorization's factors converge like 0.27^i (P1) from the rod's start; the far end's rows differ,
    # and so do the rows where the last chunk has only padding
    assert 1 <= lo <= 16 and _last_chunk_rows(table, elements + 1) - 16 <= hi <= rows - 1
    rng = np.random.default_rng(order)
    graded = discretize_rod(Rod(1.1, 2.0, 3.0, 0.5), _graded_nodes(rng, elements, 1.1, 1.01), order, "consistent")
    _, table = prepare_mass(graded)
    lo, hi = _uniform_rows(table)
    assert lo == hi
    assert table[L_SHAPE, 0] == -(-(elements + 1) // LANES)  # nothing held: the fewest rows per chunk


@pytest.mark.parametrize("order", [1, 2])
def test_uniform_rows_run_with_constants_as_the_arrays_would(order):
    """The step with the uniform rows' constants equals, bit for bit, the step reading the same (held)
    values from the table's arrays (the uniform run switched off after the set-up)."""
    disc = discretize_rod(Rod(1.1, 2.0, 3.0, 0.5), np.linspace(0.0, 1.1, 2534), order, "consistent")
    kind, table = prepare_mass(disc)
    assert _uniform_rows(table)[1] - _uniform_rows(table)[0] > 20
    arrays = table.copy()
    arrays[interleaved_step.L_UNIFORM, :2] = 1.0
    rng = np.random.default_rng(4)
    u, v = rng.normal(size=disc.n_nodes), rng.normal(size=disc.n_nodes)
    results = []
    for step_table in (table, arrays):
        x, w, scratch = u.copy(), v.copy(), np.empty(disc.n_nodes)
        for _ in range(5):
            step_rod(x, w, scratch, disc.stiffness_bands, kind, step_table, 1e-4)
        results.append((x, w))
    np.testing.assert_array_equal(results[0][0], results[1][0])
    np.testing.assert_array_equal(results[0][1], results[1][1])


@pytest.mark.parametrize("order", [1, 2])
@pytest.mark.parametrize("remainder", [0.0, 1.0 / 3.0, 2.0 / 3.0])
def test_uniform_rows_with_far_end_remainders_equal_a_banded_solve(order, remainder):
    """400 steps near the stability limit against LAPACK's banded solve, on meshes of equal elements of
    2^-10 (node coordinates exact, so the held constants are the entries up to the factors' rounding) whose
    far end carries the remainder of 0, 1/3 or 2/3 of an element as a lumped mass."""
    element = 2.0**-10
    elements = 1599  # 1600 unknowns (P1) or vertices (P2): 8 chunks of 200 rows, no padding
    length = (elements + remainder) * element
    nodes = matched_nodes(length, element, from_left=True)
    assert nodes.size == elements + 1 and np.all(np.diff(nodes) == element)
    disc = discretize_rod(Rod(length, 2.0, 3.0, 0.5), nodes, order, "consistent", remainder_at="right")
    kind, table = prepare_mass(disc)
    lo, hi = _uniform_rows(table)
    assert lo <= 16 and hi >= _last_chunk_rows(table, elements + 1) - 16
    rng = np.random.default_rng(order + int(3 * remainder))
    assert_steps_equal_a_banded_solve(disc, kind, table, rng)


@pytest.mark.parametrize("order", [1, 2])
def test_held_constants_change_an_acceleration_by_the_rounding_of_the_node_coordinates(order):
    """On ``linspace`` nodes the elements differ by the rounding of their end points (a relative ``E``
    ulps at most); the accelerations with the held constants differ from LAPACK's banded solve of the
    assembled matrices by no more than that relative size."""
    elements = 2533
    disc = discretize_rod(Rod(1.1, 2.0, 3.0, 0.5), np.linspace(0.0, 1.1, elements + 1), order, "consistent")
    kind, table = prepare_mass(disc)
    assert _uniform_rows(table)[1] - _uniform_rows(table)[0] > 20
    (lower, upper), banded = _banded_mass(disc)
    rng = np.random.default_rng(order)
    u = rng.normal(size=disc.n_nodes)
    v = np.zeros(disc.n_nodes)
    dt = 2.0**-20
    step_rod(u.copy(), v, np.empty(disc.n_nodes), disc.stiffness_bands, kind, table, dt)
    expected = solve_banded((lower, upper), banded, -(disc.stiffness @ u))
    np.testing.assert_allclose(v / dt, expected, rtol=0, atol=8 * elements * 2.0**-52 * np.abs(expected).max())


def test_held_constants_do_not_change_a_collision_beyond_the_rounding_of_the_coordinates(monkeypatch):
    """gamma = 0.6, 3200 elements, P1 consistent, with the held constants and with none (every row from the
    arrays): the contact force and epsilon agree to a few 1e-12.  Holding one element's values instead of
    the rows' mean would make every interior element that one and shift the wave speed (measured: 4e-10 of
    the force, 5e-10 in epsilon)."""
    scene = wavecontact.two_rods(0.6, 100)
    results = []
    for ulps in (interleaved_step.UNIFORM_ULPS_PER_ELEMENT, -1.0):
        monkeypatch.setattr(interleaved_step, "UNIFORM_ULPS_PER_ELEMENT", ulps)
        setup = build_setup(scene, elements=3200, order=1, mass="consistent")
        run = _Run(setup, 0.05)
        held = [np.diff(_uniform_rows(table))[0] for _, table in run.mass_solves]
        assert all(rows > 50 for rows in held) if ulps > 0 else held == [0, 0]
        results.append(run_collision(setup))
    held, arrays = results
    assert held["steps"] == arrays["steps"]
    scale = np.abs(arrays["contact_force"]).max()
    np.testing.assert_allclose(held["contact_force"], arrays["contact_force"], rtol=0, atol=2e-11 * scale)
    np.testing.assert_allclose(held["relative_velocity"], arrays["relative_velocity"], rtol=0, atol=2e-11)


@pytest.mark.parametrize("order", [1, 2])
def test_more_rows_per_chunk_move_the_far_end_up_and_equal_a_banded_solve(order):
    """162 unknowns (P1) or vertices (P2) of equal elements of 2^-10: the fewest rows per chunk, 21, would
    leave the far end in row 14 of the last chunk (and its padding below unheld); 22 put it in row 7, among
    the start's unconverged rows, and every row from there to the last but one is held.  400 steps against
    LAPACK."""
    element = 2.0**-10
    elements = 161
    nodes = np.arange(elements + 1) * element
    disc = discretize_rod(Rod(elements * element, 2.0, 3.0, 0.5), nodes, order, "consistent")
    kind, table = prepare_mass(disc)
    rows = int(table[L_SHAPE, 0])
    assert rows == 22 > -(-(elements + 1) // LANES) == 21
    assert elements == (LANES - 1) * rows + 7  # the last unknown in row 7 of the last chunk
    lo, hi = _uniform_rows(table)
    assert 7 < lo <= 16 and hi == rows - 1
    assert_steps_equal_a_banded_solve(disc, kind, table, np.random.default_rng(order))


@pytest.mark.parametrize("order", [1, 2])
def test_held_padding_stays_zero_and_the_steps_equal_a_banded_solve(order, monkeypatch):
    """155 unknowns (P1) or vertices (P2) of equal elements of 2^-10 in chunks of 21 rows: the last chunk ends
    after 8 rows, above the held ones, and 13 rows of padding follow.  The padding after the first padding
    unknown counts as uniform and takes the held constants; it must stay exactly zero while the rod moves
    (400 steps against LAPACK), and the first padding unknown keeps its zero coefficients."""
    monkeypatch.setattr(interleaved_step, "LANE_MIN_UNKNOWNS", 0)
    monkeypatch.setattr(interleaved_step, "LANE_MIN_VERTICES", 0)
    element = 2.0**-10
    elements = 154
    disc = discretize_rod(Rod(elements * element, 2.0, 3.0, 0.5), np.arange(elements + 1) * element, order,
                          "consistent")
    kind, table = prepare_mass(disc)
    rows = int(table[L_SHAPE, 0])
    assert rows == 21 and table[L_SHAPE, 2] == rows  # the backward burn-in covers whole chunks
    lo, hi = _uniform_rows(table)
    unknowns = elements + 1
    first_padding = interleaved_step.position(unknowns, rows)  # row 8 of the last chunk
    width = rows * LANES
    index = np.arange(width).reshape(LANES, rows).T.ravel()  # the unknown at each place of the layout
    held = (index > unknowns) & (np.arange(width) >= lo * LANES) & (np.arange(width) < hi * LANES)
    assert hi - lo >= 5 and held.any()  # the last chunk's padding rows among the held ones
    backward = interleaved_step.L_BACKWARD
    assert table[backward, ORIGIN + first_padding] == 0.0
    held_value = table[interleaved_step.L_UNIFORM, 5 if order == 1 else 9]
    assert np.all(table[backward, ORIGIN : ORIGIN + width][held] == held_value)
    assert_steps_equal_a_banded_solve(disc, kind, table, np.random.default_rng(order))
    for row in (interleaved_step.L_U, interleaved_step.L_V):
        for half, start in enumerate((ORIGIN, midpoint_origin(rows))[:order]):
            packed = table[row, start : start + width]
            assert np.all(packed[index >= unknowns - half] == 0.0)  # P2 midpoints: one fewer than vertices


def _loaded_steps(disc, kind, table, end, forces, u, v, dt):
    """``forces.size`` steps of the interleaved step with ``forces[k]`` on node ``end`` (0 or the last) through
    the mass solve's right-hand side (``step_*_loaded``), from ``u, v``; returns the unpacked ``u, v``."""
    rows = int(table[L_SHAPE, 0])
    pack_nodes(u, table[interleaved_step.L_U], rows, disc.order)
    pack_nodes(v, table[interleaved_step.L_V], rows, disc.order)
    where = node_position(end, rows, disc.order)
    scale = table[T_CHAIN_INVERSE, end // disc.order]  # 1 / D at the end node (P2: its vertex)
    step = interleaved_step.step_tridiagonal_loaded if disc.order == 1 else interleaved_step.step_condensed_loaded
    for force in forces:
        step(table, dt, where, force * scale)
    x, w = np.zeros(disc.n_nodes), np.zeros(disc.n_nodes)
    unpack_nodes(table[interleaved_step.L_U], x, rows, disc.order)
    unpack_nodes(table[interleaved_step.L_V], w, rows, disc.order)
    return x, w


@pytest.mark.parametrize("order", [1, 2])
@pytest.mark.parametrize("mesh", ["graded", "equal 161", "equal 1333"])
@pytest.mark.parametrize("end", ["first", "last"])
def test_an_end_load_equals_a_banded_solve_with_the_force_on_the_end_node(order, mesh, end):
    """The force scheme's contact force entering the mass solve (``step_*_loaded``): 400 steps near the
    stability limit with a random force on the first or last node each step, against ``v += dt M^-1 (-K u +
    F e_end)`` with LAPACK's banded solve. Graded (the arrays), and equal elements of 2^-10 (exact nodes; the
    held constants; 161 elements: chunks of 22 rows, the far end in row 7 of the last chunk, the held rows
    reaching into its padding)."""
    rng = np.random.default_rng(order + 10 * len(mesh) + len(end))
    if mesh == "graded":
        nodes = _graded_nodes(rng, 1250, 1.0, 2.0)
    else:
        elements = int(mesh.split()[1])
        nodes = np.arange(elements + 1) * 2.0**-10
    disc = discretize_rod(Rod(nodes[-1], 2.0, 3.0, 0.5), nodes, order, "consistent")
    kind, table = prepare_mass(disc)
    assert table[L_SHAPE, 0] > 0
    if mesh != "graded":
        lo, hi = _uniform_rows(table)
        assert hi - lo >= 5
        # the chunks' boundary values from their neighbour's alone (no sequential pass); 161 elements: the
        # backward sums cover whole chunks (their neighbour's first value added), 1333: they do not
        assert table[L_SHAPE, 3] == table[L_SHAPE, 4] == 0.0
        assert (table[L_SHAPE, 2] == table[L_SHAPE, 0]) == (mesh == "equal 161")
    node = 0 if end == "first" else disc.n_nodes - 1
    (lower, upper), banded = _banded_mass(disc)
    stiffness = disc.stiffness
    highest = highest_eigenvalue(disc)
    dt = 1.9 / np.sqrt(highest)
    u = 1e-3 * np.sin(3.0 * disc.x) + 1e-6 * rng.normal(size=disc.n_nodes)
    v = rng.normal(size=disc.n_nodes) * 1e-3
    forces = rng.normal(size=400) * np.abs(stiffness @ u).max()
    x, w = _loaded_steps(disc, kind, table, node, forces, u, v, dt)
    load = np.zeros(disc.n_nodes)
    for force in forces:
        load[node] = force
        v += dt * solve_banded((lower, upper), banded, load - stiffness @ u)
        u += dt * v
    np.testing.assert_allclose(w, v, rtol=0, atol=1e-11 * np.abs(v).max())
    np.testing.assert_allclose(x, u, rtol=0, atol=1e-11 * np.abs(u).max())


@pytest.mark.parametrize("elements", [70, 800])
def test_chunk_coupling_compiled_equals_its_pure_python_form_bit_for_bit(monkeypatch, elements):
    """The coupling pass, chained (chunks of 9 rows) and from the neighbour's values alone (800 elements of
    2^-10), compiled and as plain Python on the same forward values."""
    monkeypatch.setattr(interleaved_step, "LANE_MIN_VERTICES", 0)
    nodes = np.arange(elements + 1) * 2.0**-10
    disc = discretize_rod(Rod(nodes[-1], 2.0, 3.0, 0.5), nodes, 2, "consistent")
    _, table = prepare_mass(disc)
    n = int(table[L_SHAPE, 0])
    assert table[L_SHAPE, 3] == table[L_SHAPE, 4] == float(elements == 70)
    rows = min(max(int(table[L_SHAPE, 1]), int(table[L_SHAPE, 2])), n)
    forward = np.random.default_rng(elements).normal(size=table.shape[1])
    results = []
    for couple in (interleaved_step._couple_chunks, interleaved_step._couple_chunks.py_func):
        scratch = table.copy()
        scratch[interleaved_step.L_WORK] = forward
        per_row = (scratch[row, ORIGIN:] for row in (interleaved_step.L_WORK, interleaved_step.L_FORWARD,
                                                     interleaved_step.L_WEIGHT))  # as the steps pass them
        per_chunk = (scratch[row] for row in (interleaved_step.L_FORWARD_END, interleaved_step.L_BACKWARD_START,
                                              interleaved_step.L_CARRY, interleaved_step.L_CORRECTION,
                                              interleaved_step.L_BURN))
        couple(*per_row, *per_chunk, n, rows, table[L_SHAPE, 3] != 0.0, table[L_SHAPE, 4] != 0.0)
        results.append(scratch[interleaved_step.L_WORK])
    np.testing.assert_array_equal(results[0], results[1])


@pytest.mark.parametrize("order", [1, 2])
@pytest.mark.parametrize("scheme", ["interface", "splitting", "force"])
def test_every_contact_scheme_reads_the_packed_ends_where_they_are(monkeypatch, order, scheme):
    """The contact of each scheme reads and moves the rods' facing ends through their positions in the layout
    (the second rod's first node is not at index 0 of its row: the ghost row comes first): with both rods
    interleaved the relative velocity equals the flat layout's to rounding throughout (gamma = 0.6, kappa =
    100, 300 elements), and so does epsilon."""
    results = []
    for threshold in (10**9, 0):
        monkeypatch.setattr(interleaved_step, "LANE_MIN_UNKNOWNS", threshold)
        monkeypatch.setattr(interleaved_step, "LANE_MIN_VERTICES", threshold)
        setup = build_setup(wavecontact.two_rods(0.6, 100), elements=300, order=order, mass="consistent",
                            scheme=scheme)
        run = _Run(setup, 0.05)
        assert [int(table[L_SHAPE, 0]) > 0 for _, table in run.mass_solves] == [threshold == 0] * 2
        results.append(run_collision(setup))
    flat, packed = results
    assert flat["steps"] == packed["steps"]
    np.testing.assert_allclose(packed["relative_velocity"], flat["relative_velocity"], rtol=0, atol=1e-12)
