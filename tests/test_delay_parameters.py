"""The numbers of the two-material delay equation (wavecontact.delay.parameters)."""

import math

import numpy as np
import pytest

import wavecontact
from wavecontact.delay.parameters import delay_parameters, echoes_from_ratios
from wavecontact.errors import InvalidParameterError, UnsupportedSceneError
from wavecontact.scene import two_rod_parameters

STEEL = {"density": 7850.0, "youngs_modulus": 210e9}
ALUMINIUM = {"density": 2700.0, "youngs_modulus": 70e9}


@pytest.mark.parametrize("impedance_ratio", [0.01, 0.3, 1.0, 2.5, 100.0])
@pytest.mark.parametrize("time_ratio", [0.1, 0.6, 1.0, 7.0])
def test_weights_conserve_momentum_and_reproduce_the_ratios(impedance_ratio, time_ratio):
    (g1, g2), (b1, b2) = echoes_from_ratios(impedance_ratio, time_ratio)
    assert b1 + b2 == pytest.approx(2.0, rel=1e-15)  # the instantaneous compliance is 1/Z_s
    assert b1 / g1 + b2 / g2 == pytest.approx(1.0, rel=1e-14)  # mean end motion = rigid motion
    assert b1 / b2 == pytest.approx(impedance_ratio, rel=1e-14)
    assert g1 / g2 == pytest.approx(time_ratio, rel=1e-14)


@pytest.mark.parametrize("gamma", [0.1, 0.6, 1.0])
def test_one_material_gives_the_papers_equation(gamma):
    (g1, g2), weights = echoes_from_ratios(1.0, gamma)
    assert weights == (1.0, 1.0)
    assert g1 == pytest.approx(1.0 + gamma, rel=1e-15)
    assert g2 == pytest.approx(1.0 + 1.0 / gamma, rel=1e-15)


def test_a_one_material_scene_in_si_units_has_the_papers_numbers():
    rods = (wavecontact.Rod(0.3, area=2e-4, **STEEL), wavecontact.Rod(0.5, area=2e-4, **STEEL))
    scene = wavecontact.Scene(rods=rods, velocities=(3.0, -1.0), contact=wavecontact.Exponential(2e4))
    params, paper = delay_parameters(scene), two_rod_parameters(scene)
    assert params.kappa == pytest.approx(paper.kappa, rel=1e-13)
    assert params.time_unit == pytest.approx(paper.time_unit, rel=1e-13)
    assert params.round_trip_times == pytest.approx(paper.round_trip_times, rel=1e-13)
    assert params.echo_weights == (1.0, 1.0)
    assert params.force_unit == pytest.approx(0.5 * rods[0].impedance * 4.0, rel=1e-13)


def test_swapping_the_rods_swaps_the_echoes():
    rods = (wavecontact.Rod(0.2, area=1e-4, **STEEL), wavecontact.Rod(1.0, area=3e-4, **ALUMINIUM))
    forward = delay_parameters(wavecontact.Scene(rods=rods, velocities=(5.0, 0.0), contact=wavecontact.Hard()))
    backward = delay_parameters(wavecontact.Scene(rods=rods[::-1], velocities=(0.0, -5.0), contact=wavecontact.Hard()))
    assert backward.round_trip_times == pytest.approx(forward.round_trip_times[::-1], rel=1e-14)
    assert backward.echo_weights == pytest.approx(forward.echo_weights[::-1], rel=1e-14)
    assert math.isinf(forward.kappa)
    z1, z2 = rods[0].impedance, rods[1].impedance
    assert forward.series_impedance == pytest.approx(z1 * z2 / (z1 + z2))
    assert forward.impedance_ratio == pytest.approx(z2 / z1)


@pytest.mark.parametrize("bad", [0.0, -1.0, np.nan, np.inf, 1e-7, 1e7, "x"])
def test_ratios_out_of_range_are_refused(bad):
    with pytest.raises(InvalidParameterError, match="impedance_ratio"):
        echoes_from_ratios(bad, 1.0)
    with pytest.raises(InvalidParameterError, match="time_ratio"):
        echoes_from_ratios(1.0, bad)


def test_scenes_without_two_approaching_rods_are_refused():
    rods = (wavecontact.Rod(1.0), wavecontact.Rod(2.0, density=3.0), wavecontact.Rod(1.0))
    with pytest.raises(UnsupportedSceneError, match="solver='fem'"):
        delay_parameters(wavecontact.Scene(rods=rods, velocities=(1.0, 0.0, 0.0), contact=wavecontact.Hard()))
    with pytest.raises(InvalidParameterError, match="approach"):
        delay_parameters(wavecontact.Scene(rods=rods[:2], velocities=(1.0, 1.0), contact=wavecontact.Hard()))
