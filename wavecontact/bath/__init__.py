"""The thermal bath: equipartitioned rod vibrations that drive all three solvers (Sec. VI)."""

from .model import BathRealisation, ThermalBath, seed_sequence
from .noise import covariance_eq19, covariance_series, noise_tables

__all__ = ["BathRealisation", "ThermalBath", "covariance_eq19", "covariance_series", "noise_tables", "seed_sequence"]
