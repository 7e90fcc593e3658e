"""Peer for the FE benchmark: the straightforward scikit-fem + scipy.sparse loop.

Two rods meshed with scikit-fem P1 elements, lumped mass (row sums),
central differences written as a Python loop over time steps with a
``scipy.sparse`` stiffness product per step and the paper's exponential force
evaluated at the two facing end nodes.  Same meshes (element size matched on
both rods, the remainder of the long rod lumped on its far node), start gap as
``wavecontact``'s FE solver and a step of 0.99 h / c (at exactly h / c the contact
stiffness pushes this scheme over its stability limit), so the cost per
element-step is directly comparable.  This is the scheme that is accurate
where the contact is resolved and blows up where it is not (docs/fem.md).

Usage from other benchmarks::

    from peers.fem_scipy_loop import scipy_fem_restitution
    epsilon, seconds = scipy_fem_restitution(0.6, 100, 800)
"""

from __future__ import annotations

import math
import time

import numpy as np
import scipy.sparse as sp
from skfem import Basis, ElementLineP1, MeshLine
from skfem.models.poisson import laplace, mass

__all__ = ["scipy_fem_restitution", "scipy_fem_run"]


def _rod_matrices(length: float, h: float):
    count = max(1, math.floor(length / h * (1 + 1e-12)))
    span = min(count * h, length)
    basis = Basis(MeshLine(np.linspace(0.0, span, count + 1)), ElementLineP1())
    stiffness = laplace.assemble(basis)  # E = A = 1
    lumped = np.asarray(mass.assemble(basis).sum(axis=1)).ravel()  # rho = A = 1
    order = np.argsort(basis.doflocs[0])
    stiffness = stiffness.tocsr()[order][:, order]
    lumped = lumped[order]
    lumped[-1] += length - span  # far end of the rod (the contact end is node 0)
    return stiffness.tocsr(), lumped, count


def scipy_fem_run(gamma: float, kappa: float, elements: int, courant: float = 0.99):
    """Run the loop; return ``(epsilon, wall_seconds, steps, element_steps)`` (setup excluded)."""
    l1 = 0.5 * (1 + gamma)
    l2 = l1 / gamma
    h = l1 / elements
    k1, m1, n1 = _rod_matrices(l1, h)
    k2, m2, n2 = _rod_matrices(l2, h)
    # rod 1 is mirrored so that its contact end is its last node
    flip = np.arange(k1.shape[0])[::-1]
    k1 = k1[flip][:, flip]
    m1 = m1[flip]
    stiffness = sp.block_diag((k1, k2), format="csr")
    masses = np.concatenate([m1, m2])
    end1, end2 = m1.size - 1, m1.size
    mass1, mass2 = m1.sum(), m2.sum()
    alpha = kappa
    strength = 0.5 / kappa**2  # B = mu / kappa^2, mu = 1/2
    gap0 = math.log(strength / (1e-16 * 0.25)) / alpha
    v = np.concatenate([np.full(m1.size, mass2 / (mass1 + mass2)), np.full(m2.size, -mass1 / (mass1 + mass2))])
    u = np.zeros_like(v)
    dt = courant * h
    t_end = gap0 + 2 * l1 + 2 * l2 + 1.0
    steps = math.ceil(t_end / dt)
    started = time.perf_counter()
    force = np.zeros_like(u)
    for _ in range(steps):
        gap = gap0 + u[end2] - u[end1]
        push = alpha * strength * math.exp(min(-alpha * gap, 700.0))
        force[end1] = -push
        force[end2] = push
        acceleration = (force - stiffness @ u) / masses
        v += dt * acceleration
        u += dt * v
    seconds = time.perf_counter() - started
    velocity1 = masses[: end1 + 1] @ v[: end1 + 1] / mass1
    velocity2 = masses[end2:] @ v[end2:] / mass2
    epsilon = (velocity2 - velocity1) / 1.0
    return float(epsilon), seconds, steps, steps * (n1 + n2)


def scipy_fem_restitution(gamma: float, kappa: float, elements: int):
    """``(epsilon, wall_seconds)`` of the straightforward loop (the comparison's interface)."""
    epsilon, seconds, _, _ = scipy_fem_run(gamma, kappa, elements)
    return epsilon, seconds


if __name__ == "__main__":
    for kappa in (100, 1e4):
        print(kappa, scipy_fem_run(0.6, kappa, 800))
