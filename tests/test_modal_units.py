"""The modal solver does not depend on the units (issue 23, item 2).

A scene written in another consistent unit system (length unit L, mass unit M, time unit T) is the
same physical collision, so its restitution must be the same number. The scenes below are two
rods of different materials in hard contact, where the modal solver's collocation used to fail
below its smallest ladder step in some unit systems and not in others, and fell back to a
splitting run whose error (up to 5e-2) its estimate (1e-11) did not see.
"""

import pytest

from wavecontact import Hard, Rod, Scene, solve

# (lengths, densities, Young's moduli, areas in SI, approach speed m/s, modes); the first is issue 23's
# (rounded to the digits it printed), the others failed with the SI numbers on the earlier code
SCENES = [
    ((0.16538, 0.50474), (1813.71, 3367.81), (1.97261e11, 4.07944e10), (3.16684e-5, 3.21736e-5), 1.62297, 36),
    ((0.539961432516334, 0.9898258000310377), (1523.85387826041, 9183.730699136573),
     (158992103398.09027, 52709724328.40216), (6.509296649439987e-05, 4.007272769307762e-05), 2.1378026599784508, 65),
    ((0.2128881957878377, 0.9181647665643746), (2531.5793097977853, 6611.618624250871),
     (220314529399.95825, 21852421645.293808), (1.077884805297305e-05, 1.514732998186984e-05), 2.4324467641527656, 14),
]
# (L, M, T) in SI: metres/kilograms/seconds, millimetres/grams/milliseconds, kilometres/tonnes/microseconds
UNITS = [(1.0, 1.0, 1.0), (1e-3, 1e-3, 1e-3), (1e3, 1e3, 1e-6)]


def _in_units(scene, units):
    lengths, densities, moduli, areas, speed, _modes = scene
    length, mass, time = units
    rods = tuple(Rod(lengths[i] / length, densities[i] / (mass / length**3), moduli[i] / (mass / (length * time**2)),
                     areas[i] / length**2) for i in range(2))
    return Scene(rods=rods, velocities=(speed / (length / time), 0.0), contact=Hard())


@pytest.mark.parametrize("scene", SCENES)
def test_the_same_scene_in_three_unit_systems_gives_the_same_restitution(scene):
    results = [solve(_in_units(scene, units), "modal", modes=scene[-1]) for units in UNITS]
    values = [r.restitution for r in results]
    assert max(values) - min(values) < 1e-9, values
    for result in results:
        assert "fallback" not in result.work, result.work
    delay = solve(_in_units(scene, UNITS[0]), "delay")
    for result in results:
        assert abs(result.restitution - delay.restitution) <= result.error_estimate + delay.error_estimate, (
            result.restitution, delay.restitution, result.error_estimate, delay.error_estimate)
