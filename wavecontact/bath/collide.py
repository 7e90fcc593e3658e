"""One collision of the paper's two rods in a thermal bath, with any solver."""

from __future__ import annotations

from ..scene import two_rods, validate_gamma_kappa
from .model import ThermalBath, seed_sequence

__all__ = ["thermal_scene"]


def thermal_scene(gamma, kappa, bath: ThermalBath, seed, *, contact="exponential"):
    """The paper's two rods with vibrations drawn from ``bath`` (see :func:`wavecontact.two_rods`).

    The gap is chosen from the drawn amplitudes (beyond the ends' reach), so
    it differs between realisations; the outcome does not depend on it.
    ``metadata['bath']`` records the bath's parameters and the seed; every
    solver's result of this scene carries them as ``extra['bath']``, with each
    rod's vibrational energy gain ``extra['vibration_energy_gain']`` where the
    solver gives one (its ``vibration_energy_gain``, :mod:`wavecontact.solvers.base`).
    """
    g, _k = validate_gamma_kappa(gamma, kappa)
    lengths = (0.5 * (1.0 + g), 0.5 * (1.0 + g) / g)  # two_rods' rods (l = 1), built once below
    vibrations = bath.draw(lengths, seed_sequence(seed))
    scene = two_rods(gamma, kappa, contact=contact, vibrations=vibrations)
    scene.metadata["bath"] = {"temperature": list(bath.temperature), "modes": bath.modes,
                              "seed": seed if isinstance(seed, int) else repr(seed)}
    return scene
