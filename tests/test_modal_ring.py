"""Two rods on a ring: energy over many collisions, the far pair's sign pattern, exact resume."""

import itertools
import math

import numpy as np
import pytest

import wavecontact
import wavecontact as wc
from wavecontact import Scene
from wavecontact.errors import InvalidParameterError
from wavecontact.modal import RingSimulation
from wavecontact.scene import two_rods_on_a_ring

GAMMA = 0.6173


def _ring(gamma, kappa, modes, circumference=None, **options):
    return RingSimulation(two_rods_on_a_ring(gamma, kappa, circumference), modes, **options)


@pytest.fixture(scope="module")
def long_run():
    ring = _ring(GAMMA, 1000, 20)
    return ring, [ring.next_collision() for _ in range(300)]


def test_energy_is_conserved_over_hundreds_of_collisions(long_run):
    ring, records = long_run
    assert ring.total_energy == pytest.approx(0.5 * ring.reduced_mass * 1.0, rel=1e-14)
    totals = np.array([r.total_energy for r in records])
    # the splitting's error budget is 1e-6 of the total energy per collision (measured: 3e-7)
    assert np.max(np.abs(totals - ring.total_energy)) / ring.total_energy < 300 * 1e-6
    assert abs(float(np.sum(ring.system.mass * ring.system.U))) < 1e-12  # momentum stays zero


def test_collision_records_are_consistent(long_run):
    _, records = long_run
    assert [r.index for r in records] == list(range(300))
    pairs = [r.pair for r in records]
    assert pairs[0] == 0
    assert all(a != b for a, b in itertools.pairwise(pairs))  # the rods go round: near and far alternate
    for before, after in itertools.pairwise(records):
        assert after.translational_energy_before == pytest.approx(before.translational_energy_after, rel=1e-12)
    for r in records:
        assert r.restitution ** 2 == pytest.approx(r.translational_energy_after / r.translational_energy_before, rel=1e-10)
        assert r.modal_energies.shape == (2, 20)
        assert r.bath_energy == pytest.approx(r.modal_energies.sum(), rel=1e-12)
        assert r.total_energy == pytest.approx(r.bath_energy + r.translational_energy_after, rel=1e-9)
    # the cascade cools the translation well below its start
    assert np.mean([r.translational_energy_after for r in records[100:]]) < 0.2 * records[0].translational_energy_before


def test_first_collision_is_the_line_collision():
    ring = _ring(0.6, 100, 40)
    first = ring.next_collision()
    line = wc.collide(0.6, 100, solver="modal", modes=40, correction="static")  # the ring's correction
    assert first.pair == 0
    assert first.restitution == pytest.approx(line.restitution, abs=1e-6)
    np.testing.assert_allclose(first.modal_energies, line.extra["modal_energies"], atol=1e-7)


def test_far_pair_is_the_mirror_image_of_the_near_pair():
    """Reversed velocities: the far pair (across the seam) meets first; by reflection symmetry of
    uniform rods the outcome must equal the near pair's, mode by mode (checks the far pair's geometry;
    its end signs need warm rods, see the next test)."""
    near = _ring(0.6, 100, 30).next_collision()
    ring = _ring(0.6, 100, 30)
    ring.system.U *= -1.0
    far = ring.next_collision()
    assert far.pair == 1
    assert far.restitution == pytest.approx(near.restitution, abs=1e-9)
    np.testing.assert_allclose(far.modal_energies, near.modal_energies, atol=1e-10)


def test_resume_from_a_state_is_bit_for_bit():
    ring = _ring(GAMMA, 4000, 15)
    for _ in range(5):
        ring.next_collision()
    state = {k: np.array(v, copy=True) for k, v in ring.get_state().items()}
    first = [ring.next_collision() for _ in range(5)]
    other = _ring(GAMMA, 4000, 15)
    other.set_state(state)
    second = [other.next_collision() for _ in range(5)]
    for a, b in zip(first, second):
        assert a.restitution == b.restitution
        assert a.index == b.index
        np.testing.assert_array_equal(a.modal_energies, b.modal_energies)


def test_hard_contact_ring_runs():
    """Every hard-contact collision conserves energy; the first (cold) one is the line collision
    by the same integrator, which tends to epsilon = gamma as the modes grow."""
    ring = _ring(GAMMA, math.inf, 20)
    records = [ring.next_collision() for _ in range(20)]
    for record in records:
        assert abs(record.total_energy - ring.total_energy) < 1e-5 * ring.total_energy
    line = wavecontact.collide(GAMMA, math.inf, solver="modal", modes=20, correction="static")
    assert records[0].restitution == pytest.approx(line.restitution, abs=1e-9)
    split_ring = _ring(GAMMA, math.inf, 20, step_method="splitting")
    split_line = wavecontact.collide(GAMMA, math.inf, solver="modal", modes=20, step_method="splitting")
    assert split_ring.next_collision().restitution == pytest.approx(split_line.restitution, abs=1e-9)
    errors = [abs(wavecontact.collide(GAMMA, math.inf, solver="modal", modes=m, step_method="splitting").restitution
                  - GAMMA) for m in (10, 40)]
    assert errors[1] < errors[0]


def test_bad_ring_parameters_are_refused():
    with pytest.raises(InvalidParameterError, match="circumference"):
        _ring(GAMMA, 100, 10, circumference=1.0)
    ring = _ring(GAMMA, 100, 10)
    state = _ring(GAMMA, 100, 12).get_state()
    with pytest.raises(InvalidParameterError):
        ring.set_state(state)


def test_three_rods_on_a_ring_conserve_energy_and_momentum():
    """The modal system is not limited to two rods: three rods, three facing pairs."""
    from wavecontact import Exponential, Rod
    from wavecontact.modal import ModalSystem, analytic_modes

    rods = [Rod(0.8), Rod(1.0), Rod(1.3)]
    circumference = 8.0
    positions = [0.4, 2.5, 5.4]
    velocities = np.array([0.7, -0.2, -0.3])
    velocities -= np.sum([r.mass for r in rods] * velocities) / sum(r.mass for r in rods)
    system = ModalSystem(
        [analytic_modes(r, 20) for r in rods], positions, velocities,
        [(0, 1, 0.0), (1, 2, 0.0), (2, 0, circumference)],
        Exponential(alpha=500.0, strength=0.5 / 500.0**2), force_scale=0.5,
    )
    energy = system.total_energy()
    pairs = set()
    for _ in range(60):
        system.episode[0] = -1
        before = system.U.copy()
        status = system.run_episode()
        assert status == 1
        pairs.add(int(system.episode[0]))
        # a real collision every time (not a pair that had just separated and was still close)
        assert np.max(np.abs(system.U - before)) > 1e-6
    assert pairs == {0, 1, 2}
    assert abs(system.total_energy() - energy) < 1e-5 * energy
    assert abs(system.momentum()) < 1e-12


def test_far_pair_of_warm_rods_is_the_mirror_image_of_a_near_pair():
    """A cold collision cannot tell the end signs apart (modal energies are squares), a warm one can.

    After the first (near) collision the long rod rings. Mirroring the ring (x -> -x) maps the next,
    far-pair impact onto a near-pair impact of the mirrored state: each rod's displacement field
    u(s) -> -u(l - s), i.e. q_nu -> -(-1)^nu q_nu, rigid velocities reversed, and the centre distance
    across the seam becomes the near distance. Both must give the same collision; a far pair coupled
    with the near pair's sign pattern fails this by orders of magnitude."""
    ring = _ring(0.6, 100, 30)
    ring.next_collision()
    state = ring.get_state()
    far = ring.next_collision()
    assert far.pair == 1

    mirrored = _ring(0.6, 100, 30)
    modes = mirrored.modes
    flip = -np.tile((-1.0) ** np.arange(1, modes + 1), 2)
    swapped = dict(state)
    swapped["q"] = state["q"] * flip
    swapped["v"] = state["v"] * flip
    x1, x2 = state["X"]
    swapped["X"] = np.array([-x1, mirrored.circumference - x2])
    swapped["U"] = -state["U"]
    mirrored.set_state(swapped)
    near = mirrored.next_collision()
    assert near.pair == 0
    assert near.restitution == pytest.approx(far.restitution, abs=1e-9)
    np.testing.assert_allclose(near.modal_energies, far.modal_energies, atol=1e-10)


def _ring_state_in_more_modes(state, modes, refined):
    """The same fields in ``refined``, a ring that keeps more modes per rod (the extra ones at rest)."""
    more = refined.modes
    padded = refined.get_state()
    padded.update({name: state[name] for name in ("X", "U", "clock", "episode", "counters", "collisions")})
    for name in ("q", "v"):
        values = np.zeros(2 * more)
        values[:modes], values[more:more + modes] = state[name][:modes], state[name][modes:]
        padded[name] = values
    return padded


def _modal_field(coefficients, rod):
    """``u(s) = sum_nu c_nu sqrt(2/m) cos(nu pi s / l)``: the free-free modes in physical space."""
    nu = np.arange(1, coefficients.size + 1)
    return lambda s: math.sqrt(2.0 / rod.mass) * (np.cos(np.outer(np.atleast_1d(s), nu) * math.pi / rod.length)
                                                  @ coefficients)


def test_warm_far_pair_collision_agrees_with_the_fe_solver():
    """Second collision of the ring (far pair, the long rod ringing from the first) against the FE
    solver started from the same fields on a line (rod 2 left, rod 1 right): the modal result
    converges to the FE one as modes are added to the same initial state."""
    gamma, kappa, modes = GAMMA, 4000, 30
    ring = _ring(gamma, kappa, modes)
    ring.next_collision()
    state = ring.get_state()
    rod1, rod2 = wc.two_rods(gamma, kappa).rods
    q, v, (x1, x2), (u1, u2) = state["q"], state["v"], state["X"], state["U"]
    gap = (x1 + ring.circumference - 0.5 * rod1.length) - (x2 + 0.5 * rod2.length)
    scene = Scene(rods=(rod2, rod1), velocities=(u2, u1), contact=wc.two_rods(gamma, kappa).contact, gaps=(gap,),
                  initial_displacement=(_modal_field(q[modes:], rod2), _modal_field(q[:modes], rod1)),
                  initial_velocity=(_modal_field(v[modes:], rod2), _modal_field(v[:modes], rod1)))
    fe = wc.solve(scene, solver="fem", elements=800).restitution
    errors = []
    for more in (modes, 8 * modes):
        refined = _ring(gamma, kappa, more)
        refined.set_state(_ring_state_in_more_modes(state, modes, refined))
        record = refined.next_collision()
        assert record.pair == 1
        errors.append(abs(record.restitution - fe))
    assert errors[1] < 1e-5 and errors[1] < errors[0] / 10, errors


def test_collocation_collisions_agree_with_a_fine_splitting():
    """The ring's default integrator (exponential collocation) against the other integrator of the same
    equations (the kick-rotate-kick splitting, second order in its step) from the same warm states: the
    splitting converges to the collocation's result as its step shrinks (not yet at its asymptotic rate on
    every warm state at step/8: a state where split/8 was 4.5e-8 off and split/32 4e-9, while the collocation
    agreed with a four times finer one at tolerance 1e-7 to 7e-11)."""
    ring = _ring(GAMMA, 1000, 20)
    states = []
    for index in range(24):
        if index % 8 == 7:
            states.append(ring.get_state())
        ring.next_collision()
    for state in states:
        results = {}
        for name, options in (("collocation", {}), ("split", {"step_method": "splitting", "step_accuracy": 0.0125}),
                              ("split/8", {"step_method": "splitting", "step_accuracy": 0.0125 / 8}),
                              ("split/32", {"step_method": "splitting", "step_accuracy": 0.0125 / 32})):
            other = _ring(GAMMA, 1000, 20, **options)
            other.set_state(state)
            results[name] = other.next_collision()
        errors = [abs(results[name].restitution - results["collocation"].restitution)
                  for name in ("split", "split/8", "split/32")]
        assert results["collocation"].pair == results["split/32"].pair
        assert errors[2] < 1e-8, errors
        assert errors[2] < errors[1] / 4 or errors[1] < 3e-9, errors  # second order: 16x smaller for 4x smaller
        assert errors[1] < errors[0] / 10 or errors[0] < 3e-9, errors  # ... and 64x for 8x
        np.testing.assert_allclose(results["collocation"].modal_energies, results["split/32"].modal_energies,
                                   atol=1e-8 * ring.total_energy)


def test_quick_newton_solves_the_same_collisions_with_fewer_iterations(monkeypatch, long_run):
    """The ring's quick Newton rules (force-free start where the forces barely move the gaps, stop on
    quadratic convergence, no load for negligible forces) against the rules before from the same warm
    states: the same restitution within the collocation's own error (3e-8; the step sequences may differ
    once a step's size rounds differently: 7e-9 on one of these states), fewer Newton iterations per step."""
    import wavecontact.modal.ring as ring_module

    ring, _ = long_run
    walker = _ring(GAMMA, 1000, 20)
    walker.set_state(ring.get_state())
    states = []
    for _ in range(5):
        states.append(walker.get_state())
        walker.next_collision()
    results = {}
    for quick in (False, True):
        monkeypatch.setattr(ring_module, "QUICK_NEWTON", quick)
        restitutions, iterations, steps = [], 0, 0
        for state in states:
            other = _ring(GAMMA, 1000, 20)
            other.set_state(state)
            record = other.next_collision()
            restitutions.append(record.restitution)
            pair = other._pairs[record.pair]
            iterations += int(pair.counters[4])
            steps += int(pair.counters[0])
        results[quick] = (np.array(restitutions), iterations / steps)
    np.testing.assert_allclose(results[True][0], results[False][0], rtol=0.0, atol=3e-8)
    assert results[True][1] < 0.75 * results[False][1], (results[True][1], results[False][1])
