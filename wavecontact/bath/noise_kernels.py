"""Bounds of tabulated noise in one pass over the table (compiled; see :mod:`wavecontact.bath.noise`)."""

from __future__ import annotations

import numpy as np

from .._jit import kernel

__all__ = ["table_bounds"]

# |H10|, |H11| <= 4/27 on [0, 1]: the cubic Hermite interpolant of a cell exceeds the larger
# end value by at most 4/27 h (|m0| + |m1|)
HERMITE_SLOPE_BOUND = 4.0 / 27.0


@kernel
def table_bounds(periods, values, slopes, block):
    """Block maxima of each row's cubic Hermite interpolant and each row's largest slope change.

    Parameters
    ----------
    periods : ndarray (R,)
        Each row's period (time units).
    values, slopes : ndarray (R, n)
        Nodes ``j period / n`` of one period (a scaled length and its rate).
    block : int
        Cells per block, a divisor of ``n``.

    Returns
    -------
    block_max : ndarray (R, n / block)
        Upper bound of the interpolant on cells ``k block .. (k + 1) block - 1``.
    curvature : ndarray (R,)
        ``max_j |slopes[j + 1] - slopes[j]| / h`` over the period (``h = period / n``): by the
        mean value theorem each term is the curvature at some point of cell ``j``.
    """
    rows = values.shape[0]
    n = values.shape[1]
    blocks = n // block
    block_max = np.empty((rows, blocks))
    curvature = np.zeros(rows)
    for i in range(rows):
        h = periods[i] / n
        reach = HERMITE_SLOPE_BOUND * h
        peak = 0.0
        for k in range(blocks):
            best = -np.inf
            for j in range(k * block, (k + 1) * block):
                j1 = j + 1
                if j1 == n:
                    j1 = 0
                v0 = values[i, j]
                v1 = values[i, j1]
                s0 = slopes[i, j]
                s1 = slopes[i, j1]
                best = max(best, max(v0, v1) + reach * (abs(s0) + abs(s1)))
                peak = max(peak, abs(s1 - s0))
            block_max[i, k] = best
        curvature[i] = peak / h
    return block_max, curvature
