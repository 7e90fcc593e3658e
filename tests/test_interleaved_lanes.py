"""benchmarks/interleaved_lanes.py: the copies of the interleaved step it times with other lane counts are
the library's step (the same solve to rounding), so its table compares the layouts the library would run."""

import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.linalg import solve_banded
from test_fem_explicit_step import _banded_mass

from wavecontact import Rod, _jit
from wavecontact._jit import NUMBA_ENABLED
from wavecontact.fem import interleaved_step
from wavecontact.fem.discretization import discretize_rod

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
import interleaved_lanes as lanes_bench

pytestmark = pytest.mark.skipif(not NUMBA_ENABLED, reason="the benchmark times compiled kernels")


def _python_copy(lanes, directory):
    """The benchmark's copy of ``interleaved_step`` with ``lanes`` lanes, its kernels left as plain Python.

    Compiling the copy's steps cost 6-8 s per order on every test run (the copy lives in a temporary
    folder, so numba's cache never keeps it); the arithmetic checked here is the same either way, and the
    compiled steps of the layout equal the plain Python ones bit for bit
    (test_fem_explicit_step::test_pure_python_steps_equal_the_compiled_ones_bit_for_bit)."""
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(_jit, "NUMBA_ENABLED", False)  # read by _jit.kernel when the copy's kernels are decorated
        patch.setattr(_jit, "row_view", _jit._row_view_python)
        copy = lanes_bench.lanes_module(lanes, directory)
    assert not hasattr(copy.step_tridiagonal, "signatures") and copy.row_view is _jit._row_view_python
    return copy


@pytest.mark.parametrize("order", [1, 2])
def test_a_copy_with_other_lanes_steps_as_a_banded_solve(tmp_path, order):
    """One step of the 16-chunk copy (run as plain Python) and of the library's own lane count (compiled) on
    a rod of 300 elements: the accelerations of LAPACK's banded solve of the assembled matrices."""
    disc = discretize_rod(Rod(1.0), np.linspace(0.0, 1.0, 301), order, "consistent")
    (lower, upper), banded = _banded_mass(disc)
    u = 1e-3 * np.sin(3.0 * disc.x)
    expected = solve_banded((lower, upper), banded, -(disc.stiffness @ u))
    dt = 2.0**-20
    copy = _python_copy(16, tmp_path)
    assert copy.LANES == 16 != interleaved_step.LANES
    for module in (copy, interleaved_step):
        table = lanes_bench._interleaved_tables(module, disc)[0]
        assert int(table[module.L_SHAPE, 0]) in module.candidate_rows(disc.n_elements + 1)
        (module.step_tridiagonal if order == 1 else module.step_condensed)(table, dt)
        velocity = np.zeros(disc.n_nodes)
        module.unpack_nodes(table[module.L_V], velocity, int(table[module.L_SHAPE, 0]), order)
        np.testing.assert_allclose(velocity / dt, expected, rtol=0, atol=1e-11 * np.abs(expected).max())
