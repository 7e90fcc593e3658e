"""One central-difference step of a rod on any mesh: stiffness stencil, mass solve, update.

The mass solve is prepared once per run (:func:`prepare_mass`) as a few plain
arrays, so that a step allocates nothing and runs a handful of operations per
node:

* lumped mass: a multiplication by the inverse masses;
* consistent P1 mass (tridiagonal): ``L D L^T`` factorized once; each of the
  two triangular sweeps is a first-order recurrence ``y_i = r_i + a_i y_(i-1)``,
  whose speed would be the latency of one multiply-add per node.  Unrolled
  four times (``y_i = r_i + a_i r_(i-1) + a_i a_(i-1) r_(i-2) + ... +
  (a_i ... a_(i-3)) y_(i-4)``, the products tabulated once) it runs four
  independent recurrences at the price of three more multiply-adds per node;
* consistent P2 mass: the midpoint nodes couple only to their element's two
  vertices, so they are eliminated first (static condensation) and the
  vertices solve a tridiagonal system as above.

``prepare_mass`` returns ``(kind, table)``: ``table`` a 2D float array whose
rows are listed at ``T_*``; the kernels read it by row.
"""

from __future__ import annotations

import numpy as np

from .._jit import kernel

__all__ = ["MASS_CONDENSED", "MASS_LUMPED", "MASS_TRIDIAGONAL", "mass_acceleration", "prepare_mass", "step_rod"]

MASS_LUMPED = 0
MASS_TRIDIAGONAL = 1  # P1 consistent
MASS_CONDENSED = 2  # P2 consistent: midpoints condensed, vertices tridiagonal

UNROLL = 4  # independent recurrences per triangular sweep
# rows of the table of a tridiagonal solve over m unknowns (L D L^T, L unit lower bidiagonal)
T_FORWARD = 0  # rows 0..3: products a_i, a_i a_(i-1), ... of the forward sweep y_i = r_i + a_i y_(i-1)
T_INVERSE_PIVOT = 4  # 1 / D_i
T_BACKWARD = 5  # rows 5..8: products b_i, b_i b_(i+1), ... of x_i = y_i / D_i + b_i x_(i+1)
T_MID_INVERSE = 9  # condensed P2 (over all n nodes, midpoint j = 2e + 1): 1 / M[j, j]
T_MID_LEFT = 10  # M[j, j - 1]
T_MID_RIGHT = 11  # M[j, j + 1]
T_WORK = 12  # rows 12, 13: scratch of the sweeps (no allocation per step)
T_ROWS = 14


def _tridiagonal(diagonal: np.ndarray, off: np.ndarray, table: np.ndarray) -> None:
    """``L D L^T`` of the symmetric tridiagonal ``(diagonal, off)`` as the unrolled sweeps' products."""
    m = diagonal.size
    pivot = np.empty(m)
    forward = np.zeros(m)  # a_i = -L[i, i-1]
    pivot[0] = diagonal[0]
    for i in range(1, m):
        multiplier = off[i - 1] / pivot[i - 1]
        forward[i] = -multiplier
        pivot[i] = diagonal[i] - multiplier * off[i - 1]
    backward = np.zeros(m)  # b_i = -L[i+1, i] = -off_i / D_i
    backward[: m - 1] = -off / pivot[: m - 1]
    table[T_INVERSE_PIVOT, :m] = 1.0 / pivot
    product_forward = np.ones(m)
    product_backward = np.ones(m)
    for k in range(UNROLL):
        earlier = np.zeros(m)  # a_(i-k)
        earlier[k:] = forward[: max(m - k, 0)]
        later = np.zeros(m)  # b_(i+k)
        later[: max(m - k, 0)] = backward[k:]
        product_forward = product_forward * earlier
        product_backward = product_backward * later
        table[T_FORWARD + k, :m] = product_forward
        table[T_BACKWARD + k, :m] = product_backward


def prepare_mass(disc) -> tuple:
    """``(kind, table)`` of the mass solve of one rod (see the module docstring).

    ``disc`` is a :class:`~wavecontact.fem.discretization.RodDiscretization`.
    """
    n = disc.n_nodes
    table = np.zeros((T_ROWS, n))
    if disc.mass_kind == "lumped":
        table[0] = 1.0 / disc.lumped_mass
        return MASS_LUMPED, table
    matrix = disc.mass_matrix.tocsr()
    if disc.order == 1:
        _tridiagonal(matrix.diagonal(0).copy(), matrix.diagonal(1).copy(), table)
        return MASS_TRIDIAGONAL, table
    if disc.order != 2:
        raise ValueError(f"no mass solve for order {disc.order}")
    # static condensation of the midpoints (odd nodes): S = M_vv - M_vm M_mm^-1 M_mv, tridiagonal
    dense_diag = matrix.diagonal(0)
    mids = np.arange(1, n, 2)
    left = np.asarray(matrix[mids, mids - 1]).ravel()
    right = np.asarray(matrix[mids, mids + 1]).ravel()
    inverse = 1.0 / dense_diag[mids]
    vertices = np.arange(0, n, 2)
    diagonal = dense_diag[vertices].copy()
    diagonal[:-1] -= left * left * inverse  # vertex 2e couples to midpoint 2e + 1 through M[2e + 1, 2e]
    diagonal[1:] -= right * right * inverse  # vertex 2e + 2 through M[2e + 1, 2e + 2]
    off = np.asarray(matrix[vertices[:-1], vertices[1:]]).ravel() - right * inverse * left
    _tridiagonal(diagonal, off, table)
    table[T_MID_INVERSE, mids] = inverse
    table[T_MID_LEFT, mids] = left
    table[T_MID_RIGHT, mids] = right
    return MASS_CONDENSED, table


@kernel(fastmath=False)
def _stiffness_forces(u, bands, out):
    """``out = -K u`` written with differences (``K`` rows sum to zero): tridiagonal or pentadiagonal."""
    n = u.size
    if bands.shape[0] == 2:
        if n == 1:
            out[0] = 0.0
            return
        out[0] = -bands[1, 0] * (u[1] - u[0])
        for i in range(1, n - 1):
            out[i] = -bands[1, i - 1] * (u[i - 1] - u[i]) - bands[1, i] * (u[i + 1] - u[i])
        out[n - 1] = -bands[1, n - 2] * (u[n - 2] - u[n - 1])
        return
    for i in range(n):
        total = 0.0
        if i >= 2:
            total -= bands[2, i - 2] * (u[i - 2] - u[i])
        if i >= 1:
            total -= bands[1, i - 1] * (u[i - 1] - u[i])
        if i + 1 < n:
            total -= bands[1, i] * (u[i + 1] - u[i])
        if i + 2 < n:
            total -= bands[2, i] * (u[i + 2] - u[i])
        out[i] = total


@kernel(fastmath=False)
def _tridiagonal_solve(table, r, x, m):
    """``x = T^-1 r`` for the tridiagonal ``T`` of ``table`` (``m`` unknowns; ``r`` is overwritten)."""
    y = r
    if m <= UNROLL:
        for i in range(1, m):
            y[i] += table[T_FORWARD, i] * y[i - 1]
        x[m - 1] = y[m - 1] * table[T_INVERSE_PIVOT, m - 1]
        for i in range(m - 2, -1, -1):
            x[i] = y[i] * table[T_INVERSE_PIVOT, i] + table[T_BACKWARD, i] * x[i + 1]
        return
    # forward: four recurrences y_i = c_i + (a_i ... a_(i-3)) y_(i-4); c_i from the original r
    work = table[T_WORK]
    for i in range(m):
        work[i] = r[i]
    for i in range(1, UNROLL):
        y[i] += table[T_FORWARD, i] * y[i - 1]
    for i in range(UNROLL, m):
        y[i] = (work[i] + table[T_FORWARD, i] * work[i - 1] + table[T_FORWARD + 1, i] * work[i - 2]
                + table[T_FORWARD + 2, i] * work[i - 3] + table[T_FORWARD + 3, i] * y[i - 4])
    # backward: x_i = e_i + b_i x_(i+1), e_i = y_i / D_i
    for i in range(m):
        work[i] = y[i] * table[T_INVERSE_PIVOT, i]
    x[m - 1] = work[m - 1]
    for i in range(m - 2, m - 1 - UNROLL, -1):
        x[i] = work[i] + table[T_BACKWARD, i] * x[i + 1]
    for i in range(m - 1 - UNROLL, -1, -1):
        x[i] = (work[i] + table[T_BACKWARD, i] * work[i + 1] + table[T_BACKWARD + 1, i] * work[i + 2]
                + table[T_BACKWARD + 2, i] * work[i + 3] + table[T_BACKWARD + 3, i] * x[i + 4])


@kernel(fastmath=False)
def mass_acceleration(kind, table, r):
    """Overwrite the forces ``r`` with ``M^-1 r`` (the mass solve prepared by :func:`prepare_mass`)."""
    n = r.size
    if kind == MASS_LUMPED:
        for i in range(n):
            r[i] *= table[0, i]
        return
    if kind == MASS_TRIDIAGONAL:
        _tridiagonal_solve(table, r, r, n)
        return
    # condensed P2: vertex right-hand sides lose the midpoints' share, then the midpoints follow
    m = (n + 1) // 2
    vertex = table[T_WORK + 1]
    for e in range(m):
        vertex[e] = r[2 * e]
    for e in range(m - 1):
        share = r[2 * e + 1] * table[T_MID_INVERSE, 2 * e + 1]
        vertex[e] -= table[T_MID_LEFT, 2 * e + 1] * share
        vertex[e + 1] -= table[T_MID_RIGHT, 2 * e + 1] * share
    _tridiagonal_solve(table, vertex, vertex, m)
    for e in range(m):
        r[2 * e] = vertex[e]
    for j in range(1, n, 2):
        r[j] = (r[j] - table[T_MID_LEFT, j] * r[j - 1] - table[T_MID_RIGHT, j] * r[j + 1]) * table[T_MID_INVERSE, j]


@kernel(fastmath=False)
def elastic_acceleration(u, bands, kind, table, out):
    """``out = M^-1 (-K u)`` (length/time^2)."""
    _stiffness_forces(u, bands, out)
    mass_acceleration(kind, table, out)


@kernel(fastmath=False)
def step_rod(u, v, a, bands, kind, table, dt):
    """One leapfrog step of a free rod: ``v += dt M^-1 (-K u)``, ``u += dt v`` (``a``: scratch)."""
    elastic_acceleration(u, bands, kind, table, a)
    for i in range(u.size):
        velocity = v[i] + dt * a[i]
        v[i] = velocity
        u[i] += dt * velocity
