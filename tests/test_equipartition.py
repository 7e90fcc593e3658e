"""Equipartition study (Fig. 2 for several N): the cold start against Eq. 25, the settled level
against the Boltzmann value (Eq. 11, finite-N form), the settling rule, the figure and the CLI."""

import json
import math

import numpy as np
import pytest

from wavecontact.analytic import equilibrium_spectral_entropy_finite, hard_core_modal_energies
from wavecontact.cli import main
from wavecontact.errors import InvalidParameterError
from wavecontact.plotting.equipartition import plot_equipartition
from wavecontact.studies.equipartition import equipartition_by_modes, settling_collision
from wavecontact.studies.ring_statistics import (
    decorrelation_stride,
    relative_modal_energies,
    spectral_entropy,
)

GAMMA = 0.6173


@pytest.fixture(scope="module")
def study():
    return equipartition_by_modes(GAMMA, 4000, modes=(20, 6), collisions=150, realisations=3, progress=False)


def test_first_collision_spectrum_is_the_hard_impact_of_eq25():
    # kappa = inf: the long rod carries Eq. 25; the short rod keeps only the truncation residue
    # (< 2e-3 of E_tr, tests/test_modal_solver.py), spread over its 40 modes: worth about 0.01 in eta
    modes = 40
    study = equipartition_by_modes(GAMMA, math.inf, modes=(modes,), collisions=1, realisations=1, progress=False)
    expected = spectral_entropy(relative_modal_energies(hard_core_modal_energies(GAMMA, modes)))
    assert study.entropy[modes][0, 0] == pytest.approx(expected, abs=0.02)
    assert study.entropy[modes][0, 0] > 0.7  # far from equipartition: the low modes of one rod hold it all


def test_settled_level_is_the_boltzmann_mean(study):
    # independent exponential modal energies give <eta> = 1 - (H_2N - 1)/ln 2N (Eq. 11 for large N)
    # over the realisations, with the standard error from their own (decorrelated) spread; 3 % of
    # the level allows for the residual coupling that keeps the modes from exact independence
    stationary = study.entropy[20][:, 50:]
    errors = [np.std(row, ddof=1) * math.sqrt(decorrelation_stride(row) / row.size) for row in stationary]
    combined = math.sqrt(np.sum(np.square(errors))) / len(errors)
    exact = equilibrium_spectral_entropy_finite(20)
    assert abs(stationary.mean() - exact) < 4 * combined + 0.03 * exact
    assert study.entropy[20].shape == (3, 150)


def test_realisations_share_the_cold_first_collision_and_then_differ(study):
    series = study.entropy[20]
    np.testing.assert_allclose(series[:, 0], series[0, 0], rtol=1e-9)
    assert np.ptp(series[:, 20]) > 1e-3
    lengths = study.circumferences[20]
    np.testing.assert_allclose(np.diff(lengths), 0.015 * lengths[0], rtol=1e-12)


def test_table_settling_and_scaling(study):
    assert study.modes == (6, 20)
    rows = study.table()
    for row in rows:
        level = 1.5 * row["equilibrium_finite"]
        for series, settled in zip(study.entropy[row["modes"]], row["settling"]):
            assert settled is not None
            assert series[settled - 1] <= level and np.all(series[: settled - 1] > level)
        assert row["eta_after_1"] > row["eta_after_10"]
    assert study.scaling_exponent() is not None


def test_settling_collision_counts_from_one():
    assert settling_collision([0.9, 0.5, 0.1, 0.3], 0.2) == 3
    assert settling_collision([0.9, 0.5], 0.2) is None


@pytest.mark.parametrize(
    "kwargs, field",
    [({"modes": (1,)}, "modes"), ({"modes": (5, 5)}, "modes"), ({"modes": ()}, "modes"),
     ({"modes": (4.5,)}, "modes"), ({"collisions": 0}, "collisions"), ({"realisations": 2.5}, "realisations"),
     ({"threshold": 1.0}, "threshold"), ({"threshold": math.nan}, "threshold"),
     ({"circumference_factors": (1.0, 0.0)}, r"circumference_factors\[1\]"),
     ({"circumference_factors": ()}, "circumference_factors")],
)
def test_bad_parameters_are_refused(kwargs, field):
    with pytest.raises(InvalidParameterError, match=field):
        equipartition_by_modes(GAMMA, 4000, **{"modes": (5,), "collisions": 3, "progress": False, **kwargs})


def test_figure_and_csv(study, tmp_path):
    path = plot_equipartition(study, tmp_path / "fig.png")
    assert path.stat().st_size > 10_000
    rows = study.save_csv(tmp_path / "eta.csv").read_text().splitlines()
    assert rows[0] == "modes,realisation,circumference,collision,eta"
    assert len(rows) == 1 + 2 * 3 * 150


def test_cli_writes_table_json_and_figure(tmp_path, capsys):
    out = tmp_path / "eq"
    code = main(["equipartition", "--gamma", "0.6173", "--kappa", "4000", "--modes", "4", "8",
                 "--collisions", "12", "--realisations", "2", "--out", str(out), "--no-progress"])
    assert code == 0
    printed = capsys.readouterr().out
    assert "| 8 |" in printed and "settling" in printed
    summary = json.loads((out / "equipartition.json").read_text())
    assert [row["modes"] for row in summary["modes"]] == [4, 8]
    assert (out / "fig2_equipartition_vs_modes.png").stat().st_size > 10_000
    assert (out / "entropy.csv").exists()


@pytest.mark.parametrize("argv", [["--threshold", "1"], ["--modes", "0"], ["--realisations", "-2"]])
def test_cli_refuses_bad_arguments(argv, tmp_path, capsys):
    base = ["equipartition", "--gamma", "0.6", "--kappa", "100", "--modes", "4", "--out", str(tmp_path / "x")]
    with pytest.raises(SystemExit) as exc:
        main(base + argv)
    assert exc.value.code == 2
    assert "error" in capsys.readouterr().err


def test_circumference_factors_set_each_realisations_ring(study):
    """Factors given explicitly: one realisation per factor, on that multiple of the paper's ring; the factors of
    the default grid reproduce the default study's series bit for bit (same scenes, same runs)."""
    base = study.circumferences[6][0]
    factors = (1.0, 1.015, 1.03)
    again = equipartition_by_modes(GAMMA, 4000, modes=(6,), collisions=150, circumference_factors=factors,
                                   progress=False)
    np.testing.assert_array_equal(again.circumferences[6], base * np.array(factors))
    np.testing.assert_array_equal(again.entropy[6], study.entropy[6])
    drawn = equipartition_by_modes(GAMMA, 4000, modes=(6,), collisions=20, circumference_factors=(1.0123, 1.0456),
                                   progress=False)
    np.testing.assert_array_equal(drawn.circumferences[6], base * np.array((1.0123, 1.0456)))
    assert drawn.entropy[6].shape == (2, 20)
