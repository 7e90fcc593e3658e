"""The two-material restitution map: known lines, symmetry, the wave theory, the command."""

import json
import math

import numpy as np
import pytest

import wavecontact
from wavecontact.analytic import two_material_impact
from wavecontact.cli import main
from wavecontact.delay.parameters import delay_parameters
from wavecontact.errors import InvalidParameterError
from wavecontact.studies.material_map import MaterialMap, material_map, special_line_restitution

IMPEDANCE = np.geomspace(0.01, 100.0, 9)  # symmetric about 1, contains 1
TIME = np.geomspace(0.1, 10.0, 7)  # symmetric about 1, contains 1


@pytest.fixture(scope="module")
def hard():
    return material_map(IMPEDANCE, TIME, progress=False)


def test_known_lines_of_the_hard_core(hard):
    deviations = hard.special_line_deviation()
    assert set(deviations) == {"equal impedances", "equal transit times"}
    assert max(deviations.values()) < 1e-12
    assert special_line_restitution(1.0, 0.25) == pytest.approx(0.25)
    assert special_line_restitution(7.0, 1.0) == 1.0
    assert math.isnan(special_line_restitution(7.0, 0.25))


def test_hard_map_is_the_wave_theory(hard):
    for i, z in enumerate(IMPEDANCE):
        for j, t in enumerate(TIME):
            rods = wavecontact.Rod(1.0), wavecontact.Rod(1.0 / t, density=z, youngs_modulus=z)
            assert hard.restitution[i, j] == pytest.approx(two_material_impact(*rods, 1.0)["restitution"], abs=1e-12)


def test_relabelling_the_rods_mirrors_the_map(hard):
    # rod 1 <-> rod 2 maps (Z2/Z1, T1/T2) to (Z1/Z2, T2/T1): the grid reversed in both directions
    assert np.allclose(hard.restitution, hard.restitution[::-1, ::-1], atol=1e-12, rtol=0)


def test_finite_kappa_map_matches_the_solver_and_is_elastic_for_equal_transit_times():
    soft = material_map([0.2, 1.0, 3.0], [0.5, 1.0], kappa=30.0, rtol=1e-9, workers=2, progress=False)
    for i, z in enumerate(soft.impedance_ratios):
        for j, t in enumerate(soft.time_ratios):
            rod_2 = wavecontact.Rod(1.0 / t, density=z, youngs_modulus=z)
            hard_scene = wavecontact.Scene(rods=(wavecontact.Rod(1.0), rod_2), velocities=(1.0, 0.0),
                                           contact=wavecontact.Hard())
            alpha = 30.0 / delay_parameters(hard_scene).time_unit  # kappa = alpha V mu / Z_s
            scene = wavecontact.Scene(rods=hard_scene.rods, velocities=(1.0, 0.0),
                                      contact=wavecontact.Exponential(alpha))
            assert soft.restitution[i, j] == pytest.approx(wavecontact.solve(scene, "delay").restitution, abs=1e-8)
    # equal transit times: the memory is that of two equal rods (gamma = 1), elastic at any kappa
    assert np.allclose(soft.restitution[:, 1], 1.0, atol=1e-9)
    # the equal-impedance column is the paper's collision gamma = 0.5
    assert soft.restitution[1, 0] == pytest.approx(wavecontact.collide(0.5, 30.0).restitution, abs=1e-8)


def test_bad_input_is_refused():
    with pytest.raises(InvalidParameterError, match="impedance_ratio"):
        material_map([0.0, 1.0], [1.0])
    with pytest.raises(InvalidParameterError, match="time_ratio"):
        material_map([1.0], [1e9])
    with pytest.raises(InvalidParameterError, match="kappa"):
        material_map([1.0], [1.0], kappa=-1.0)
    with pytest.raises(InvalidParameterError, match="at most"):
        material_map(np.ones(2000), np.ones(1000))


def test_command_writes_figure_table_and_maps(tmp_path, capsys):
    code = main(["map", "--impedance-ratio", "0.1:10:5", "--time-ratio", "0.5,1,2", "--kappa", "inf", "50",
                 "--out", str(tmp_path), "--no-progress"])
    assert code == 0
    printed = capsys.readouterr().out
    assert "kappa = inf (hard core)" in printed and "kappa = 50" in printed
    assert (tmp_path / "map.png").stat().st_size > 10_000
    assert (tmp_path / "map.md").read_text().startswith("epsilon for kappa = inf")
    loaded = MaterialMap.load(tmp_path / "map_inf.json")
    assert loaded.restitution.shape == (5, 3) and math.isinf(loaded.kappa)
    assert json.loads((tmp_path / "map_50.json").read_text())["kappa"] == 50.0
    assert loaded.restitution[2, 0] == pytest.approx(0.5, abs=1e-12)  # equal impedances, T1/T2 = 1/2


def test_command_refuses_a_bad_range(capsys):
    with pytest.raises(SystemExit):
        main(["map", "--impedance-ratio", "1:0.1:5", "--out", "unused"])
    assert "LOW:HIGH:N" in capsys.readouterr().err
