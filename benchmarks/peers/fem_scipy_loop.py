"""Peer for the FE benchmark: the straightforward scikit-fem + scipy.sparse loop, per discretization.

Two rods meshed with scikit-fem (``ElementLineP1`` or ``ElementLineP2`` on
``MeshLine``), stiffness and mass from ``laplace`` and ``mass``; the mass
either lumped (row sums) or consistent, the consistent one factorized once
with ``scipy.sparse.linalg.splu`` as a careful user would.  Central
differences written as a Python loop over time steps: one sparse product,
one solve (consistent) or one division (lumped) per step, the paper's
exponential force evaluated at the two facing end nodes.  Meshes: the short
rod has ``elements`` elements, the long one as many of about the same size as
fit its whole length (wavecontact's meshes for every discretization but the
exact lattice).  The caller passes the step (wavecontact's, so that both
loops take the same number of steps) or a Courant number.

Usage from other benchmarks::

    from peers.fem_scipy_loop import scipy_fem_run
    epsilon, seconds, steps, element_steps = scipy_fem_run(0.6, 100, 800, order=2, mass="consistent")
"""

from __future__ import annotations

import math
import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spl
from skfem import Basis, ElementLineP1, ElementLineP2, MeshLine
from skfem.models.poisson import laplace, mass

__all__ = ["STABLE_COURANT", "scipy_fem_restitution", "scipy_fem_run"]

# stable step of central differences in units of h / c (docs/fem.md section 2)
STABLE_COURANT = {(1, "lumped"): 1.0, (1, "consistent"): 1 / math.sqrt(3), (2, "lumped"): 1 / math.sqrt(6),
                  (2, "consistent"): 1 / math.sqrt(15)}


def _rod(length: float, elements: int, order: int):
    """Stiffness, consistent mass (E = rho = A = 1) and the DOF order left to right of one rod."""
    basis = Basis(MeshLine(np.linspace(0.0, length, elements + 1)), (ElementLineP1, ElementLineP2)[order - 1]())
    order_ = np.argsort(basis.doflocs[0])
    stiffness = laplace.assemble(basis).tocsr()[order_][:, order_]
    consistent = mass.assemble(basis).tocsr()[order_][:, order_]
    return stiffness.tocsr(), consistent.tocsr()


def scipy_fem_run(gamma: float, kappa: float, elements: int, order: int = 1, mass_kind: str = "lumped",
                  dt: float | None = None, courant: float = 0.99, max_steps: int | None = None):
    """Run the loop; return ``(epsilon, wall_seconds, steps, element_steps)`` (set-up excluded).

    ``max_steps`` stops the loop early, to time the cost per step on large meshes
    (epsilon is then NaN).
    """
    l1 = 0.5 * (1 + gamma)
    l2 = l1 / gamma
    h = l1 / elements
    n2 = max(1, round(l2 / h))
    k1, m1 = _rod(l1, elements, order)
    k2, m2 = _rod(l2, n2, order)
    stiffness = sp.block_diag((k1, k2), format="csr")
    consistent = sp.block_diag((m1, m2), format="csc")
    lumped = np.asarray(consistent.sum(axis=1)).ravel()
    solve = spl.splu(consistent).solve if mass_kind == "consistent" else None
    end1, end2 = k1.shape[0] - 1, k1.shape[0]  # the facing ends: rod 1's last node, rod 2's first
    mass1, mass2 = l1, l2
    alpha = kappa
    strength = 0.5 / kappa**2  # B = mu / kappa^2, mu = 1/2
    gap0 = math.log(strength / (1e-16 * 0.25)) / alpha
    v = np.concatenate([np.full(k1.shape[0], mass2 / (mass1 + mass2)), np.full(k2.shape[0], -mass1 / (mass1 + mass2))])
    u = np.zeros_like(v)
    step = dt if dt is not None else courant * STABLE_COURANT[(order, mass_kind)] * h
    steps = math.ceil((gap0 + 2 * l1 + 2 * l2 + 1.0) / step)
    complete = max_steps is None or max_steps >= steps
    steps = steps if complete else max_steps
    force = np.zeros_like(u)
    started = time.perf_counter()
    for _ in range(steps):
        gap = gap0 + u[end2] - u[end1]
        push = alpha * strength * math.exp(min(-alpha * gap, 700.0))
        force[end1] = -push
        force[end2] = push
        load = force - stiffness @ u
        acceleration = solve(load) if solve is not None else load / lumped
        v += step * acceleration
        u += step * v
    seconds = time.perf_counter() - started
    momentum = lumped * v
    velocity1 = momentum[: end1 + 1].sum() / mass1
    velocity2 = momentum[end2:].sum() / mass2
    epsilon = float(velocity2 - velocity1) if complete else math.nan
    return epsilon, seconds, steps, steps * (elements + n2)


def scipy_fem_restitution(gamma: float, kappa: float, elements: int):
    """``(epsilon, wall_seconds)`` of the straightforward P1 lumped loop (the comparison's interface)."""
    epsilon, seconds, _, _ = scipy_fem_run(gamma, kappa, elements)
    return epsilon, seconds


if __name__ == "__main__":
    for order, kind in STABLE_COURANT:
        print(order, kind, scipy_fem_run(0.6, 100, 200, order, kind, courant=0.95))
