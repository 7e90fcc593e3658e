"""One collision of the paper's two rods in a thermal bath, with any solver."""

from __future__ import annotations

from ..scene import _assemble_two_rods, _validated_two_rods
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
    g, k, rods = _validated_two_rods(gamma, kappa)  # checked once, here; two_rods' rods (l = 1)
    vibrations = bath.draw((rods[0].length, rods[1].length), seed_sequence(seed))
    scene = _assemble_two_rods(g, k, rods, contact=contact, vibrations=vibrations)
    scene.metadata["bath"] = {"temperature": list(bath.temperature), "modes": bath.modes,
                              "seed": seed if isinstance(seed, int) else repr(seed)}
    return scene
