"""The package's one integer check, errors.require_integer (issue 25: it replaced 22 inline checks)."""

import math

import numpy as np
import pytest

from wavecontact.errors import InvalidParameterError, require_integer


@pytest.mark.parametrize("value", [3, np.int64(3), np.uint8(3), 3.0, np.float64(3.0)])
def test_whole_numbers_pass_as_int(value):
    number = require_integer("n", value, 1, 10)
    assert number == 3 and type(number) is int


@pytest.mark.parametrize("value", [True, False, 2.5, math.nan, math.inf, -math.inf, "3", None, [3], 1 + 0j])
def test_other_values_are_refused_naming_the_option(value):
    with pytest.raises(InvalidParameterError, match=r"^n must be an integer in \[0, 10\], got "):
        require_integer("n", value, 0, 10)


def test_bounds_and_messages():
    assert require_integer("n", 0, 0) == 0 and require_integer("n", -5) == -5
    with pytest.raises(InvalidParameterError, match=r"^n must be an integer >= 1, got 0$"):
        require_integer("n", 0, 1)
    with pytest.raises(InvalidParameterError, match=r"^n must be an integer in \[2, 4\], got 5$"):
        require_integer("n", 5, 2, 4)
    with pytest.raises(InvalidParameterError, match=r"^seed must be a non-negative integer, got -1$"):
        require_integer("seed", -1, 0, allowed="a non-negative integer")
    assert "\n" not in str(pytest.raises(InvalidParameterError, require_integer, "n", 10**20, 0, 9).value)
