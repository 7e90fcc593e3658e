"""How fast the rods' modes reach equipartition, for several mode counts (the paper's Fig. 2).

Two rods on a ring start with a cold bath; after every collision the
normalised spectral entropy ``eta`` (Eq. 10) of the modal energies is
recorded.  ``eta`` starts at 1 (empty bath) and falls towards its
equipartition mean (Eq. 11; :func:`~wavecontact.analytic.equilibrium_spectral_entropy_finite`
for the exact finite-``N`` value).  The *settling collision* of one
realisation is the first collision after which ``eta`` lies below
``threshold`` times that mean.

The motion is chaotic, so one realisation says little about the spread.
Realisations here differ only in the ring's circumference (by default each 1.5 %
longer than the previous one; or factors drawn from a root seed), which changes the free flights and hence
the phases of the modes at every later impact, while the first collision
(the cold line collision) is the same for all.

Example
-------
>>> from wavecontact.studies.equipartition import equipartition_by_modes
>>> study = equipartition_by_modes(0.6173, 4000, modes=(10, 75), collisions=60, progress=False)
>>> [row["median_settling"] for row in study.table()]  # doctest: +SKIP
[4.0, 25.0]
"""

from __future__ import annotations

import csv
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..analytic import equilibrium_spectral_entropy, equilibrium_spectral_entropy_finite
from ..errors import InvalidParameterError, require_integer, require_positive
from ..progress import Progress
from ..scene import two_rods_on_a_ring
from ..solvers import solver_for
from ..solvers.base import RING
from .ring_statistics import spectral_entropy

__all__ = ["EquipartitionStudy", "equipartition_by_modes", "settling_collision"]

CIRCUMFERENCE_STEP = 0.015


def settling_collision(entropy, level: float) -> int | None:
    """First collision (counted from 1) after which ``eta <= level``; ``None`` if never."""
    below = np.flatnonzero(np.asarray(entropy, dtype=float) <= level)
    return int(below[0]) + 1 if below.size else None


@dataclass
class EquipartitionStudy:
    """Spectral entropy after each collision, per mode count and realisation.

    Attributes
    ----------
    gamma, kappa : float
        Length ratio and softness ``alpha V l / c`` (``inf``: hard contact).
    threshold : float
        Settling level in units of the finite-``N`` equipartition mean.
    entropy : dict
        ``modes -> ndarray (realisations, collisions)`` of ``eta`` after each collision.
    circumferences : dict
        ``modes -> ndarray (realisations,)`` ring circumference of each realisation (in ``l``).
    wall_time_s : float
        Wall-clock time of the whole study (s).
    """

    gamma: float
    kappa: float
    threshold: float
    entropy: dict = field(default_factory=dict)
    circumferences: dict = field(default_factory=dict)
    wall_time_s: float = 0.0

    @property
    def modes(self) -> tuple:
        return tuple(sorted(self.entropy))

    def equilibrium(self, modes: int) -> float:
        """Finite-``N`` mean of ``eta`` at equipartition (the settling reference)."""
        return equilibrium_spectral_entropy_finite(modes)

    def settling(self, modes: int) -> list:
        """Settling collision of each realisation (``None`` where ``eta`` never got there)."""
        level = self.threshold * self.equilibrium(modes)
        return [settling_collision(series, level) for series in self.entropy[modes]]

    def table(self) -> list[dict]:
        """One row per mode count: equilibrium levels, settling collisions, ``eta`` after 1, 5 and 10 collisions.

        ``median_settling`` is ``None`` unless every realisation settled.
        """
        rows = []
        for n in self.modes:
            series = self.entropy[n]
            settled = self.settling(n)
            complete = all(s is not None for s in settled)
            rows.append({
                "modes": n,
                "eq11": equilibrium_spectral_entropy(n),
                "equilibrium_finite": self.equilibrium(n),
                "settling": settled,
                "median_settling": float(np.median(settled)) if complete else None,
                **{f"eta_after_{k}": float(np.mean(series[:, k - 1])) for k in (1, 5, 10) if k <= series.shape[1]},
            })
        return rows

    def scaling_exponent(self) -> float | None:
        """Slope of log(median settling) against log(N); ``None`` with fewer than two settled mode counts."""
        points = [(row["modes"], row["median_settling"]) for row in self.table() if row["median_settling"]]
        if len(points) < 2:
            return None
        n, s = np.log(np.array(points, dtype=float)).T
        return float(np.polyfit(n, s, 1)[0])

    def save_csv(self, path) -> Path:
        """Write ``modes, realisation, circumference, collision, eta`` rows (one per collision)."""
        path = Path(path)
        with open(path, "w", newline="") as handle:
            writer = csv.writer(handle)
            writer.writerow(["modes", "realisation", "circumference", "collision", "eta"])
            for n in self.modes:
                for r, (series, length) in enumerate(zip(self.entropy[n], self.circumferences[n])):
                    for k, eta in enumerate(series, start=1):
                        writer.writerow([n, r, repr(float(length)), k, repr(float(eta))])
        return path


def equipartition_by_modes(
    gamma: float,
    kappa: float,
    modes=(10, 20, 40, 75),
    collisions: int = 100,
    realisations: int = 5,
    threshold: float = 1.5,
    static_correction: bool = True,
    progress: bool = True,
    circumference_factors=None,
) -> EquipartitionStudy:
    """Record ``eta`` over the first ``collisions`` collisions for each mode count.

    Parameters
    ----------
    gamma : float
        Length ratio ``l1 / l2`` in (0, 1].
    kappa : float
        Softness ``alpha V l / c`` in (0, inf].
    modes : sequence of int
        Modes per rod ``N`` to compare (each >= 2).
    collisions : int
        Collisions per realisation (>= 1).
    realisations : int
        Ring circumferences per mode count (>= 1).
    threshold : float
        Settling level as a multiple (> 1) of the finite-``N`` equipartition mean of ``eta``.
    static_correction : bool
        Passed to :class:`~wavecontact.modal.ring.RingSimulation`.
    progress : bool
        Show a tqdm progress bar on stderr.
    circumference_factors : sequence of float, optional
        The realisations' circumferences as multiples (> 0) of the paper's ring circumference, e.g.
        drawn from a root seed (:func:`~wavecontact.studies.paper_figures.ring_circumference_factor`);
        one realisation per factor, replacing ``realisations``.  Default: the fixed grid
        ``1 + 0.015 r``, ``r = 0 .. realisations - 1``.

    Returns
    -------
    EquipartitionStudy
    """
    import time

    mode_counts = _mode_counts(modes)
    collisions = require_integer("collisions", collisions, 1)
    if circumference_factors is None:
        realisations = require_integer("realisations", realisations, 1)
        factors = [1.0 + CIRCUMFERENCE_STEP * r for r in range(realisations)]
    else:
        factors = [require_positive(f"circumference_factors[{i}]", f) for i, f in enumerate(circumference_factors)]
        if not factors:
            raise InvalidParameterError("circumference_factors must hold at least one factor")
        realisations = len(factors)
    threshold = require_positive("threshold", threshold)
    if threshold <= 1.0:
        raise InvalidParameterError(f"threshold must exceed 1 (a multiple of the equilibrium mean), got {threshold!r}")
    study = EquipartitionStudy(float(gamma), float(kappa), threshold)
    started = time.perf_counter()
    engine = solver_for(RING)
    base = two_rods_on_a_ring(gamma, kappa).ring_circumference
    with Progress(len(mode_counts) * realisations * collisions, "equipartition", unit="collision",
                  enabled=progress) as bar:
        for n in mode_counts:
            options = engine.options({"modes": n, "static_correction": static_correction})
            series, lengths = [], []
            for factor in factors:
                scene = two_rods_on_a_ring(gamma, kappa, base * factor)
                simulation = engine.simulate(scene, options)
                eta = np.empty(collisions)
                for k in range(collisions):
                    record = simulation.next_collision()
                    eta[k] = spectral_entropy(record.modal_energies / record.bath_energy)
                    bar.advance()
                series.append(eta)
                lengths.append(scene.ring_circumference)
            study.entropy[n] = np.array(series)
            study.circumferences[n] = np.array(lengths)
    study.wall_time_s = time.perf_counter() - started
    return study


def _mode_counts(modes) -> tuple:
    values = np.atleast_1d(np.asarray(modes))
    if values.size == 0 or values.ndim != 1:
        raise InvalidParameterError(f"modes must be a non-empty list of integers >= 2, got {modes!r}")
    counts = []
    for value in values:
        counts.append(require_integer("modes", value, 2, allowed="integers >= 2"))
    if len(set(counts)) != len(counts):
        raise InvalidParameterError(f"modes must not repeat, got {counts}")
    return tuple(sorted(counts))

