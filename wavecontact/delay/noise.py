"""The noise term ``Q(tau)`` of the delay equation (Eq. 17).

``Q`` is the end displacement that the rods' initial vibrations would cause
on their own, a Fourier series with the rods' mode frequencies
``2 pi nu / Gamma_i`` (dimensionless time).  A cold bath has ``Q = 0``.
Drawing thermal coefficients (Eq. 18) is left to the thermal-bath study; the
solver only needs the series.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InvalidParameterError

__all__ = ["COLD", "FourierNoise"]


@dataclass(frozen=True)
class FourierNoise:
    """``Q(tau) = sum_j cos_amp[j] cos(freq[j] tau) + sin_amp[j] sin(freq[j] tau)``.

    Parameters
    ----------
    freq : array_like
        Angular frequencies in units of ``c / l`` (dimensionless), finite.
    cos_amp, sin_amp : array_like
        Amplitudes in units of ``1 / alpha`` (``Q`` is a scaled length), finite.
    """

    freq: np.ndarray
    cos_amp: np.ndarray
    sin_amp: np.ndarray

    def __post_init__(self):
        arrays = []
        for name in ("freq", "cos_amp", "sin_amp"):
            a = np.ascontiguousarray(getattr(self, name), dtype=float).ravel()
            if not np.all(np.isfinite(a)):
                raise InvalidParameterError(f"noise {name} must be finite")
            arrays.append(a)
        if not (arrays[0].shape == arrays[1].shape == arrays[2].shape):
            raise InvalidParameterError("noise freq, cos_amp and sin_amp must have the same length")
        for name, a in zip(("freq", "cos_amp", "sin_amp"), arrays):
            object.__setattr__(self, name, a)

    def __call__(self, tau):
        """``Q`` at the dimensionless times ``tau``."""
        tau = np.asarray(tau, dtype=float)[..., None]
        return (self.cos_amp * np.cos(self.freq * tau) + self.sin_amp * np.sin(self.freq * tau)).sum(-1)

    @property
    def amplitude_bound(self) -> float:
        """An upper bound of ``|Q(tau)|`` for all ``tau``."""
        return float(np.sum(np.hypot(self.cos_amp, self.sin_amp)))


COLD = FourierNoise(np.zeros(0), np.zeros(0), np.zeros(0))
