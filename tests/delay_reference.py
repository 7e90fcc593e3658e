"""An independent reference for the delay equation, shared by the delay-solver tests.

Radau (scipy) on ``W' = exp(kappa tau - a0 - W - sum_i beta_i sum_n W(tau - n Gamma_i))``
window by window (method of steps), the delayed values from the dense output
of earlier windows: nothing in common with the solver's kernel but the equation.
"""

import math

from scipy.integrate import solve_ivp


def radau_method_of_steps(delays, weights, kappa, a0=40.0, rtol=1e-11):
    """An independent reference: Radau on W' = exp(kappa tau - a0 - W - sum beta_i W(tau - n Gamma_i)),
    window by window, delayed values from the dense output of earlier windows."""
    pieces = []

    def history(s):
        if s <= 0.0:
            return 0.0
        for start, stop, sol in pieces:
            if start <= s <= stop:
                return sol.sol(s)[0]
        raise AssertionError(s)

    def memory(s):
        return sum(b * history(s - n * g) for g, b in zip(delays, weights) for n in range(1, int(s // g) + 1))

    t, w, end = 0.0, 0.0, a0 / kappa + 3.0 * sum(delays)
    while t < end:
        stop = min(t + 0.999 * min(delays), end)
        rhs = lambda s, y: [math.exp(min(kappa * s - a0 - y[0] - memory(s), 700.0))]
        sol = solve_ivp(rhs, (t, stop), [w], method="Radau", rtol=rtol, atol=1e-12, dense_output=True)
        pieces.append((t, stop, sol))
        t, w = stop, sol.y[0, -1]
    return w / kappa - 1.0
