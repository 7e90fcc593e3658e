"""The vibration rule's data: a restitution table computed from rod collisions, and the per-collision solve.

:func:`rod_table`
    loads the table shipped with the package (``wavecontact/data/``), an
    ensemble of stochastic collisions of the paper's two rods (delay solver,
    ``kappa = 100``, 250 bath modes) per point of a ``(gamma, T_B/E_tr)``
    grid.  It was produced by the package's own command; docs/gas.md quotes
    it and :data:`REGENERATE` holds it.
:func:`collision_draw`
    a ``draw`` for :class:`~wavecontact.gas.rules.VibrationSolve`: one
    thermal collision solved with :func:`wavecontact.collide` per gas
    collision, seeded by the collision's own ``SeedSequence``.
"""

from __future__ import annotations

import math
from importlib import resources

from ..errors import InvalidParameterError
from ..restitution_table import RestitutionTable, load

__all__ = ["DEFAULT_TABLE_FILE", "REGENERATE", "collision_draw", "rod_table"]

DEFAULT_TABLE_FILE = "restitution_table_kappa100.npz"
REGENERATE = ("python -m wavecontact restitution-table --gamma 0.6 0.8 1.0 "
              "--temperature 0 0.3 1 3 10 30 100 --samples 120 --seed 2026 --kappa 100 --bath-modes 250 "
              "--levels 41 --workers 2 --out wavecontact/data/restitution_table_kappa100.npz")


def rod_table() -> RestitutionTable:
    """The restitution table shipped with the package (computed from rod collisions; see :data:`REGENERATE`)."""
    with resources.as_file(resources.files("wavecontact") / "data" / DEFAULT_TABLE_FILE) as path:
        return load(path)


def collision_draw(kappa=100.0, *, solver="delay", max_temperature_ratio=100.0, **options):
    """A per-collision ``draw(gamma, temperature_ratio, seed) -> (eps2, rod1_share)`` from a real solve.

    Parameters
    ----------
    kappa : float
        Softness ``alpha V l / c`` of every collision (finite: the split needs it), as the table's.
    solver : str
        Solver of :func:`wavecontact.collide`.
    max_temperature_ratio : float
        Largest ``T_B/E_tr`` accepted (a slow pair in hot baths makes the
        ratio, and the solve's cost, unbounded); beyond it the draw raises.
    **options
        Passed to :func:`wavecontact.collide` (e.g. ``bath_modes``, ``rtol``).

    Returns
    -------
    callable
        ``eps2`` is the solved ``restitution**2``; ``rod1_share`` is this
        collision's short-rod share of the vibrations' gain (any real number:
        one bath may give energy while the other takes it).
    """
    kappa = float(kappa)
    if not (math.isfinite(kappa) and kappa > 0):
        raise InvalidParameterError(f"kappa must be finite and > 0 for the per-collision solve, got {kappa!r}")

    def draw(gamma, temperature_ratio, seed):
        from ..api import collide

        if not 0.0 <= temperature_ratio <= max_temperature_ratio:
            raise InvalidParameterError(
                f"the per-collision solve accepts T_B/E_tr in [0, {max_temperature_ratio:g}], got {temperature_ratio:g}")
        result = collide(gamma, kappa, solver, bath_temperature=temperature_ratio, seed=seed, **options)
        eps2 = float(result.restitution) ** 2
        gain = result.extra.get("vibration_energy_gain")
        if gain is None:
            raise InvalidParameterError(f"solver {solver!r} gives no per-rod energy split; use delay, modal or fem")
        total = float(gain[0] + gain[1])
        share = float(gain[0]) / total if total != 0.0 else 0.5
        return eps2, share

    return draw
