"""The FE solver on impact scenes against the independent references of tests/references/ (docs/impact.md).

Tolerances come from the method: on the exact lattice (P1 lumped at Courant number 1 on matched
meshes, every interface and event on the lattice) 1e-9; elsewhere the solver's error estimate must
bound its error against the reference, and the observed order (a log-log fit over three meshes) must
be the method's.
"""

import numpy as np
import pytest
from references.central_differences import extrapolate, run
from references.characteristics import chain
from references.saint_venant import saint_venant

from wavecontact import Hard, Hertz, PiecewiseRod, RigidBody, Rod, Scene, Segment, solve

EXACT = 1e-9


def fem(scene, elements, **options):
    return solve(scene, solver="fem", elements=elements, order=1, mass="lumped", **options)


def observed_order(elements, errors):
    """Slope of log(error) against log(h), h ~ 1 / elements."""
    return -np.polyfit(np.log(elements), np.log(errors), 1)[0]


def assert_matches_lattice(result, reference):
    """Velocities, impulses, contact counts, durations and times to 1e-9.

    The FE record's ``last_contact`` is the start of the last step in which the contact acted, the
    reference's the end of it: one step ``dt = result.work['dt']`` apart by definition.  Internal
    energies are not compared here: the FE measures them from nodal values, which spreads each jump of
    the piecewise-constant exact state over one element (first order, see
    test_lattice_internal_energies_converge_at_first_order).
    """
    np.testing.assert_allclose(result.velocities, reference.velocities, rtol=0, atol=EXACT)
    assert len(result.contacts) == len(reference.contacts)
    dt = result.work["dt"]
    for got, want in zip(result.contacts, reference.contacts):
        assert got.impulse == pytest.approx(want.impulse, abs=EXACT)
        assert got.intervals == len(want.intervals)
        assert got.duration == pytest.approx(want.duration, abs=EXACT)
        assert got.first_contact == pytest.approx(want.first_contact, abs=EXACT)
        assert got.last_contact + dt == pytest.approx(want.last_contact, abs=EXACT)


# -- Saint-Venant: a rigid mass on a free-free rod ------------------------------------------------------------

SAINT_VENANT_ELEMENTS = (50, 100, 200)


@pytest.mark.parametrize("ratio", [0.25, 1.0, 4.0])
def test_saint_venant_fem_against_the_method_of_steps(ratio):
    """M / m_rod = ratio on a unit rod (rho = E = A = 1, V = 1): one contact of one round trip (2 l / c),
    mass velocity V exp(-2 m / M); the FE error within its estimate and falling at order >= 1."""
    reference = saint_venant(mass=ratio, rod_length=1.0, impedance=1.0, wave_speed=1.0, velocity=1.0)
    want = np.array([reference.mass_velocity, reference.rod_velocity])
    scene = Scene(rods=(RigidBody(mass=ratio), Rod(1.0)), velocities=(1.0, 0.0), contact=Hard(), gaps=(0.0,))
    errors = []
    for n in SAINT_VENANT_ELEMENTS:
        result = fem(scene, n)
        error = float(np.max(np.abs(np.asarray(result.velocities) - want)))
        assert error <= result.error_estimate, (n, error, result.error_estimate)
        errors.append(max(error, 1e-16))
        (contact,) = result.contacts
        assert contact.intervals == len(reference.intervals) == 1
        assert contact.duration == pytest.approx(reference.duration, abs=result.work["dt"] + 1e-12)
        # the impulse is the mass's momentum change: its error is M times the mass's velocity error
        assert contact.impulse == pytest.approx(reference.impulse, abs=result.error_estimate * ratio)
    if errors[-1] > 1e-13:  # below round-off the fit means nothing
        assert observed_order(SAINT_VENANT_ELEMENTS, errors) >= 0.9


def test_hertz_striker_on_a_long_bar_against_the_semi_infinite_rod():
    """A rigid mass (M = 1, V = 1) with Hertz contact (F = K delta^(3/2), K = 10) on a free rod of length 4
    (rho = E = A = 1, Z = 1): until the far end's echo returns (2 l / c = 8) the struck end moves at F / Z, so
    M y'' = -F, u' = F / Z, F = K (y - u)^(3/2) is the whole problem (integrated here by scipy to 1e-12; contact
    ends after 4.95, before the echo).  The FE's mass velocity within its error estimate, one contact
    interval, the impulse the mass lost, the duration within two steps."""
    from scipy.integrate import solve_ivp

    mass, speed, stiffness, length = 1.0, 1.0, 10.0, 4.0

    def rhs(t, state):
        y, v, u = state
        force = stiffness * max(y - u, 0.0) ** 1.5
        return [v, -force / mass, force / 1.0]

    def separated(t, state):
        return state[0] - state[2]

    separated.terminal, separated.direction = True, -1
    ode = solve_ivp(rhs, (0.0, 50.0), [1e-12, speed, 0.0], events=separated, rtol=1e-12, atol=1e-14, method="DOP853")
    duration, mass_velocity = ode.t_events[0][0], ode.y_events[0][0][1]
    assert duration < 2 * length  # the echo arrives after the contact: the semi-infinite rod holds
    scene = Scene(rods=(RigidBody(mass=mass), Rod(length)), velocities=(speed, 0.0), contact=Hertz(stiffness),
                  gaps=(0.0,))
    for n in (100, 200):
        result = fem(scene, n)
        (contact,) = result.contacts
        assert abs(result.velocities[0] - mass_velocity) <= result.error_estimate, (n, result.velocities)
        assert contact.intervals == 1
        assert contact.impulse == pytest.approx(mass * (speed - result.velocities[0]), abs=1e-12)
        assert contact.duration == pytest.approx(duration, abs=2 * result.work["dt"])


# -- stepped bar ----------------------------------------------------------------------------------------------


@pytest.mark.parametrize("z2", [2.0, 0.5])
def test_stepped_bar_fem_on_the_exact_lattice(z2):
    """Striker (l = 1, Z = 1) on a bar of two unit segments, the second of impedance z2 (E and rho both
    scaled by z2: the same wave speed, so the lattice holds both); the characteristic solution."""
    reference = chain([[(1.0, 1.0)], [(1.0, 1.0), (1.0, z2)]], [1.0, 0.0])
    bar = PiecewiseRod((Segment(length=1.0, area=1.0), Segment(length=1.0, area=1.0, youngs_modulus=z2, density=z2)))
    scene = Scene(rods=(Rod(1.0), bar), velocities=(1.0, 0.0), contact=Hard(), gaps=(0.0,))
    assert_matches_lattice(fem(scene, 40), reference)


@pytest.mark.parametrize("z2", [2.0, 0.5])
def test_stepped_bar_fem_stress_transmitted_and_reflected_with_the_impedance_ratio(z2):
    """The FE's own stress field on the stepped bar: striker [0, 1] (Z1 = 1, V = 1) on a bar [1, 4] (Z1) +
    [4, 7] (Z2 = z2 Z1, E and rho scaled by z2, one wave speed c = 1, unit areas).  Wave theory of impact:
    the incident stress is -Z1 V / 2 for 2 l / c = 2; past the step (t > 3) it is 2 Z2 / (Z1 + Z2) of the
    incident, behind the incident's tail (x < t - 1) the reflection alone is (Z2 - Z1) / (Z1 + Z2) of it,
    ahead of the transmitted front nothing.  P1 lumped at Courant number 1: exact at sample times."""
    bar = PiecewiseRod((Segment(length=3.0, area=1.0), Segment(length=3.0, area=1.0, youngs_modulus=z2, density=z2)))
    scene = Scene(rods=(Rod(1.0), bar), velocities=(1.0, 0.0), contact=Hard(), gaps=(0.0,))
    result = fem(scene, 40, estimate_error=False, record_fields=True, field_samples=400)
    incident = -0.5
    transmitted, reflected = 2 * z2 / (1.0 + z2) * incident, (z2 - 1.0) / (1.0 + z2) * incident
    fields = result.fields["rods"][1]
    x, margin = fields["x"], 0.1
    checked = {"transmitted": 0, "reflected": 0, "ahead": 0}
    for k, t in enumerate(result.fields["time"]):
        if not 3.2 < t < 4.9:  # transmitted front at 4 + (t - 3); the incident pulse ends at the step at t = 5
            continue
        stress = fields["stress"][k]
        region = (x > 4.0 + margin) & (x < 4.0 + (t - 3.0) - margin)
        np.testing.assert_allclose(stress[region], transmitted, rtol=0, atol=EXACT)
        checked["transmitted"] += region.sum()
        region = (x > 7.0 - t + margin) & (x < t - 1.0 - margin)  # reflected front at 4 - (t - 3), incident tail t - 1
        np.testing.assert_allclose(stress[region], reflected, rtol=0, atol=EXACT)
        checked["reflected"] += region.sum()
        region = x > 4.0 + (t - 3.0) + margin
        np.testing.assert_allclose(stress[region], 0.0, rtol=0, atol=EXACT)
        checked["ahead"] += region.sum()
    assert min(checked.values()) > 50, checked


def test_stepped_bar_by_area_on_the_exact_lattice():
    """The same step made by the area (A2 = 2 A1, one material): only the impedance matters."""
    reference = chain([[(1.0, 1.0)], [(1.0, 1.0), (1.0, 2.0)]], [1.0, 0.0])
    bar = PiecewiseRod((Segment(length=1.0, area=1.0), Segment(length=1.0, area=2.0)))
    scene = Scene(rods=(Rod(1.0), bar), velocities=(1.0, 0.0), contact=Hard(), gaps=(0.0,))
    assert_matches_lattice(fem(scene, 40), reference)


# -- chains -----------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("n", [3, 5])
def test_equal_chain_stops_all_but_the_last(n):
    scene = Scene(rods=(Rod(1.0),) * n, velocities=(1.0,) + (0.0,) * (n - 1), contact=Hard(), gaps=(0.0,) * (n - 1))
    result = fem(scene, 20)
    np.testing.assert_allclose(result.velocities, [0.0] * (n - 1) + [1.0], rtol=0, atol=EXACT)
    assert_matches_lattice(result, chain([[(1.0, 1.0)]] * n, [1.0] + [0.0] * (n - 1)))


@pytest.mark.parametrize("lengths", [(0.5, 1.5, 1.0), (0.5, 1.5, 1.0, 0.75, 0.25)])
def test_unequal_chain_fem_on_the_exact_lattice(lengths):
    """Equal impedance, unequal lengths (multiples of 0.25): re-contacts on the lattice."""
    n = len(lengths)
    reference = chain([[(L, 1.0)] for L in lengths], [1.0] + [0.0] * (n - 1))
    scene = Scene(rods=tuple(Rod(L) for L in lengths), velocities=(1.0,) + (0.0,) * (n - 1), contact=Hard(),
                  gaps=(0.0,) * (n - 1))
    assert_matches_lattice(fem(scene, 8 * round(min(lengths) / 0.25)), reference)


def test_mixed_chain_with_a_re_contact_on_the_exact_lattice():
    """Striker 0.5 (Z 1), rod 1.5 (Z 1), stepped rod 1.0 (Z 2) + 0.75 (Z 1), rod 0.25 (Z 0.5), every
    impedance set by E and rho together (one wave speed): the striker touches the second rod twice."""
    layout = [[(0.5, 1.0)], [(1.5, 1.0)], [(1.0, 2.0), (0.75, 1.0)], [(0.25, 0.5)]]
    reference = chain(layout, [1.0, 0.0, 0.0, 0.0])
    assert len(reference.contacts[0].intervals) == 2

    def body(segments):
        if len(segments) == 1:
            (length, z), = segments
            return Rod(length, density=z, youngs_modulus=z)
        return PiecewiseRod(tuple(Segment(length=L, youngs_modulus=z, density=z) for L, z in segments))

    scene = Scene(rods=tuple(body(s) for s in layout), velocities=(1.0, 0.0, 0.0, 0.0), contact=Hard(),
                  gaps=(0.0, 0.0, 0.0))
    assert_matches_lattice(fem(scene, 8), reference)


@pytest.mark.parametrize("layout, velocities", [
    ([[(1.0, 1.0)], [(1.0, 1.0), (1.0, 2.0)]], [1.0, 0.0]),
    ([[(0.5, 1.0)], [(1.5, 1.0)], [(1.0, 1.0)]], [1.0, 0.0, 0.0]),
])
def test_lattice_internal_energies_converge_at_first_order(layout, velocities):
    """The FE's internal energies of vibrating bodies on the lattice: error ~ 1/N (fit 0.9-1.1)."""
    reference = chain(layout, velocities)

    def body(segments):
        return PiecewiseRod(tuple(Segment(length=L, youngs_modulus=z, density=z) for L, z in segments))

    scene = Scene(rods=tuple(body(s) for s in layout), velocities=tuple(velocities), contact=Hard(),
                  gaps=(0.0,) * (len(layout) - 1))
    sizes = (8, 16, 32)
    errors = [np.max(np.abs(np.asarray(fem(scene, n).internal_energies) - reference.internal_energies)) for n in sizes]
    assert 0.9 <= observed_order(sizes, errors) <= 1.1, errors


# -- tapered bar: the observed order against a run at 4x the resolution ---------------------------------------

TAPER_ELEMENTS = (25, 50, 100)


def test_tapered_bar_converges_at_the_observed_order():
    """A striker (l = 0.5) on a linear taper (area 1 -> 1/4 over unit length): velocities at N = 25, 50,
    100 against the run at 400 elements; each error within the solver's estimate, order >= 0.9, and
    momentum exact at every resolution."""
    horn = PiecewiseRod((Segment(length=1.0, area=1.0, end_area=0.25),))
    scene = Scene(rods=(Rod(0.5), horn), velocities=(1.0, 0.0), contact=Hard(), gaps=(0.0,))
    fine = np.asarray(fem(scene, 4 * TAPER_ELEMENTS[-1]).velocities)
    horn_mass = (1.0 + 0.25) / 2.0
    errors = []
    for n in TAPER_ELEMENTS:
        result = fem(scene, n)
        v = np.asarray(result.velocities)
        assert 0.5 * v[0] + horn_mass * v[1] == pytest.approx(0.5, abs=1e-12)
        error = float(np.max(np.abs(v - fine)))
        assert error <= result.error_estimate, (n, error, result.error_estimate)
        errors.append(error)
    assert observed_order(TAPER_ELEMENTS, errors) >= 0.9, errors


def test_tapered_bar_against_separately_written_finite_differences():
    """The same scene by tests/references/central_differences.py at 400, 800, 1600 cells per unit length,
    extrapolated (Richardson, observed order, bound twice the correction): the FE result at 100 elements
    within its own estimate plus that bound."""
    levels = [run([[(0.5, 1.0, 1.0, 1.0, 1.0)], [(1.0, 1.0, 0.25, 1.0, 1.0)]], [1.0, 0.0], n, 5.0)
              for n in (400, 800, 1600)]
    assert all(o.last_contact < 2.0 for o in levels)  # separated long before the end (round trips 1 and 2)
    reference, bound, _ = extrapolate([o.velocities for o in levels])
    horn = PiecewiseRod((Segment(length=1.0, area=1.0, end_area=0.25),))
    scene = Scene(rods=(Rod(0.5), horn), velocities=(1.0, 0.0), contact=Hard(), gaps=(0.0,))
    result = fem(scene, 100)
    error = np.abs(np.asarray(result.velocities) - reference)
    assert np.all(error <= result.error_estimate + bound), (error, result.error_estimate, bound)


def test_uniform_limit_of_the_taper_is_the_lattice():
    """end_area = area: the taper is a uniform rod, exact on the lattice."""
    horn = PiecewiseRod((Segment(length=1.0, area=1.0, end_area=1.0),))
    scene = Scene(rods=(Rod(0.5), horn), velocities=(1.0, 0.0), contact=Hard(), gaps=(0.0,))
    assert_matches_lattice(fem(scene, 8), chain([[(0.5, 1.0)], [(1.0, 1.0)]], [1.0, 0.0]))
