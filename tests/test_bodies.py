"""Scene model of many bodies on a line (wavecontact.bodies): validation, and who takes such scenes."""

import math

import pytest

from wavecontact import (
    Exponential,
    Hard,
    InvalidParameterError,
    PiecewiseRod,
    RigidBody,
    Rod,
    Scene,
    Segment,
    UnsupportedSceneError,
    Wall,
    solve,
    two_rod_parameters,
    two_rods,
)


def test_segment_of_zero_length_is_refused():
    with pytest.raises(InvalidParameterError, match="zero length"):
        Segment(length=0.0)


def test_taper_to_zero_area_is_refused():
    with pytest.raises(InvalidParameterError, match="taper to zero area"):
        Segment(length=1.0, area=1.0, end_area=0.0)


def test_overlapping_bodies_are_refused():
    with pytest.raises(InvalidParameterError, match="overlap"):
        Scene(rods=(RigidBody(1.0), Rod(1.0)), velocities=(1.0, 0.0), contact=Hard(), gaps=(-0.1,))


def test_wall_inside_a_rod_is_refused():
    with pytest.raises(InvalidParameterError, match="wall inside a rod"):
        Wall(gap=-0.01)


def test_one_law_per_pair():
    with pytest.raises(InvalidParameterError, match="one law per facing pair"):
        Scene(rods=(Rod(1.0), Rod(1.0), Rod(1.0)), velocities=(1.0, 0.0, 0.0), contact=(Hard(),))


def test_a_lone_body_needs_a_wall():
    with pytest.raises(InvalidParameterError, match="needs a wall"):
        Scene(rods=(RigidBody(1.0),), velocities=(1.0,), contact=())


def test_rigid_bodies_take_no_initial_field():
    with pytest.raises(InvalidParameterError, match="rigid"):
        Scene(rods=(RigidBody(1.0), Rod(1.0)), velocities=(1.0, 0.0), contact=Hard(),
              initial_velocity=(lambda s: s, None))


def test_piecewise_rod_geometry():
    bar = PiecewiseRod((Segment(length=1.0, area=1.0), Segment(length=2.0, area=2.0, youngs_modulus=4.0, density=1.0),
                        Segment(length=1.0, area=1.0, end_area=0.5)))
    assert bar.length == 4.0
    assert bar.mass == pytest.approx(1.0 + 4.0 + 0.75, rel=1e-15)
    assert bar.travel_time == pytest.approx(1.0 + 1.0 + 1.0, rel=1e-15)  # c = 2 in the middle segment


def test_which_scenes_are_line_scenes():
    assert not two_rods(0.6, 20).is_line_scene
    assert Scene(rods=(Rod(1.0), Rod(1.0), Rod(1.0)), velocities=(1.0, 0.0, 0.0), contact=Hard()).is_line_scene
    assert Scene(rods=(Rod(1.0), Rod(1.0)), velocities=(1.0, 0.0), contact=Hard(),
                 walls=(None, Wall(0.0))).is_line_scene
    assert Scene(rods=(RigidBody(2.0), Rod(1.0)), velocities=(1.0, 0.0), contact=(Exponential(10.0),)).is_line_scene


def test_two_rod_parameters_refuse_line_scenes():
    scene = Scene(rods=(RigidBody(2.0), Rod(1.0)), velocities=(1.0, 0.0), contact=Hard())
    with pytest.raises(InvalidParameterError):
        two_rod_parameters(scene)


@pytest.mark.parametrize("solver", ["delay", "modal"])
def test_other_solvers_refuse_line_scenes_naming_fem(solver):
    # a striker on a chain: beyond the delay solver's rigid mass on one rod and the modal solver's two rods
    scene = Scene(rods=(RigidBody(2.0), Rod(1.0), Rod(1.0)), velocities=(1.0, 0.0, 0.0), contact=Hard(),
                  gaps=(0.0, 0.0))
    with pytest.raises(UnsupportedSceneError, match="solver='fem'"):
        solve(scene, solver)


def test_the_paper_scene_is_unchanged():
    scene = two_rods(0.6, math.inf, contact="hard")
    assert scene.walls is None and scene.contact == Hard()
