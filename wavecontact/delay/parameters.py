"""The numbers of the two-material delay equation, from a scene or from two ratios.

Each rod's contact end answers a force ``F(t)`` (its far end free) with the
displacement ``(I(t) + 2 sum_{n>=1} I(t - n T_i)) / Z_i``, ``I`` the impulse so
far, ``T_i = 2 l_i / c_i`` the round trip and ``Z_i = rho_i c_i A_i`` the
impedance (docs/theory.md, section "Two materials").  With the series
impedance ``Z_s = Z_1 Z_2 / (Z_1 + Z_2)``, the reduced mass ``mu`` and the
time unit ``mu / Z_s`` the gap equation becomes

    W' = exp(kappa tau - a0 - W - sum_i beta_i sum_{n>=1} W(tau - n Gamma_i))

with ``Gamma_i = T_i Z_s / mu`` (dimensionless round trips), echo weights
``beta_i = 2 Z_s / Z_i`` and ``kappa = alpha V mu / Z_s``; epsilon is
``W(inf) / kappa - 1`` as in Eq. 16.  The weights obey ``beta_1 + beta_2 = 2``
and ``beta_1 / Gamma_1 + beta_2 / Gamma_2 = 1`` (momentum), so two ratios
fix everything but ``kappa``: the impedance ratio ``Z_2 / Z_1`` and the
transit-time ratio ``T_1 / T_2``.  For rods of one material and section
``beta_i = 1``, ``Gamma_i = 2 l_i / l``, the time unit is ``l / c`` and the
equation is the paper's Eq. 16.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..errors import InvalidParameterError, UnsupportedSceneError, require_positive

__all__ = ["DelayParameters", "delay_parameters", "echoes_from_ratios"]

# beyond these ratios the weights or the round trips differ by more than 1e6: refuse (bounded work)
RATIO_RANGE = (1e-6, 1e6)


@dataclass(frozen=True)
class DelayParameters:
    """Everything the two-material delay equation needs from a scene.

    Attributes
    ----------
    kappa : float
        ``alpha V mu / Z_s`` (dimensionless, ``inf`` for hard contact).
    round_trip_times : tuple of float
        ``(Gamma_1, Gamma_2) = T_i Z_s / mu`` (dimensionless).
    echo_weights : tuple of float
        ``(beta_1, beta_2) = 2 Z_s / Z_i`` (dimensionless, sum 2).
    time_unit : float
        ``mu / Z_s`` (scene time units): ``t = tau * time_unit``.
    approach_speed : float
        ``V = v_1 - v_2`` (scene velocity units), > 0 for a collision.
    series_impedance : float
        ``Z_s = Z_1 Z_2 / (Z_1 + Z_2)`` (mass/time); the force unit is ``Z_s V``.
    reduced_mass : float
        ``mu = m_1 m_2 / (m_1 + m_2)`` (mass).
    """

    kappa: float
    round_trip_times: tuple
    echo_weights: tuple
    time_unit: float
    approach_speed: float
    series_impedance: float
    reduced_mass: float

    @property
    def impedance_ratio(self) -> float:
        """``Z_2 / Z_1 = beta_1 / beta_2``."""
        return self.echo_weights[0] / self.echo_weights[1]

    @property
    def time_ratio(self) -> float:
        """``T_1 / T_2 = Gamma_1 / Gamma_2``."""
        return self.round_trip_times[0] / self.round_trip_times[1]

    @property
    def equal_impedances(self) -> bool:
        return math.isclose(self.echo_weights[0], self.echo_weights[1], rel_tol=1e-12)

    @property
    def force_unit(self) -> float:
        """``Z_s V`` (force): the contact force is ``W' / kappa`` in this unit."""
        return self.series_impedance * self.approach_speed


def _check_ratio(name, value):
    value = require_positive(name, value)
    if not RATIO_RANGE[0] <= value <= RATIO_RANGE[1]:
        raise InvalidParameterError(f"{name} must lie in [{RATIO_RANGE[0]:g}, {RATIO_RANGE[1]:g}], got {value!r}")
    return value


def echoes_from_ratios(impedance_ratio, time_ratio):
    """Round trips and echo weights for ``Z_2 / Z_1`` and ``T_1 / T_2``.

    Parameters
    ----------
    impedance_ratio : float
        ``Z_2 / Z_1`` in [1e-6, 1e6].
    time_ratio : float
        ``T_1 / T_2`` (round-trip times ``2 l_i / c_i``) in [1e-6, 1e6].

    Returns
    -------
    delays, weights : tuple of float
        ``(Gamma_1, Gamma_2)`` and ``(beta_1, beta_2)``.

    Examples
    --------
    >>> echoes_from_ratios(1.0, 0.6)  # one material: (1 + gamma, 1 + 1/gamma), weights 1
    ((1.6, 2.666666666666667), (1.0, 1.0))
    """
    ratio_z = _check_ratio("impedance_ratio", impedance_ratio)
    ratio_t = _check_ratio("time_ratio", time_ratio)
    beta_1 = 2.0 * ratio_z / (1.0 + ratio_z)
    beta_2 = 2.0 / (1.0 + ratio_z)
    # beta_1 / Gamma_1 + beta_2 / Gamma_2 = 1 with Gamma_2 = Gamma_1 / ratio_t
    gamma_1 = beta_1 + beta_2 * ratio_t
    return (gamma_1, gamma_1 / ratio_t), (beta_1, beta_2)


def delay_parameters(scene) -> DelayParameters:
    """The delay-equation numbers of a two-rod scene on a line, any materials.

    Raises
    ------
    UnsupportedSceneError
        For rings or more than two rods (use solver 'modal' or 'fem').
    InvalidParameterError
        If the rods do not approach each other.
    """
    if scene.is_ring or len(scene.rods) != 2:
        raise UnsupportedSceneError(
            f"the delay solver models two rods on a line, got {len(scene.rods)} rods"
            f"{' on a ring' if scene.is_ring else ''}; use solver='fem' (any line) or 'modal' (two rods, or "
            "wavecontact.modal.RingSimulation for a ring)"
        )
    rod_1, rod_2 = scene.rods
    speed = float(scene.velocities[0] - scene.velocities[1])
    if not speed > 0.0:
        raise InvalidParameterError(
            f"the rods must approach each other (velocities[0] > velocities[1]), got {scene.velocities!r}"
        )
    z_1, z_2 = rod_1.impedance, rod_2.impedance
    series = z_1 * z_2 / (z_1 + z_2)
    reduced_mass = rod_1.mass * rod_2.mass / (rod_1.mass + rod_2.mass)
    time_unit = reduced_mass / series
    delays, weights = echoes_from_ratios(z_2 / z_1, rod_1.round_trip_time / rod_2.round_trip_time)
    law = scene.contact
    if law.decay_rate > 0.0:
        kappa = law.decay_rate * speed * time_unit
    else:  # hard: the limit kappa -> inf; a law acting on overlap only has no alpha (its own numbers)
        kappa = math.inf if law.hard else math.nan
    return DelayParameters(
        kappa=kappa,
        round_trip_times=delays,
        echo_weights=weights,
        time_unit=time_unit,
        approach_speed=speed,
        series_impedance=series,
        reduced_mass=reduced_mass,
    )
