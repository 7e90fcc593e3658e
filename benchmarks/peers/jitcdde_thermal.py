"""Peer: JiTCDDE on Eq. 16 with one realisation's noise Q(tau) as an input (``jitcdde_input``).

The noise enters as a cubic Hermite spline (CHSPy) through the values and
slopes of wavecontact's own noise tables, so both solvers see the same
``Q``.  As in ``jitcdde_delay.py`` the exponent is clipped at 50 and the
delays are passed explicitly.  Optional: ``pip install jitcdde symengine``.
"""

from __future__ import annotations

import contextlib
import math
import tempfile
import time

import numpy as np


def restitution(gamma: float, kappa: float, scene, rtol: float, a0: float, tables, span: float):
    """``(epsilon, wall time s, compile time s)`` for one realisation.

    ``tables`` are the per-rod noise tables of the delay solver (origin
    ``tau = 0``); ``span`` is the integration end time.
    """
    import symengine
    from chspy import CubicHermiteSpline
    from jitcdde import input as system_input
    from jitcdde import jitcdde_input, t, y

    # the input spline: anchors on a grid fine enough for the fastest mode (the tables' own nodes)
    step = min(p / tables.values.shape[1] for p in tables.periods)
    times = np.arange(0.0, span + step, step)
    values = np.zeros(times.size)
    slopes = np.zeros(times.size)
    for i, period in enumerate(tables.periods):
        n = tables.values.shape[1]
        x = np.mod(times, period) / period * n
        values += np.interp(x, np.arange(n + 1), np.append(tables.values[i], tables.values[i][0]))
        slopes += np.interp(x, np.arange(n + 1), np.append(tables.slopes[i], tables.slopes[i][0]))
    spline = CubicHermiteSpline(n=1, anchors=[(tt, [v], [d]) for tt, v, d in zip(times, values, slopes)])
    delays = []
    for gamma_i in (1.0 + gamma, 1.0 + 1.0 / gamma):
        delays += [n * gamma_i for n in range(1, int(span / gamma_i) + 1)]
    memory = sum(y(0, t - d) for d in delays)
    exponent = kappa * t - a0 - y(0) - memory + system_input(0)
    started = time.perf_counter()
    dde = jitcdde_input([symengine.exp(symengine.Min(exponent, 50))], spline, delays=delays,
                        max_delay=max(delays), verbose=False)
    # built in a scratch directory: setuptools would read this project's pyproject.toml otherwise
    with tempfile.TemporaryDirectory() as scratch, contextlib.chdir(scratch):
        dde.compile_C(simplify=False, do_cse=False, verbose=False)
    compiled = time.perf_counter() - started
    started = time.perf_counter()
    dde.constant_past([0.0], time=0.0)
    dde.set_integration_parameters(atol=rtol * kappa, rtol=rtol, first_step=1e-3 / kappa, min_step=1e-14,
                                   max_step=step)
    dde.adjust_diff()
    w = dde.integrate(span)[0]
    wall = time.perf_counter() - started
    return (w / kappa - 1.0 if math.isfinite(w) else math.nan), wall, compiled
