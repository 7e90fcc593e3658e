"""The FE solver's kept meshes (wavecontact.fem.reuse): same numbers as a fresh assembly, never written
into by a solve, and bounded in count and size."""

import numpy as np
import pytest

from wavecontact import collide, two_rods
from wavecontact.fem import reuse
from wavecontact.fem.simulation import build_setup

# every discretization and contact treatment of the two-rod solve (docs/fem.md)
CASES = [
    {"order": 1, "mass": "lumped"},  # characteristic lattice
    {"order": 1, "mass": "consistent"},
    {"order": 2, "mass": "lumped"},
    {"order": 2, "mass": "consistent"},
    {"order": 1, "mass": "lumped", "scheme": "force"},
    {"order": 1, "mass": "lumped", "scheme": "interface"},
    {"order": 1, "mass": "lumped", "scheme": "splitting"},
    {"order": 1, "mass": "lumped", "courant": 0.9},
]


def _arrays(discretization) -> list:
    """Every number a discretization holds, copied."""
    out = []
    for value in vars(discretization).values():
        if isinstance(value, np.ndarray):
            out.append(value.copy())
        elif hasattr(value, "toarray"):
            out.append(value.toarray())
    return out


@pytest.mark.parametrize("options", CASES)
def test_a_kept_mesh_gives_the_numbers_of_a_fresh_one_and_is_not_written_into(options):
    reuse.clear()
    fresh = collide(0.6, 30.0, solver="fem", elements=24, **options)  # builds N, N/2, N/4 and keeps them
    kept = [(key, [_arrays(d) for d in value[0]], value[1]) for key, value in reuse._RECENT.items()]
    assert len(kept) == 3
    again = collide(0.6, 30.0, solver="fem", elements=24, **options)  # from the kept meshes
    if len(options) == 2:  # the automatic scheme also on a warm collision (its runs at 2N join the kept meshes)
        warm = collide(0.6, 30.0, solver="fem", elements=24, bath_temperature=0.5, bath_modes=8, seed=3, **options)
        assert warm.error_estimate > 0.0
    for key, before, step in kept:  # nothing a solve does writes into a kept discretization
        assert reuse._RECENT[key][1] == step
        for disc, arrays in zip(reuse._RECENT[key][0], before):
            assert all(np.array_equal(a, b) for a, b in zip(_arrays(disc), arrays))
    assert again.restitution == fresh.restitution
    assert again.error_estimate == fresh.error_estimate
    assert np.array_equal(again.contact_force, fresh.contact_force)
    reuse.clear()
    cold = collide(0.6, 30.0, solver="fem", elements=24, **options)
    assert (cold.restitution, cold.error_estimate) == (fresh.restitution, fresh.error_estimate)


def test_the_kept_meshes_are_bounded_and_a_users_mesh_is_not_kept(monkeypatch):
    reuse.clear()
    scene = two_rods(0.6, 30.0)
    for elements in range(10, 10 + reuse.RECENT + 4):
        build_setup(scene, elements=elements)
    assert len(reuse._RECENT) == reuse.RECENT
    reuse.clear()
    build_setup(scene, nodes=(np.linspace(0.0, 0.8, 9), np.linspace(0.0, 4.0 / 3.0, 15)))
    assert not reuse._RECENT
    monkeypatch.setattr(reuse, "MOST_NODES", 50)
    build_setup(scene, elements=20)  # 20 + 34 elements: 56 nodes
    assert not reuse._RECENT
    build_setup(scene, elements=10)
    assert len(reuse._RECENT) == 1
    reuse.clear()


def test_solves_on_threads_share_the_kept_meshes_and_give_the_serial_numbers():
    """A thread pool (or dask's threaded workers) runs FE solves at once: more meshes than are kept, so the
    table is read, filled and trimmed from several threads; every result must be the serial one."""
    from concurrent.futures import ThreadPoolExecutor

    calls = [(gamma, kappa) for gamma in (0.3, 0.45, 0.6, 0.75, 0.9) for kappa in (20.0, 100.0)] * 2
    reuse.clear()
    serial = [collide(g, k, solver="fem", elements=40).restitution for g, k in calls]
    reuse.clear()
    with ThreadPoolExecutor(4) as pool:
        threaded = list(pool.map(lambda c: collide(c[0], c[1], solver="fem", elements=40).restitution, calls))
    assert threaded == serial
    assert len(reuse._RECENT) <= reuse.RECENT
