"""One central-difference step of a rod on any mesh: stiffness stencil, mass solve, update.

The mass solve is prepared once per run (:func:`prepare_mass`) as a few plain
arrays, so that a step allocates nothing and runs a handful of operations per
node:

* lumped mass: a multiplication by the inverse masses, fused with the
  stiffness stencil and the update into one sweep (P2: the two left
  neighbours' old displacements kept in registers);
* consistent P1 mass (tridiagonal): a twisted factorization about the middle
  unknown, done once.  A triangular sweep is a first-order recurrence ``y_i =
  r_i + a_i y_(i-1)`` whose speed is the latency of a multiply and an add per
  node; the twisted solve eliminates the upper half downwards and the lower
  half upwards at the same time, and unrolls each twice (``y_i = r_i + a_i
  r_(i-1) + (a_i a_(i-1)) y_(i-2)``), so four independent chains are in
  flight in every phase.  Every solve takes its right-hand side already
  divided by its pivots (row ``T_SCALE``), so that no sweep multiplies by an
  inverse pivot: the stencil pass of the step does that multiplication;
* consistent P2 mass: the midpoint nodes couple only to their element's two
  vertices, so they are eliminated (static condensation) and the vertices
  solve a tridiagonal system as above.  The step forms the condensed
  right-hand sides straight from the displacements, element by element (two
  differences per element and per-element coefficient rows, the pivots'
  scaling folded in; no dependence between elements, so the compiler
  vectorizes the pass), solves, then computes the midpoints' accelerations
  and updates every node in a second element-wise pass
  (:func:`_condensed_step`);
* large tridiagonal systems (at least ``CHAINS * CHAIN_MIN_LENGTH`` burn-in
  lengths, about 560 unknowns for P1 and 420 vertices for P2) are solved by
  :func:`_chained_solve` instead: a plain ``L D L^T`` factorization whose two
  sweeps each run as ``CHAINS`` = 8 interleaved recurrences, each started a
  burn-in length early so that the value it starts from is damped below
  rounding (the mass matrices are diagonally dominant).  Equal to the direct
  solve to rounding, not bit for bit (tests/test_fem_explicit_step.py).

``prepare_mass`` returns ``(kind, table)``: ``table`` a 2D float array whose
rows are listed at ``T_*``; the kernels read it by row.
"""

from __future__ import annotations

import numpy as np

from .._jit import kernel
from . import interleaved_step as lanes

__all__ = ["MASS_CONDENSED", "MASS_LUMPED", "MASS_TRIDIAGONAL", "mass_acceleration", "prepare_mass", "rod_acceleration",
           "step_flat", "step_rod"]

MASS_LUMPED = 0
MASS_TRIDIAGONAL = 1  # P1 consistent
MASS_CONDENSED = 2  # P2 consistent: midpoints condensed, vertices tridiagonal

# rows of the table of a tridiagonal solve over m unknowns: a twisted factorization about the middle
# unknown k = m // 2 (rows above k eliminated downwards, rows below upwards; both sweeps run at once).
# Every solve takes its right-hand side scaled by its pivots' inverses (row T_SCALE), r_i / p_i, so that
# no sweep multiplies by a pivot: the step kernels fold the scaling into the pass that forms r.
T_FORWARD = 0  # above k: a_i of y_i = r_i / p_i + a_i y_(i-1) (a_0 = 0), a_i = -off_(i-1) / p_i; a_k at the twist
T_INVERSE_PIVOT = 1  # 1 / p_i: pivots D_i above k, the twist's gamma_k at k, E_i below k
T_BACKWARD = 2  # outward sweeps: x_i = y_i + b_i x_(i+1) above k, x_i = z_i + b_i x_(i-1) below
T_MID_INVERSE = 3  # condensed P2, per element e (its midpoint j = 2e + 1): 1 / M[j, j]
T_MID_LEFT = 4  # M[j, j - 1]
T_MID_RIGHT = 5  # M[j, j + 1]
T_WORK = 6  # rows 6, 7: scratch (the vertex system of P2; no allocation per step)
T_UPWARD = 8  # k and below: c_i of z_i = r_i / p_i + c_i z_(i+1) (c_(m-1) = 0), c_i = -off_i / p_i
# the same system as CHAINS independent recurrences (see _chained_solve): a plain L D L^T factorization
T_CHAIN_FORWARD = 9  # y_i = r_i / D_i + f_i y_(i-1), f_i = -off_(i-1) / D_i, f_0 = 0
T_CHAIN_BACKWARD = 10  # x_i = y_i + g_i x_(i+1), g_i = -off_i / D_i, g_(m-1) = 0
T_CHAIN_INVERSE = 11  # 1 / D_i
T_CHAIN_BURN_IN = 12  # [0]: burn-in length w of each chain (0: the system is solved by the twisted sweeps)
# condensed P2 step from the displacements, per element e (vertices 2e, 2e + 2, midpoint 2e + 1; see
# _condensed_step): with da = u_2e - u_(2e+1) and dc = u_(2e+2) - u_(2e+1), the midpoint's share
# s_e = -(T_P_MID_LEFT da + T_P_MID_RIGHT dc) and the element's parts of the condensed right-hand sides of
# its two vertices, T_P_LEFT_A da + T_P_LEFT_C dc and T_P_RIGHT_A da + T_P_RIGHT_C dc
T_P_MID_LEFT = 13  # K[j, j - 1] / M[j, j] (j = 2e + 1)
T_P_MID_RIGHT = 14  # K[j, j + 1] / M[j, j]
T_P_LEFT_A = 15
T_P_LEFT_C = 16
T_P_RIGHT_A = 17
T_P_RIGHT_C = 18
T_P_BACK_LEFT = 19  # M[j, j - 1] / M[j, j]: the midpoint's acceleration is s_e - this x_e - T_P_BACK_RIGHT x_(e+1)
T_P_BACK_RIGHT = 20  # M[j, j + 1] / M[j, j]
T_P_SHARE = 21  # scratch: s_e
T_P_CARRY = 22  # scratch: element e's part of vertex e + 1
T_SCALE = 23  # the scaling of the right-hand side of the solve in use: T_CHAIN_INVERSE or T_INVERSE_PIVOT
# rows lanes.L_SHAPE .. lanes.L_ROWS_END - 1: the interleaved layout of large consistent masses (interleaved_step.py)
T_ROWS = lanes.L_ROWS_END
TWISTED_MIN = 8  # smaller systems take the plain sweeps (same table)
CHAINS = 8  # independent recurrences of the chained solve
CHAIN_TOLERANCE = 2.0**-64  # what a chain may inherit from the value it was started with, relative
CHAIN_MIN_LENGTH = 2  # chains at least this many burn-in lengths long, else the twisted solve


def _tridiagonal(diagonal: np.ndarray, off: np.ndarray, table: np.ndarray) -> None:
    """Twisted factorization of the symmetric tridiagonal ``(diagonal, off)`` about ``k = m // 2``.

    Pivots ``D_i`` from the top (``L D L^T``) for ``i < k``, ``E_i`` from the
    bottom (``U E U^T``) for ``i > k``, and at the twist ``gamma_k = d_k -
    off_(k-1)^2 / D_(k-1) - off_k^2 / E_(k+1)``; the sweeps' factors are those
    of the right-hand side scaled by the inverse pivots (rows ``T_FORWARD``,
    ``T_UPWARD``).
    """
    m = diagonal.size
    k = m // 2
    top = np.empty(m)  # D_i
    top[0] = diagonal[0]
    for i in range(1, k):
        top[i] = diagonal[i] - off[i - 1] * off[i - 1] / top[i - 1]
    bottom = np.empty(m)  # E_i
    bottom[m - 1] = diagonal[m - 1]
    for i in range(m - 2, k, -1):
        bottom[i] = diagonal[i] - off[i] * off[i] / bottom[i + 1]
    forward = np.zeros(m)
    upward = np.zeros(m)
    backward = np.zeros(m)
    pivot = np.empty(m)  # p_i: D_i above k, gamma_k, E_i below
    twist = diagonal[k]
    if k > 0:
        twist -= off[k - 1] * off[k - 1] / top[k - 1]
        backward[:k] = -off[:k] / top[:k]
        pivot[:k] = top[:k]
    if k < m - 1:
        twist -= off[k] * off[k] / bottom[k + 1]
        backward[k + 1 :] = -off[k:] / bottom[k + 1 :]
        pivot[k + 1 :] = bottom[k + 1 :]
    pivot[k] = twist
    forward[1 : k + 1] = -off[:k] / pivot[1 : k + 1]
    upward[k : m - 1] = -off[k:] / pivot[k : m - 1]
    inverse = 1.0 / pivot
    table[T_FORWARD, :m] = forward
    table[T_UPWARD, :m] = upward
    table[T_BACKWARD, :m] = backward
    table[T_INVERSE_PIVOT, :m] = inverse
    _chain_factors(diagonal, off, table)


def _chain_factors(diagonal: np.ndarray, off: np.ndarray, table: np.ndarray) -> None:
    """Plain ``L D L^T`` factors of the tridiagonal ``(diagonal, off)`` and the chains' burn-in length.

    The forward sweep takes the right-hand side scaled by ``1 / D_i`` (its
    factors ``f_i = -off_(i-1) / D_i``), the backward one none.  A chain
    started ``w`` unknowns early with a zero value carries the error
    ``prod f_j`` (forward) or ``prod g_j`` (backward) over those ``w`` steps
    times an entry of the sweep's result; ``w`` is chosen so that the product
    of any ``w`` consecutive factors is at most ``CHAIN_TOLERANCE``, so the
    chains agree with the direct sweeps to rounding relative to the largest
    entry (mass matrices are diagonally dominant: the factors are at most
    about 1/2 in magnitude, 0.27 inside a uniform P1 mesh).  Left at 0 (twisted
    solve) when the chains would be shorter than ``CHAIN_MIN_LENGTH`` burn-ins.
    """
    m = diagonal.size
    pivot = np.empty(m)
    pivot[0] = diagonal[0]
    for i in range(1, m):
        pivot[i] = diagonal[i] - off[i - 1] * off[i - 1] / pivot[i - 1]
    forward = np.zeros(m)
    backward = np.zeros(m)
    forward[1:] = -off / pivot[1:]
    backward[:-1] = -off / pivot[:-1]
    table[T_CHAIN_FORWARD, :m] = forward
    table[T_CHAIN_BACKWARD, :m] = backward
    table[T_CHAIN_INVERSE, :m] = 1.0 / pivot
    table[T_CHAIN_BURN_IN, 0] = 0.0
    table[T_SCALE, :m] = table[T_INVERSE_PIVOT, :m]
    burn_in = _burn_in(forward[1:], backward[:-1], m // CHAINS // CHAIN_MIN_LENGTH)
    if burn_in:
        table[T_CHAIN_BURN_IN, 0] = burn_in
        table[T_SCALE, :m] = table[T_CHAIN_INVERSE, :m]


def _burn_in(forward: np.ndarray, backward: np.ndarray, longest: int) -> int:
    """Fewest steps ``w <= longest`` such that every ``w`` consecutive factors, forward or backward, have
    ``prod |f| <= CHAIN_TOLERANCE`` (0 if there is no such ``w``)."""
    needed = 0
    tiny = np.finfo(float).tiny
    for factors in (forward, backward):
        logs = np.log(np.maximum(np.abs(factors), tiny))
        sums = np.concatenate(([0.0], np.cumsum(logs)))
        for w in range(1, min(longest, factors.size) + 1):
            if np.max(sums[w:] - sums[:-w]) <= np.log(CHAIN_TOLERANCE):
                needed = max(needed, w)
                break
        else:
            return 0
    return needed


def prepare_mass(disc, interleaved: bool = True) -> tuple:
    """``(kind, table)`` of the mass solve of one rod (see the module docstring).

    ``disc`` is a :class:`~wavecontact.fem.discretization.RodDiscretization`.
    With ``interleaved`` (the default) a consistent mass of at least
    ``interleaved_step.LANE_MIN_UNKNOWNS`` unknowns is also prepared for the
    interleaved layout, which :func:`step_rod` and the time loop then use;
    False keeps the flat layout (for comparisons).
    """
    n = disc.n_nodes
    table = np.zeros((T_ROWS, n))
    if disc.mass_kind == "lumped":
        table[0] = 1.0 / disc.lumped_mass
        return MASS_LUMPED, table
    matrix = disc.mass_matrix.tocsr()
    if disc.order == 1:
        wide = interleaved and n >= max(lanes.LANE_MIN_UNKNOWNS, 2 * lanes.LANES)
        if wide:
            table = lanes.aligned_table(T_ROWS, lanes.table_width(max(n, lanes.lanes_width(n))))
        _tridiagonal(matrix.diagonal(0).copy(), matrix.diagonal(1).copy(), table)
        if wide:
            lanes.lane_rows(disc.stiffness_bands[1, : n - 1], table[T_CHAIN_INVERSE, :n], table[T_CHAIN_FORWARD, :n],
                            table[T_CHAIN_BACKWARD, :n], table)
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
    vertex_count = vertices.size
    wide = interleaved and vertex_count >= max(lanes.LANE_MIN_VERTICES, 2 * lanes.LANES)  # two rows at least
    if wide:
        table = lanes.aligned_table(T_ROWS, lanes.table_width(max(n, 2 * lanes.lanes_width(vertex_count))))
    _tridiagonal(diagonal, off, table)
    table[T_MID_INVERSE, : mids.size] = inverse
    table[T_MID_LEFT, : mids.size] = left
    table[T_MID_RIGHT, : mids.size] = right
    coefficients = _condensed_coefficients(disc.stiffness_bands, inverse, left, right)
    _condensed_step_rows(coefficients, table[T_SCALE, :vertex_count], table)
    if wide:
        lanes.condensed_lane_rows(coefficients, table[T_CHAIN_INVERSE, :vertex_count].copy(),
                                  table[T_CHAIN_FORWARD, :vertex_count].copy(),
                                  table[T_CHAIN_BACKWARD, :vertex_count].copy(), table)
    return MASS_CONDENSED, table


def _condensed_coefficients(bands: np.ndarray, inverse: np.ndarray, left: np.ndarray, right: np.ndarray) -> dict:
    """Per-element coefficients of the condensed P2 step from the stiffness bands and the midpoint masses.

    With ``k_l = K[2e, 2e+1]``, ``k_r = K[2e+1, 2e+2]`` and ``k_f = K[2e, 2e+2]``, element ``e``'s part
    of the force ``-K u`` is ``(k_l + k_f) da - k_f dc`` on its left vertex, ``-k_f da + (k_r + k_f) dc``
    on its right vertex and ``-(k_l da + k_r dc)`` on its midpoint; condensing the midpoint subtracts
    ``M[2e+1, 2e] s_e`` and ``M[2e+1, 2e+2] s_e`` from the two vertices (``s_e``: the midpoint force
    over ``M[2e+1, 2e+1]``).  ``inverse``, ``left``, ``right``: ``1 / M[j, j]``, ``M[j, j-1]``,
    ``M[j, j+1]`` per midpoint ``j = 2e + 1``.  The vertices' parts (``left_*``, ``right_*``) are not
    yet scaled for a solve.
    """
    elements = inverse.size
    near_left = bands[1, 0 : 2 * elements : 2]
    near_right = bands[1, 1 : 2 * elements : 2]
    far = bands[2, 0 : 2 * elements : 2]
    mid_left = near_left * inverse
    mid_right = near_right * inverse
    return {
        "mid_left": mid_left,
        "mid_right": mid_right,
        "left_a": near_left + far + left * mid_left,
        "left_c": -far + left * mid_right,
        "right_a": -far + right * mid_left,
        "right_c": near_right + far + right * mid_right,
        "back_left": left * inverse,
        "back_right": right * inverse,
    }


def _condensed_step_rows(coefficients: dict, scale: np.ndarray, table: np.ndarray) -> None:
    """Rows ``T_P_*`` of :func:`_condensed_step`: ``coefficients`` of :func:`_condensed_coefficients`, each
    vertex's parts scaled by ``scale``, the vertex solve's ``T_SCALE`` row."""
    rows = {
        T_P_MID_LEFT: coefficients["mid_left"],
        T_P_MID_RIGHT: coefficients["mid_right"],
        T_P_LEFT_A: coefficients["left_a"] * scale[:-1],
        T_P_LEFT_C: coefficients["left_c"] * scale[:-1],
        T_P_RIGHT_A: coefficients["right_a"] * scale[1:],
        T_P_RIGHT_C: coefficients["right_c"] * scale[1:],
        T_P_BACK_LEFT: coefficients["back_left"],
        T_P_BACK_RIGHT: coefficients["back_right"],
    }
    for row, values in rows.items():
        table[row, : values.size] = values


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


@kernel(fastmath=False, internal=True)
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


@kernel(fastmath=False, internal=True)
def _leapfrog_pentadiagonal(u, v, bands, inverse, dt):
    """P2 lumped step in one sweep: ``v += dt M^-1 (-K u)``, ``u += dt v`` (at least 5 nodes).

    The two previous nodes' old displacements are kept in registers, so each
    node is updated right after its force is known, without a scratch array.
    """
    n = u.size
    older = u[0]
    old = u[1]
    force0 = _pentadiagonal_force(u, bands, np.int64(0), n)  # not literals: no specialisation for each
    force1 = _pentadiagonal_force(u, bands, np.int64(1), n)
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


@kernel(fastmath=False, internal=True)
def _scaled_solve(table, x, m):
    """``x <- T^-1 r`` from ``x = r / p`` (the right-hand side times the row ``T_SCALE``; in place).

    Twisted: the upper half is eliminated downwards while the lower half is
    eliminated upwards, then both halves are back-substituted outwards from
    the middle, so two recurrences run side by side in every phase.  Each is
    also unrolled twice (``y_i = r_i + a_i r_(i-1) + (a_i a_(i-1)) y_(i-2)``),
    four independent dependency chains in all.
    """
    if table[T_CHAIN_BURN_IN, 0] > 0.0:
        _chained_solve(table, x, m)
        return
    if m < TWISTED_MIN:
        _tridiagonal_solve_plain(table, x, m)
        return
    a = table[T_FORWARD]
    c = table[T_UPWARD]
    b = table[T_BACKWARD]
    k = m // 2
    # inward: top i = 2 .. k - 1 (k - 2 steps), bottom j = m - 3 .. k + 1 (m - k - 3 steps)
    top_old = x[1]  # r_(i-1)
    top_older = x[0]  # y_(i-2)
    top_last = top_old + a[1] * top_older  # y_(i-1)
    x[1] = top_last
    bottom_old = x[m - 2]
    bottom_older = x[m - 1]
    bottom_last = bottom_old + c[m - 2] * bottom_older
    x[m - 2] = bottom_last
    a_prev = a[1]
    c_prev = c[m - 2]
    for t in range(m - k - 3):
        i = t + 2
        current = x[i]
        a_now = a[i]
        value = current + a_now * top_old + (a_now * a_prev) * top_older
        x[i] = value
        top_old = current
        top_older = top_last
        top_last = value
        a_prev = a_now
        j = m - 3 - t
        current = x[j]
        c_now = c[j]
        value = current + c_now * bottom_old + (c_now * c_prev) * bottom_older
        x[j] = value
        bottom_old = current
        bottom_older = bottom_last
        bottom_last = value
        c_prev = c_now
    if k - 2 > m - k - 3:  # even m: the top half has one more step
        i = k - 1
        current = x[i]
        value = current + a[i] * top_old + (a[i] * a_prev) * top_older
        x[i] = value
        top_last = value
    middle = x[k] + a[k] * top_last + c[k] * bottom_last
    x[k] = middle
    # outward: top i = k - 1 .. 0, bottom i = k + 1 .. m - 1; x_i = e_i + b_i e_(i+-1) + (b_i b_(i+-1)) x_(i+-2)
    top_old = x[k - 1]  # e_(i+1)
    top_older = middle  # x_(i+2)
    top_last = top_old + b[k - 1] * middle
    x[k - 1] = top_last
    bottom_old = x[k + 1]
    bottom_older = middle
    bottom_last = bottom_old + b[k + 1] * middle
    x[k + 1] = bottom_last
    b_top = b[k - 1]
    b_bottom = b[k + 1]
    for t in range(m - k - 2):
        i = k - 2 - t
        current = x[i]
        b_now = b[i]
        value = current + b_now * top_old + (b_now * b_top) * top_older
        x[i] = value
        top_old = current
        top_older = top_last
        top_last = value
        b_top = b_now
        j = k + 2 + t
        current = x[j]
        b_now = b[j]
        value = current + b_now * bottom_old + (b_now * b_bottom) * bottom_older
        x[j] = value
        bottom_old = current
        bottom_older = bottom_last
        bottom_last = value
        b_bottom = b_now
    if k - 1 > m - k - 2:  # even m: the top half has one more step (i = 0)
        current = x[0]
        x[0] = current + b[0] * top_old + (b[0] * b_top) * top_older


@kernel(fastmath=False, internal=True)
def _chained_solve(table, x, m):
    """``x <- T^-1 x`` as ``CHAINS`` independent recurrences per sweep, interleaved (``m`` unknowns, in place).

    A first-order recurrence ``y_i = r_i + f_i y_(i-1)`` costs the latency of a
    multiplication and an addition per unknown when run as one chain.  Here the
    unknowns are cut into ``CHAINS`` consecutive pieces whose recurrences run
    side by side, so the processor overlaps them.  Each piece but the first is
    started ``w`` unknowns early from zero (burn-in, nothing stored): the value
    it inherits is damped by ``prod |f_j| <= CHAIN_TOLERANCE`` over those steps
    (see :func:`_chain_factors`), far below rounding.  The back substitution
    ``x_i = y_i + g_i x_(i+1)`` runs the same way towards lower indices
    (on reversed views, so that every index is a counter plus a constant).
    """
    burn_in = int(table[T_CHAIN_BURN_IN, 0])
    # both sweeps on views with a step (numba's layout 'A'), so that _chains compiles once, not once for the
    # contiguous forward arrays and once more for the reversed ones
    forward = x[::1]
    _chains(forward, forward, table[T_CHAIN_FORWARD, ::1], m, burn_in)
    reverse = x[m - 1 :: -1]  # the table's rows are longer than m for the vertices of P2
    _chains(reverse, reverse, table[T_CHAIN_BACKWARD, m - 1 :: -1], m, burn_in)


@kernel(fastmath=False, inline="always")
def _link(r, f, i, previous):
    """One step of a chain: ``r_i + f_i previous``."""
    return r[i] + f[i] * previous


@kernel(fastmath=False, internal=True)
def _chains(r, out, f, m, burn_in):
    """``out_i = r_i + f_i out_(i-1)`` as ``CHAINS`` = 8 interleaved chains.

    Chain ``c`` owns ``[c L, (c + 1) L)`` (``L = m // 8``; the last one also the
    remainder) and, for ``c > 0``, starts ``burn_in`` steps before it from zero.
    ``r`` and ``out`` may be the same array: each entry is read before it is
    written and burn-in steps only read entries of earlier pieces, ahead of
    their own chain.
    """
    length = m // 8
    y0 = 0.0
    y1 = 0.0
    y2 = 0.0
    y3 = 0.0
    y4 = 0.0
    y5 = 0.0
    y6 = 0.0
    y7 = 0.0
    start = length - burn_in
    for t in range(burn_in):
        s = start + t
        y1 = _link(r, f, s, y1)
        y2 = _link(r, f, length + s, y2)
        y3 = _link(r, f, 2 * length + s, y3)
        y4 = _link(r, f, 3 * length + s, y4)
        y5 = _link(r, f, 4 * length + s, y5)
        y6 = _link(r, f, 5 * length + s, y6)
        y7 = _link(r, f, 6 * length + s, y7)
    for s in range(length):
        y0 = _link(r, f, s, y0)
        y1 = _link(r, f, length + s, y1)
        y2 = _link(r, f, 2 * length + s, y2)
        y3 = _link(r, f, 3 * length + s, y3)
        y4 = _link(r, f, 4 * length + s, y4)
        y5 = _link(r, f, 5 * length + s, y5)
        y6 = _link(r, f, 6 * length + s, y6)
        y7 = _link(r, f, 7 * length + s, y7)
        out[s] = y0
        out[length + s] = y1
        out[2 * length + s] = y2
        out[3 * length + s] = y3
        out[4 * length + s] = y4
        out[5 * length + s] = y5
        out[6 * length + s] = y6
        out[7 * length + s] = y7
    for i in range(8 * length, m):
        y7 = _link(r, f, i, y7)
        out[i] = y7

@kernel(fastmath=False, internal=True)
def _tridiagonal_solve_plain(table, x, m):
    """The twisted solve of :func:`_scaled_solve` with plain (not unrolled) sweeps, for any ``m``."""
    a = table[T_FORWARD]
    c = table[T_UPWARD]
    b = table[T_BACKWARD]
    k = m // 2
    for i in range(1, k):
        x[i] += a[i] * x[i - 1]
    for i in range(m - 2, k, -1):
        x[i] += c[i] * x[i + 1]
    middle = x[k]
    if k > 0:
        middle += a[k] * x[k - 1]
    if k < m - 1:
        middle += c[k] * x[k + 1]
    x[k] = middle
    for i in range(k - 1, -1, -1):
        x[i] += b[i] * x[i + 1]
    for i in range(k + 1, m):
        x[i] += b[i] * x[i - 1]


@kernel(fastmath=False, internal=True)
def mass_acceleration(kind, table, r):
    """Overwrite the forces ``r`` with ``M^-1 r`` (the mass solve prepared by :func:`prepare_mass`)."""
    n = r.size
    if kind == MASS_LUMPED:
        for i in range(n):
            r[i] *= table[0, i]
        return
    if kind == MASS_TRIDIAGONAL:
        scale = table[T_SCALE]
        for i in range(n):
            r[i] *= scale[i]
        _scaled_solve(table, r, n)
        return
    # condensed P2: vertex right-hand sides lose the midpoints' share, then the midpoints follow
    vertex = _condensed_vertex_solve(table, r)
    mid_inverse = table[T_MID_INVERSE]
    mid_left = table[T_MID_LEFT]
    mid_right = table[T_MID_RIGHT]
    for e in range((n - 1) // 2):
        j = 2 * e + 1
        r[j - 1] = vertex[e]
        r[j] = (r[j] - mid_left[e] * vertex[e] - mid_right[e] * vertex[e + 1]) * mid_inverse[e]
    r[n - 1] = vertex[(n - 1) // 2]


@kernel(fastmath=False, internal=True)
def _condensed_vertex_solve(table, r):
    """Vertex accelerations of the condensed P2 mass for the forces ``r`` (a row of ``table``).

    One pass forms every vertex's right-hand side, its force less the shares of
    its two midpoints (in the order of the assembly: the left element's, then
    the right one's), then the tridiagonal vertex system is solved.
    """
    m = (r.size + 1) // 2
    vertex = table[T_WORK + 1]
    scale = table[T_SCALE]  # each right-hand side scaled for the solve as soon as it is formed
    mid_inverse = table[T_MID_INVERSE]
    mid_left = table[T_MID_LEFT]
    mid_right = table[T_MID_RIGHT]
    share = r[1] * mid_inverse[0]
    vertex[0] = (r[0] - mid_left[0] * share) * scale[0]
    carried = mid_right[0] * share  # the right-hand midpoint's share of the previous vertex's element
    for e in range(1, m - 1):
        value = r[2 * e] - carried
        share = r[2 * e + 1] * mid_inverse[e]
        vertex[e] = (value - mid_left[e] * share) * scale[e]
        carried = mid_right[e] * share
    vertex[m - 1] = (r[2 * m - 2] - carried) * scale[m - 1]
    _scaled_solve(table, vertex, m)
    return vertex


@kernel(fastmath=False, internal=True)
def _scaled_tridiagonal_forces(u, near, scale, out):
    """``out = scale * (-K u)`` for a tridiagonal ``K`` with upper band ``near`` (the right-hand side of
    :func:`_scaled_solve`)."""
    n = u.size
    if n == 1:
        out[0] = 0.0
        return
    out[0] = scale[0] * (-near[0] * (u[1] - u[0]))
    for j in range(n - 2):  # node i = j + 1
        current = u[j + 1]
        out[j + 1] = scale[j + 1] * (-near[j] * (u[j] - current) - near[j + 1] * (u[j + 2] - current))
    out[n - 1] = scale[n - 1] * (-near[n - 2] * (u[n - 2] - u[n - 1]))


@kernel(fastmath=False, internal=True)
def _condensed_step(u, v, table, dt):
    """Consistent P2 step ``v += dt M^-1 (-K u)``, ``u += dt v`` with the midpoints condensed (``T_P_*`` rows).

    Three passes, the first and the last element-wise with no dependence
    between elements, so that the compiler vectorizes them: (1) each
    element's two differences ``da, dc`` give its midpoint share ``s_e`` and
    its parts of its two vertices' condensed right-hand sides (already
    scaled for the solve), summed per vertex in a short second loop; (2) the
    tridiagonal vertex solve; (3) each midpoint's acceleration ``s_e - b_l
    x_e - b_r x_(e+1)`` and the update of every node.
    """
    elements = (u.size - 1) // 2
    share = table[T_P_SHARE]
    carry = table[T_P_CARRY]
    vertex = table[T_WORK + 1]
    mid_left = table[T_P_MID_LEFT]
    mid_right = table[T_P_MID_RIGHT]
    left_a = table[T_P_LEFT_A]
    left_c = table[T_P_LEFT_C]
    right_a = table[T_P_RIGHT_A]
    right_c = table[T_P_RIGHT_C]
    for e in range(elements):
        middle = u[2 * e + 1]
        da = u[2 * e] - middle
        dc = u[2 * e + 2] - middle
        share[e] = -(mid_left[e] * da + mid_right[e] * dc)
        vertex[e] = left_a[e] * da + left_c[e] * dc
        carry[e] = right_a[e] * da + right_c[e] * dc
    vertex[elements] = carry[elements - 1]
    for e in range(1, elements):
        vertex[e] += carry[e - 1]
    _scaled_solve(table, vertex, elements + 1)
    back_left = table[T_P_BACK_LEFT]
    back_right = table[T_P_BACK_RIGHT]
    for e in range(elements):
        left = vertex[e]
        middle = share[e] - back_left[e] * left - back_right[e] * vertex[e + 1]
        velocity = v[2 * e] + dt * left
        v[2 * e] = velocity
        u[2 * e] += dt * velocity
        velocity = v[2 * e + 1] + dt * middle
        v[2 * e + 1] = velocity
        u[2 * e + 1] += dt * velocity
    velocity = v[2 * elements] + dt * vertex[elements]
    v[2 * elements] = velocity
    u[2 * elements] += dt * velocity


def rod_acceleration(u, bands, kind, table, out):
    """:func:`elastic_acceleration` called from Python: a lumped mass compiles its stencil alone, not the
    solves of the consistent masses (the exact lattice's runs need no other kernel of this module)."""
    if kind == MASS_LUMPED:
        _stiffness_forces(u, bands, out)
        out *= table[0, : out.size]  # the same products as mass_acceleration's loop
    else:
        elastic_acceleration(u, bands, kind, table, out)


@kernel(fastmath=False)
def elastic_acceleration(u, bands, kind, table, out):
    """``out = M^-1 (-K u)`` (length/time^2)."""
    _stiffness_forces(u, bands, out)
    mass_acceleration(kind, table, out)


@kernel(fastmath=False)
def step_rod(u, v, a, bands, kind, table, dt):
    """One leapfrog step of a free rod: ``v += dt M^-1 (-K u)``, ``u += dt v`` (``a``: scratch), in the
    interleaved layout when ``table`` holds one (packed and unpacked around the step), else :func:`step_flat`."""
    if kind != MASS_LUMPED and table[lanes.L_SHAPE, 0] > 0.0:  # the interleaved layout
        rows = int(table[lanes.L_SHAPE, 0])
        order = bands.shape[0] - 1
        lanes.pack_nodes(u, table[lanes.L_U], rows, order)
        lanes.pack_nodes(v, table[lanes.L_V], rows, order)
        if kind == MASS_CONDENSED:
            lanes.step_condensed(table, dt)
        else:
            lanes.step_tridiagonal(table, dt)
        lanes.unpack_nodes(table[lanes.L_U], u, rows, order)
        lanes.unpack_nodes(table[lanes.L_V], v, rows, order)
        return
    step_flat(u, v, a, bands, kind, table, dt)


@kernel(fastmath=False, internal=True)
def step_flat(u, v, a, bands, kind, table, dt):
    """:func:`step_rod` in the flat layout (the table's interleaved rows unused): the step of the time loops
    (two rods, many bodies), which run the interleaved layout themselves, so that they do not compile the
    packing here."""
    if kind == MASS_LUMPED and bands.shape[0] == 3 and u.size >= 5:
        _leapfrog_pentadiagonal(u, v, bands, table[0], dt)
        return
    if kind == MASS_CONDENSED:
        _condensed_step(u, v, table, dt)
        return
    if kind == MASS_TRIDIAGONAL:  # the solve's scaling in the stencil pass
        _scaled_tridiagonal_forces(u, bands[1], table[T_SCALE], a)
        _scaled_solve(table, a, u.size)
        for i in range(u.size):
            velocity = v[i] + dt * a[i]
            v[i] = velocity
            u[i] += dt * velocity
        return
    # lumped P1, or lumped P2 on fewer than 5 nodes: the mass and the update in one pass
    _stiffness_forces(u, bands, a)
    inverse = table[0]
    for i in range(u.size):
        velocity = v[i] + dt * (a[i] * inverse[i])
        v[i] = velocity
        u[i] += dt * velocity
