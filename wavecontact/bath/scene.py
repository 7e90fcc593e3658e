"""A realisation placed in a scene: the start gap, the initial fields, the delay solver's noise."""

from __future__ import annotations

import math

import numpy as np

from ..errors import InvalidParameterError
from .model import BathRealisation
from .noise import POINTS_PER_PERIOD, NoiseTables, noise_tables

__all__ = ["EXPONENTIAL_MARGIN", "HARD_MARGIN", "end_reach", "end_reaches", "end_speed", "scene_noise", "start_gap",
           "vibration_fields"]

EXPONENTIAL_MARGIN = 40.0  # alpha * (gap - reach): exp(-40) ~ 4e-18, the force at the start is below round-off
HARD_MARGIN = 0.01  # gap beyond the reach (length units) for contacts without range


def end_reach(vibrations: BathRealisation) -> float:
    """An upper bound of how far both facing ends together can move towards each other (length)."""
    return float(sum(math.sqrt(2.0) * np.sum(np.hypot(q, r))
                     for q, r in zip(vibrations.displacement, vibrations.velocity_amplitude)))


def end_speed(vibrations: BathRealisation) -> float:
    """An upper bound of how fast both facing ends together can move towards each other through their
    vibrations alone (length / time): ``sqrt(2) sum_i sum_nu omega_nu |(q, r)_nu|``, the rate of
    :func:`end_reach`'s sum."""
    return float(sum(math.sqrt(2.0) * np.sum(vibrations.frequencies(i) * np.hypot(q, r))
                     for i, (q, r) in enumerate(zip(vibrations.displacement, vibrations.velocity_amplitude))))


def end_reaches(q, r) -> np.ndarray:
    """:func:`end_reach` of many realisations, bit for bit, from the amplitude arrays ``(S, 2, modes)``
    of :meth:`ThermalBath.draw_amplitudes`."""
    spans = np.hypot(q, r)
    return np.array([float(sum(math.sqrt(2.0) * np.sum(spans[k, i]) for i in range(2))) for k in range(q.shape[0])])


def start_gap(vibrations: BathRealisation, contact) -> float:
    """The start gap a solver uses for this realisation: out of range of the force whatever the phase."""
    reach = end_reach(vibrations)
    if contact.decay_rate > 0.0:
        return reach + EXPONENTIAL_MARGIN / contact.decay_rate
    return reach + HARD_MARGIN


def _check(vibrations, rods):
    if not isinstance(vibrations, BathRealisation):
        raise InvalidParameterError("vibrations must be a wavecontact.bath.BathRealisation (ThermalBath(...).draw(...))")
    for i, rod in enumerate(rods):
        if not math.isclose(vibrations.lengths[i], rod.length, rel_tol=1e-12) or \
                not math.isclose(vibrations.wave_speeds[i], rod.wave_speed, rel_tol=1e-12) or \
                not math.isclose(vibrations.masses[i], rod.mass, rel_tol=1e-12):
            raise InvalidParameterError(
                f"vibrations were drawn for rod {i + 1} of length {vibrations.lengths[i]:g}, "
                f"the scene's rod has length {rod.length:g} (draw them for this scene's rods)"
            )


def vibration_fields(vibrations: BathRealisation, rods, contact, gap):
    """Start gap and initial fields ``(gap, displacement fields, velocity fields)``.

    The realisation holds at the nominal contact time ``gap / V`` (``V = 1``);
    the fields are its free vibration at ``t = 0``.
    """
    _check(vibrations, rods)
    if gap is None:
        gap = start_gap(vibrations, contact)
    at_start = vibrations.evolved(-float(gap))
    displacement = tuple(at_start.displacement_field(i) for i in range(2))
    velocity = tuple(at_start.velocity_field(i) for i in range(2))
    return float(gap), displacement, velocity


def scene_noise(scene, kappa: float, a0: float, points_per_period: int = POINTS_PER_PERIOD,
                tolerance: float | None = None) -> NoiseTables:
    """The delay solver's noise ``Q(tau)`` (tables per rod) for a two-rod scene with vibrations.

    ``tau = 0`` is the solver's start, ``a0 / kappa`` the nominal contact time; ``tolerance`` (a
    scaled length, None: none) refines the tables until their interpolation error is below it
    (:func:`wavecontact.bath.noise.noise_tables`).
    """
    vibrations = scene.vibrations
    if vibrations is None:
        return NoiseTables.empty()
    gamma = scene.metadata["two_rods"].gamma
    periods = (1.0 + gamma, 1.0 + 1.0 / gamma)
    coefficients = vibrations.noise_coefficients(kappa)  # alpha = kappa in the two-rod units
    return noise_tables(coefficients, periods, a0 / kappa, 0.0, points_per_period, tolerance)
