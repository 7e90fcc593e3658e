"""Bounds of tabulated noise in one pass over the table (compiled; see :mod:`wavecontact.bath.noise`)."""

from __future__ import annotations

import numpy as np

from .._jit import kernel

__all__ = ["table_bounds"]

# |H10|, |H11| <= 4/27 on [0, 1]: the cubic Hermite interpolant of a cell exceeds the larger
# end value by at most 4/27 h (|m0| + |m1|)
HERMITE_SLOPE_BOUND = 4.0 / 27.0


@kernel
def table_bounds(periods, values, slopes, block, curvature_block):
    """Block maxima of each row's cubic Hermite interpolant and of its slope changes.

    Parameters
    ----------
    periods : ndarray (R,)
        Each row's period (time units).
    values, slopes : ndarray (R, n)
        Nodes ``j period / n`` of one period (a scaled length and its rate).
    block, curvature_block : int
        Cells per block of the value bounds and of the curvature samples, divisors of ``n``.

    Returns
    -------
    block_max : ndarray (R, n / block)
        Upper bound of the interpolant on cells ``k block .. (k + 1) block - 1``.
    curvature : ndarray (R, n / curvature_block)
        ``max_j |slopes[j + 1] - slopes[j]| / h`` over the cells of each block (``h = period / n``):
        by the mean value theorem each term is the curvature at some point of cell ``j``.
    """
    rows = values.shape[0]
    n = values.shape[1]
    blocks = n // block
    block_max = np.empty((rows, blocks))
    curvature = np.zeros((rows, n // curvature_block))
    for i in range(rows):
        h = periods[i] / n
        reach = HERMITE_SLOPE_BOUND * h
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
                c = j // curvature_block
                curvature[i, c] = max(curvature[i, c], abs(s1 - s0) / h)
            block_max[i, k] = best
    return block_max, curvature
