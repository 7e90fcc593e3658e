"""Gas ensembles: identical runs serially, on a thread pool and on a real Dask LocalCluster."""

from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest
from analytic_kick_table import analytic_kick_table

from wavecontact.errors import InvalidParameterError
from wavecontact.gas import FixedRestitution, GasSimulation, UniformLengths, VibrationTable, random_gas
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
    rule = VibrationTable(analytic_kick_table(levels=51))
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
    with pytest.raises(TypeError, match="unexpected keyword argument 'packing'"):
        gas_ensemble(2, rule=FixedRestitution(0.9), packing=0.2, **SPEC)


def test_the_gas_keywords_are_random_gas_s_with_its_defaults():
    """A member is the gas random_gas builds from the ensemble's keywords (its defaults where not given) and
    the run of that gas, rebuilt here from the documented split of the stream."""
    rule = FixedRestitution(0.9)
    spec = {"rods": 20, "collisions": 200, "seed": 5, "temperature": 2.0}
    ensemble = gas_ensemble(2, rule=rule, **spec)
    assert ensemble.spec["packing_fraction"] == 0.1 and ensemble.spec["boundary"] == "ring"
    assert ensemble.spec["temperature"] == 2.0
    initial, dynamics = np.random.SeedSequence(5).spawn(2)[1].spawn(2)
    gas = random_gas(20, seed=initial, temperature=2.0)
    again = GasSimulation(gas, rule, seed=dynamics, record_every=1, max_frames=0).run(200)
    np.testing.assert_array_equal(again.velocities, ensemble.results[1].velocities)
