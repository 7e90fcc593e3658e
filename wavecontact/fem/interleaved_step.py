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
factors from the chunk boundary to ``i``, is added on the rows where ``|P_i|``
exceeds ``LANE_TOLERANCE`` (``w`` rows; the mass matrices are diagonally
dominant, so ``|f|, |g| <= 1/2`` and ``w`` is about 33 on uniform meshes).  The
terms left out are below ``2^-64`` of an entry of the result, so the solve
equals the direct one to rounding, not bit for bit.

The layout lives only inside the time loop: :func:`pack` and :func:`unpack`
convert at its start, at its energy checks and at its end.  The state and the
coefficients are rows of the mass solve's table (rows ``L_*``); the kernels'
loops are written as single loops with constant offsets (``j + LANES``) and
counting down to zero where they run upwards through the rod, the forms the
compiler vectorizes.
"""

from __future__ import annotations

import numpy as np

from .._jit import kernel

__all__ = ["LANES", "LANE_MIN_UNKNOWNS", "lane_rows", "lanes_width", "pack", "step_tridiagonal", "unpack"]

LANES = 32
LANE_TOLERANCE = 2.0**-64  # contributions of a neighbouring chunk left out, relative to an entry of the result
LANE_MIN_UNKNOWNS = 2000  # smaller systems keep the flat layout (the chunks' corrections would dominate)

# rows of the mass solve's table used by the interleaved layout (the flat solve's rows come first)
L_SHAPE = 24  # [0]: rows n per chunk (0: flat layout), [1]: forward correction rows, [2]: backward ones
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
L_V = 35  # velocities
L_ROWS_END = 36


def lanes_width(unknowns: int) -> int:
    """Length of a row of the interleaved layout for ``unknowns`` unknowns (one spare row)."""
    return (-(-unknowns // LANES) + 1) * LANES


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
