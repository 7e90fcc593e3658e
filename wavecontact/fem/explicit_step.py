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
  independent recurrences at the price of a few more multiplications per node
  (the products are formed on the fly and the last four values kept in
  registers, so the sweep reads one coefficient and one value per node);
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
T_FORWARD = 0  # a_i of the forward sweep y_i = r_i + a_i y_(i-1) (a_0 = 0)
T_INVERSE_PIVOT = 1  # 1 / D_i
T_BACKWARD = 2  # b_i of x_i = y_i / D_i + b_i x_(i+1) (b_(m-1) = 0)
T_MID_INVERSE = 3  # condensed P2 (over all n nodes, midpoint j = 2e + 1): 1 / M[j, j]
T_MID_LEFT = 4  # M[j, j - 1]
T_MID_RIGHT = 5  # M[j, j + 1]
T_WORK = 6  # rows 6, 7: scratch (the vertex system of P2; no allocation per step)
T_ROWS = 8


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
    table[T_FORWARD, :m] = forward
    table[T_BACKWARD, :m] = backward


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
    # pentadiagonal (P2).  The guarded form is kept on purpose: a branch-free interior loop
    # (range(2, n - 2)) measured 14 times slower with numba 0.6x (negative-index wraparound checks)
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
def _tridiagonal_solve(table, x, m):
    """``x <- T^-1 x`` for the tridiagonal ``T`` of ``table`` (``m`` unknowns, in place).

    Each sweep is unrolled four times with the last four inputs and outputs
    carried in registers: ``y_i = r_i + a_i r_(i-1) + a_i a_(i-1) r_(i-2) +
    a_i a_(i-1) a_(i-2) r_(i-3) + (a_i ... a_(i-3)) y_(i-4)``, so four
    independent recurrences are in flight.
    """
    a = table[T_FORWARD]
    b = table[T_BACKWARD]
    inverse = table[T_INVERSE_PIVOT]
    if m <= UNROLL:
        for i in range(1, m):
            x[i] += a[i] * x[i - 1]
        x[m - 1] *= inverse[m - 1]
        for i in range(m - 2, -1, -1):
            x[i] = x[i] * inverse[i] + b[i] * x[i + 1]
        return
    # forward sweep, y_i = r_i + a_i y_(i-1); o* are inputs r, y* outputs, a* coefficients before i
    o3 = x[0]
    y4 = o3
    o2 = x[1]
    y3 = o2 + a[1] * y4
    x[1] = y3
    o1 = x[2]
    y2 = o1 + a[2] * y3
    x[2] = y2
    current = x[3]
    y1 = current + a[3] * y2
    x[3] = y1
    o3, o2, o1 = o2, o1, current
    a3, a2, a1 = a[1], a[2], a[3]
    for i in range(UNROLL, m):
        current = x[i]
        a0 = a[i]
        p1 = a0 * a1
        p2 = p1 * a2
        p3 = p2 * a3
        value = current + a0 * o1 + p1 * o2 + p2 * o3 + p3 * y4
        x[i] = value
        o3, o2, o1 = o2, o1, current
        y4, y3, y2, y1 = y3, y2, y1, value
        a3, a2, a1 = a2, a1, a0
    # backward sweep, x_i = e_i + b_i x_(i+1) with e_i = y_i / D_i
    e3 = x[m - 1] * inverse[m - 1]
    z4 = e3
    x[m - 1] = z4
    e2 = x[m - 2] * inverse[m - 2]
    z3 = e2 + b[m - 2] * z4
    x[m - 2] = z3
    e1 = x[m - 3] * inverse[m - 3]
    z2 = e1 + b[m - 3] * z3
    x[m - 3] = z2
    current = x[m - 4] * inverse[m - 4]
    z1 = current + b[m - 4] * z2
    x[m - 4] = z1
    e3, e2, e1 = e2, e1, current
    b3, b2, b1 = b[m - 2], b[m - 3], b[m - 4]
    for i in range(m - 1 - UNROLL, -1, -1):
        current = x[i] * inverse[i]
        b0 = b[i]
        q1 = b0 * b1
        q2 = q1 * b2
        q3 = q2 * b3
        value = current + b0 * e1 + q1 * e2 + q2 * e3 + q3 * z4
        x[i] = value
        e3, e2, e1 = e2, e1, current
        z4, z3, z2, z1 = z3, z2, z1, value
        b3, b2, b1 = b2, b1, b0


@kernel(fastmath=False)
def mass_acceleration(kind, table, r):
    """Overwrite the forces ``r`` with ``M^-1 r`` (the mass solve prepared by :func:`prepare_mass`)."""
    n = r.size
    if kind == MASS_LUMPED:
        for i in range(n):
            r[i] *= table[0, i]
        return
    if kind == MASS_TRIDIAGONAL:
        _tridiagonal_solve(table, r, n)
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
    _tridiagonal_solve(table, vertex, m)
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
    _stiffness_forces(u, bands, a)
    if kind == MASS_LUMPED:  # the mass and the update in one pass
        inverse = table[0]
        for i in range(u.size):
            velocity = v[i] + dt * (a[i] * inverse[i])
            v[i] = velocity
            u[i] += dt * velocity
        return
    mass_acceleration(kind, table, a)
    for i in range(u.size):
        velocity = v[i] + dt * a[i]
        v[i] = velocity
        u[i] += dt * velocity
