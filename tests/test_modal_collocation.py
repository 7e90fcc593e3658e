"""Step control of the exponential collocation: the proof behind its long steps where the force is negligible."""

import functools
import math

import numpy as np

from wavecontact.modal.collocation import _free_amplitudes, _free_fall


def _true_fall(h, q, v, omega, coupling, rigid_rate, samples=20001):
    """Largest fall of ``rigid_rate t + sum_j c_j (q_j cos w_j t + v_j sin(w_j t) / w_j)`` below its start on
    ``[0, h]``, by dense sampling (independent of the bound)."""
    t, cosines, sines = _sampled_phases(h, tuple(omega), samples)
    gap = rigid_rate * t[:, 0] + (coupling * (q * cosines + v * sines / omega)).sum(axis=1)
    return gap[0] - gap.min()


@functools.lru_cache(maxsize=4)
def _sampled_phases(h, omega, samples):
    """``t`` (a column) and ``cos(w t)``, ``sin(w t)`` on it: the samples' trigonometry, shared by the many states
    a test samples for one step length and one set of frequencies (the same numbers as computed per state)."""
    t = np.linspace(0.0, h, samples)[:, None]
    omega = np.asarray(omega)
    return t, np.cos(omega * t), np.sin(omega * t)


def _bound(h, q, v, omega, coupling, rigid_rate):
    amplitude = np.empty(q.size)
    _free_amplitudes(q, v, omega, coupling, amplitude)
    return _free_fall(h, q, v, omega, coupling, amplitude, np.cos(omega * h), np.sin(omega * h) / omega, rigid_rate,
                      math.inf)


def test_free_fall_bounds_the_gaps_fall_over_the_step():
    """Rough ends (random amplitudes and phases over 40 modes), any step length: the bound is never below the
    fall found by sampling the free motion densely."""
    rng = np.random.default_rng(np.random.SeedSequence(29).spawn(1)[0])
    omega = np.pi * np.arange(1, 41) * rng.uniform(0.9, 1.1, 40)
    coupling = rng.choice([-1.0, 1.0], 40) * np.sqrt(2.0)
    worst = 0.0
    for _ in range(200):
        energy = rng.exponential(1e-3, 40)
        phase = rng.uniform(0.0, 2.0 * np.pi, 40)
        q = np.sqrt(2.0 * energy) / omega * np.cos(phase)
        v = -np.sqrt(2.0 * energy) * np.sin(phase)
        h = rng.choice([0.003, 0.03, 0.1, 0.5])
        rigid_rate = rng.uniform(-0.3, 0.3)
        true = _true_fall(h, q, v, omega, coupling, rigid_rate)
        bound = _bound(h, q, v, omega, coupling, rigid_rate)
        assert bound >= true - 1e-12, (h, true, bound)
        worst = max(worst, bound / max(true, 1e-300))
    assert worst > 1.0  # the sum of per-mode falls is an upper bound, not the fall itself


def test_free_fall_of_one_mode_is_exact():
    """One mode and no rigid motion: the bound is the mode's own fall (down to its trough where its slope turns
    inside the step), as sampling finds it."""
    omega = np.array([3.0])
    coupling = np.array([0.7])
    for phase in np.linspace(0.0, 2.0 * np.pi, 13):
        q = np.array([0.2 * np.cos(phase)])
        v = np.array([-0.6 * np.sin(phase)])
        for h in (0.1, 0.5, 1.0):  # w h < pi: the exact branch
            np.testing.assert_allclose(_bound(h, q, v, omega, coupling, 0.0), _true_fall(h, q, v, omega, coupling, 0.0),
                                       atol=1e-7)
