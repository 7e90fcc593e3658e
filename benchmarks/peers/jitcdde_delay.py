"""Peer: JiTCDDE on the same delay equation (Eq. 16), as a user would set it up.

JiTCDDE integrates ``W' = exp(kappa t - a0 - W - sum_{i,n} W(t - n Gamma_i))``
with its Bogacki-Shampine pair and Hermite history.  Two precautions
(found while setting it up): the exponent is clipped at 50, otherwise a rejected trial step can
overflow to NaN and be accepted silently; the delays are passed explicitly
(automatic detection needs sympy).  ``kappa`` is a control parameter, so one
compilation serves every ``kappa`` at a given ``gamma``.

Optional dependency: ``pip install jitcdde`` (it compiles C code with the
system compiler).
"""

from __future__ import annotations

import contextlib
import math
import tempfile
import time

import numpy as np

A0 = 40.0
SETTLE = 8.0  # integrate this long after tau_free; W has settled by then for kappa >= 1


class JitcddePeer:
    """A compiled JiTCDDE model of Eq. 16 for one ``gamma`` and up to ``t_max``."""

    def __init__(self, gamma: float, t_max: float):
        import symengine
        from jitcdde import jitcdde, t, y

        self.gamma = gamma
        self.t_max = t_max
        kappa = symengine.Symbol("kappa")
        delays = []
        for gamma_i in (1.0 + gamma, 1.0 + 1.0 / gamma):
            delays += [n * gamma_i for n in range(1, int(t_max / gamma_i) + 1)]
        memory = sum(y(0, t - d) for d in delays)
        exponent = kappa * t - A0 - y(0) - memory
        rhs = [symengine.exp(symengine.Min(exponent, 50))]
        started = time.perf_counter()
        self.dde = jitcdde(rhs, control_pars=[kappa], delays=delays, max_delay=max(delays), verbose=False)
        # JiTCDDE builds its C module with setuptools in the working directory, which would read this
        # project's pyproject.toml (with an older setuptools than the project needs): build elsewhere
        with tempfile.TemporaryDirectory() as scratch, contextlib.chdir(scratch):
            self.dde.compile_C(simplify=False, do_cse=False, verbose=False)
        self.compile_time = time.perf_counter() - started

    def restitution(self, kappa: float, rtol: float) -> float:
        """epsilon = W(end) / kappa - 1 at relative/absolute tolerance ``rtol``."""
        dde = self.dde
        dde.purge_past()
        dde.constant_past([0.0], time=0.0)
        dde.set_parameters(kappa)
        dde.set_integration_parameters(atol=rtol * kappa, rtol=rtol, first_step=1e-3 / kappa,
                                       min_step=1e-14, max_step=0.1)
        dde.adjust_diff()
        end = min(A0 / kappa + SETTLE, self.t_max)
        w = dde.integrate(end)[0]
        if not math.isfinite(w):
            return math.nan
        return w / kappa - 1.0


def timed_restitution(peer: JitcddePeer, kappa: float, rtol: float, repeats: int = 3):
    """Median wall time (s) and the epsilon of ``repeats`` solves."""
    times = []
    for _ in range(repeats):
        started = time.perf_counter()
        value = peer.restitution(kappa, rtol)
        times.append(time.perf_counter() - started)
    return float(np.median(times)), value
