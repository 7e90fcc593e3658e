"""The thermal bath: rods whose vibrations start in equipartition (Eq. 18).

A :class:`ThermalBath` says how warm each rod is and how many of its modes
are excited; :meth:`ThermalBath.draw` turns a seed into one
:class:`BathRealisation`, the modal amplitudes of both rods.  One realisation
drives all three solvers: the delay solver through the noise ``Q(tau)``
(Eq. 17), the modal solver through its initial modal coordinates and the FE
solver through initial displacement and velocity fields on its mesh, all
derived here from the same numbers.

Conventions
-----------
Rod ``i`` (length ``l_i``, mass ``m_i``, wave speed ``c_i``) vibrates as

    u_i(s, t) = sum_nu sqrt(2) cos(nu pi s / l_i) q_{i,nu}(t),
    q(t) = q cos(omega t) + r sin(omega t),   omega_{i,nu} = c_i pi nu / l_i,

with ``r = p / (m omega)``.  Equipartition at temperature ``T_i`` makes ``q``
and ``r`` independent Gaussians of variance ``T_i / (m_i omega^2)``.  The
amplitudes of a realisation describe the rods at the *nominal contact time*,
the moment the rigid ends would meet without vibrations; a solver that starts
earlier evolves them back (free vibration) to its own start.  So the outcome
of one realisation does not depend on how far apart a solver starts the rods.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import InvalidParameterError, require_integer

__all__ = ["MAX_BATH_MODES", "BathRealisation", "ThermalBath", "seed_sequence"]

MAX_BATH_MODES = 100_000  # bounds the memory and the cost of one draw


def seed_sequence(seed) -> np.random.SeedSequence:
    """``seed`` (a non-negative int or a SeedSequence) as a SeedSequence."""
    if isinstance(seed, np.random.SeedSequence):
        return seed
    return np.random.SeedSequence(require_integer("seed", seed, 0,
                                                  allowed="a non-negative integer or a numpy SeedSequence"))


@dataclass(frozen=True)
class ThermalBath:
    """Equipartition of each rod's vibrations, per rod temperature.

    Parameters
    ----------
    temperature : float or pair of float
        ``T_B / E_tr``: bath temperature in units of the translational energy
        ``E_tr = mu V^2 / 2`` of the relative motion, >= 0; a pair gives each
        rod its own temperature ``(T_1, T_2)`` (short rod first).
    modes : int
        Number of excited modes per rod ``nu_max``, in [1, 100000]; the paper uses 250.
    """

    temperature: float | tuple = 0.0
    modes: int = 250

    def __post_init__(self):
        values = self.temperature if isinstance(self.temperature, (tuple, list, np.ndarray)) else (self.temperature,) * 2
        if len(values) != 2:
            raise InvalidParameterError(f"bath temperature must be one number or a pair (T_1, T_2), got {len(values)} values")
        checked = []
        for value in values:
            try:
                number = float(value)
            except (TypeError, ValueError):
                raise InvalidParameterError(f"bath temperature T_B/E_tr must be a number >= 0, got {value!r}") from None
            if not (math.isfinite(number) and number >= 0.0):
                raise InvalidParameterError(f"bath temperature T_B/E_tr must be finite and >= 0, got {number!r}")
            checked.append(number)
        object.__setattr__(self, "temperature", tuple(checked))
        modes = self.modes
        object.__setattr__(self, "modes", require_integer("bath modes (nu_max)", modes, 1, MAX_BATH_MODES))

    @property
    def is_cold(self) -> bool:
        return self.temperature == (0.0, 0.0)

    def draw(self, lengths, seed, *, translational_energy: float = 0.25, masses=None, wave_speeds=(1.0, 1.0)):
        """One realisation of both rods' modal amplitudes.

        Parameters
        ----------
        lengths : pair of float
            Rod lengths ``(l_1, l_2)`` (length units).
        seed : int or numpy.random.SeedSequence
            Source of the realisation; equal seeds give equal realisations.
        translational_energy : float
            ``E_tr`` (energy units) that the temperature ratio refers to; 1/4
            in the paper's units (``mu = 1/2``, ``V = 1``).
        masses : pair of float or None
            Rod masses; ``None`` means ``m_i = l_i`` (``rho A = 1``).
        wave_speeds : pair of float
            Bar wave speeds ``c_i``.

        Returns
        -------
        BathRealisation
            Drawn as ``standard_normal((2, modes))`` per rod, rod 1 first:
            row 0 scales to ``q``, row 1 to ``r = p / (m omega)``.
        """
        rng = np.random.default_rng(seed_sequence(seed))
        lengths = tuple(float(x) for x in lengths)
        masses = lengths if masses is None else tuple(float(m) for m in masses)
        q, r = [], []
        nu = np.arange(1, self.modes + 1)
        draws = rng.standard_normal((2, 2, self.modes))  # the same numbers as two (2, modes) draws, rod 1 first
        for i in range(2):
            normals = draws[i]
            omega = wave_speeds[i] * math.pi * nu / lengths[i]
            spread = np.sqrt(self.temperature[i] * translational_energy / masses[i]) / omega
            q.append(normals[0] * spread)
            r.append(normals[1] * spread)
        return BathRealisation(lengths, masses, tuple(float(c) for c in wave_speeds), tuple(q), tuple(r))


    def draw_amplitudes(self, lengths, seeds, *, translational_energy: float = 0.25, masses=None,
                        wave_speeds=(1.0, 1.0)):
        """The modal amplitudes of many realisations as arrays: :meth:`draw` for every seed, bit for bit.

        Parameters
        ----------
        lengths, translational_energy, masses, wave_speeds
            As for :meth:`draw`.
        seeds : sequence of int or numpy.random.SeedSequence
            One realisation per seed.

        Returns
        -------
        q, r : ndarray (S, 2, modes)
            ``q`` and ``r = p / (m omega)`` of both rods (length units), realisation ``k`` in row ``k``.
        """
        lengths = tuple(float(x) for x in lengths)
        masses = lengths if masses is None else tuple(float(m) for m in masses)
        draws = np.stack([np.random.default_rng(seed_sequence(seed)).standard_normal((2, 2, self.modes))
                          for seed in seeds]) if len(seeds) else np.zeros((0, 2, 2, self.modes))
        nu = np.arange(1, self.modes + 1)
        q = np.empty((len(seeds), 2, self.modes))
        r = np.empty_like(q)
        for i in range(2):  # the arithmetic of draw(), on every realisation at once
            omega = wave_speeds[i] * math.pi * nu / lengths[i]
            spread = np.sqrt(self.temperature[i] * translational_energy / masses[i]) / omega
            q[:, i] = draws[:, i, 0] * spread
            r[:, i] = draws[:, i, 1] * spread
        return q, r


@dataclass(frozen=True)
class BathRealisation:
    """Both rods' modal amplitudes at the nominal contact time (see module docstring).

    Attributes
    ----------
    lengths, masses, wave_speeds : tuple of float
        Per rod, short rod (the left one) first.
    displacement : tuple of ndarray
        ``q_{i,nu}`` (length units), ``nu = 1..modes``.
    velocity_amplitude : tuple of ndarray
        ``r_{i,nu} = p_{i,nu} / (m_i omega_{i,nu})`` (length units).
    """

    lengths: tuple
    masses: tuple
    wave_speeds: tuple
    displacement: tuple
    velocity_amplitude: tuple

    @property
    def modes(self) -> int:
        return int(self.displacement[0].size)

    def frequencies(self, rod: int) -> np.ndarray:
        """Angular frequencies ``omega_{i,nu} = c pi nu / l_i`` (1/time)."""
        nu = np.arange(1, self.displacement[rod].size + 1)
        return self.wave_speeds[rod] * math.pi * nu / self.lengths[rod]

    def evolved(self, time: float) -> BathRealisation:
        """The amplitudes after a free vibration of ``time`` (negative: earlier)."""
        q, r = [], []
        for i in range(2):
            phase = self.frequencies(i) * time
            c, s = np.cos(phase), np.sin(phase)
            q.append(self.displacement[i] * c + self.velocity_amplitude[i] * s)
            r.append(self.velocity_amplitude[i] * c - self.displacement[i] * s)
        return BathRealisation(self.lengths, self.masses, self.wave_speeds, tuple(q), tuple(r))

    def modal_energies(self) -> list:
        """Energy of each mode ``m omega^2 (q^2 + r^2) / 2`` per rod (energy units)."""
        return [
            0.5 * self.masses[i] * self.frequencies(i) ** 2 * (self.displacement[i] ** 2 + self.velocity_amplitude[i] ** 2)
            for i in range(2)
        ]

    def vibration_energy(self) -> np.ndarray:
        """Vibrational energy of each rod (energy units)."""
        return np.array([float(e.sum()) for e in self.modal_energies()])

    def displacement_field(self, rod: int):
        """``u_i(s)`` at this realisation's time, a callable of ``s`` in ``[0, l_i]`` (length units)."""
        return _ModeSum(self.lengths[rod], self.displacement[rod], 1.0)

    def velocity_field(self, rod: int):
        """``du_i/dt(s)`` at this realisation's time (length/time): ``q' = omega r``."""
        return _ModeSum(self.lengths[rod], self.frequencies(rod) * self.velocity_amplitude[rod], 1.0)

    def contact_end_signs(self) -> tuple:
        """Per rod and mode, the factor that turns ``sqrt(2) q`` into the gap-closing end displacement.

        Rod 1's right end (``s = l_1``) closes the gap when it moves right,
        ``cos(nu pi) = (-1)^nu``; rod 2's left end (``s = 0``) closes it when it
        moves left: ``-1``.
        """
        nu = np.arange(1, self.modes + 1)
        return ((-1.0) ** nu, -np.ones(self.displacement[1].size))

    def noise_coefficients(self, alpha: float):
        """Fourier coefficients of each rod's noise term ``Q_i = alpha x (gap-closing end displacement)``.

        Returns
        -------
        list of (omega, a, b)
            ``Q_i(t) = sum a cos(omega (t - t_c)) + b sin(omega (t - t_c))``
            with ``t_c`` the nominal contact time; ``Q = Q_1 + Q_2`` (Eq. 17).
        """
        out = []
        for i, sign in enumerate(self.contact_end_signs()):
            factor = alpha * math.sqrt(2.0) * sign
            out.append((self.frequencies(i), factor * self.displacement[i], factor * self.velocity_amplitude[i]))
        return out


@dataclass(frozen=True)
class _ModeSum:
    """``s -> sum_nu sqrt(2) a_nu cos(nu pi s / l)`` (vectorised, chunked to bound memory)."""

    length: float
    amplitudes: np.ndarray
    scale: float

    def __call__(self, s):
        s = np.asarray(s, dtype=float)
        flat = s.ravel()
        out = np.empty_like(flat)
        nu = np.arange(1, self.amplitudes.size + 1) * (math.pi / self.length)
        chunk = max(1, 2_000_000 // max(1, nu.size))
        for start in range(0, flat.size, chunk):
            part = flat[start:start + chunk]
            out[start:start + chunk] = math.sqrt(2.0) * self.scale * (np.cos(np.outer(part, nu)) @ self.amplitudes)
        return out.reshape(s.shape)
