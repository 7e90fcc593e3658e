"""The vibration rule's data: a restitution table computed from rod collisions, and the per-collision solve.

:func:`rod_table`
    loads the table shipped with the package (``wavecontact/data/``), an
    ensemble of stochastic collisions of the paper's two rods (delay solver,
    ``kappa = 100``, 250 bath modes) per point of a ``(gamma, T_B/E_tr)``
    grid.  It was produced by the package's own command; docs/gas.md quotes
    it and :data:`REGENERATE` holds it.
:func:`hard_core_draw`
    the solve rule of the default (hard-core) vibration law: one
    :func:`~wavecontact.gas.hardcore_collision.hard_core_collision` per gas
    collision, any temperature ratio, this collision's own per-rod split.
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

__all__ = ["DEFAULT_TABLE_FILE", "REGENERATE", "collision_draw", "hard_core_draw", "rod_table"]

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


def hard_core_draw(*, bath_modes=250, resolution=16):
    """A per-collision ``draw(gamma, temperature_ratio, seed) -> (eps2, rod1_share)``: one hard-core solve.

    The exact counterpart of :class:`~wavecontact.gas.rules.VibrationLaw` (same ``kappa = inf`` model;
    with ``VibrationSolve(draw, per_rod=True)`` each rod at its own temperature, otherwise both at the
    pair's mean, as the law assumes): ``rod1_share = gain_1 / (1 - eps2)`` reproduces this collision's own
    gain of the short rod, ``gain_1 E_tr`` (0.5 when ``eps2 == 1`` exactly, where nothing is lost).
    Any ``T_B/E_tr`` is accepted; the cost grows like its square root (the solve refuses grids beyond
    :data:`~wavecontact.delay.stochastic_hardcore_split.MAX_GRID_POINTS`).
    """
    from .hardcore_collision import hard_core_collision

    def draw(gamma, temperature_ratio, seed):
        pair = tuple(temperature_ratio) if isinstance(temperature_ratio, tuple) else None
        eps2, gain_1, _gain_2 = hard_core_collision(gamma, 0.0 if pair else temperature_ratio, seed,
                                                    bath_modes=bath_modes, resolution=resolution, temperatures=pair)
        lost = 1.0 - eps2
        return eps2, (gain_1 / lost if lost != 0.0 else 0.5)

    return draw


def contact_draw(*, bath_modes=250, resolution=16):
    """A per-collision ``draw(gamma, temperatures, seed, kappa=inf) -> (eps2, rod1_share)``, each rod at its own
    temperature, at the collision's own softness.

    The exact counterpart of :class:`~wavecontact.gas.rules.VibrationLaw` with a soft law: use it as
    ``VibrationSolve(contact_draw(), per_rod=True)`` in a :class:`~wavecontact.gas.GasSimulation` with a
    ``contact_stiffness``, which passes ``kappa = alpha V l``.  ``kappa = inf`` is one hard-core solve
    (``resolution`` grid points per period), finite ``kappa`` one delay solve with its per-rod energy split
    (10 ms to 1 s each).  ``rod1_share = gain_1 / (1 - eps2)`` (0.5 when ``eps2 == 1`` exactly).
    """
    from .collision_law import solve_collision

    def draw(gamma, temperatures, seed, kappa=math.inf):
        if not isinstance(temperatures, tuple):
            temperatures = (float(temperatures), float(temperatures))
        eps2, gain_1 = solve_collision(gamma, float(kappa), temperatures, seed, bath_modes, resolution)
        lost = 1.0 - eps2
        return eps2, (gain_1 / lost if lost != 0.0 else 0.5)

    return draw
