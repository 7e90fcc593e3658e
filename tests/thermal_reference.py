"""An independent integrator for one thermal collision (delay equation with the noise Q, Eq. 16-17).

Nothing in common with the solver but the equation: ``(e^W)' = e^g`` with
``g = kappa tau - a0 - sum_i sum_n W(tau - n Gamma_i) + Q(tau)`` is summed
on a uniform grid, cell by cell with ``g`` taken linear in the cell
(``int e^g = delta (e^g1 - e^g0) / (g1 - g0)``, second order), in logarithms.
``Q`` is each rod's Fourier series evaluated by an inverse FFT on 2^19 points
per period and read by linear interpolation; the delayed ``W`` by linear
interpolation of the grid.  Windows shorter than ``Gamma_1`` only need ``W``
from earlier windows.
"""

import math

import numpy as np


def _noise_on(tau, coefficients, periods, contact_time, points=1 << 19):
    total = np.zeros_like(tau)
    for (_omega, a, b), period in zip(coefficients, periods):
        spectrum = np.zeros(points // 2 + 1, dtype=complex)
        spectrum[1:a.size + 1] = 0.5 * points * (a - 1j * b)
        table = np.fft.irfft(spectrum, points)  # Q_i at contact_time + j period / points
        phase = np.mod(tau - contact_time, period) / period * points
        total += np.interp(phase, np.arange(points + 1), np.append(table, table[0]))
    return total


def thermal_restitution(gamma, kappa, vibrations, a0, end, delta):
    """epsilon of the realisation ``vibrations`` (start gap ``a0``, up to ``tau = end``, grid ``delta``)."""
    delays = (1.0 + gamma, 1.0 + 1.0 / gamma)
    coefficients = vibrations.noise_coefficients(kappa)
    contact_time = a0 / kappa
    count = math.ceil(end / delta)
    tau = np.arange(count + 1) * delta
    w = np.zeros(count + 1)
    window = int(0.5 * delays[0] / delta)
    log_y = 0.0  # Y = e^W = 1 at the start
    for start in range(0, count, window):
        stop = min(start + window, count)
        s = tau[start:stop + 1]
        memory = np.zeros_like(s)
        for period in delays:
            n = 1
            while s[-1] - n * period > 0.0:
                memory += np.interp(s - n * period, tau[:start + 1], w[:start + 1], left=0.0)
                n += 1
        g = kappa * s - a0 - memory + _noise_on(s, coefficients, delays, contact_time)
        g0, g1 = g[:-1], g[1:]
        d = np.abs(g1 - g0)
        factor = np.where(d > 1e-12, -np.expm1(-d) / np.where(d > 1e-12, d, 1.0), 1.0 - 0.5 * d)
        cells = np.maximum(g0, g1) + math.log(delta) + np.log(factor)
        logs = np.logaddexp.accumulate(np.concatenate([[log_y], cells]))
        w[start:stop + 1] = logs
        log_y = logs[-1]
    return w[-1] / kappa - 1.0
