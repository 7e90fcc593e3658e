"""One collision of the paper's two rods in a thermal bath, with any solver."""

from __future__ import annotations

import numpy as np

from ..scene import two_rods
from .model import ThermalBath, seed_sequence

__all__ = ["thermal_scene", "vibration_energy_gain"]


def thermal_scene(gamma, kappa, bath: ThermalBath, seed, *, contact="exponential"):
    """The paper's two rods with vibrations drawn from ``bath`` (see :func:`wavecontact.two_rods`).

    The gap is chosen from the drawn amplitudes (beyond the ends' reach), so
    it differs between realisations; the outcome does not depend on it.
    """
    cold = two_rods(gamma, kappa, contact=contact)
    lengths = tuple(rod.length for rod in cold.rods)
    vibrations = bath.draw(lengths, seed_sequence(seed))
    return two_rods(gamma, kappa, contact=contact, vibrations=vibrations)


def vibration_energy_gain(result, scene):
    """Energy each rod's vibrations gained in the collision (units with ``E_tr = 1/4``).

    delay: from the per-rod memory and noise terms
    (:mod:`wavecontact.delay.energy_split`); modal: modal energies after minus
    the realisation's energy in the modes the solver keeps; fem: the rods'
    internal energy after minus the realisation's (continuous) energy.
    ``None`` in the stochastic hard-core mode, which gives only the total,
    and for the delay solver run with ``energy_split=False``.
    """
    if result.extra.get("hard_core"):
        return None  # the max-plus grid does not resolve the split (see solvers/delay.py)
    if "vibration_energy_gain" in result.extra:
        return np.asarray(result.extra["vibration_energy_gain"], dtype=float)
    if result.solver == "delay":
        return None  # the split was not asked for (energy_split=False)
    vibrations = scene.vibrations
    energies = vibrations.modal_energies() if vibrations is not None else [np.zeros(0), np.zeros(0)]
    if result.solver == "modal":
        after = np.asarray(result.extra["vibration_energy"], dtype=float)
        kept = int(result.work["modes"])
        before = np.array([float(e[:kept].sum()) for e in energies])
        return after - before
    if result.solver == "fem":
        after = np.asarray(result.extra["rod_energy_after"], dtype=float)
        before = np.array([float(e.sum()) for e in energies])
        return after - before
    raise ValueError(f"no vibrational energy bookkeeping for solver {result.solver!r}")
