"""Peer for the modal solver: the same modal equations handed to scipy's ``solve_ivp``.

The rods, modes, residual compliance, contact law and starting gap are those
of ``wavecontact.modal.solver`` (built by its own set-up code), so the only
difference is the time integrator: a general-purpose one (DOP853 explicit
Runge-Kutta or Radau implicit), which must follow every mode's oscillation
and the contact at once, over the same time span, instead of rotating the
oscillators exactly and stepping only the contact.

Usage: ``restitution(gamma, kappa, modes, rtol) -> (epsilon, wall_time_s)``.
"""

from __future__ import annotations

import time

import numpy as np
from scipy.integrate import solve_ivp

from wavecontact.modal import kernels
from wavecontact.modal.solver import _build
from wavecontact.scene import two_rods

__all__ = ["modal_equations", "restitution"]


def modal_equations(gamma, kappa, modes, static_correction=True, scene=None):
    """Right-hand side, Jacobian, initial state and time span of the modal system.

    The state is ``(X1, X2, U1, U2, q (2 modes), v (2 modes))`` with
    mass-normalised mode coordinates.  ``scene`` (optional) replaces
    ``two_rods(gamma, kappa)``, e.g. a thermal start.
    """
    scene = two_rods(gamma, kappa) if scene is None else scene
    system, gap = _build(scene, modes, static_correction, "analytic", None, 1, 0.025)
    n_modes = system.omega.size
    first = system.rod_first.astype(int)
    coupling = np.zeros(n_modes)  # d gap / d q, and the generalised force per unit contact force
    coupling[first[0]:first[1]] = -system.right[first[0]:first[1]]
    coupling[first[1]:first[2]] = system.left[first[1]:first[2]]
    omega2 = system.omega**2
    mass = system.mass
    offset = -system.half[1] - system.half[0]
    law = (system.law_code, system.alpha, system.strength, system.stiffness)
    compliance = float(system.pair_compliance[0])

    def contact(y):
        r = y[1] - y[0] + offset + coupling @ y[4:4 + n_modes]
        return kernels.contact_response(r, *law, compliance)

    def rhs(t, y):
        force = contact(y)[0]
        out = np.empty_like(y)
        out[0:2] = y[2:4]
        out[2] = -force / mass[0]
        out[3] = force / mass[1]
        out[4:4 + n_modes] = y[4 + n_modes:]
        out[4 + n_modes:] = -omega2 * y[4:4 + n_modes] + coupling * force
        return out

    def jac(t, y):
        stiffness = contact(y)[2]  # d force / d gap (>= 0); force = F(gap), dF/dgap = -stiffness
        size = y.size
        out = np.zeros((size, size))
        out[0, 2] = out[1, 3] = 1.0
        out[4:4 + n_modes, 4 + n_modes:] = np.eye(n_modes)
        out[4 + n_modes:, 4:4 + n_modes] = -np.diag(omega2)
        gradient = np.zeros(size)  # d gap / d state
        gradient[0], gradient[1] = -1.0, 1.0
        gradient[4:4 + n_modes] = coupling
        load = np.zeros(size)  # d state' / d force
        load[2], load[3] = -1.0 / mass[0], 1.0 / mass[1]
        load[4 + n_modes:] = coupling
        out += np.outer(load, -stiffness * gradient)
        return out

    y0 = np.concatenate([system.X, system.U, system.q, system.v])
    approach = float(system.U[0] - system.U[1])
    # the contact lasts about 2 l1 / c; allow the longer rod's round trip on top
    span = gap / approach + 2.0 * (system.half[0] + system.half[1]) * 2.0
    return rhs, jac, y0, (0.0, span)


def restitution(gamma, kappa, modes, rtol, method="DOP853", static_correction=True, scene=None):
    """epsilon of the modal system integrated by ``solve_ivp`` and the wall time (s).

    ``atol`` is ``rtol`` times 1e-3 (the end displacements are ~1e-3 of the
    rod length during contact).
    """
    rhs, jac, y0, span = modal_equations(gamma, kappa, modes, static_correction, scene)
    start = time.perf_counter()
    options = {"jac": jac} if method in ("Radau", "BDF", "LSODA") else {}
    solution = solve_ivp(rhs, span, y0, method=method, rtol=rtol, atol=rtol * 1e-3, **options)
    wall = time.perf_counter() - start
    if not solution.success:
        raise RuntimeError(f"solve_ivp({method}) failed: {solution.message}")
    y = solution.y[:, -1]
    before = y0[3] - y0[2]
    return abs(y[3] - y[2]) / abs(before), wall
