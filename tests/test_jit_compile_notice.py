"""wavecontact._jit.CompileClock and announce_compilation: the first run's compile time, said once."""

from __future__ import annotations

import io

import pytest

from wavecontact._jit import NUMBA_ENABLED, CompileClock, announce_compilation

pytestmark = pytest.mark.skipif(not NUMBA_ENABLED, reason="needs numba")


def _fresh_function():
    import numba

    @numba.njit(cache=False)
    def add(x):
        return x + 1.5

    return add


def test_compile_clock_measures_each_compilation_and_not_a_compiled_call():
    add = _fresh_function()
    with CompileClock() as clock:
        add(1.0)
    assert clock.compilations == 1 and clock.wall_s > 0.0 and clock.cpu_s > 0.0
    with CompileClock() as again:
        add(2.0)  # compiled already: nothing to measure
        add(3)  # a new signature compiles
    assert again.compilations == 1


def test_announce_compilation_says_so_once_past_the_threshold():
    stream = io.StringIO()
    with announce_compilation(stream, after=0.0, message="compiling"):
        _fresh_function()(1.0)
        _fresh_function()(1.0)
    assert stream.getvalue() == "compiling\n"


def test_announce_compilation_is_silent_below_the_threshold_and_without_compilation():
    stream = io.StringIO()
    with announce_compilation(stream, after=60.0, message="compiling"):
        _fresh_function()(1.0)
    add = _fresh_function()
    add(1.0)
    with announce_compilation(stream, after=0.0, message="compiling"):
        add(2.0)
    assert stream.getvalue() == ""
