"""Ensembles of rod-gas runs on any executor (``concurrent.futures`` or a ``dask.distributed.Client``).

Realisation ``i`` draws everything from ``SeedSequence(seed).spawn(realisations)[i]``,
split once more into the initial state and the collision draws, so an
ensemble gives the same runs serially, on threads, on processes or on a
Dask cluster, in any order.
"""

from __future__ import annotations

import inspect
import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import require_integer
from ..gas import GasSimulation, random_gas

__all__ = ["GasEnsemble", "gas_ensemble", "run_member"]

MAX_REALISATIONS = 100_000
# the keywords of random_gas that describe the gas (besides rods and seed), with its defaults
GAS_KEYWORDS = {name: parameter.default for name, parameter in inspect.signature(random_gas).parameters.items()
                if name not in ("rods", "seed")}


def run_member(spec: dict, sequence: np.random.SeedSequence):
    """One realisation: build the gas from ``spec`` and run it (a plain function, so executors can ship it)."""
    initial, dynamics = sequence.spawn(2)
    gas = random_gas(spec["rods"], seed=initial, lengths=spec["lengths"], packing_fraction=spec["packing_fraction"],
                     temperature=spec["temperature"], bath_temperature=spec["bath_temperature"],
                     boundary=spec["boundary"])
    sim = GasSimulation(gas, spec["rule"], damping=spec["damping"], seed=dynamics, record_every=spec["record_every"],
                        max_frames=spec["max_frames"])
    return sim.run(spec["collisions"], max_time=spec["max_time"])


@dataclass
class GasEnsemble:
    """The runs of an ensemble, in realisation order."""

    results: list
    seed: int
    spec: dict = field(default_factory=dict)

    def summary(self) -> dict:
        """Counts and means over the realisations (JSON-ready)."""
        collapsed = [r.collapsed for r in self.results]
        energies = np.array([r.final_energy for r in self.results])
        return {
            "realisations": len(self.results),
            "seed": self.seed,
            "collapsed": int(sum(collapsed)),
            "mean_collisions": float(np.mean([r.collisions for r in self.results])),
            "mean_final_energy": float(np.mean(energies)),
            "std_final_energy": float(np.std(energies, ddof=1)) if len(energies) > 1 else 0.0,
            "statuses": [r.status for r in self.results],
        }


def gas_ensemble(realisations, *, rods, collisions, rule, seed, damping=None, record_every=None, max_frames=0,
                 max_time=math.inf, executor=None, **gas) -> GasEnsemble:
    """Run ``realisations`` independent gases.

    Parameters
    ----------
    realisations : int
        Number of runs (1 ... 100,000).
    rods, collisions, rule, damping
        As for :func:`wavecontact.gas.random_gas` and :class:`wavecontact.gas.GasSimulation`.
    seed : int
        Root seed of the ensemble.
    record_every : int, optional
        Collisions between records (default ``max(1, collisions // 200)``).
    max_frames : int
        Space-time frames kept per run (default none).
    max_time : float
        Simulated time at which each run stops.
    executor : object with ``submit(fn, *args)``, optional
        A ``concurrent.futures.Executor`` or a ``dask.distributed.Client``;
        None runs serially here.
    **gas
        The gas of every realisation: the other keywords of :func:`wavecontact.gas.random_gas`
        (``lengths``, ``packing_fraction``, ``temperature``, ``bath_temperature``, ``boundary``; its
        defaults where not given).
    """
    unknown = sorted(set(gas) - set(GAS_KEYWORDS))
    if unknown:
        raise TypeError(f"gas_ensemble() got an unexpected keyword argument {unknown[0]!r}")
    require_integer("realisations", realisations, 1, MAX_REALISATIONS)
    require_integer("seed", seed, 0)
    spec = {
        "rods": rods, "collisions": collisions, "rule": rule, **GAS_KEYWORDS, **gas,
        "damping": damping, "max_frames": max_frames, "max_time": max_time,
        "record_every": record_every if record_every is not None else max(1, int(collisions) // 200),
    }
    # check the whole specification once, here, before anything is shipped to workers
    run_member(dict(spec, collisions=1, rods=rods), np.random.SeedSequence(seed))
    sequences = np.random.SeedSequence(int(seed)).spawn(int(realisations))
    if executor is None:
        results = [run_member(spec, s) for s in sequences]
    else:
        futures = [executor.submit(run_member, spec, s) for s in sequences]
        results = [f.result() for f in futures]
    return GasEnsemble(results, int(seed), spec)
