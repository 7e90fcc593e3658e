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
        near = bands[1]
        for j in range(n - 2):  # node i = j + 1
            current = u[j + 1]
            out[j + 1] = -near[j] * (u[j] - current) - near[j + 1] * (u[j + 2] - current)
        out[n - 1] = -bands[1, n - 2] * (u[n - 2] - u[n - 1])
        return
    # pentadiagonal (P2): the four edge nodes guarded, the interior branch-free
    if n < 5:
        for i in range(n):
            out[i] = _pentadiagonal_force(u, bands, i, n)
        return
    for i in (0, 1):
        out[i] = _pentadiagonal_force(u, bands, i, n)
    near = bands[1]
    far = bands[2]
    for j in range(n - 4):  # node i = j + 2; indices written as j + k >= 0 (no wraparound checks)
        current = u[j + 2]
        total = 0.0
        total -= far[j] * (u[j] - current)
        total -= near[j + 1] * (u[j + 1] - current)
        total -= near[j + 2] * (u[j + 3] - current)
        total -= far[j + 2] * (u[j + 4] - current)
        out[j + 2] = total
    for i in (n - 2, n - 1):
        out[i] = _pentadiagonal_force(u, bands, i, n)


@kernel(fastmath=False)
def _pentadiagonal_force(u, bands, i, n):
    """``-(K u)_i`` of a pentadiagonal ``K`` at any node (the guarded form, for the edges)."""
    total = 0.0
    if i >= 2:
        total -= bands[2, i - 2] * (u[i - 2] - u[i])
    if i >= 1:
        total -= bands[1, i - 1] * (u[i - 1] - u[i])
    if i + 1 < n:
        total -= bands[1, i] * (u[i + 1] - u[i])
    if i + 2 < n:
        total -= bands[2, i] * (u[i + 2] - u[i])
    return total


@kernel(fastmath=False)
def _leapfrog_pentadiagonal(u, v, bands, inverse, dt):
    """P2 lumped step in one sweep: ``v += dt M^-1 (-K u)``, ``u += dt v`` (at least 5 nodes).

    The two previous nodes' old displacements are kept in registers, so each
    node is updated right after its force is known, without a scratch array.
    """
    n = u.size
    older = u[0]
    old = u[1]
    force0 = _pentadiagonal_force(u, bands, 0, n)
    force1 = _pentadiagonal_force(u, bands, 1, n)
    velocity = v[0] + dt * (force0 * inverse[0])
    v[0] = velocity
    u[0] = older + dt * velocity
    velocity = v[1] + dt * (force1 * inverse[1])
    v[1] = velocity
    u[1] = old + dt * velocity
    near = bands[1]
    far = bands[2]
    for j in range(n - 4):  # node i = j + 2; indices written as j + k >= 0 (no wraparound checks)
        current = u[j + 2]
        total = 0.0
        total -= far[j] * (older - current)
        total -= near[j + 1] * (old - current)
        total -= near[j + 2] * (u[j + 3] - current)
        total -= far[j + 2] * (u[j + 4] - current)
        velocity = v[j + 2] + dt * (total * inverse[j + 2])
        v[j + 2] = velocity
        u[j + 2] = current + dt * velocity
        older = old
        old = current
    # the last two nodes see the old values of their left neighbours
    last1 = u[n - 2]
    last0 = u[n - 1]
    total = 0.0
    total -= bands[2, n - 4] * (older - last1)
    total -= bands[1, n - 3] * (old - last1)
    total -= bands[1, n - 2] * (last0 - last1)
    velocity = v[n - 2] + dt * (total * inverse[n - 2])
    v[n - 2] = velocity
    u[n - 2] = last1 + dt * velocity
    total = 0.0
    total -= bands[2, n - 3] * (old - last0)
    total -= bands[1, n - 2] * (last1 - last0)
    velocity = v[n - 1] + dt * (total * inverse[n - 1])
    v[n - 1] = velocity
    u[n - 1] = last0 + dt * velocity


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
    vertex = _condensed_vertex_solve(table, r)
    for e in range((n - 1) // 2):
        j = 2 * e + 1
        r[j - 1] = vertex[e]
        r[j] = (r[j] - table[T_MID_LEFT, j] * vertex[e] - table[T_MID_RIGHT, j] * vertex[e + 1]) * table[
            T_MID_INVERSE, j
        ]
    r[n - 1] = vertex[(n - 1) // 2]


@kernel(fastmath=False)
def _condensed_vertex_solve(table, r):
    """Vertex accelerations of the condensed P2 mass for the forces ``r`` (a row of ``table``).

    One pass forms every vertex's right-hand side, its force less the shares of
    its two midpoints (in the order of the assembly: the left element's, then
    the right one's), then the tridiagonal vertex system is solved.
    """
    m = (r.size + 1) // 2
    vertex = table[T_WORK + 1]
    carried = 0.0  # the right-hand midpoint's share of the previous vertex's element
    for e in range(m):
        value = r[2 * e]
        if e > 0:
            value -= carried
        if e < m - 1:
            j = 2 * e + 1
            share = r[j] * table[T_MID_INVERSE, j]
            value -= table[T_MID_LEFT, j] * share
            carried = table[T_MID_RIGHT, j] * share
        vertex[e] = value
    _tridiagonal_solve(table, vertex, m)
    return vertex


@kernel(fastmath=False)
def elastic_acceleration(u, bands, kind, table, out):
    """``out = M^-1 (-K u)`` (length/time^2)."""
    _stiffness_forces(u, bands, out)
    mass_acceleration(kind, table, out)


@kernel(fastmath=False)
def step_rod(u, v, a, bands, kind, table, dt):
    """One leapfrog step of a free rod: ``v += dt M^-1 (-K u)``, ``u += dt v`` (``a``: scratch)."""
    if kind == MASS_LUMPED and bands.shape[0] == 3 and u.size >= 5:
        _leapfrog_pentadiagonal(u, v, bands, table[0], dt)
        return
    _stiffness_forces(u, bands, a)
    if kind == MASS_LUMPED:  # the mass and the update in one pass
        inverse = table[0]
        for i in range(u.size):
            velocity = v[i] + dt * (a[i] * inverse[i])
            v[i] = velocity
            u[i] += dt * velocity
        return
    if kind == MASS_CONDENSED:  # the midpoints' accelerations and the update in one pass
        vertex = _condensed_vertex_solve(table, a)
        for e in range((u.size - 1) // 2):
            j = 2 * e + 1
            left = vertex[e]
            middle = (a[j] - table[T_MID_LEFT, j] * left - table[T_MID_RIGHT, j] * vertex[e + 1]) * table[
                T_MID_INVERSE, j
            ]
            velocity = v[j - 1] + dt * left
            v[j - 1] = velocity
            u[j - 1] += dt * velocity
            velocity = v[j] + dt * middle
            v[j] = velocity
            u[j] += dt * velocity
        last = u.size - 1
        velocity = v[last] + dt * vertex[last // 2]
        v[last] = velocity
        u[last] += dt * velocity
        return
    mass_acceleration(kind, table, a)
    for i in range(u.size):
        velocity = v[i] + dt * a[i]
        v[i] = velocity
        u[i] += dt * velocity
