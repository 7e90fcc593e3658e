"""The many-collision ring study: statistics, checkpoint/resume, CLI, and the physics of Sec. III."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy import special, stats

from wavecontact import analytic
from wavecontact.analytic import equilibrium_spectral_entropy, equilibrium_translational_energy
from wavecontact.cli import main as cli_main
from wavecontact.errors import CheckpointError, InvalidParameterError
from wavecontact.result import CollisionRecord
from wavecontact.studies import ring as ring_study
from wavecontact.studies.ring import RingRun, run_ring
from wavecontact.studies.ring_statistics import (
    decorrelation_stride,
    ks_exponential,
    relative_modal_energies,
    relaxation_collisions,
    restitution_correlation,
    settling_index,
    spectral_entropy,
)

try:
    from wavecontact.modal.ring import RingSimulation  # noqa: F401

    HAVE_RING_SIMULATION = True
except ImportError:
    HAVE_RING_SIMULATION = False

needs_ring_simulation = pytest.mark.skipif(
    not HAVE_RING_SIMULATION, reason="wavecontact.modal.ring.RingSimulation not available"
)


class ExchangeToyRing:
    """A stand-in for RingSimulation with an exactly known stationary law.

    The state is the translational energy and the 2N modal energies.  A
    "collision" first splits the pooled energy of the translation and a
    random mode by a uniform fraction, then does the same for ``2N`` random
    pairs of energies.  Every such move leaves the uniform law on the simplex
    ``sum = E_total`` invariant (a Dirichlet(1, ..., 1) conditioned on the sum
    of two entries splits that sum uniformly), so in the stationary state
    ``E_tr / E_total ~ Beta(1, 2N)``, mean ``E_total / (2N + 1)`` (Eq. 8), and
    ``w`` is uniform on the simplex of the 2N modes.
    """

    def __init__(self, scene, options):
        self.modes = options.modes
        self.reduced_mass = 0.5
        self.total_energy = 0.25
        self.energies = np.zeros(2 * self.modes + 1)
        self.energies[0] = self.total_energy
        self.time = 0.0
        self.count = 0

    def _split(self, rng, a, b):
        pooled = self.energies[a] + self.energies[b]
        self.energies[a] = rng.random() * pooled
        self.energies[b] = pooled - self.energies[a]

    def next_collision(self):
        rng = np.random.default_rng([12345, self.count])  # one stream per collision: the state is plain arrays
        before = self.energies[0]
        self.time += 1.0 / math.sqrt(2.0 * before / self.reduced_mass)
        size = self.energies.size
        self._split(rng, 0, int(rng.integers(1, size)))
        for _ in range(size - 1):
            a, b = rng.choice(size, 2, replace=False)
            self._split(rng, int(a), int(b))
        after = self.energies[0]
        record = CollisionRecord(
            index=self.count, time=self.time, pair=self.count % 2, translational_energy_before=before,
            translational_energy_after=after, restitution=math.sqrt(after / before),
            modal_energies=self.energies[1:].reshape(2, self.modes), bath_energy=float(self.energies[1:].sum()),
            total_energy=float(self.energies.sum()), steps=1,
        )
        self.count += 1
        return record

    def get_state(self):
        return {"energies": self.energies.copy(), "time": np.asarray(self.time), "count": np.asarray(self.count)}

    def set_state(self, state):
        self.energies = np.array(state["energies"], copy=True)
        self.time = float(state["time"])
        self.count = int(state["count"])


# ----------------------------------------------------------------------------
# Statistics on inputs with known answers
# ----------------------------------------------------------------------------


def test_equilibrium_formulas():
    assert equilibrium_translational_energy(75) == pytest.approx(0.5 / (2 * 151))
    assert equilibrium_translational_energy(10, reduced_mass=2.0, approach_speed=3.0) == pytest.approx(18.0 / 42.0)
    assert equilibrium_spectral_entropy(75) == pytest.approx(0.423 / math.log(150))
    # 0.423 is 1 - Euler's constant, the mean of x ln x for exponential x of mean 1.
    assert analytic.ENTROPY_CONSTANT == pytest.approx(0.423, abs=5e-4)
    for bad in (0, -3, 2.5, True):
        with pytest.raises(InvalidParameterError):
            equilibrium_translational_energy(bad)


def test_spectral_entropy_limits():
    n = 7
    uniform = np.full((2, n), 1.0 / (2 * n))
    assert spectral_entropy(uniform) == pytest.approx(0.0, abs=1e-14)
    single = np.zeros((2, n))
    single[1, 3] = 1.0
    assert spectral_entropy(single) == pytest.approx(1.0)
    # two equal modes: h = ln 2
    pair = np.zeros((2, n))
    pair[0, 0] = pair[1, 0] = 0.5
    assert spectral_entropy(pair) == pytest.approx(1.0 - math.log(2) / math.log(2 * n))
    # cold bath: w undefined, eta = 1 as in the paper (h = 0 at t = 0)
    w = relative_modal_energies(np.zeros((3, 2, n)))
    assert np.all(w == 0.0)
    np.testing.assert_allclose(spectral_entropy(w), 1.0)
    with pytest.raises(InvalidParameterError):
        relative_modal_energies(np.array([[1.0, -1.0], [0.0, 1.0]]))


def test_spectral_entropy_of_boltzmann_modes_matches_eq11():
    """Modal energies i.i.d. exponential: E[h] = H_M - 1 exactly (uniform Dirichlet), and Eq. 11 for large M."""
    rng = np.random.default_rng(3)
    n = 75
    energies = rng.exponential(size=(20000, 2, n))
    eta = spectral_entropy(relative_modal_energies(energies))
    m = 2 * n
    exact = 1.0 - (special.digamma(m + 1) - special.digamma(2)) / math.log(m)
    assert analytic.equilibrium_spectral_entropy_finite(n) == pytest.approx(exact, rel=1e-12)
    harmonic = sum(1.0 / k for k in range(1, m + 1))
    assert exact == pytest.approx(1.0 - (harmonic - 1.0) / math.log(m), rel=1e-12)
    standard_error = np.std(eta) / math.sqrt(eta.size)
    assert abs(np.mean(eta) - exact) < 4 * standard_error
    assert exact == pytest.approx(equilibrium_spectral_entropy(n), rel=0.01)


def test_correlation_of_iid_data_is_small_and_of_ar1_is_phi():
    rng = np.random.default_rng(11)
    n = 20000
    iid = rng.normal(0.6, 0.1, size=n)
    corr = restitution_correlation(iid, max_lag=5)
    assert corr[0] == pytest.approx(0.01, rel=0.05)
    assert np.all(np.abs(corr[1:] / corr[0]) < 4 / math.sqrt(n))
    # an AR(1) series with coefficient phi has C(k)/C(0) = phi^k
    phi = 0.7
    x = np.empty(n)
    x[0] = 0.0
    noise = rng.normal(size=n)
    for j in range(1, n):
        x[j] = phi * x[j - 1] + noise[j]
    corr = restitution_correlation(x, max_lag=3, start=100)
    np.testing.assert_allclose(corr[1:] / corr[0], phi ** np.arange(1, 4), atol=0.03)
    # 0.7^6 = 0.118 > 0.1 > 0.7^7 = 0.082: thinning by 6-8 makes the samples nearly independent
    assert 6 <= decorrelation_stride(x, threshold=0.1) <= 8
    assert decorrelation_stride(iid) == 1
    with pytest.raises(InvalidParameterError):
        restitution_correlation(iid[:5], max_lag=4)


def test_ks_accepts_exponential_and_rejects_uniform():
    rng = np.random.default_rng(5)
    mean = 0.002
    assert ks_exponential(rng.exponential(mean, size=2000), mean).pvalue > 0.01
    assert ks_exponential(rng.uniform(0, 2 * mean, size=2000), mean).pvalue < 1e-6
    # the right law with the wrong mean (10 % off) is rejected too
    assert ks_exponential(rng.exponential(1.1 * mean, size=5000), mean).pvalue < 1e-3


def test_relaxation_and_settling():
    rng = np.random.default_rng(8)
    level = 0.01
    decay = 0.25 * np.exp(-np.arange(60) / 6.0) + level
    series = np.concatenate([decay, rng.exponential(level, size=2000)])
    j = relaxation_collisions(series, level, window=20)
    # the excess 0.25 exp(-j/6) falls below 10x the band (2 level / sqrt(20)) at j = 10.3 and below
    # the band itself at j = 24; a forward window mean enters the band in between
    assert j is not None and 10 <= j <= 25
    assert relaxation_collisions(np.full(100, 10 * level), level) is None
    assert settling_index([5, 4, 3, 2, 1, 1, 1], 1.0, 0.01, 2) == 4


# ----------------------------------------------------------------------------
# Running, checkpoints and resume (stand-in simulation)
# ----------------------------------------------------------------------------


def _toy_run(tmp_path=None, collisions=300, modes=6, **kwargs):
    return run_ring(0.6173, 4000, modes, collisions, out_dir=tmp_path, progress=False,
                    simulation_factory=ExchangeToyRing, **kwargs)


def _assert_same_run(a: RingRun, b: RingRun):
    for name in RingRun._ARRAYS:
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)


def test_toy_run_reaches_its_known_stationary_law():
    """The study, on a system whose answer is known, finds Eq. 8, Eq. 9 and Eq. 11."""
    modes = 10
    run = _toy_run(collisions=3000, modes=modes)
    assert run.n_collisions == 3000
    assert run.modal_energies.shape == (3000, 2, modes)
    np.testing.assert_allclose(run.total_energy, 0.25, rtol=1e-12)
    s = run.statistics()
    e_eq = equilibrium_translational_energy(modes)
    assert s.relaxation_collisions is not None and s.relaxation_collisions < 30
    assert abs(s.mean_translational_energy - e_eq) < 4 * s.translational_energy_standard_error
    # the exact law is Beta(1, 2N) * E_total; at N = 10 the exponential Eq. 9 is close to it
    exact = stats.kstest(run.translational_energy[s.transient:] / 0.25, "beta", args=(1, 2 * modes))
    assert exact.pvalue > 1e-3
    assert s.ks_pvalue > 1e-3
    exact_eta = 1.0 - (special.digamma(2 * modes + 1) - special.digamma(2)) / math.log(2 * modes)
    assert s.mean_spectral_entropy == pytest.approx(exact_eta, abs=0.01)
    assert abs(s.restitution_correlation_coefficient_lag1) < 0.15
    assert s.entropy_settling_collisions is not None and s.entropy_settling_collisions <= 10
    assert s.energy_drift < 1e-12


def test_interrupted_run_resumes_to_the_same_result(tmp_path):
    reference = _toy_run(tmp_path / "straight", collisions=120, checkpoint_every=25)

    def interrupt(index, record):
        if index == 61:
            raise KeyboardInterrupt

    interrupted = []
    with pytest.raises(KeyboardInterrupt):
        _toy_run(tmp_path / "broken", collisions=120, checkpoint_every=25, callback=interrupt,
                 log=interrupted.append)
    assert interrupted == ["interrupted; run again to resume from the checkpoint after collision 50"]
    assert (tmp_path / "broken" / ring_study.CHECKPOINT_NAME).exists()
    assert not list((tmp_path / "broken").glob(".*.tmp")), "a temporary checkpoint file was left behind"
    messages = []
    resumed = _toy_run(tmp_path / "broken", collisions=120, checkpoint_every=25, log=messages.append)
    assert resumed.resumed_from == 50
    assert "collision 50" in messages[0]
    _assert_same_run(reference, resumed)
    # the written data agree as well
    _assert_same_run(RingRun.load_npz(tmp_path / "straight" / "ring.npz"),
                     RingRun.load_npz(tmp_path / "broken" / "ring.npz"))
    assert (tmp_path / "straight" / "ring.csv").read_text() == (tmp_path / "broken" / "ring.csv").read_text()


def test_a_run_stopped_between_its_rows_and_its_checkpoint_resumes_to_the_same_result(tmp_path, monkeypatch):
    """The rows new since the last checkpoint go to a chunk file first, then the checkpoint that lists
    them: a stop in between leaves the previous checkpoint, which resumes bit for bit; the stray chunk
    is discarded and the folder ends with only the chunks the final checkpoint lists."""
    reference = _toy_run(collisions=100)
    original, calls = ring_study.write_checkpoint, []

    def stopped_third(*args, **kwargs):
        calls.append(args[0])
        if len(calls) == 3:
            raise KeyboardInterrupt  # the rows of collisions 21-30 are written, their checkpoint is not
        return original(*args, **kwargs)

    monkeypatch.setattr(ring_study, "write_checkpoint", stopped_third)
    with pytest.raises(KeyboardInterrupt):
        _toy_run(tmp_path, collisions=100, checkpoint_every=10)
    monkeypatch.setattr(ring_study, "write_checkpoint", original)
    assert (tmp_path / "checkpoint.rows-000000020-000000030.npz").exists()
    resumed = _toy_run(tmp_path, collisions=100, checkpoint_every=10)
    assert resumed.resumed_from == 20
    _assert_same_run(reference, resumed)
    with np.load(tmp_path / ring_study.CHECKPOINT_NAME) as head:
        listed = {f"checkpoint.rows-{a:09d}-{b:09d}.npz" for a, b in zip(head["chunks/start"], head["chunks/stop"])}
    assert {p.name for p in tmp_path.glob("checkpoint.rows-*")} == listed
    assert len(listed) <= 1 + math.log2(10)


def test_finished_run_can_be_extended(tmp_path):
    reference = _toy_run(collisions=150)
    _toy_run(tmp_path, collisions=90, checkpoint_every=40)
    extended = _toy_run(tmp_path, collisions=150, checkpoint_every=40)
    assert extended.resumed_from == 90
    _assert_same_run(reference, extended)


def test_checkpoint_of_another_run_is_refused(tmp_path):
    _toy_run(tmp_path, collisions=20, modes=4)
    with pytest.raises(CheckpointError, match="modes"):
        _toy_run(tmp_path, collisions=20, modes=5)
    (tmp_path / ring_study.CHECKPOINT_NAME).write_bytes(b"not a checkpoint")
    with pytest.raises(CheckpointError, match="unreadable"):
        _toy_run(tmp_path, collisions=20, modes=4)


def test_shorter_run_on_a_longer_checkpoint_says_what_it_keeps(tmp_path):
    _toy_run(tmp_path, collisions=60, checkpoint_every=20)
    messages = []
    short = _toy_run(tmp_path, collisions=20, checkpoint_every=20, log=messages.append)
    assert short.n_collisions == 20
    assert messages == [(f"the checkpoint {tmp_path / ring_study.CHECKPOINT_NAME} holds 60 collisions; keeping "
                        "the first 20 (the checkpoint is left as it is)")]


@pytest.mark.parametrize(
    "kwargs, field",
    [
        ({"gamma": 0.0}, "gamma"),
        ({"gamma": 1.5}, "gamma"),
        ({"kappa": -1.0}, "kappa"),
        ({"kappa": float("nan")}, "kappa"),
        ({"modes": 0}, "modes"),
        ({"collisions": 0}, "collisions"),
        ({"checkpoint_every": 0}, "checkpoint_every"),
    ],
)
def test_run_ring_refuses_bad_parameters(kwargs, field):
    args = {"gamma": 0.6, "kappa": 100.0, "modes": 4, "collisions": 10, "checkpoint_every": 5}
    args.update(kwargs)
    with pytest.raises(InvalidParameterError, match=field):
        run_ring(progress=False, simulation_factory=ExchangeToyRing, **args)


def test_npz_round_trip(tmp_path):
    run = _toy_run(collisions=40, modes=3)
    path = run.save_npz(tmp_path / "x.npz")
    back = RingRun.load_npz(path)
    _assert_same_run(run, back)
    assert back.gamma == run.gamma and back.modes == run.modes and back.static_correction


def test_figures_are_written(tmp_path):
    from wavecontact.plotting.ring import plot_ring_figures, plot_spectral_entropy

    run = _toy_run(collisions=200, modes=5)
    paths = plot_ring_figures(run, tmp_path)
    for path in paths:
        assert path.stat().st_size > 10_000
        assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    other = _toy_run(collisions=100, modes=12)
    assert plot_spectral_entropy([run, other], tmp_path / "both.png").exists()


# ----------------------------------------------------------------------------
# Command line
# ----------------------------------------------------------------------------


@pytest.mark.parametrize(
    "argv",
    [
        ["--gamma", "0", "--kappa", "100", "--modes", "4", "--collisions", "10"],
        ["--gamma", "0.6", "--kappa", "-1", "--modes", "4", "--collisions", "10"],
        ["--gamma", "0.6", "--kappa", "100", "--modes", "0", "--collisions", "10"],
        ["--gamma", "0.6", "--kappa", "100", "--modes", "4", "--collisions", "x"],
        ["--gamma", "0.6", "--kappa", "100", "--modes", "4", "--collisions", "10", "--checkpoint-every", "0"],
        ["--gamma", "0.6", "--kappa", "100", "--modes", "4", "--collisions", "2"],
    ],
)
def test_cli_refuses_bad_arguments(argv, tmp_path, capsys):
    with pytest.raises(SystemExit) as info:
        code = cli_main(["ring", *argv, "--out", str(tmp_path / "out"), "--no-progress"])
        raise SystemExit(code)
    assert info.value.code != 0
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err


class _ToyEngine:
    """A registry entry whose ``simulate`` is the stand-in ring."""

    def __init__(self):
        from wavecontact.solvers import get_solver

        self._modal = get_solver("modal")

    def options(self, given):
        return self._modal.options(given)

    def simulate(self, scene, options):
        return ExchangeToyRing(scene, options)


def test_cli_end_to_end_with_stand_in(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(ring_study, "get_solver", lambda name: _ToyEngine())
    out = tmp_path / "ring"
    argv = ["ring", "--gamma", "0.6173", "--kappa", "4000", "--modes", "5", "--collisions", "100",
            "--out", str(out), "--checkpoint-every", "30", "--no-progress"]
    assert cli_main(argv) == 0
    first = capsys.readouterr()
    assert "Eq. 8" in first.out and "resuming" not in first.err
    for name in ("ring.npz", "ring.csv", "summary.json", "modal_spectrum.csv", "checkpoint.npz",
                 "fig1_translational_energy.png", "fig2_spectral_entropy.png", "fig3_restitution_correlation.png"):
        assert (out / name).stat().st_size > 0, name
    import json

    summary = json.loads((out / "summary.json").read_text())
    assert summary["collisions"] == 100 and summary["modes"] == 5
    assert summary["equilibrium_translational_energy"] == pytest.approx(0.5 / 22)
    assert len((out / "ring.csv").read_text().splitlines()) == 101
    # running again resumes from the final checkpoint and says so; asking for more extends the run,
    # with a progress bar on stderr this time
    assert cli_main(argv) == 0
    assert "resuming from checkpoint" in capsys.readouterr().err
    longer = [a for a in argv if a != "--no-progress"]
    longer[longer.index("--collisions") + 1] = "120"
    monkeypatch.setattr("wavecontact.progress.shows_bars", lambda: True)  # as on a terminal: bars only there
    assert cli_main(longer) == 0
    err = capsys.readouterr().err
    assert "after collision 100" in err and "120/120" in err
    assert len((out / "ring.csv").read_text().splitlines()) == 121


# ----------------------------------------------------------------------------
# The real ring simulation (issue 4, item 4-5)
# ----------------------------------------------------------------------------


@needs_ring_simulation
def test_real_ring_resume_is_bit_for_bit(tmp_path):
    straight = run_ring(0.6173, 200.0, 8, 40, out_dir=tmp_path / "a", checkpoint_every=15, progress=False)

    def interrupt(index, record):
        if index == 20:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_ring(0.6173, 200.0, 8, 40, out_dir=tmp_path / "b", checkpoint_every=15, progress=False,
                 callback=interrupt)
    resumed = run_ring(0.6173, 200.0, 8, 40, out_dir=tmp_path / "b", checkpoint_every=15, progress=False)
    assert resumed.resumed_from == 15
    _assert_same_run(straight, resumed)


def _realisations(modes: int, collisions: int, count: int):
    """``count`` realisations of the ring: circumferences 1.5 % apart (chaos makes them independent)."""
    from wavecontact.scene import two_rods_on_a_ring

    base = two_rods_on_a_ring(0.6173, 4000.0).ring_circumference
    return [run_ring(0.6173, 4000.0, modes, collisions, progress=False, circumference=base * (1 + 0.015 * r))
            for r in range(count)]


def _physics_checks(runs, relax_median_max: int, corr_max: float):
    """Sec. III over several realisations: properties of every run, and statistics pooled with
    tolerances from the runs' own standard errors."""
    stats_ = [run.statistics() for run in runs]
    modes = runs[0].modes
    e_eq = equilibrium_translational_energy(modes)
    for run, s in zip(runs, stats_):
        # every realisation: energy bookkeeping of the integrator, and the restitution identities
        assert s.energy_drift < 1e-3
        np.testing.assert_allclose(run.translational_energy[1:], run.translational_energy_after[:-1], rtol=1e-12)
        np.testing.assert_allclose(run.restitution ** 2, run.translational_energy_after / run.translational_energy,
                                   rtol=1e-9)
        assert s.relaxation_collisions is not None  # every run relaxes
    # Eq. 8: relaxation in "about 60" collisions (median over realisations) and the stationary mean
    assert np.median([s.relaxation_collisions for s in stats_]) <= relax_median_max
    means = np.array([s.mean_translational_energy for s in stats_])
    errors = np.array([s.translational_energy_standard_error for s in stats_])
    combined = math.sqrt(np.sum(errors**2)) / len(runs)
    assert abs(means.mean() - e_eq) < 4 * combined
    # Eq. 9: Boltzmann fluctuations, KS on the decorrelated samples of all realisations pooled
    pooled = np.concatenate([run.translational_energy[s.transient:][::s.ks_stride] for run, s in zip(runs, stats_)])
    assert pooled.size >= 200
    assert ks_exponential(pooled, e_eq).pvalue > 1e-3
    # Eq. 10-11: equipartition among the modes; at N = 12 Eq. 11 (0.133) and its exact finite-N value
    # for Boltzmann modes (0.1265) differ by 5 %: compare with the latter
    eta = np.array([s.mean_spectral_entropy for s in stats_])
    eta_error = math.sqrt(sum(s.spectral_entropy_standard_error**2 for s in stats_)) / len(runs)
    exact = stats_[0].equilibrium_spectral_entropy_finite
    assert abs(eta.mean() - exact) < 0.04 * exact + 4 * eta_error
    w = np.mean([s.mean_relative_spectrum for s in stats_], axis=0)
    assert np.max(np.abs(w * 2 * modes - 1.0)) < 0.3
    # Eq. 13: successive collisions nearly uncorrelated
    assert abs(np.mean([s.restitution_correlation_coefficient_lag1 for s in stats_])) < corr_max
    return stats_


@needs_ring_simulation
def test_real_ring_relaxes_to_equipartition():
    """Sec. III at a small size over three realisations: Eq. 8 mean, Eq. 9 law (KS), Eq. 11 entropy,
    weak C_eps(1)."""
    _physics_checks(_realisations(12, 1500, 3), relax_median_max=120, corr_max=0.15)


@pytest.mark.slow
@needs_ring_simulation
def test_real_ring_paper_size():
    """The paper's run: gamma = 0.6173, kappa = 4000, N = 75, 4500 collisions, three realisations."""
    stats_ = _physics_checks(_realisations(75, 4500, 3), relax_median_max=120, corr_max=0.1)
    assert all(s.entropy_settling_collisions is not None for s in stats_)


# ----------------------------------------------------------------------------
# The run controller (issue 25 Deliver 3, issue 23 items 4 and 8)
# ----------------------------------------------------------------------------


def test_a_signal_during_a_collision_leaves_a_checkpoint_of_it(tmp_path):
    import os
    import signal

    reference = _toy_run(collisions=80)

    def terminate(index, record):
        if index == 30:
            os.kill(os.getpid(), signal.SIGTERM)  # handled after this collision, not inside it

    messages = []
    with pytest.raises(KeyboardInterrupt):
        _toy_run(tmp_path, collisions=80, checkpoint_every=25, callback=terminate, log=messages.append)
    assert messages == ["interrupted; run again to resume from the checkpoint after collision 31"]
    resumed = _toy_run(tmp_path, collisions=80, checkpoint_every=25)
    assert resumed.resumed_from == 31
    _assert_same_run(reference, resumed)


def test_a_second_run_into_the_folder_is_refused_and_overwrite_replaces_another_run(tmp_path):
    import subprocess
    import sys

    from wavecontact.io.run_controller import LOCK_NAME

    holder = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        tmp_path.mkdir(exist_ok=True)
        (tmp_path / LOCK_NAME).write_text(f"{holder.pid} {__import__('os').uname().nodename}\n")
        with pytest.raises(InvalidParameterError, match="in use by another wavecontact run"):
            _toy_run(tmp_path, collisions=20)
        assert not (tmp_path / ring_study.CHECKPOINT_NAME).exists()
    finally:
        holder.kill()
        holder.wait()
    _toy_run(tmp_path, collisions=20, modes=4)
    with pytest.raises(CheckpointError, match="modes"):
        _toy_run(tmp_path, collisions=20, modes=5)
    replaced = _toy_run(tmp_path, collisions=20, modes=5, overwrite=True)
    assert replaced.resumed_from == 0
    _assert_same_run(replaced, _toy_run(collisions=20, modes=5))


_RING_TAMPERING = {
    "pair out of range": lambda a: a["run/pair"].__setitem__(3, 7),
    "NaN modal energy": lambda a: a["run/modal_energies"].__setitem__((2, 0, 1), np.nan),
    "negative energy": lambda a: a["run/translational_energy"].__setitem__(0, -1.0),
    "rows of unequal length": lambda a: a.__setitem__("run/restitution", a["run/restitution"][:-1]),
    "missing rows": lambda a: a.pop("run/bath_energy"),
    "state at another collision": lambda a: a.__setitem__("state/count", np.asarray(3)),
    "NaN in the state": lambda a: a["state/energies"].__setitem__(0, np.nan),
    "infinite wall time": lambda a: a.__setitem__("wall_time_s", np.asarray(np.inf)),
}


_ROW_CHANGES = {name for name in _RING_TAMPERING if "rows" in name or name in (
    "pair out of range", "NaN modal energy", "negative energy")}


def _tamper_rows(checkpoint, change):
    """Apply ``change`` to the rows (as ``run/NAME``) in the checkpoint's one chunk file, and list that file's new
    checksum in the checkpoint: a crafted run whose every checksum holds."""
    from test_io_run_controller import tamper

    (chunk,) = checkpoint.parent.glob(f"{checkpoint.stem}.rows-*.npz")

    def rows(arrays):
        prefixed = {f"run/{name}": value for name, value in arrays.items()}
        change(prefixed)
        arrays.clear()
        arrays.update({name[len("run/"):]: value for name, value in prefixed.items()})

    tamper(chunk, rows)
    with np.load(chunk, allow_pickle=False) as data:
        checksum = json.loads(str(data["__checkpoint__"]))["checksum"]
    tamper(checkpoint, lambda arrays: arrays.__setitem__("chunks/checksum", np.array([checksum])))


@pytest.mark.parametrize("change", list(_RING_TAMPERING), ids=list(_RING_TAMPERING))
def test_a_crafted_ring_checkpoint_is_refused_in_one_line(tmp_path, change):
    from test_io_run_controller import tamper

    class CountedToy(ExchangeToyRing):  # a state that says at which collision it is, as RingSimulation's does
        def get_state(self):
            return {**super().get_state(), "collisions": np.asarray(self.count)}

        def set_state(self, state):
            super().set_state(state)

    _toy_run(tmp_path, collisions=20, checkpoint_every=10)
    if change in _ROW_CHANGES:
        _tamper_rows(tmp_path / ring_study.CHECKPOINT_NAME, _RING_TAMPERING[change])
    else:
        tamper(tmp_path / ring_study.CHECKPOINT_NAME, _RING_TAMPERING[change])
    if change == "state at another collision":
        tamper(tmp_path / ring_study.CHECKPOINT_NAME, lambda a: a.__setitem__("state/collisions", np.asarray(3)))
    with pytest.raises(CheckpointError) as info:
        run_ring(0.6173, 4000, 6, 30, out_dir=tmp_path, progress=False, simulation_factory=CountedToy)
    assert "\n" not in str(info.value) and "invalid" in str(info.value)


def test_load_npz_refuses_garbage_and_impossible_rows_in_one_line(tmp_path):
    (tmp_path / "garbage.npz").write_bytes(b"PK\x03\x04 not a zip")
    with pytest.raises(InvalidParameterError, match="not a ring run") as info:
        RingRun.load_npz(tmp_path / "garbage.npz")
    assert "\n" not in str(info.value)
    run = _toy_run(collisions=10, modes=3)
    run.pair[4] = 3
    run.save_npz(tmp_path / "bad.npz")
    with pytest.raises(InvalidParameterError, match="pair") as info:
        RingRun.load_npz(tmp_path / "bad.npz")
    assert "\n" not in str(info.value)
    np.save(tmp_path / "other.npy", np.zeros(3))
    with pytest.raises(InvalidParameterError, match="not a ring run"):
        RingRun.load_npz(tmp_path / "other.npy")


def test_run_settings_as_one_object_or_as_keywords_are_the_same_run(tmp_path):
    from wavecontact.studies.ring import RingRunSettings

    flat = run_ring(0.6173, 200.0, 6, 12, out_dir=tmp_path / "a", checkpoint_every=5, progress=False)
    grouped = run_ring(0.6173, 200.0, 6, 12, settings=RingRunSettings(out_dir=tmp_path / "b", checkpoint_every=5,
                                                                       progress=False))
    np.testing.assert_array_equal(flat.restitution, grouped.restitution)
    assert (tmp_path / "b" / "checkpoint.npz").exists()
    with pytest.raises(InvalidParameterError, match="not both"):
        run_ring(0.6173, 200.0, 6, 12, settings=RingRunSettings(progress=False), progress=False)
    with pytest.raises(TypeError, match="out_dri"):
        run_ring(0.6173, 200.0, 6, 12, out_dri=tmp_path, progress=False)
