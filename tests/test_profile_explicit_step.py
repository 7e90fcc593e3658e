"""benchmarks/profile_explicit_step.py: its rows run on small meshes, and its "cheapest P2 lumped step" (the
floor that docs/fem.md section 7 sets against the 20x goal) is a correct P2 lumped step."""

import re
import sys
from pathlib import Path

import numpy as np
import pytest

from wavecontact import Rod
from wavecontact.fem.discretization import discretize_rod
from wavecontact.fem.explicit_step import prepare_mass, step_rod

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
import profile_explicit_step as profile

ROW = re.compile(r"^\| .+ \|$")


def _numbers(row):
    return [float(x) for x in re.findall(r"(?<![\w.])[+-]?\d+\.\d+", row)]


@pytest.mark.parametrize("name, order, mass", profile.DISCRETIZATIONS)
def test_the_profiles_rows_run_on_a_small_mesh(name, order, mass):
    # the script calls the library's kernels directly: a change of their signatures must show here,
    # not first when the profile is regenerated
    for row in (profile.profile_row(name, order, mass, 40, 1), profile.loop_row(name, order, mass, 40, 1)):
        assert ROW.match(row) and row.startswith(f"| {name} | ")
        times = _numbers(row.split("|", 3)[3])
        assert times and all(t > 0 for t in times[:2])


def test_the_floor_row_runs_on_a_small_mesh():
    row = profile.floor_row(40, 1, 0.06)
    assert ROW.match(row) and all(t > 0 for t in _numbers(row))


def test_the_cheapest_p2_lumped_step_is_the_p2_lumped_step_on_equal_elements():
    # one step of the floor kernel on the interior of a mesh of equal elements against the library's P2 lumped
    # step: the same displacements and velocities to rounding, so its time is that of a correct step
    elements = 24
    disc = discretize_rod(Rod(1.0), np.linspace(0.0, 1.0, elements + 1), 2, "lumped")
    rng = np.random.default_rng(7)
    u, v = rng.standard_normal(disc.n_nodes), rng.standard_normal(disc.n_nodes)
    dt = 0.5 / elements / 4
    kind, table = prepare_mass(disc)
    u_lib, v_lib, a = u.copy(), v.copy(), np.zeros(disc.n_nodes)
    step_rod(u_lib, v_lib, a, disc.stiffness_bands, kind, table, dt)
    vertex = 2 * (elements // 2)  # an interior vertex: node 2k is vertex k, node 2k + 1 the midpoint to its right
    constants = np.array([-disc.stiffness_bands[1, vertex], -disc.stiffness_bands[2, vertex],
                          dt / disc.lumped_mass[vertex], dt / disc.lumped_mass[vertex + 1]])
    uv, um = u[0::2].copy(), u[1::2].copy()
    vv, vm = v[0::2].copy(), v[1::2].copy()
    uv_new, um_new = np.zeros_like(uv), np.zeros_like(um)
    profile._p2_lumped_floor(uv, um, vv, vm, uv_new, um_new, constants, dt)
    # the floor updates vertices 1 .. E-1 and the midpoints 1 .. E-1 (to their right)
    inner = slice(1, elements)
    for ours, library in ((uv_new, u_lib[0::2]), (um_new, u_lib[1::2]), (vv, v_lib[0::2]), (vm, v_lib[1::2])):
        # rounding of a few terms as large as the largest entry
        np.testing.assert_allclose(ours[inner], library[inner], rtol=0, atol=1e-13 * np.max(np.abs(library)))
