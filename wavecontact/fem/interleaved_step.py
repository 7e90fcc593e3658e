"""The consistent-mass explicit step with the rod's unknowns stored in ``LANES`` interleaved chunks.

A tridiagonal solve is two first-order recurrences, ``y_i = r_i + f_i y_(i-1)``
downwards and ``x_i = y_i + g_i x_(i+1)`` upwards; as one chain each costs the
latency of a multiplication and an addition per unknown.  Here the ``m``
unknowns are cut into ``LANES`` = 8 consecutive chunks of ``n = ceil(m /
LANES)`` and stored chunk-interleaved: unknown ``k = c n + i`` (chunk ``c``,
position ``i``) at ``X[i LANES + c]`` (padding unknowns beyond ``m`` are
decoupled and stay zero), after one ghost row (``ORIGIN = LANES``: unknown ``k`` at
``ORIGIN + position(k)`` of its table row).  Row ``i`` of all chunks is then contiguous, the
stencil's neighbours ``i +- 1`` are the previous and next rows, and every pass
(stencil, both sweeps, update) is one loop over the array whose iterations
``LANES`` apart depend on each other: the compiler runs the chunks as SIMD
lanes (a row of 8 doubles is one 512-bit vector, one cache line).  Only a chunk's first and last rows see a neighbouring chunk: before
each step the displacements' ghost rows before the first row and after the
last receive, in lane ``c``, chunk ``c - 1``'s last row and chunk ``c + 1``'s
first, so that those rows run in the same vectorized loop as the others (the
ghosts of the rod's own ends meet zero coefficients).

The forward sweep first runs every chunk from zero, then adds what the chunk
before it contributes: the chunks' true end values follow from their local
ones in a short sequential pass over the chunks (or, where the products of two
neighbouring chunks' factors are below ``LANE_TOLERANCE``, from the neighbour's
local one alone: two terms, no pass), and their effect on a chunk,
``P_i e`` with ``P_i`` the product of the sweep's factors from the chunk
boundary to ``i`` and ``e`` the neighbour's end value, is added by the same
recurrence without right-hand side (``delta_i = f_i delta_(i-1)``, a cheap
streaming pass) on the rows where ``|P_i|`` exceeds ``LANE_TOLERANCE`` (``w``
rows; the mass matrices are diagonally dominant, so ``|f|, |g| <= 1/2`` and
``w`` is about 33 on uniform meshes (P1, 26 for the P2 vertices); all rows of chunks shorter than that).
The same pass sums, per chunk, ``G_i y_i`` over its first rows (``G_i`` the
product of the backward factors above row ``i``): that sum is the chunk's first
unknown after the backward sweep, up to terms below ``LANE_TOLERANCE``, and is
written below the chunk before it, so that every chunk's backward sweep starts
from its exact neighbour and runs, with the update, in one pass.  The terms
left out are below ``2^-64`` of an entry of the result, so the solve equals
the direct one to rounding, not bit for bit.

The rows per chunk are chosen at set-up among a few (:func:`candidate_rows`) so
that as many rows as possible hold their coefficients as constants on meshes of
equal elements (:func:`uniform_rows`).

The layout lives only inside the time loop (``kernels.advance``):
:func:`pack_nodes` and :func:`unpack_nodes` convert at its start, at its energy
checks and at its end.  The state and the
coefficients are rows of the mass solve's table (rows ``L_*``); the kernels'
loops are written as single loops with constant offsets (``j + LANES``) and
counting down to zero where they run upwards through the rod, the forms the
compiler vectorizes.
"""

from __future__ import annotations

import numpy as np

from .._jit import kernel, row_view

__all__ = ["LANES", "LANE_MIN_UNKNOWNS", "LANE_MIN_VERTICES", "ORIGIN", "aligned_table", "condensed_lane_rows",
           "lane_rows", "lanes_width", "midpoint_origin", "node_position", "pack_nodes", "step_condensed",
           "step_condensed_loaded", "step_tridiagonal", "step_tridiagonal_loaded", "table_width", "unpack_nodes"]

LANES = 8  # measured against 4, 16 and 32 (benchmarks/interleaved_lanes.py, docs/fem.md section 7; an AVX-512
# machine): 8 was the fastest for P1 and P2 at 800 to 12800 elements (with 32, the chunks' coupling over their
# first ~30 rows covered every row of a short rod).  The results do not depend on the processor's vector
# width: the lanes never mix, so a given LANES rounds the same everywhere (another one moves them at rounding)
ORIGIN = LANES  # index of row 0 in a table row of the layout: one ghost row before it
LANE_TOLERANCE = 2.0**-64  # contributions of a neighbouring chunk left out, relative to an entry of the result
# smaller systems keep the flat layout: with few rows per chunk the chunks' coupling covers most rows and
# costs more than the lanes save (measured crossings, one rod's step alone, equal elements: between 60 and
# 100 unknowns for P1, 100 and 150 vertices for P2; docs/fem.md section 7)
LANE_MIN_UNKNOWNS = 100
LANE_MIN_VERTICES = 150  # the same for the vertex system of P2 (condensed midpoints)

# rows of the mass solve's table used by the interleaved layout (the flat solve's rows come first)
L_SHAPE = 24  # [0]: rows n per chunk (0: flat layout), [1]: forward correction rows, [2]: backward burn-in rows,
# [3], [4]: 1 when the chunks' end values (forward) and first values (backward) are chained (_chunk_couplings)
L_LEFT = 25  # stencil, P1: r_i = -(left_i (u_(i-1) - u_i) + right_i (u_(i+1) - u_i)), scaled by 1 / D_i
L_RIGHT = 26
L_FORWARD = 27  # f_i of y_i = r_i + f_i y_(i-1) (0 on the padding; 1 at the rod's first unknown, whose
# y_(i-1), the work row's ghost, carries the load on that unknown: see step_tridiagonal_loaded)
L_BACKWARD = 28  # g_i of x_i = y_i + g_i x_(i+1) (0 at the last unknown and on the padding)
L_FORWARD_END = 29  # per chunk: product of its forward factors (first LANES entries)
L_BACKWARD_START = 30  # per chunk: product of its backward factors (first LANES entries)
L_CARRY = 31  # scratch: true end values of the chunks
L_CORRECTION = 32  # scratch: the forward sweep's corrections, then the backward burn-in
L_WORK = 33  # scratch: the sweeps' values; its row n: the first unknown of the next chunk (backward); its ghost
# row: 0, but the load on the rod's first unknown in lane 0
L_U = 34  # displacements in the interleaved layout (inside the time loop)
L_V = 35  # velocities (P2: the vertices' first, then the midpoints' from midpoint_origin(n), each n LANES long)
# P2 consistent (midpoints condensed), per vertex k: its condensed right-hand side from the displacements,
# c1 (uv_(k-1) - uv_k) + c2 (um_(k-1) - uv_k) + c3 (um_k - uv_k) + c4 (uv_(k+1) - uv_k) (uv vertices, um the
# midpoints, um_k that of element k, from vertex k to k + 1), scaled by 1 / D_k; per element k: the midpoint's
# force over its mass, s_k = -(m_l (uv_k - um_k) + m_r (uv_(k+1) - um_k)), and its acceleration
# s_k - b_l x_k - b_r x_(k+1) from the vertices' accelerations x
L_C1 = 36
L_C2 = 37
L_C3 = 38
L_C4 = 39
L_MID_LEFT = 40  # m_l
L_MID_RIGHT = 41  # m_r
L_BACK_LEFT = 42  # b_l
L_BACK_RIGHT = 43  # b_r
L_SHARE = 44  # scratch: s_k
# uniform rows: [0], [1] the rows [lo, hi) (1 <= lo <= hi <= n - 1) whose coefficients, in every lane, are the
# constants [2:] (P1: left, right, f, g; P2: c1 .. c4, m_l, m_r, f, g, b_l, b_r); the step holds those in registers
L_UNIFORM = 45
L_WEIGHT = 46  # G_i: per chunk, the product of the backward factors g above row i (1 at row 0)
L_BURN = 47  # scratch: per chunk, sum of G_i y_i over its rows so far
L_ROWS_END = 48
UNIFORM_ULPS_PER_ELEMENT = 4.0  # uniform to the rounding of the node coordinates (see uniform_rows)
HELD_ROW_COST = 0.6  # a held row's cost against one read from the arrays (P2 step, 1333 elements, 32 lanes, measured)
UNCONVERGED_ROWS = 16  # rows at the rod's start where the factorization's factors still differ from their limits
P1_UNIFORM_ROWS = (L_LEFT, L_RIGHT, L_FORWARD, L_BACKWARD)
P2_UNIFORM_ROWS = (L_C1, L_C2, L_C3, L_C4, L_MID_LEFT, L_MID_RIGHT, L_FORWARD, L_BACKWARD, L_BACK_LEFT,
                   L_BACK_RIGHT)


def candidate_rows(unknowns: int) -> range:
    """The rows per chunk the set-up chooses from for ``unknowns`` unknowns (see :func:`_fill_rows`).

    From the fewest, ``ceil(unknowns / LANES)``, upwards: one more row moves the rod's far end about
    ``LANES - 1`` rows up its chunk, so a few reach every position of it within a few rows of the top.  An
    extra row costs a row and can only pay by holding the rows it frees below the far end, at most the
    chunk's padding (below ``LANES`` rows) and the start's unconverged rows, at ``1 - HELD_ROW_COST`` of a
    row each: more extra rows than that never pay, and are not tried.
    """
    fewest = -(-unknowns // LANES)
    worth = int((1.0 - HELD_ROW_COST) * (LANES + UNCONVERGED_ROWS))
    return range(fewest, fewest + min(fewest // (LANES - 1) + 3, worth + 1))


def lanes_width(unknowns: int) -> int:
    """Length of a row of the interleaved layout for ``unknowns`` unknowns, for any of their
    :func:`candidate_rows` (the ghost row before, one row after)."""
    return ORIGIN + (candidate_rows(unknowns)[-1] + 1) * LANES


@kernel(fastmath=False, internal=True)
def midpoint_origin(n):
    """Index of the P2 midpoints' row 0 in the displacement and velocity rows (``n`` rows per chunk): after the
    vertices' rows and their ghost row after, and the midpoints' own ghost row before."""
    return ORIGIN + n * LANES + 2 * LANES


def table_width(minimum: int) -> int:
    """A row length of at least ``minimum`` doubles whose rows start 3 cache lines apart modulo 4 KiB.

    The step streams some twenty rows of the table at the same index; rows a multiple of 4 KiB apart
    would make every load look like it depends on the store just made to another row (the processor
    compares the addresses' low 12 bits first), which costs about a factor two in the P2 step.
    """
    return -(-(minimum - 24) // 512) * 512 + 24 if minimum > 24 else 24


def aligned_table(rows: int, width: int) -> np.ndarray:
    """A zero ``(rows, width)`` table whose rows start on 64-byte boundaries (``width`` a multiple of 8).

    A row of the layout is ``LANES`` doubles, a whole number of cache lines; on a table placed 16 bytes off a
    cache line every vector load and store of the step straddles two lines, which cost the P1 step about half
    again and the P2 step a quarter (measured with 32 lanes, 1333-element rod: 2.07 against 1.37 and 2.9
    against 2.35 ns per element; numpy aligns large arrays to 16 bytes only).
    """
    if width % 8:
        raise ValueError(f"width must be a multiple of 8 doubles, got {width}")
    buffer = np.zeros(rows * width + 8)
    start = (-buffer.ctypes.data % 64) // 8
    return buffer[start : start + rows * width].reshape(rows, width)


def _interleave(values: np.ndarray, n: int) -> np.ndarray:
    """``values`` (padded with zeros to ``n LANES``) in the interleaved order."""
    padded = np.zeros(n * LANES)
    padded[: values.size] = values
    return padded.reshape(LANES, n).T.ravel()


def _correction_rows(factors: np.ndarray) -> tuple:
    """Per chunk (``factors``: one row per chunk), the products of its factors from its first row down: the
    whole chunk's product and the number of rows where it exceeds ``LANE_TOLERANCE`` (at least 1)."""
    products = np.cumprod(factors, axis=1)
    rows = int(np.max(np.sum(np.abs(products) > LANE_TOLERANCE, axis=1)))
    return products[:, -1].copy(), max(rows, 1)


def _chunk_couplings(table: np.ndarray, n: int) -> None:
    """Rows ``L_SHAPE``, ``L_FORWARD_END``, ``L_BACKWARD_START``, ``L_WEIGHT`` from the solve's factors in the
    table (``n`` rows per chunk).

    Forward: the chunk before adds ``P_i e`` to row ``i`` of a chunk (``P_i`` the product of its factors
    ``f`` from the first row to ``i``, ``e`` that chunk's true last value), on the rows where ``|P_i|``
    exceeds ``LANE_TOLERANCE``.  Backward: a chunk's first unknown is ``x_0 = sum_(i<n) G_i y_i + G_n
    x_n`` (``G_i``, row ``L_WEIGHT``, the product of its factors ``g`` above row ``i``; ``x_n`` the next
    chunk's first unknown), summed over the rows where ``|G_i|`` exceeds ``LANE_TOLERANCE`` (the burn-in
    rows; the last term only when they are all the chunk's rows, with ``G_n`` per chunk in
    ``L_BACKWARD_START``).
    """
    rows = slice(ORIGIN, ORIGIN + n * LANES)
    forward = table[L_FORWARD, rows].reshape(n, LANES).T
    backward = table[L_BACKWARD, rows].reshape(n, LANES).T
    end, forward_rows = _correction_rows(forward)
    start, backward_rows = _correction_rows(backward)
    table[L_FORWARD_END, :LANES] = end
    table[L_BACKWARD_START, :LANES] = start
    weights = np.ones((LANES, n))
    weights[:, 1:] = np.cumprod(backward[:, :-1], axis=1)
    table[L_WEIGHT, :] = 0.0
    table[L_WEIGHT, rows] = weights.T.ravel()
    # [3], [4]: 1 when the whole products of two neighbouring chunks exceed LANE_TOLERANCE, so that the chunks'
    # true end values (forward) or first values (backward) need a sequential pass over the chunks; else each
    # is its local one plus its neighbour's share, up to terms below the tolerance (see _couple_chunks)
    table[L_SHAPE, :5] = (n, forward_rows, min(backward_rows + 1, n), float(_chained(end)), float(_chained(start)))


def _chained(products: np.ndarray) -> bool:
    """Whether two neighbouring chunks' whole products of factors (``products``, one per chunk) exceed
    ``LANE_TOLERANCE`` somewhere: then a chunk's boundary value depends on more than its neighbour's."""
    return bool(np.any(np.abs(products[1:] * products[:-1]) > LANE_TOLERANCE))


def _fill_rows(table: np.ndarray, per_unknown: dict, held: tuple, m: int) -> None:
    """Write ``per_unknown`` (table row: values of the ``m`` unknowns) in the interleaved layout with the rows
    per chunk among :func:`candidate_rows` that costs least, hold the uniform rows, fill the couplings.

    The cost of a layout counts its rows, a held row as ``HELD_ROW_COST`` of one read from the arrays: more
    rows per chunk can move the rod's far end up into the rows where the factors have not yet converged
    at its start, which are not held anyway, and so lengthen the run of held rows.
    """
    best = None
    for n in candidate_rows(m):
        lo, hi = _layout_rows(table, per_unknown, held, n, m)
        cost = n - (1.0 - HELD_ROW_COST) * (hi - lo)
        if best is None or cost < best[0]:
            best = (cost, n)
    n = best[1]
    _layout_rows(table, per_unknown, held, n, m)
    _chunk_couplings(table, n)
    # the rod's first unknown has no y_(i-1): its factor 1 adds the work row's ghost, the load on that unknown
    table[L_FORWARD, ORIGIN] = 1.0


def _layout_rows(table: np.ndarray, per_unknown: dict, held: tuple, n: int, m: int) -> tuple:
    """:func:`_fill_rows` for ``n`` rows per chunk, without the couplings; returns the held rows ``(lo, hi)``."""
    for row, values in per_unknown.items():
        table[row, :] = 0.0
        table[row, ORIGIN : ORIGIN + n * LANES] = _interleave(values, n)
    return uniform_rows(table, held, n, m)


def uniform_rows(table: np.ndarray, rows: tuple, n: int, m: int) -> tuple:
    """Find and hold the rows of the interleaved layout whose coefficients are the same in every chunk.

    A mesh of equal elements gives equal stiffness and mass entries, and the
    factorization's ``f_i``, ``g_i`` converge geometrically to their limits
    within a few dozen rows; but node coordinates are rounded, so element
    lengths of ``L / E`` may differ by about an ulp of ``L``, a relative
    ``E 2^-52``, and so do the coefficients (measured: up to 1.5 ``E`` ulps on
    ``linspace`` nodes; none on nodes that are multiples of a power of two).
    Each of ``rows`` gets its constant, its mean over the unknowns at least
    ``UNCONVERGED_ROWS`` from either end of the rod (all along it, so that the
    rounding of the coordinates in every binade they cover counts; the mean,
    not one element's value, so that the held elements keep the mesh's mean
    length and the waves their speed),
    and a tolerance: twice the largest distance from it over those
    unknowns, at least 4 ulps and at most
    ``UNIFORM_ULPS_PER_ELEMENT E`` ulps (``E = m - 1`` elements).  A row of
    the layout (all ``LANES`` chunks) is uniform when each of ``rows`` is
    within its tolerance at every unknown of the row (the run's constants
    then become the means over its own unknowns, so that the held elements
    keep their mean length, not the whole rod's; on ``linspace`` nodes that
    halves epsilon's change at 3200 and 12800 elements, docs/fem.md); padding beyond the
    first padding unknown counts as uniform (it stays zero whatever its
    coefficients: the first one, after the rod's last unknown, keeps its
    zero coefficients and decouples it).  The longest run ``[lo, hi)`` of
    uniform rows inside ``[1, n - 1)`` gets the constants written into the
    table (so the table describes exactly the operator the step applies) and
    the constants go to row ``L_UNIFORM``.  Graded meshes have no such rows
    (``lo = hi = 1``, nothing changes).  Returns ``(lo, hi)``.
    """
    ulp = 2.0**-52
    index = np.arange(n * LANES).reshape(LANES, n).T  # the unknown at (row, chunk)
    free = index > m
    middle = (index >= UNCONVERGED_ROWS) & (index < m - UNCONVERGED_ROWS)
    if not middle.any():  # a rod too short for that: all its unknowns
        middle = index < m
    elements = max(m - 1, 1)
    layout = slice(ORIGIN, ORIGIN + n * LANES)
    constants = np.array([np.mean(table[row, layout].reshape(n, LANES)[middle]) for row in rows])
    uniform = np.ones(n, dtype=bool)
    for row, value in zip(rows, constants):
        entries = table[row, layout].reshape(n, LANES)
        spread = np.max(np.abs(entries[middle] - value))
        tolerance = min(max(2.0 * spread, 4.0 * ulp * abs(value)), UNIFORM_ULPS_PER_ELEMENT * elements * ulp * abs(value))
        uniform &= np.all((np.abs(entries - value) <= tolerance) | free, axis=1)
    uniform[0] = uniform[n - 1] = False  # the first and last rows read the neighbouring chunks
    lo, hi, start = 1, 1, None
    for i in range(1, n):
        if uniform[i] and start is None:
            start = i
        if not uniform[i] and start is not None:
            if i - start > hi - lo:
                lo, hi = start, i
            start = None
    if hi > lo:  # the held rows keep their own mean (their elements' mean length: the waves keep their time)
        held = np.zeros((n, LANES), dtype=bool)
        held[lo:hi] = index[lo:hi] < m
        constants = np.array([np.mean(table[row, layout].reshape(n, LANES)[held]) for row in rows])
    for row, value in zip(rows, constants):
        table[row, ORIGIN + lo * LANES : ORIGIN + hi * LANES] = value
    table[L_UNIFORM, :] = 0.0
    table[L_UNIFORM, : 2 + len(rows)] = (lo, hi, *constants)
    return lo, hi


def lane_rows(near: np.ndarray, scale: np.ndarray, forward: np.ndarray, backward: np.ndarray,
              table: np.ndarray) -> None:
    """Fill the rows ``L_*`` of ``table`` for a tridiagonal solve in the interleaved layout (P1 consistent).

    Parameters
    ----------
    near : ndarray
        Upper band ``K[i, i + 1]`` of the stiffness (force/length), ``m - 1`` entries.
    scale, forward, backward : ndarray
        The plain ``L D L^T`` factorization of the mass, ``m`` entries each:
        ``1 / D_i`` (1/mass), ``f_i = -off_(i-1) / D_i`` and ``g_i = -off_i / D_i``.
    table : ndarray
        The mass solve's table, at least :func:`lanes_width` wide.
    """
    m = scale.size
    left = np.zeros(m)
    right = np.zeros(m)
    left[1:] = scale[1:] * near
    right[:-1] = scale[:-1] * near
    _fill_rows(table, {L_LEFT: left, L_RIGHT: right, L_FORWARD: forward, L_BACKWARD: backward}, P1_UNIFORM_ROWS, m)


def condensed_lane_rows(coefficients: dict, scale: np.ndarray, forward: np.ndarray, backward: np.ndarray,
                        table: np.ndarray) -> None:
    """Fill the rows ``L_*`` of ``table`` for the condensed P2 step in the interleaved layout.

    Parameters
    ----------
    coefficients : dict
        Per element ``e`` (``E`` entries): ``mid_left``, ``mid_right`` (``K[j, j -+ 1] / M[j, j]`` at its
        midpoint ``j``, 1/time^2), ``back_left``, ``back_right`` (``M[j, j -+ 1] / M[j, j]``) and the
        element's parts of its vertices' condensed right-hand sides, ``left_a``, ``left_c``,
        ``right_a``, ``right_c`` (unscaled, force/length; see ``explicit_step._condensed_step_rows``).
    scale, forward, backward : ndarray
        The plain ``L D L^T`` factorization of the condensed vertex mass (``E + 1`` entries each).
    table : ndarray
        The mass solve's table, at least twice :func:`lanes_width` of the vertices wide.
    """
    m = scale.size
    la, lc = coefficients["left_a"], coefficients["left_c"]
    ra, rc = coefficients["right_a"], coefficients["right_c"]
    c1, c2, c3, c4 = (np.zeros(m) for _ in range(4))
    c1[1:] = ra  # uv_(k-1) in element k - 1's right part
    c2[1:] = -(ra + rc)
    c3[:-1] = -(la + lc)
    c4[:-1] = lc
    per_unknown = {L_C1: c1 * scale, L_C2: c2 * scale, L_C3: c3 * scale, L_C4: c4 * scale, L_FORWARD: forward,
                   L_BACKWARD: backward}
    for row, name in ((L_MID_LEFT, "mid_left"), (L_MID_RIGHT, "mid_right"), (L_BACK_LEFT, "back_left"),
                      (L_BACK_RIGHT, "back_right")):
        per_unknown[row] = coefficients[name]
    _fill_rows(table, per_unknown, P2_UNIFORM_ROWS, m)


@kernel(fastmath=False, internal=True)
def pack(x, first, stride, packed, start, n):
    """``packed[start + i LANES + c] = y[c n + i]`` for the unknowns ``y = x[first::stride]`` (the padding
    untouched; indices, not a strided view, so that one compilation serves every stride)."""
    count = (x.size - first + stride - 1) // stride
    for c in range(LANES):
        for i in range(n):
            k = c * n + i
            if k < count:
                packed[start + i * LANES + c] = x[first + stride * k]


@kernel(fastmath=False, internal=True)
def unpack(packed, start, x, first, stride, n):
    """The inverse of :func:`pack`."""
    count = (x.size - first + stride - 1) // stride
    for c in range(LANES):
        for i in range(n):
            k = c * n + i
            if k < count:
                x[first + stride * k] = packed[start + i * LANES + c]


@kernel(fastmath=False, internal=True)
def position(k, n):
    """Index of unknown ``k`` in the interleaved layout with ``n`` rows."""
    return (k % n) * LANES + k // n


@kernel(fastmath=False, internal=True)
def _p1_rows(u, y, left, right, forward, count):
    """Stencil and local forward sweep of the rows after the first of the views (``count`` entries)."""
    for j in range(count):
        current = u[j + LANES]
        force = -(left[j + LANES] * (u[j] - current) + right[j + LANES] * (u[j + 2 * LANES] - current))
        y[j + LANES] = force + forward[j + LANES] * y[j]


@kernel(fastmath=False, internal=True)
def _p1_rows_uniform(u, y, constants, count):
    """:func:`_p1_rows` with the coefficients the constants of ``L_UNIFORM`` (same operations, same order)."""
    left = constants[2]
    right = constants[3]
    forward = constants[4]
    for j in range(count):
        current = u[j + LANES]
        force = -(left * (u[j] - current) + right * (u[j + 2 * LANES] - current))
        y[j + LANES] = force + forward * y[j]


@kernel(fastmath=False, internal=True)
def _ghost_rows(x, n, after):
    """Fill the ghost rows of the displacements ``x`` (a view whose row 0 starts at ``LANES``, ``n`` rows):
    before row 0, lane ``c >= 1`` gets the last row of chunk ``c - 1``; with ``after``, after row ``n - 1``
    lane ``c <= LANES - 2`` gets the first row of chunk ``c + 1``.  Lane 0 before and lane ``LANES - 1``
    after stay as they are (zero): beyond the rod's ends, where the stencil's coefficients are zero."""
    last = n * LANES  # row n - 1
    for c in range(1, LANES):
        x[c] = x[last + c - 1]
    if after:
        following = (n + 1) * LANES
        for c in range(LANES - 1):
            x[following + c] = x[LANES + c + 1]


@kernel(fastmath=False, internal=True)
def _forward_p1(u, y, left, right, forward, constants, n):
    """Stencil and local forward sweep of every chunk, fused: ``y_i = r_i + f_i y_(i-1)`` from the work row's
    ghost row (zero, or the load on the rod's first unknown) above each chunk, on table rows (row 0 at
    ``ORIGIN``) whose ghost rows are filled first; rows ``[0, lo)`` and ``[hi, n)`` with the arrays, the
    uniform rows ``[lo, hi)`` of ``constants`` with the constants, each run one vectorized loop."""
    base = ORIGIN - LANES  # the views below start one row before the first row they compute
    _ghost_rows(u[base:], n, np.bool_(True))
    lo = base + int(constants[0]) * LANES
    hi = base + int(constants[1]) * LANES
    _p1_rows(u[base:], y[base:], left[base:], right[base:], forward[base:], lo - base)
    _p1_rows_uniform(u[lo:], y[lo:], constants, hi - lo)
    _p1_rows(u[hi:], y[hi:], left[hi:], right[hi:], forward[hi:], base + n * LANES - hi)


@kernel(fastmath=False, internal=True)
def _couple_chunks(y, forward, weight, end, start, carry, correction, burn, n, rows, chained, chained_starts):
    """Couple the chunks' local forward sweeps ``y`` and prepare the backward sweep's exact starts.

    Forward: ``carry[c]`` the true last value of chunk ``c``, ``y_c + end_c carry[c - 1]`` (with
    ``chained``, a short sequential pass; else the products ``end_c end_(c-1)`` are all below
    ``LANE_TOLERANCE`` and the two terms ``y_c + end_c y_(c-1)`` of the local last values suffice), then ``delta_i = f_i
    delta_(i-1)`` from ``delta_0 = f_0 carry[c - 1]`` added to the first ``rows`` rows.  In the same pass, per
    chunk, ``burn_i = burn_(i-1) + G_i y_i`` (``weight``: ``G_i``, the product of the backward factors above
    row ``i`` of the chunk) on the corrected ``y``: the chunk's first unknown after the backward sweep is
    ``x_0 = burn_(rows-1) + G_n x_n`` (``x_n``: the next chunk's, ``G_n`` in ``start``; the last term only
    when ``rows`` covers the chunk, else it is below ``LANE_TOLERANCE`` of an entry; sequential with
    ``chained_starts``, else, as forward, two terms), written below the chunk before (row ``n`` of ``y``,
    lane ``c - 1``), where that chunk's backward sweep starts from it.
    """
    last = (n - 1) * LANES
    if chained:
        previous = y[last]
        carry[0] = previous
        for c in range(1, LANES):
            previous = y[last + c] + end[c] * previous
            carry[c] = previous
    else:
        carry[0] = y[last]
        for c in range(1, LANES):
            carry[c] = y[last + c] + end[c] * y[last + c - 1]
    correction[0] = 0.0
    burn[0] = weight[0] * y[0]
    for c in range(1, LANES):
        delta = forward[c] * carry[c - 1]
        correction[c] = delta
        value = y[c] + delta
        y[c] = value
        burn[c] = weight[c] * value
    for j in range((rows - 1) * LANES):
        delta = forward[j + LANES] * correction[j]
        correction[j + LANES] = delta
        value = y[j + LANES] + delta
        y[j + LANES] = value
        burn[j + LANES] = burn[j] + weight[j + LANES] * value
    sums = (rows - 1) * LANES
    below = n * LANES
    y[below + LANES - 1] = 0.0
    y[below + LANES - 2] = burn[sums + LANES - 1]
    if rows == n and chained_starts:
        following = burn[sums + LANES - 1]
        for c in range(LANES - 2, 0, -1):
            following = burn[sums + c] + start[c] * following
            y[below + c - 1] = following
    elif rows == n:
        for c in range(1, LANES - 1):
            y[below + c - 1] = burn[sums + c] + start[c] * burn[sums + c + 1]
    else:
        for c in range(1, LANES - 1):
            y[below + c - 1] = burn[sums + c]


@kernel(fastmath=False, internal=True)
def _couple_table(table, n):
    """:func:`_couple_chunks` on the rows of ``table`` (``n`` rows per chunk), after the forward sweep: its
    corrected rows and its sequential passes as :func:`_chunk_couplings` set them up."""
    coupled_rows = min(max(int(table[L_SHAPE, 1]), int(table[L_SHAPE, 2])), n)
    _couple_chunks(row_view(table, L_WORK)[ORIGIN:], row_view(table, L_FORWARD)[ORIGIN:],
                   row_view(table, L_WEIGHT)[ORIGIN:], row_view(table, L_FORWARD_END), row_view(table, L_BACKWARD_START),
                   row_view(table, L_CARRY), row_view(table, L_CORRECTION), row_view(table, L_BURN), n, coupled_rows,
                   table[L_SHAPE, 3] != 0.0, table[L_SHAPE, 4] != 0.0)


@kernel(fastmath=False, internal=True)
def _sweep_up_update(u, v, y, backward, count, dt):
    """The backward sweep over ``j = count - 1 .. 0`` with the leapfrog update of those unknowns."""
    for j in range(count - 1, -1, -1):
        acceleration = y[j] + backward[j] * y[j + LANES]
        y[j] = acceleration
        velocity = v[j] + dt * acceleration
        v[j] = velocity
        u[j] += dt * velocity


@kernel(fastmath=False, internal=True)
def _sweep_up_update_uniform(u, v, y, constants, count, dt):
    """:func:`_sweep_up_update` with ``g`` the constant of ``L_UNIFORM``."""
    backward = constants[5]
    for j in range(count - 1, -1, -1):
        acceleration = y[j] + backward * y[j + LANES]
        y[j] = acceleration
        velocity = v[j] + dt * acceleration
        v[j] = velocity
        u[j] += dt * velocity


@kernel(fastmath=False, internal=True)
def _backward_update(u, v, y, backward, constants, n, dt):
    """Backward sweep of every chunk from its exact start (row ``n`` of ``y``) with the leapfrog update, on the
    true forward result ``y`` (overwritten with the accelerations): rows ``[hi, n)`` and ``[0, lo)`` with the
    arrays, the uniform rows ``[lo, hi)`` of ``constants`` with the constants."""
    hi = int(constants[1]) * LANES
    lo = int(constants[0]) * LANES
    _sweep_up_update(u[hi:], v[hi:], y[hi:], backward[hi:], n * LANES - hi, dt)
    _sweep_up_update_uniform(u[lo:], v[lo:], y[lo:], constants, hi - lo, dt)
    _sweep_up_update(u, v, y, backward, lo, dt)


@kernel(fastmath=False, internal=True)
def step_tridiagonal(table, dt):
    """One leapfrog step ``v += dt M^-1 (-K u)``, ``u += dt v`` of a P1 consistent rod held in the rows
    ``L_U``, ``L_V`` of its table (interleaved layout)."""
    step_tridiagonal_loaded(table, dt, np.int64(-1), 0.0)  # not a literal -1: no specialisation of its own


@kernel(fastmath=False, internal=True)
def step_tridiagonal_loaded(table, dt, where, load):
    """:func:`step_tridiagonal` with a force on the rod's first or last unknown: ``v += dt M^-1 (-K u + F
    e_k)``, ``load = F / D_k`` (``D_k`` the pivot of ``L D L^T`` at unknown ``k``), ``where`` its position in
    the table row (:func:`node_position`; -1: no force).

    The load is added to the scaled right-hand side as the forward sweep forms it: on the first unknown
    through the work row's ghost (its ``y_(i-1)``, with factor 1), on the last after the sweep (the rows
    after it in its chunk are decoupled padding), so the solve spreads the force as ``M^-1 e_k`` exactly,
    with no column over the nodes near the end (an unknown inside the rod would need the sweep's
    propagation within its chunk, which is not done here)."""
    n = int(table[L_SHAPE, 0])
    u = row_view(table, L_U)
    y = row_view(table, L_WORK)
    forward = row_view(table, L_FORWARD)
    constants = row_view(table, L_UNIFORM)
    y[ORIGIN - LANES] = load if where == ORIGIN else 0.0
    _forward_p1(u, y, row_view(table, L_LEFT), row_view(table, L_RIGHT), forward, constants, n)
    if where > ORIGIN:
        y[where] += load
    _couple_table(table, n)
    _backward_update(u[ORIGIN:], row_view(table, L_V)[ORIGIN:], y[ORIGIN:], row_view(table, L_BACKWARD)[ORIGIN:],
                     constants, n, dt)


@kernel(fastmath=False, internal=True)
def pack_nodes(x, packed, n, order):
    """:func:`pack` of a rod's nodes into a table row from ``ORIGIN`` (P1: all; P2: the vertices, even nodes),
    P2's midpoints from :func:`midpoint_origin` (the ghost rows untouched)."""
    # np.int64: literal arguments would compile pack once more for each
    pack(x, np.int64(0), order, packed, np.int64(ORIGIN), n)
    if order == 2:
        pack(x, np.int64(1), order, packed, midpoint_origin(n), n)


@kernel(fastmath=False, internal=True)
def unpack_nodes(packed, x, n, order):
    """The inverse of :func:`pack_nodes`."""
    unpack(packed, np.int64(ORIGIN), x, np.int64(0), order, n)
    if order == 2:
        unpack(packed, midpoint_origin(n), x, np.int64(1), order, n)


@kernel(fastmath=False)
def node_position(node, n, order):
    """Index of a rod's node in the table row of :func:`pack_nodes`."""
    if order == 1:
        return ORIGIN + position(node, n)
    if node % 2 == 0:
        return ORIGIN + position(node // 2, n)
    return midpoint_origin(n) + position(node // 2, n)


@kernel(fastmath=False, internal=True)
def _condensed_rows(uv, um, y, share, c1, c2, c3, c4, mid_left, mid_right, forward, count):
    """Shares, right-hand sides and local forward sweep of the rows after the first of the views (``count``
    entries, rows inside a chunk)."""
    for j in range(count):
        current = uv[j + LANES]
        middle = um[j + LANES]
        following = uv[j + 2 * LANES]
        share[j + LANES] = -(mid_left[j + LANES] * (current - middle) + mid_right[j + LANES] * (following - middle))
        force = (c1[j + LANES] * (uv[j] - current) + c2[j + LANES] * (um[j] - current)
                 + c3[j + LANES] * (middle - current) + c4[j + LANES] * (following - current))
        y[j + LANES] = force + forward[j + LANES] * y[j]


@kernel(fastmath=False, internal=True)
def _condensed_rows_uniform(uv, um, y, share, constants, count):
    """:func:`_condensed_rows` with the coefficients the constants of ``L_UNIFORM`` (same operations, same order)."""
    c1 = constants[2]
    c2 = constants[3]
    c3 = constants[4]
    c4 = constants[5]
    mid_left = constants[6]
    mid_right = constants[7]
    forward = constants[8]
    for j in range(count):
        current = uv[j + LANES]
        middle = um[j + LANES]
        following = uv[j + 2 * LANES]
        share[j + LANES] = -(mid_left * (current - middle) + mid_right * (following - middle))
        force = (c1 * (uv[j] - current) + c2 * (um[j] - current) + c3 * (middle - current)
                 + c4 * (following - current))
        y[j + LANES] = force + forward * y[j]


@kernel(fastmath=False, internal=True)
def _forward_condensed(u, y, share, c1, c2, c3, c4, mid_left, mid_right, forward, constants, n):
    """Midpoint shares, condensed right-hand sides and the local forward sweep of every chunk, fused, as
    :func:`_forward_p1`: ``u`` the displacement row (vertices from ``ORIGIN``, midpoints from
    :func:`midpoint_origin`), the other rows indexed as the vertices."""
    base = ORIGIN - LANES  # the views below start one row before the first row they compute
    middle = midpoint_origin(n) - LANES
    _ghost_rows(u[base:], n, np.bool_(True))  # not literals: one specialisation for both
    _ghost_rows(u[middle:], n, np.bool_(False))
    lo = int(constants[0]) * LANES
    hi = int(constants[1]) * LANES
    _condensed_rows(u[base:], u[middle:], y[base:], share[base:], c1[base:], c2[base:], c3[base:], c4[base:],
                    mid_left[base:], mid_right[base:], forward[base:], lo)
    _condensed_rows_uniform(u[base + lo :], u[middle + lo :], y[base + lo :], share[base + lo :], constants, hi - lo)
    at = base + hi
    _condensed_rows(u[at:], u[middle + hi :], y[at:], share[at:], c1[at:], c2[at:], c3[at:], c4[at:], mid_left[at:],
                    mid_right[at:], forward[at:], n * LANES - hi)


@kernel(fastmath=False, internal=True)
def _sweep_up_update_condensed(uv, vv, um, vm, y, share, backward, back_left, back_right, count, dt):
    """Backward sweep over ``j = count - 1 .. 0`` with the update of the vertices and midpoints."""
    for j in range(count - 1, -1, -1):
        following = y[j + LANES]
        acceleration = y[j] + backward[j] * following
        y[j] = acceleration
        velocity = vv[j] + dt * acceleration
        vv[j] = velocity
        uv[j] += dt * velocity
        middle = share[j] - back_left[j] * acceleration - back_right[j] * following
        velocity = vm[j] + dt * middle
        vm[j] = velocity
        um[j] += dt * velocity


@kernel(fastmath=False, internal=True)
def _sweep_up_update_condensed_uniform(uv, vv, um, vm, y, share, constants, count, dt):
    """:func:`_sweep_up_update_condensed` with the coefficients the constants of ``L_UNIFORM``."""
    backward = constants[9]
    back_left = constants[10]
    back_right = constants[11]
    for j in range(count - 1, -1, -1):
        following = y[j + LANES]
        acceleration = y[j] + backward * following
        y[j] = acceleration
        velocity = vv[j] + dt * acceleration
        vv[j] = velocity
        uv[j] += dt * velocity
        middle = share[j] - back_left * acceleration - back_right * following
        velocity = vm[j] + dt * middle
        vm[j] = velocity
        um[j] += dt * velocity


@kernel(fastmath=False, internal=True)
def step_condensed(table, dt):
    """One leapfrog step of a P2 consistent rod held in the rows ``L_U``, ``L_V`` of its table (interleaved
    layout, :func:`pack_nodes`): midpoints condensed, the vertex system solved in chunks."""
    step_condensed_loaded(table, dt, np.int64(-1), 0.0)  # not a literal -1: no specialisation of its own


@kernel(fastmath=False, internal=True)
def step_condensed_loaded(table, dt, where, load):
    """:func:`step_condensed` with a force ``F`` on the rod's first or last vertex (an end node): ``load = F /
    D_k`` (``D_k`` the pivot of the condensed vertex mass's ``L D L^T`` at that vertex), ``where`` its
    position (:func:`node_position`, -1: no force); as :func:`step_tridiagonal_loaded` (the midpoints see the
    force through the vertices' accelerations only)."""
    n = int(table[L_SHAPE, 0])
    width = n * LANES
    mid = midpoint_origin(n)
    u = row_view(table, L_U)
    v = row_view(table, L_V)
    y = row_view(table, L_WORK)
    share = row_view(table, L_SHARE)
    forward = row_view(table, L_FORWARD)
    constants = row_view(table, L_UNIFORM)
    y[ORIGIN - LANES] = load if where == ORIGIN else 0.0
    _forward_condensed(u, y, share, row_view(table, L_C1), row_view(table, L_C2), row_view(table, L_C3),
                       row_view(table, L_C4), row_view(table, L_MID_LEFT), row_view(table, L_MID_RIGHT), forward,
                       constants, n)
    if where > ORIGIN:
        y[where] += load
    _couple_table(table, n)
    # every row of every chunk downwards from its exact start (row n of y): [hi, n) and [0, lo) with the
    # arrays, the uniform rows between with the constants; the views from row 0
    uv = u[ORIGIN:]
    um = u[mid:]
    vv = v[ORIGIN:]
    vm = v[mid:]
    y = y[ORIGIN:]
    share = share[ORIGIN:]
    backward = row_view(table, L_BACKWARD)[ORIGIN:]
    back_left = row_view(table, L_BACK_LEFT)[ORIGIN:]
    back_right = row_view(table, L_BACK_RIGHT)[ORIGIN:]
    hi = int(constants[1]) * LANES
    lo = int(constants[0]) * LANES
    _sweep_up_update_condensed(uv[hi:], vv[hi:], um[hi:], vm[hi:], y[hi:], share[hi:], backward[hi:], back_left[hi:],
                               back_right[hi:], width - hi, dt)
    _sweep_up_update_condensed_uniform(uv[lo:], vv[lo:], um[lo:], vm[lo:], y[lo:], share[lo:], constants, hi - lo, dt)
    _sweep_up_update_condensed(uv, vv, um, vm, y, share, backward, back_left, back_right, lo, dt)
