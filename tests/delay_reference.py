"""An independent reference for the delay equation, shared by the delay-solver tests.

Radau (scipy) on ``W' = exp(kappa tau - a0 - W - sum_i beta_i sum_n W(tau - n Gamma_i))``
window by window (method of steps), the delayed values from the dense output
of earlier windows: nothing in common with the solver's kernel but the equation.
"""

import math

from scipy.integrate import solve_ivp


def radau_windows(delays, weights, kappa, a0=40.0, rtol=1e-11):
    """Radau on W' = exp(kappa tau - a0 - W - sum beta_i W(tau - n Gamma_i)), window by window, delayed
    values from the dense output of earlier windows.

    Returns ``(windows, rate)``: ``(start, stop, solution)`` of each window (scipy's dense output) and
    ``rate(tau, W)``, the right-hand side.
    """
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

    def rate(s, w):
        return math.exp(min(kappa * s - a0 - w - memory(s), 700.0))

    t, w, end = 0.0, 0.0, a0 / kappa + 3.0 * sum(delays)
    while t < end:
        stop = min(t + 0.999 * min(delays), end)
        sol = solve_ivp(lambda s, y: [rate(s, y[0])], (t, stop), [w], method="Radau", rtol=rtol, atol=1e-12,
                        dense_output=True)
        pieces.append((t, stop, sol))
        t, w = stop, sol.y[0, -1]
    return pieces, rate


def radau_method_of_steps(delays, weights, kappa, a0=40.0, rtol=1e-11):
    """An independent reference: epsilon = W(end) / kappa - 1 from :func:`radau_windows`."""
    pieces, _rate = radau_windows(delays, weights, kappa, a0, rtol)
    return pieces[-1][2].y[0, -1] / kappa - 1.0
