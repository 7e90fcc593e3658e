"""``solver="auto"`` on line scenes (a rigid mass on a rod, chains, stepped and tapered bars) against the
independent references of tests/references/: the answer meets the tolerance on its velocities (relative to
the largest initial speed, as the line scenes' error estimate), says what it chose, and a tolerance the
limits cannot reach is refused before any run, with the work it would need."""

import numpy as np
import pytest
from references.central_differences import extrapolate, run
from references.characteristics import chain
from references.saint_venant import saint_venant

from wavecontact import Hard, PiecewiseRod, RigidBody, Rod, Scene, Segment, solve
from wavecontact.errors import AccuracyError, LimitError
from wavecontact.fem import multibody
from wavecontact.solvers.auto import _level_change, _observed_order
from wavecontact.solvers.cost_model import load_model, scene_class


def velocity_error(result, reference) -> float:
    return float(np.max(np.abs(np.asarray(result.velocities) - np.asarray(reference))))


def assert_reports_its_choice(result, tolerance):
    auto = result.diagnostics["auto"]
    assert auto["tolerance"] == tolerance
    assert auto["method"] and auto["reason"]
    assert auto["predicted_cpu_s"] > 0.0 and auto["actual_cpu_s"] > 0.0
    assert result.error_estimate <= tolerance


def hammer(ratio):
    return Scene(rods=(RigidBody(mass=ratio), Rod(1.0)), velocities=(1.0, 0.0), contact=Hard(), gaps=(0.0,))


@pytest.mark.parametrize("ratio, tolerance", [(0.7, 1e-6), (2.0, 1e-3), (1.2, 1e-8)])
def test_a_rigid_mass_on_a_rod_is_the_delay_equations_against_saint_venant(ratio, tolerance):
    """The delay solver takes Saint-Venant's scene (second order, milliseconds): auto chooses it, and its
    velocities meet the tolerance against the method of steps' closed form."""
    result = solve(hammer(ratio), tolerance=tolerance)
    assert_reports_its_choice(result, tolerance)
    assert result.solver == "delay"
    assert result.diagnostics["auto"]["scene_class"] == "line_rigid"
    reference = saint_venant(mass=ratio, rod_length=1.0, impedance=1.0, wave_speed=1.0, velocity=1.0)
    assert velocity_error(result, (reference.mass_velocity, reference.rod_velocity)) <= tolerance


def lattice_body(segments):
    if len(segments) == 1:
        (length, z), = segments
        return Rod(length, density=z, youngs_modulus=z)
    return PiecewiseRod(tuple(Segment(length=length, youngs_modulus=z, density=z) for length, z in segments))


@pytest.mark.parametrize("layout, kind", [
    ([[(0.5, 1.0)], [(1.5, 1.0)], [(1.0, 2.0), (0.75, 1.0)], [(0.25, 0.5)]], "line_stepped"),
    ([[(0.5, 1.0)], [(1.5, 1.0)], [(1.0, 1.0)]], "line_chain"),
    ([[(1.0, 1.0)], [(1.0, 1.0), (1.0, 2.0)]], "line_stepped"),
])
def test_chains_and_stepped_bars_are_fem_against_the_characteristics(layout, kind):
    """Chains and stepped bars (one wave speed): only the fem solver takes them; at 1e-3 the answer meets
    the tolerance against the exact characteristic solution."""
    tolerance = 1e-3
    velocities = [1.0] + [0.0] * (len(layout) - 1)
    scene = Scene(rods=tuple(lattice_body(s) for s in layout), velocities=tuple(velocities), contact=Hard(),
                  gaps=(0.0,) * (len(layout) - 1))
    result = solve(scene, tolerance=tolerance)
    assert_reports_its_choice(result, tolerance)
    assert result.solver == "fem" and result.diagnostics["auto"]["scene_class"] == kind
    assert velocity_error(result, chain(layout, velocities).velocities) <= tolerance


def test_a_taper_meets_the_tolerance_against_separately_written_finite_differences():
    """A striker (l = 0.5) on a taper (area 1 -> 1/4): the reference is the central-difference solver at
    400, 800, 1600 cells, extrapolated with its bound; auto at 1e-2 within the tolerance plus that bound."""
    tolerance = 1e-2
    levels = [run([[(0.5, 1.0, 1.0, 1.0, 1.0)], [(1.0, 1.0, 0.25, 1.0, 1.0)]], [1.0, 0.0], n, 5.0)
              for n in (400, 800, 1600)]
    reference, bound, _ = extrapolate([o.velocities for o in levels])
    horn = PiecewiseRod((Segment(length=1.0, area=1.0, end_area=0.25),))
    scene = Scene(rods=(Rod(0.5), horn), velocities=(1.0, 0.0), contact=Hard(), gaps=(0.0,))
    result = solve(scene, tolerance=tolerance)
    assert_reports_its_choice(result, tolerance)
    assert result.diagnostics["auto"]["scene_class"] == "line_tapered"
    assert np.all(np.abs(np.asarray(result.velocities) - reference) <= tolerance + bound)


#: A chain off the exact lattice of every mesh of the ladder: 232/300 is no multiple of 0.5 / (25 2^k)
#: (232 2^k / 6 is never whole); the central differences take it at 300 x 2^j cells per unit.
THIRD = 232.0 / 300.0
OFF_LATTICE = Scene(rods=(Rod(0.5), Rod(1.3), Rod(THIRD)), velocities=(1.0, 0.0, 0.0), contact=Hard(),
                    gaps=(0.0, 0.0))


def test_a_tolerance_first_order_fem_cannot_reach_is_refused_before_any_run(monkeypatch):
    """A chain at 1e-9: the fem solver is first order on line scenes, the elements its fit needs are over
    max_work; refused with the elements and the work, and no run of the multi-body loop made."""
    def no_run(*args, **kwargs):
        raise AssertionError("a run was made before the refusal")

    monkeypatch.setattr(multibody, "run_line", no_run)
    with pytest.raises(LimitError) as refused:
        solve(OFF_LATTICE, tolerance=1e-9)
    message = str(refused.value)
    assert "tolerance=1e-09" in message and "fem: elements=" in message and "max_work" in message


def test_a_rigid_mass_gets_one_bounded_delay_attempt_before_the_refusal(monkeypatch):
    """1e-12 on a hammer: the delay equations stop near 1e-9 (8192 steps per round trip, about 0.1 s) and fem
    would need more than max_work: one delay run at the smallest predicted error, no fem run, then the refusal
    with the fem work it would need."""
    def no_run(*args, **kwargs):
        raise AssertionError("a fem run was made")

    monkeypatch.setattr(multibody, "run_line", no_run)
    with pytest.raises(AccuracyError) as refused:
        solve(hammer(1.0), tolerance=1e-12)
    message = str(refused.value)
    assert message.startswith("auto: delay: rtol=") and "fem: elements=" in message and "max_work" in message
    assert refused.value.result.error_estimate > 1e-12


def test_at_1e_9_the_bounded_delay_attempt_meets_a_light_hammer():
    """M/m = 0.25: the delay equations' finest grid meets 1e-9 though the model predicts a little above it."""
    result = solve(hammer(0.25), tolerance=1e-9)
    assert_reports_its_choice(result, 1e-9)
    reference = saint_venant(mass=0.25, rod_length=1.0, impedance=1.0, wave_speed=1.0, velocity=1.0)
    assert velocity_error(result, (reference.mass_velocity, reference.rod_velocity)) <= 1e-9


def test_the_refusal_follows_max_work(monkeypatch):
    """What runs at the default limits (1e-3, hundreds of elements) is refused at max_work=1e6, before any run."""
    def no_run(*args, **kwargs):
        raise AssertionError("a run was made before the refusal")

    monkeypatch.setattr(multibody, "run_line", no_run)
    with pytest.raises(LimitError, match="max_work"):
        solve(OFF_LATTICE, tolerance=1e-3, max_work=1e6)


def test_off_the_lattice_a_chain_meets_1e_3_against_central_differences():
    """The off-lattice chain against the separately written central differences (300/600/1200 cells per unit),
    extrapolated with its bound."""
    tolerance = 1e-3
    levels = [run([[(0.5, 1.0, 1.0, 1.0, 1.0)], [(1.3, 1.0, 1.0, 1.0, 1.0)], [(THIRD, 1.0, 1.0, 1.0, 1.0)]],
                  [1.0, 0.0, 0.0], n, 8.0) for n in (300, 600, 1200)]
    reference, bound, _ = extrapolate([o.velocities for o in levels])
    result = solve(OFF_LATTICE, tolerance=tolerance)
    assert_reports_its_choice(result, tolerance)
    assert np.all(np.abs(np.asarray(result.velocities) - reference) <= tolerance + bound), bound


def test_on_the_exact_lattice_even_1e_9_is_met_at_the_coarsest_mesh():
    """A chain whose lengths are multiples of the mesh: the FE is d'Alembert's solution at the nodes, auto
    says so and meets 1e-9 against the characteristics."""
    layout = [[(0.5, 1.0)], [(1.5, 1.0)], [(1.0, 1.0)]]
    scene = Scene(rods=tuple(lattice_body(s) for s in layout), velocities=(1.0, 0.0, 0.0), contact=Hard(),
                  gaps=(0.0, 0.0))
    result = solve(scene, tolerance=1e-9)
    assert_reports_its_choice(result, 1e-9)
    assert "exact lattice" in result.diagnostics["auto"]["reason"]
    assert velocity_error(result, chain(layout, [1.0, 0.0, 0.0]).velocities) <= 1e-9


def test_every_line_class_is_calibrated():
    model = load_model()
    for kind in ("line_rigid", "line_chain", "line_stepped", "line_tapered"):
        assert "fem" in model.fits[kind], kind
    assert "delay" in model.fits["line_rigid"]
    assert scene_class(hammer(1.0)) == "line_rigid"


def test_the_observed_order_reads_the_velocities_of_line_levels():
    """Levels of a line scene hold every body's velocity: the order is read from their largest change."""
    from types import SimpleNamespace

    Result = SimpleNamespace(diagnostics={"error_estimate_levels": [
        (400, [1.0, 0.25]), (200, [1.0 + 1e-4, 0.25]), (100, [1.0 + 3e-4, 0.25 - 4e-4])]})

    class Solver:
        @staticmethod
        def expected_order(options):
            return 1.0

    assert _level_change([1.0, 2.0], [1.5, 1.0]) == 1.0
    # changes 1e-4 then 4e-4 (the second body's): order 2 (the first body's alone would say 1)
    assert _observed_order(Solver, None, Result) == pytest.approx(2.0)
