"""Gas ensembles: identical runs serially, on a thread pool and on a real Dask LocalCluster."""

from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

from wavecontact.errors import InvalidParameterError
from wavecontact.gas import FixedRestitution, UniformLengths, VibrationTable, thermal_kick_table
from wavecontact.studies.gas import gas_ensemble

SPEC = {"rods": 60, "collisions": 3000, "seed": 21, "lengths": UniformLengths(0.6, 1.0), "damping": 20.0}


def _same(a, b):
    assert len(a.results) == len(b.results)
    for x, y in zip(a.results, b.results):
        np.testing.assert_array_equal(x.velocities, y.velocities)
        np.testing.assert_array_equal(x.bath_temperatures, y.bath_temperatures)
        for name in x.history:
            np.testing.assert_array_equal(x.history[name], y.history[name])


def test_realisations_differ_and_threads_reproduce_the_serial_ensemble():
    rule = VibrationTable(thermal_kick_table(levels=51))
    serial = gas_ensemble(4, rule=rule, **SPEC)
    energies = [r.final_energy for r in serial.results]
    assert len(set(energies)) == 4
    with ThreadPoolExecutor(2) as pool:
        _same(serial, gas_ensemble(4, rule=rule, executor=pool, **SPEC))
    assert serial.summary()["realisations"] == 4


def test_dask_local_cluster_with_two_processes_reproduces_the_serial_ensemble():
    distributed = pytest.importorskip("dask.distributed")
    rule = FixedRestitution(0.9)
    serial = gas_ensemble(3, rule=rule, **SPEC)
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None)
    with cluster, distributed.Client(cluster) as client:
        _same(serial, gas_ensemble(3, rule=rule, executor=client, **SPEC))


def test_bad_ensemble_options_are_refused_before_any_work():
    with pytest.raises(InvalidParameterError, match="realisations"):
        gas_ensemble(0, rule=FixedRestitution(0.9), **SPEC)
    with pytest.raises(InvalidParameterError, match="packing_fraction"):
        gas_ensemble(2, rule=FixedRestitution(0.9), packing_fraction=2.0, **SPEC)
