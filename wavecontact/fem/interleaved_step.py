"""The consistent-mass explicit step with the rod's unknowns stored in ``LANES`` interleaved chunks.

A tridiagonal solve is two first-order recurrences, ``y_i = r_i + f_i y_(i-1)``
downwards and ``x_i = y_i + g_i x_(i+1)`` upwards; as one chain each costs the
latency of a multiplication and an addition per unknown.  Here the ``m``
unknowns are cut into ``LANES`` = 32 consecutive chunks of ``n = ceil(m /
LANES)`` and stored chunk-interleaved: unknown ``k = c n + i`` (chunk ``c``,
position ``i``) at ``X[i LANES + c]`` (padding unknowns beyond ``m`` are
decoupled and stay zero).  Row ``i`` of all chunks is then contiguous, the
stencil's neighbours ``i +- 1`` are the previous and next rows, and every pass
(stencil, both sweeps, update) is one loop over the array whose iterations
``LANES`` apart depend on each other: the compiler runs the chunks as SIMD
lanes.  Only a chunk's first and last rows see a neighbouring chunk.

Each sweep first runs every chunk from zero, then adds what the chunk before
it (forward) or after it (backward) contributes: the chunks' true end values
follow from their local ones in a short sequential pass over the chunks, and
their effect on a chunk, ``P_i e`` with ``P_i`` the product of the sweep's
factors from the chunk boundary to ``i`` and ``e`` the neighbour's end value,
is added by the same recurrence without right-hand side (``delta_i = f_i
delta_(i-1)``, a cheap streaming pass) on the rows where ``|P_i|`` exceeds
``LANE_TOLERANCE`` (``w`` rows; the mass matrices are diagonally dominant, so
``|f|, |g| <= 1/2`` and ``w`` is about 33 on uniform meshes; all rows of
chunks shorter than that).  The terms left out are below ``2^-64`` of an entry
of the result, so the solve equals the direct one to rounding, not bit for
bit.

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

from .._jit import kernel

__all__ = ["LANES", "LANE_MIN_UNKNOWNS", "LANE_MIN_VERTICES", "condensed_lane_rows", "lane_rows", "lanes_width",
           "node_position", "pack_nodes", "step_condensed", "step_tridiagonal", "table_width", "unpack_nodes"]

LANES = 32
LANE_TOLERANCE = 2.0**-64  # contributions of a neighbouring chunk left out, relative to an entry of the result
# smaller systems keep the flat layout: with fewer than about 40 rows per chunk the corrections cover most
# rows and cost more than the lanes save (docs/fem.md section 7)
LANE_MIN_UNKNOWNS = 1200
LANE_MIN_VERTICES = 1200  # the same for the vertex system of P2 (condensed midpoints)

# rows of the mass solve's table used by the interleaved layout (the flat solve's rows come first)
L_SHAPE = 24  # [0]: rows n per chunk (0: flat layout), [1]: forward correction rows, [2]: backward ones (P2: + 1)
L_LEFT = 25  # stencil, P1: r_i = -(left_i (u_(i-1) - u_i) + right_i (u_(i+1) - u_i)), scaled by 1 / D_i
L_RIGHT = 26
L_FORWARD = 27  # f_i of y_i = r_i + f_i y_(i-1) (0 at the first unknown and on the padding)
L_BACKWARD = 28  # g_i of x_i = y_i + g_i x_(i+1) (0 at the last unknown and on the padding)
L_FORWARD_END = 29  # per chunk: product of its forward factors (first LANES entries)
L_BACKWARD_START = 30  # per chunk: product of its backward factors
L_CARRY = 31  # scratch: true end values of the chunks
L_CORRECTION = 32  # scratch: the corrections of a sweep
L_WORK = 33  # scratch: the sweeps' values
L_U = 34  # displacements in the interleaved layout (inside the time loop)
L_V = 35  # velocities (P2: the vertices' first, then the midpoints', each n LANES long)
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
L_ROWS_END = 45


def lanes_width(unknowns: int) -> int:
    """Length of a row of the interleaved layout for ``unknowns`` unknowns (one spare row)."""
    return (-(-unknowns // LANES) + 1) * LANES


def table_width(minimum: int) -> int:
    """A row length of at least ``minimum`` doubles whose rows start 3 cache lines apart modulo 4 KiB.

    The step streams some twenty rows of the table at the same index; rows a multiple of 4 KiB apart
    would make every load look like it depends on the store just made to another row (the processor
    compares the addresses' low 12 bits first), which costs about a factor two in the P2 step.
    """
    return -(-(minimum - 24) // 512) * 512 + 24 if minimum > 24 else 24


def _interleave(values: np.ndarray, n: int) -> np.ndarray:
    """``values`` (padded with zeros to ``n LANES``) in the interleaved order."""
    padded = np.zeros(n * LANES)
    padded[: values.size] = values
    return padded.reshape(LANES, n).T.ravel()


def _correction_rows(factors: np.ndarray, n: int, reverse: bool) -> tuple:
    """Per chunk, the products of ``factors`` from the chunk boundary (the top one, or the bottom one if
    ``reverse``): the whole chunk's product and the number of rows where it exceeds ``LANE_TOLERANCE``."""
    chunks = np.zeros(n * LANES)
    chunks[: factors.size] = factors
    chunks = chunks.reshape(LANES, n)
    if reverse:
        chunks = chunks[:, ::-1]
    products = np.cumprod(chunks, axis=1)
    rows = int(np.max(np.sum(np.abs(products) > LANE_TOLERANCE, axis=1)))
    return products[:, -1].copy(), max(rows, 1)


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
    n = -(-m // LANES)
    left = np.zeros(m)
    right = np.zeros(m)
    left[1:] = scale[1:] * near
    right[:-1] = scale[:-1] * near
    table[L_LEFT, : n * LANES] = _interleave(left, n)
    table[L_RIGHT, : n * LANES] = _interleave(right, n)
    table[L_FORWARD, : n * LANES] = _interleave(forward, n)
    table[L_BACKWARD, : n * LANES] = _interleave(backward, n)
    end, forward_rows = _correction_rows(forward, n, reverse=False)
    start, backward_rows = _correction_rows(backward, n, reverse=True)
    table[L_FORWARD_END, :LANES] = end
    table[L_BACKWARD_START, :LANES] = start
    table[L_SHAPE, :3] = (n, forward_rows, backward_rows)


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
    n = -(-m // LANES)
    la, lc = coefficients["left_a"], coefficients["left_c"]
    ra, rc = coefficients["right_a"], coefficients["right_c"]
    c1, c2, c3, c4 = (np.zeros(m) for _ in range(4))
    c1[1:] = ra  # uv_(k-1) in element k - 1's right part
    c2[1:] = -(ra + rc)
    c3[:-1] = -(la + lc)
    c4[:-1] = lc
    per_vertex = {L_C1: c1 * scale, L_C2: c2 * scale, L_C3: c3 * scale, L_C4: c4 * scale,
                  L_FORWARD: forward, L_BACKWARD: backward}
    for row, values in per_vertex.items():
        table[row, : n * LANES] = _interleave(values, n)
    for row, name in ((L_MID_LEFT, "mid_left"), (L_MID_RIGHT, "mid_right"), (L_BACK_LEFT, "back_left"),
                      (L_BACK_RIGHT, "back_right")):
        table[row, : n * LANES] = _interleave(coefficients[name], n)
    end, forward_rows = _correction_rows(forward, n, reverse=False)
    start, backward_rows = _correction_rows(backward, n, reverse=True)
    table[L_FORWARD_END, :LANES] = end
    table[L_BACKWARD_START, :LANES] = start
    # one backward row more than the solve needs: a midpoint also reads the vertex after it
    table[L_SHAPE, :3] = (n, forward_rows, backward_rows + 1)


@kernel(fastmath=False)
def pack(x, packed, n):
    """``packed[i LANES + c] = x[c n + i]`` for the ``x.size`` unknowns (the padding untouched)."""
    for c in range(LANES):
        for i in range(n):
            k = c * n + i
            if k < x.size:
                packed[i * LANES + c] = x[k]


@kernel(fastmath=False)
def unpack(packed, x, n):
    """The inverse of :func:`pack`."""
    for c in range(LANES):
        for i in range(n):
            k = c * n + i
            if k < x.size:
                x[k] = packed[i * LANES + c]


@kernel(fastmath=False)
def position(k, n):
    """Index of unknown ``k`` in the interleaved layout with ``n`` rows."""
    return (k % n) * LANES + k // n


@kernel(fastmath=False)
def _forward_p1(u, y, left, right, forward, n):
    """Stencil and local forward sweep of every chunk, fused: ``y_i = r_i + f_i y_(i-1)`` from ``y = 0``
    above each chunk (the first row of a chunk reads the last row of the chunk before it for the stencil)."""
    last = (n - 1) * LANES
    y[0] = -(right[0] * (u[LANES] - u[0]))
    for c in range(LANES - 1):
        current = u[c + 1]
        y[c + 1] = -(left[c + 1] * (u[last + c] - current) + right[c + 1] * (u[LANES + c + 1] - current))
    for j in range(last - LANES):
        current = u[j + LANES]
        force = -(left[j + LANES] * (u[j] - current) + right[j + LANES] * (u[j + 2 * LANES] - current))
        y[j + LANES] = force + forward[j + LANES] * y[j]
    for c in range(LANES - 1):
        current = u[last + c]
        force = -(left[last + c] * (u[last - LANES + c] - current) + right[last + c] * (u[c + 1] - current))
        y[last + c] = force + forward[last + c] * y[last - LANES + c]
    current = u[last + LANES - 1]
    force = -(left[last + LANES - 1] * (u[last - 1] - current))
    y[last + LANES - 1] = force + forward[last + LANES - 1] * y[last - 1]


@kernel(fastmath=False)
def _correct_forward(y, forward, end, carry, correction, n, rows):
    """Add the chunks above to the local forward sweep: ``carry[c]`` the true last value of chunk ``c``,
    then ``delta_i = f_i delta_(i-1)`` from ``delta_0 = f_0 carry[c - 1]`` over the first ``rows`` rows."""
    last = (n - 1) * LANES
    previous = y[last]
    carry[0] = previous
    for c in range(1, LANES):
        previous = y[last + c] + end[c] * previous
        carry[c] = previous
    correction[0] = 0.0
    for c in range(1, LANES):
        delta = forward[c] * carry[c - 1]
        correction[c] = delta
        y[c] += delta
    for j in range((rows - 1) * LANES):
        delta = forward[j + LANES] * correction[j]
        correction[j + LANES] = delta
        y[j + LANES] += delta


@kernel(fastmath=False)
def _sweep_up(y, backward, count):
    """``y_j <- y_j + g_j y_(j + LANES)`` for ``j = count - 1 .. 0`` (local backward sweep, no update)."""
    for j in range(count - 1, -1, -1):
        y[j] = y[j] + backward[j] * y[j + LANES]


@kernel(fastmath=False)
def _sweep_up_update(u, v, y, backward, count, dt):
    """The backward sweep over ``j = count - 1 .. 0`` with the leapfrog update of those unknowns."""
    for j in range(count - 1, -1, -1):
        acceleration = y[j] + backward[j] * y[j + LANES]
        y[j] = acceleration
        velocity = v[j] + dt * acceleration
        v[j] = velocity
        u[j] += dt * velocity


@kernel(fastmath=False)
def _correct_up_update(u, v, y, backward, correction, count, dt):
    """Correction ``e_j = g_j e_(j + LANES)`` added over ``j = count - 1 .. 0``, with the update."""
    for j in range(count - 1, -1, -1):
        delta = backward[j] * correction[j + LANES]
        correction[j] = delta
        acceleration = y[j] + delta
        y[j] = acceleration
        velocity = v[j] + dt * acceleration
        v[j] = velocity
        u[j] += dt * velocity


@kernel(fastmath=False)
def _backward_update(u, v, y, backward, start, carry, correction, n, rows, dt):
    """Backward sweep, its correction from the chunks below and the leapfrog update, on the local forward
    result ``y`` (overwritten with the accelerations)."""
    last = (n - 1) * LANES
    split = (n - rows) * LANES  # rows from here on are corrected before their update
    _sweep_up(y[split:], backward[split:], last - split)
    _sweep_up_update(u, v, y, backward, split, dt)
    following = y[LANES - 1]
    carry[LANES - 1] = following
    for c in range(LANES - 2, -1, -1):
        following = y[c] + start[c] * following
        carry[c] = following
    for c in range(LANES - 1):
        correction[last + c] = backward[last + c] * carry[c + 1]
    correction[last + LANES - 1] = 0.0
    for j in range(last, last + LANES):
        acceleration = y[j] + correction[j]
        y[j] = acceleration
        velocity = v[j] + dt * acceleration
        v[j] = velocity
        u[j] += dt * velocity
    _correct_up_update(u[split:], v[split:], y[split:], backward[split:], correction[split:], last - split, dt)


@kernel(fastmath=False)
def step_tridiagonal(table, dt):
    """One leapfrog step ``v += dt M^-1 (-K u)``, ``u += dt v`` of a P1 consistent rod held in the rows
    ``L_U``, ``L_V`` of its table (interleaved layout)."""
    n = int(table[L_SHAPE, 0])
    forward_rows = min(int(table[L_SHAPE, 1]), n)
    backward_rows = min(int(table[L_SHAPE, 2]), n)
    u = table[L_U]
    v = table[L_V]
    y = table[L_WORK]
    forward = table[L_FORWARD]
    _forward_p1(u, y, table[L_LEFT], table[L_RIGHT], forward, n)
    _correct_forward(y, forward, table[L_FORWARD_END], table[L_CARRY], table[L_CORRECTION], n, forward_rows)
    _backward_update(u, v, y, table[L_BACKWARD], table[L_BACKWARD_START], table[L_CARRY], table[L_CORRECTION],
                     n, backward_rows, dt)


@kernel(fastmath=False)
def pack_nodes(x, packed, n, order):
    """:func:`pack` of a rod's nodes: P2's vertices (even nodes) into ``packed[:W]``, midpoints into
    ``packed[W:]`` (``W = n LANES``)."""
    if order == 1:
        pack(x, packed, n)
        return
    width = n * LANES
    pack(x[0::2], packed[:width], n)
    pack(x[1::2], packed[width:], n)


@kernel(fastmath=False)
def unpack_nodes(packed, x, n, order):
    """The inverse of :func:`pack_nodes`."""
    if order == 1:
        unpack(packed, x, n)
        return
    width = n * LANES
    unpack(packed[:width], x[0::2], n)
    unpack(packed[width:], x[1::2], n)


@kernel(fastmath=False)
def node_position(node, n, order):
    """Index of a rod's node in the layout of :func:`pack_nodes`."""
    if order == 1:
        return position(node, n)
    if node % 2 == 0:
        return position(node // 2, n)
    return n * LANES + position(node // 2, n)


@kernel(fastmath=False, inline="always")
def _condensed_force(uv, um, c1, c2, c3, c4, mid_left, mid_right, share, j, before, after):
    """Vertex ``j``'s scaled condensed right-hand side and (stored) its element's midpoint share; ``before``
    and ``after`` index the vertex before and after ``j`` (``before`` is also the element before)."""
    current = uv[j]
    middle = um[j]
    following = uv[after]
    share[j] = -(mid_left[j] * (current - middle) + mid_right[j] * (following - middle))
    return (c1[j] * (uv[before] - current) + c2[j] * (um[before] - current) + c3[j] * (middle - current)
            + c4[j] * (following - current))


@kernel(fastmath=False)
def _forward_condensed(uv, um, y, share, c1, c2, c3, c4, mid_left, mid_right, forward, n):
    """Midpoint shares, condensed right-hand sides and the local forward sweep of every chunk, fused."""
    last = (n - 1) * LANES
    y[0] = _condensed_force(uv, um, c1, c2, c3, c4, mid_left, mid_right, share, 0, 0, LANES)
    for c in range(LANES - 1):
        y[c + 1] = _condensed_force(uv, um, c1, c2, c3, c4, mid_left, mid_right, share, c + 1, last + c,
                                    LANES + c + 1)
    for j in range(last - LANES):
        current = uv[j + LANES]
        middle = um[j + LANES]
        following = uv[j + 2 * LANES]
        share[j + LANES] = -(mid_left[j + LANES] * (current - middle) + mid_right[j + LANES] * (following - middle))
        force = (c1[j + LANES] * (uv[j] - current) + c2[j + LANES] * (um[j] - current)
                 + c3[j + LANES] * (middle - current) + c4[j + LANES] * (following - current))
        y[j + LANES] = force + forward[j + LANES] * y[j]
    for c in range(LANES - 1):
        force = _condensed_force(uv, um, c1, c2, c3, c4, mid_left, mid_right, share, last + c, last - LANES + c,
                                 c + 1)
        y[last + c] = force + forward[last + c] * y[last - LANES + c]
    j = last + LANES - 1
    force = _condensed_force(uv, um, c1, c2, c3, c4, mid_left, mid_right, share, j, j - LANES, j)
    y[j] = force + forward[j] * y[j - LANES]


@kernel(fastmath=False, inline="always")
def _update_pair(uv, vv, um, vm, share, back_left, back_right, j, acceleration, following, dt):
    """Leapfrog update of vertex ``j`` (acceleration given) and of its element's midpoint (``following``: the
    acceleration of the vertex after it)."""
    velocity = vv[j] + dt * acceleration
    vv[j] = velocity
    uv[j] += dt * velocity
    middle = share[j] - back_left[j] * acceleration - back_right[j] * following
    velocity = vm[j] + dt * middle
    vm[j] = velocity
    um[j] += dt * velocity


@kernel(fastmath=False)
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


@kernel(fastmath=False)
def _correct_up_update_condensed(uv, vv, um, vm, y, share, backward, back_left, back_right, correction, count, dt):
    """Correction ``e_j = g_j e_(j + LANES)`` over ``j = count - 1 .. 0`` with the updates."""
    for j in range(count - 1, -1, -1):
        delta = backward[j] * correction[j + LANES]
        correction[j] = delta
        acceleration = y[j] + delta
        y[j] = acceleration
        velocity = vv[j] + dt * acceleration
        vv[j] = velocity
        uv[j] += dt * velocity
        middle = share[j] - back_left[j] * acceleration - back_right[j] * y[j + LANES]
        velocity = vm[j] + dt * middle
        vm[j] = velocity
        um[j] += dt * velocity


@kernel(fastmath=False)
def step_condensed(table, dt):
    """One leapfrog step of a P2 consistent rod held in the rows ``L_U``, ``L_V`` of its table (interleaved
    layout, :func:`pack_nodes`): midpoints condensed, the vertex system solved in chunks."""
    n = int(table[L_SHAPE, 0])
    forward_rows = min(int(table[L_SHAPE, 1]), n)
    backward_rows = min(int(table[L_SHAPE, 2]), n)
    width = n * LANES
    uv = table[L_U, :width]
    um = table[L_U, width : 2 * width]
    vv = table[L_V, :width]
    vm = table[L_V, width : 2 * width]
    y = table[L_WORK]
    share = table[L_SHARE]
    forward = table[L_FORWARD]
    backward = table[L_BACKWARD]
    back_left = table[L_BACK_LEFT]
    back_right = table[L_BACK_RIGHT]
    carry = table[L_CARRY]
    correction = table[L_CORRECTION]
    _forward_condensed(uv, um, y, share, table[L_C1], table[L_C2], table[L_C3], table[L_C4], table[L_MID_LEFT],
                       table[L_MID_RIGHT], forward, n)
    _correct_forward(y, forward, table[L_FORWARD_END], carry, correction, n, forward_rows)
    last = (n - 1) * LANES
    split = (n - backward_rows) * LANES
    _sweep_up(y[split:], backward[split:], last - split)
    _sweep_up_update_condensed(uv, vv, um, vm, y, share, backward, back_left, back_right, split, dt)
    start = table[L_BACKWARD_START]
    following = y[LANES - 1]
    carry[LANES - 1] = following
    for c in range(LANES - 2, -1, -1):
        following = y[c] + start[c] * following
        carry[c] = following
    for c in range(LANES - 1):
        correction[last + c] = backward[last + c] * carry[c + 1]
        y[last + c] += correction[last + c]
        _update_pair(uv, vv, um, vm, share, back_left, back_right, last + c, y[last + c], carry[c + 1], dt)
    correction[last + LANES - 1] = 0.0
    _update_pair(uv, vv, um, vm, share, back_left, back_right, last + LANES - 1, y[last + LANES - 1], 0.0, dt)
    _correct_up_update_condensed(uv[split:], vv[split:], um[split:], vm[split:], y[split:], share[split:],
                                 backward[split:], back_left[split:], back_right[split:], correction[split:],
                                 last - split, dt)
