"""RestitutionTable: validation, exact interpolation of laws it can represent, sampling, files."""

import json
import math

import numpy as np
import pytest
from scipy import stats

from wavecontact.errors import InvalidParameterError
from wavecontact.restitution_table import RestitutionTable, load

GAMMA = np.array([0.4, 0.7, 1.0])
RATIO = np.array([0.0, 0.5, 2.0])
LEVELS = np.array([0.0, 1.0])


def _low(g, r):  # lower end of a uniform law of eps^2, linear in gamma and in the ratio
    return 0.2 * g + 0.1 * r


def _high(g, r):
    return 0.5 + 0.4 * g + 0.3 * r


def uniform_table(levels=LEVELS):
    """eps^2 ~ U(low, high): quantile linear in u, low/high linear in gamma and ratio, so the
    table's interpolation is exact everywhere inside the grid."""
    g, r = np.meshgrid(GAMMA, RATIO, indexing="ij")
    q = _low(g, r)[..., None] + (_high(g, r) - _low(g, r))[..., None] * levels
    return RestitutionTable(GAMMA, RATIO, levels, q, 0.25 + 0.1 * g, kappa=math.inf, bath_modes=50,
                            samples_per_point=0, solver="analytic-uniform", seed=3)


def test_interpolation_is_exact_for_a_law_linear_in_every_coordinate():
    table = uniform_table()
    g, r, u = 0.55, 1.3, np.array([0.0, 0.17, 0.5, 0.93, 1.0])
    expected = _low(g, r) + (_high(g, r) - _low(g, r)) * u
    np.testing.assert_allclose(table.quantile(g, r, u), expected, rtol=1e-14)
    a, b = _low(g, r), _high(g, r)
    assert table.mean_eps2(g, r) == pytest.approx((a + b) / 2, rel=1e-14)
    assert table.mean_restitution(g, r) == pytest.approx(2 / 3 * (b**1.5 - a**1.5) / (b - a), rel=1e-13)
    assert table.share(g, r) == pytest.approx(0.25 + 0.1 * g, rel=1e-14)


def test_samples_follow_the_tabulated_law():
    table = uniform_table()
    g, r = 0.9, 0.2
    draws = table.sample(np.random.default_rng(np.random.SeedSequence(11)), g, r, size=20000)
    a, b = _low(g, r), _high(g, r)
    assert stats.kstest(draws, stats.uniform(a, b - a).cdf).pvalue > 1e-3


def test_fine_table_of_an_exponential_law_reproduces_its_mean():
    # Glauber-like law eps^2 ~ Exp(mean m), truncated at the level 1 - 1e-9: the piecewise-linear
    # quantile function converges to the analytic mean as the levels are refined.
    errors = []
    for n in (50, 200, 800):
        u = np.concatenate([1 - np.geomspace(1.0, 1e-9, n), [1.0]])  # 0 ... 1 - 1e-9, 1
        q = -np.log1p(-np.minimum(u, 1 - 1e-9))
        table = RestitutionTable([1.0], [1.0], u, q[None, None, :], [[0.5]])
        errors.append(abs(table.mean_eps2(1.0, 1.0) - 1.0))
    assert errors[2] < errors[1] < errors[0] and errors[2] < 1e-3


@pytest.mark.parametrize("suffix", [".npz", ".json"])
def test_save_load_round_trip(tmp_path, suffix):
    table = uniform_table(np.linspace(0, 1, 7))
    back = load(table.save(tmp_path / f"t{suffix}"))
    for name in ("gamma", "temperature_ratio", "probability", "eps2_quantiles", "rod1_share"):
        np.testing.assert_array_equal(getattr(back, name), getattr(table, name))
    assert (back.kappa, back.bath_modes, back.solver, back.seed) == (math.inf, 50, "analytic-uniform", 3)


def test_csv_is_long_format_with_named_columns(tmp_path):
    table = uniform_table()
    lines = table.save(tmp_path / "t.csv").read_text().splitlines()
    assert lines[1] == "gamma,temperature_ratio,probability,eps2_quantile"
    assert len(lines) == 2 + GAMMA.size * RATIO.size * LEVELS.size


def test_load_refuses_foreign_and_pickled_files(tmp_path):
    table = uniform_table()
    doc = json.loads((table.save(tmp_path / "t.json")).read_text())
    doc["name"] = "something.else"
    (tmp_path / "bad.json").write_text(json.dumps(doc))
    with pytest.raises(InvalidParameterError, match="not a wavecontact.restitution_table"):
        load(tmp_path / "bad.json")
    np.savez(tmp_path / "obj.npz", schema=np.array([{"a": 1}], dtype=object))
    with pytest.raises(InvalidParameterError, match="obj.npz"):
        load(tmp_path / "obj.npz")
    doc = json.loads((tmp_path / "t.json").read_text())
    doc["eps2_quantiles"] = doc["eps2_quantiles"][:-1]
    (tmp_path / "short.json").write_text(json.dumps(doc))
    with pytest.raises(InvalidParameterError, match="shape"):
        load(tmp_path / "short.json")


@pytest.mark.parametrize(
    "change, message",
    [
        ({"gamma": [0.7, 0.4, 1.0]}, "gamma must be strictly ascending"),
        ({"gamma": [0.0, 0.7, 1.0]}, r"gamma must lie in \(0, 1\]"),
        ({"temperature_ratio": [-1.0, 0.5, 2.0]}, "temperature_ratio must be >= 0"),
        ({"probability": [0.1, 1.0]}, "probability must start at 0"),
        ({"rod1_share": np.full((3, 3), np.nan)}, "rod1_share must be finite"),
        ({"kappa": -1.0}, "kappa"),
        ({"bath_modes": 0}, "bath_modes"),
    ],
)
def test_invalid_tables_are_refused(change, message):
    good = uniform_table()
    fields = {"gamma": good.gamma, "temperature_ratio": good.temperature_ratio, "probability": good.probability,
                  "eps2_quantiles": good.eps2_quantiles, "rod1_share": good.rod1_share}
    fields.update(change)
    with pytest.raises(InvalidParameterError, match=message):
        RestitutionTable(**fields)


def test_decreasing_quantiles_and_points_off_the_grid_are_refused():
    good = uniform_table()
    with pytest.raises(InvalidParameterError, match="non-decreasing"):
        RestitutionTable(good.gamma, good.temperature_ratio, good.probability, good.eps2_quantiles[..., ::-1],
                         good.rod1_share)
    with pytest.raises(InvalidParameterError, match=r"gamma must lie in the table's range \[0.4, 1\]"):
        good.sample(np.random.default_rng(0), 0.3, 1.0)
    with pytest.raises(InvalidParameterError, match="temperature_ratio must lie"):
        good.mean_eps2(0.5, 3.0)
