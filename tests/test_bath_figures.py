"""The paper's thermal-bath figures: their commands run, and their statements hold (Sec. VI)."""

import math

import numpy as np
import pytest

from wavecontact.cli import main
from wavecontact.studies import bath_figures
from wavecontact.studies.ensemble import ensemble


def test_fig8_spread_grows_with_temperature_and_with_unequal_lengths():
    # hard-core mode (the paper's kappa = 250 is in the kappa-independent regime, docs/bath.md)
    data = bath_figures.spread_against_temperature(gammas=(0.6173, 0.2173), temperatures=(0.1, 1.0),
                                                   kappa=math.inf, samples=300, seed=21, modes=100)
    std, err = data["std"], data["std_error"]
    for a in range(2):  # "the fluctuations of epsilon increase with T_B/E_tr"
        assert std[a, 1] - std[a, 0] > 3.0 * math.hypot(err[a, 1], err[a, 0])
    # "the variance is larger, the larger the difference in lengths of the two rods"
    assert std[1, 1] - std[0, 1] > 3.0 * math.hypot(err[1, 1], err[0, 1])


def test_fig9_distribution_tends_to_the_deterministic_step():
    # D(eps^2) -> Theta(eps^2 - gamma^2) as T_B -> 0: the mean distance of eps^2 from gamma^2 (the
    # Wasserstein distance between D and the step) vanishes like sqrt(T_B), the size of the noise
    gamma = 0.6173
    temperatures = np.array([1e-1, 1e-2, 1e-3, 1e-4, 1e-5])
    distance = []
    for temperature in temperatures:
        result = ensemble(gamma, math.inf, temperature, 200, 31, bath_modes=100)
        distance.append(float(np.mean(np.abs(result.restitution**2 - gamma**2))))
    slope = np.polyfit(np.log(temperatures), np.log(distance), 1)[0]
    assert 0.4 < slope < 0.6
    assert distance[-1] < 0.005


def test_fig4_sampled_covariance_lies_on_eq19():
    data = bath_figures.noise_covariance(realisations=80, modes=50, seed=4, lags=25)
    # within the 2-SE band of the exact finite-mode covariance at all but a few lags, and Eq. 19 is that
    # covariance's limit (the 50-mode series differs from it by less than 2 % of C_Q(0))
    outside = np.abs(data["sampled"] - data["series"]) > 1.5 * data["band"]
    assert outside.sum() <= 3
    assert np.max(np.abs(data["series"] - data["eq19"])) < 0.02 * data["eq19"][0]


def test_fig7_trajectories_rise_monotonically_to_their_restitution():
    histories = bath_figures.stochastic_histories(modes=30, seed=2)
    for h in histories:
        w = h["W"]
        assert np.all(np.diff(w) >= -1e-9 * h["kappa"])
        assert w[-1] / h["kappa"] - 1.0 == pytest.approx(h["restitution"])
    # the softer contact smooths the rapid changes: its largest slope is smaller
    slopes = [np.max(np.diff(h["W"] / h["kappa"]) / np.diff(h["tau"])) for h in histories]
    assert slopes[0] < slopes[1]


@pytest.mark.parametrize("figure, extra", [
    ("4", ["--samples", "10", "--bath-modes", "20"]),
    ("7", ["--bath-modes", "20"]),
    ("8", ["--samples", "4", "--bath-modes", "20", "--no-progress"]),  # the default kappa = 250
    ("9", ["--kappa", "inf", "--samples", "40", "--bath-modes", "20", "--no-progress"]),
])
def test_figure_commands_write_their_images(tmp_path, figure, extra):
    out = tmp_path / f"fig{figure}.png"
    assert main(["bath-figure", figure, "--out", str(out), "--json", str(tmp_path / "data.json"), *extra]) == 0
    assert out.stat().st_size > 5000
    assert (tmp_path / "data.json").stat().st_size > 10


def test_fig8_points_run_at_once_on_an_executor_give_the_serial_numbers():
    from concurrent.futures import ThreadPoolExecutor

    args = dict(gammas=(0.6173, 0.2173), temperatures=(0.1, 1.0), kappa=math.inf, samples=12, seed=5, modes=30)  # noqa: C408
    serial = bath_figures.spread_against_temperature(**args)
    with ThreadPoolExecutor(2) as pool:
        parallel = bath_figures.spread_against_temperature(**args, executor=pool)
    for key in ("mean", "mean_error", "std", "std_error"):
        assert np.array_equal(serial[key], parallel[key])
