"""The noise ``Q(tau)`` of a realisation on FFT grids, and its covariance (Eq. 19).

Each rod's share of ``Q`` is periodic with that rod's round-trip time, so it
is tabulated once per rod on a grid of one period by an inverse real FFT
(values and slopes); a solver then reads it by cubic Hermite interpolation
(:func:`wavecontact.delay.kernels.table_value`) at a cost that does not grow
with the number of bath modes.  ``2 nu_max`` cosines per evaluation would
otherwise multiply the solver's cost.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import InvalidParameterError
from .noise_kernels import table_bounds

__all__ = ["MAX_POINTS_PER_PERIOD", "POINTS_PER_PERIOD", "NoiseTables", "block_maxima", "covariance_eq19",
           "covariance_series", "interpolation_error", "noise_table_batch", "noise_tables", "refined_points",
           "table_points"]

NOISE_EXCURSION = 4.0  # largest departure of Q from its secant over a step where the force may start
POINTS_PER_PERIOD = 32  # table nodes per period of the fastest mode: cubic Hermite error ~ (2 pi / 32)^4 / 384
BOUND_BLOCK = 64  # table cells per entry of the block maxima (NoiseTables.block_max)
CURVATURE_BLOCK = 16  # table cells per entry of the curvature bounds (NoiseTables.curvature_blocks)
CURVATURE_MARGIN = 1.1  # one curvature sample per cell (4 cells per period of the fastest mode at least): 10 %
# for what falls between the samples
MAX_POINTS_PER_PERIOD = 1024  # the finest table a tolerance may ask for (the delay option noise_resolution's range)
HERMITE_ERROR = 1.0 / 384.0  # |f - H f| <= h^4 max|f^(4)| / 384 for the cubic Hermite interpolant of a cell


def table_points(modes: int, points_per_period: int = POINTS_PER_PERIOD) -> int:
    """Table length: ``points_per_period`` nodes per period of the fastest of ``modes`` harmonics,
    at least ``2 modes + 2`` (FFT exactness) and a power of two."""
    wanted = max(points_per_period * modes, 2 * modes + 2, 16)
    return 1 << (wanted - 1).bit_length()


def interpolation_error(spans, n: int) -> float:
    """An upper bound of ``|Q_table - Q|`` anywhere: the cubic Hermite interpolation error of the tables.

    Row ``i`` is ``sum_nu a cos(omega_nu t) + b sin(omega_nu t)`` with ``omega_nu = 2 pi nu / P_i``,
    tabulated at ``n`` nodes a period (``h = P_i / n``) with exact values and slopes, so its
    interpolant is off by at most ``h^4 max|Q_i^(4)| / 384 <= sum_nu |(a, b)_nu| (2 pi nu / n)^4 / 384``
    (the period cancels); the rows' bounds add.

    Parameters
    ----------
    spans : sequence of ndarray
        Per row, ``hypot(a, b)`` of its harmonics ``nu = 1, 2, ...`` (scaled lengths, ``1 / alpha``).
    n : int
        Table nodes a period.

    Returns
    -------
    float
        The bound, in units of ``1 / alpha`` (those of the delay equation's exponent).
    """
    total = 0.0
    for span in spans:
        nu = np.arange(1, len(span) + 1)
        total += float(np.sum(np.asarray(span, dtype=float) * (2.0 * math.pi * nu / n) ** 4)) * HERMITE_ERROR
    return total


def refined_points(spans, modes: int, points_per_period: int, tolerance: float | None) -> int:
    """Table length for ``points_per_period`` (:func:`table_points`), doubled while the interpolation
    error (:func:`interpolation_error` of the rows ``spans``) is above ``tolerance`` (scaled length;
    None: never), up to :data:`MAX_POINTS_PER_PERIOD` nodes a period of the fastest mode."""
    n = table_points(modes, points_per_period)
    if tolerance is None:
        return n
    largest = table_points(modes, max(points_per_period, MAX_POINTS_PER_PERIOD))
    while n < largest and interpolation_error(spans, n) > tolerance:
        n *= 2
    return n


@dataclass(frozen=True)
class NoiseTables:
    """Per-rod periodic tables of ``Q_i`` and ``Q_i'`` (rows), one period each.

    ``values[i, j] = Q_i(origin + j periods[i] / n)``; times in the solver's unit.
    ``block_max[i, k]`` bounds rod ``i``'s interpolated table from above on the
    cells ``k B .. (k + 1) B - 1`` (``B = n / block_max.shape[1]``), so that a
    solver can bound ``Q`` on any interval with a few operations
    (:func:`wavecontact.delay.kernels.noise_upper_bound`).  ``curvature_blocks[i, k]``
    bounds ``|Q_i''|`` on the cells ``k C .. (k + 1) C - 1`` (``C = CURVATURE_BLOCK``, with
    ``CURVATURE_MARGIN``), and ``curvature_bound`` is the sum of the rows' largest bounds.
    ``interpolation_bound`` bounds ``|Q_table - Q|`` anywhere (:func:`interpolation_error`; 0 where
    not computed).
    """

    periods: np.ndarray
    values: np.ndarray
    slopes: np.ndarray
    slope_bound: float
    curvature_bound: float = 0.0
    block_max: np.ndarray = None
    curvature_blocks: np.ndarray = None
    interpolation_bound: float = 0.0

    def __post_init__(self):
        if self.block_max is None or self.curvature_blocks is None:
            block_max, curvature = _bounds(self.periods, self.values, self.slopes)
            object.__setattr__(self, "block_max", block_max)
            object.__setattr__(self, "curvature_blocks", curvature)

    @classmethod
    def empty(cls) -> NoiseTables:
        return cls(np.zeros(0), np.zeros((0, 1)), np.zeros((0, 1)), 0.0)

    @property
    def step_limit(self) -> float:
        """Step over which ``Q`` departs from its secant by at most ``NOISE_EXCURSION`` anywhere
        (``max|Q''| h^2 / 8``); 0 if no noise.  Solvers use the local bounds ``curvature_blocks``."""
        return math.sqrt(8.0 * NOISE_EXCURSION / self.curvature_bound) if self.curvature_bound > 0.0 else 0.0


def block_maxima(periods, values, slopes, block: int = BOUND_BLOCK) -> np.ndarray:
    """Upper bounds of each row's cubic Hermite interpolant over blocks of ``block`` cells.

    Parameters
    ----------
    periods : ndarray (R,)
        Each row's period (time units).
    values, slopes : ndarray (R, n)
        Nodes ``j period / n`` of one period (a scaled length and its rate).
    block : int
        Cells per block; ``min(block, n)`` is used, ``n`` must be a multiple of it.

    Returns
    -------
    ndarray (R, n / block)
    """
    return _bounds(periods, values, slopes, block)[0]


def _bounds(periods, values, slopes, block=BOUND_BLOCK):
    """``(block_max, curvature_blocks)``: :func:`wavecontact.bath.noise_kernels.table_bounds`, the
    curvature samples times ``CURVATURE_MARGIN`` (empty rows allowed)."""
    values = np.ascontiguousarray(values, dtype=float)
    rows, n = values.shape
    if rows == 0:
        return np.zeros((0, 1)), np.zeros((0, 1))
    block = min(block, n)
    curvature_block = min(CURVATURE_BLOCK, n)
    if n % block or n % curvature_block:
        raise InvalidParameterError(f"noise table length {n} is not a multiple of the bound blocks "
                                    f"{block} and {curvature_block}")
    block_max, curvature = table_bounds(np.ascontiguousarray(periods, dtype=float), values,
                                        np.ascontiguousarray(slopes, dtype=float), block, curvature_block)
    return block_max, CURVATURE_MARGIN * curvature


def _harmonic_series(a, b, period, shift, n, slopes=True):
    """Values and slopes of ``sum_nu a cos(2 pi nu (t - t_c)/P) + b sin(...)`` at ``t_c + shift + j P / n``."""
    nu = np.arange(1, a.size + 1)
    coefficients = (a - 1j * b) * np.exp(2j * math.pi * nu * shift / period)
    spectrum = np.zeros(n // 2 + 1, dtype=complex)
    spectrum[1:a.size + 1] = 0.5 * n * coefficients
    values = np.fft.irfft(spectrum, n)
    if not slopes:
        return values, None
    spectrum[1:a.size + 1] *= 2j * math.pi * nu / period
    return values, np.fft.irfft(spectrum, n)


def noise_tables(coefficients, periods, contact_time: float, origin: float = 0.0,
                 points_per_period: int = POINTS_PER_PERIOD, tolerance: float | None = None) -> NoiseTables:
    """Tabulate each rod's noise term on one period.

    Parameters
    ----------
    coefficients : list of (omega, a, b)
        From :meth:`BathRealisation.noise_coefficients`, converted to the
        solver's time unit (``omega_nu = 2 pi nu / periods[i]``).
    periods : sequence of float
        Each rod's period (its round-trip time ``Gamma_i`` in units of ``l / c``).
    contact_time : float
        Time at which the realisation's amplitudes hold (nominal contact).
    origin : float
        Time of the first table node.
    points_per_period : int
        Nodes per period of the fastest mode.
    tolerance : float or None
        Largest interpolation error of ``Q`` wanted (scaled length): the table is refined by
        doubling until :func:`interpolation_error` is below it (:func:`refined_points`); None: not.
    """
    modes = max(a.size for _omega, a, _b in coefficients)
    spans = [np.hypot(np.asarray(a, float), np.asarray(b, float)) for _omega, a, b in coefficients]
    n = refined_points(spans, modes, points_per_period, tolerance)
    shift = origin - contact_time
    # one inverse FFT for all rows: per rod the values and the slopes
    spectra = np.zeros((2 * len(coefficients), n // 2 + 1), dtype=complex)
    bound = 0.0
    for i, ((omega, a, b), period) in enumerate(zip(coefficients, periods)):
        a, b, period = np.asarray(a, float), np.asarray(b, float), float(period)
        nu = np.arange(1, a.size + 1)
        harmonics = 2 * math.pi * nu / period
        if a.size and not np.all(np.abs(omega - harmonics) <= 1e-8 + 1e-12 * np.abs(harmonics)):
            raise InvalidParameterError("noise frequencies must be the harmonics of the given period")
        # as _harmonic_series computes them
        values = 0.5 * n * ((a - 1j * b) * np.exp(2j * math.pi * nu * shift / period))
        spectra[2 * i, 1:a.size + 1] = values
        spectra[2 * i + 1, 1:a.size + 1] = values * (2j * math.pi * nu / period)
        bound += float(np.sum(omega * np.hypot(a, b)))
    return _tables(spectra, n, np.asarray(periods, dtype=float), bound, interpolation_error(spans, n))


def noise_table_batch(a, b, periods, contact_times, origin: float = 0.0,
                      points_per_period: int = POINTS_PER_PERIOD, tolerance: float | None = None) -> list:
    """:func:`noise_tables` of many realisations, bit for bit, with the spectra formed for all at once.

    Parameters
    ----------
    a, b : ndarray (S, R, M)
        Cosine and sine coefficients of each realisation's rods (``Q_i = sum a cos(omega (t - t_c))
        + b sin(...)``, ``omega_nu = 2 pi nu / periods[i]``, ``nu = 1..M``).
    periods : sequence of float (R,)
        Each rod's period.
    contact_times : ndarray (S,)
        Each realisation's nominal contact time ``t_c``.
    origin, points_per_period, tolerance
        As for :func:`noise_tables`.

    Returns
    -------
    list of NoiseTables
    """
    count, _rods, modes = a.shape
    spans = np.hypot(a, b)
    sizes = [refined_points(list(spans[k]), modes, points_per_period, tolerance) for k in range(count)]
    contact_times = np.asarray(contact_times, dtype=float)
    out = [None] * count
    for n in sorted(set(sizes)):  # the realisations whose tables have n nodes, formed together
        group = [k for k in range(count) if sizes[k] == n]
        tables = _table_group(a[group], b[group], spans[group], periods, contact_times[group], origin, n)
        for k, table in zip(group, tables):
            out[k] = table
    return out


def _table_group(a, b, spans, periods, contact_times, origin, n) -> list:
    """:func:`noise_table_batch` of realisations whose tables all have ``n`` nodes a period."""
    count, rods, modes = a.shape
    shift = origin - contact_times
    nu = np.arange(1, modes + 1)
    spectra = np.zeros((count, 2 * rods, n // 2 + 1), dtype=complex)
    weighted = np.empty((count, rods, modes))
    for i, period in enumerate(periods):  # noise_tables' arithmetic, row by row
        period = float(period)
        omega = 2 * math.pi * nu / period
        values = 0.5 * n * ((a[:, i] - 1j * b[:, i]) * np.exp(2j * math.pi * nu * shift[:, None] / period))
        spectra[:, 2 * i, 1:modes + 1] = values
        spectra[:, 2 * i + 1, 1:modes + 1] = values * (2j * math.pi * nu / period)
        weighted[:, i] = omega * np.hypot(a[:, i], b[:, i])
    periods = np.asarray(periods, dtype=float)
    out = []
    for k in range(count):
        bound = 0.0
        for i in range(rods):
            bound += float(np.sum(weighted[k, i]))
        out.append(_tables(spectra[k], n, periods, bound, interpolation_error(list(spans[k]), n)))
    return out


def _tables(spectra, n, periods, bound, interpolation_bound=0.0) -> NoiseTables:
    """The tables of one realisation from its spectra (rows: each rod's values and slopes)."""
    rows = np.fft.irfft(spectra, n, axis=1)
    values, slopes = rows[0::2].copy(), rows[1::2].copy()
    block_max, curvature = _bounds(periods, values, slopes)
    return NoiseTables(periods, values, slopes, bound, float(np.sum(np.max(curvature, axis=1))), block_max, curvature,
                       interpolation_bound)


def covariance_eq19(tau, gamma: float, kappa: float, temperatures) -> np.ndarray:
    """``C_Q(tau)`` of Eq. 19 for infinitely many modes, each rod at its own temperature.

    Parameters
    ----------
    tau : array_like
        Lag (units of ``l / c``).
    gamma, kappa : float
        The paper's numbers.
    temperatures : pair of float
        ``T_i / E_tr`` of each rod.

    Notes
    -----
    Rod ``i`` contributes ``2 kappa^2 T_i [(tau_i - Gamma_i/2)^2 / (2 Gamma_i) - Gamma_i / 24]``
    (``T_i`` in units with ``E_tr = 1/4``, ``tau_i = tau mod Gamma_i``); with
    ``T_1 = T_2`` the sum is Eq. 19 because ``Gamma_1 + Gamma_2 = Gamma_1 Gamma_2``.
    """
    tau = np.abs(np.asarray(tau, dtype=float))
    total = np.zeros_like(tau)
    for ratio, period in zip(temperatures, (1.0 + gamma, 1.0 + 1.0 / gamma)):
        x = np.mod(tau, period)
        total += 2.0 * kappa**2 * (ratio / 4.0) * ((x - 0.5 * period) ** 2 / (2.0 * period) - period / 24.0)
    return total


def covariance_series(tau, gamma: float, kappa: float, temperatures, modes: int) -> np.ndarray:
    """``C_Q(tau)`` of the noise truncated at ``modes`` modes per rod (the finite sum behind Eq. 19)."""
    tau = np.abs(np.asarray(tau, dtype=float))[..., None]
    nu = np.arange(1, modes + 1)
    total = 0.0
    for ratio, period in zip(temperatures, (1.0 + gamma, 1.0 + 1.0 / gamma)):
        length = 0.5 * period
        variance = 2.0 * kappa**2 * (ratio / 4.0) * length / (math.pi**2 * nu**2)
        total = total + np.sum(variance * np.cos(2 * math.pi * nu * tau / period), axis=-1)
    return total
