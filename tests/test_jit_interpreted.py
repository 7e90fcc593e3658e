"""wavecontact._jit.prefer_interpreted: inside answer_first (the CLI's collide), a short call runs as plain
Python while numba has no compiled code for it, instead of compiling for seconds; compiled code in memory or
on disk, a long call, or any call outside answer_first runs the kernel compiled."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest

from wavecontact import _jit

pytestmark = pytest.mark.skipif(not _jit.NUMBA_ENABLED, reason="needs numba: without it every kernel is Python")


def _uncached_kernel():
    @_jit.kernel(cache=False)  # no disk cache: only this process's memory can hold its compiled code
    def scaled_sum(values, factor):
        total = 0.0
        for value in values:
            total += factor * value
        return total

    return scaled_sum


def test_a_small_uncached_call_runs_interpreted_for_a_first_answer_only_and_gives_the_compiled_bits():
    kernel = _uncached_kernel()
    arguments = (np.linspace(0.1, 1.7, 13), 0.3)
    assert _jit.prefer_interpreted(kernel, arguments, small=True) is kernel  # outside answer_first: compiled
    before = _jit.interpreted_call_count()
    with _jit.answer_first():
        run = _jit.prefer_interpreted(kernel, arguments, small=True, compile_later=True)
        assert run is not kernel
        interpreted = run(*arguments)
        assert _jit.interpreted_call_count() == before + 1 and not kernel.overloads  # nothing compiled
        assert _jit.deferred_count() == 1
        assert _jit.prefer_interpreted(kernel, arguments, small=False) is kernel  # a long call compiles
    assert _jit.compile_deferred() == 1 and kernel.overloads  # compiled after the answer
    assert kernel(*arguments) == interpreted  # the same bits
    with _jit.answer_first():
        assert _jit.prefer_interpreted(kernel, arguments, small=True) is kernel  # compiled code in memory now


def test_interpreted_kernels_call_interpreted_kernels_and_compile_nothing():
    from wavecontact.delay import hardcore_kernels

    clone = _jit.interpreted(hardcore_kernels.max_plus_history)
    assert clone.__globals__["_window_points"] is _jit.interpreted(hardcore_kernels._window_points)
    assert clone.__globals__["_sorted"] is _jit.interpreted(hardcore_kernels._sorted)
    assert _jit.interpreted(_jit.row_view) is _jit._row_view_python  # an intrinsic has its Python version


def _env(cache):
    return dict(os.environ, NUMBA_CACHE_DIR=str(cache))


def test_the_hard_core_command_answers_without_compiling_on_an_empty_cache_and_loads_a_cached_kernel(tmp_path):
    """``wavecontact collide --gamma 0.6 --kappa inf`` on an empty cache: interpreted, nothing compiled or cached,
    no compile notice; once a compiled run has cached the kernel, the command loads and runs it."""
    command = [sys.executable, "-m", "wavecontact", "collide", "--gamma", "0.6", "--kappa", "inf"]
    first = subprocess.run(command, env=_env(tmp_path), capture_output=True, text=True, timeout=300, check=True)
    assert "interpreted" in first.stdout and "compiling" not in first.stderr, first.stdout + first.stderr
    assert not list(tmp_path.rglob("*.nbi"))
    compile_it = "import math, wavecontact; wavecontact.collide(0.6, math.inf)"  # the Python API compiles
    subprocess.run([sys.executable, "-c", compile_it], env=_env(tmp_path), timeout=300, check=True)
    assert any(path.name.startswith("hardcore_kernels.max_plus_history") for path in tmp_path.rglob("*.nbi"))
    again = subprocess.run(command, env=_env(tmp_path), capture_output=True, text=True, timeout=300, check=True)
    assert "interpreted" not in again.stdout and "numba kernel preparation" in again.stdout, again.stdout
    assert first.stdout.split("(")[0] == again.stdout.split("(")[0]  # the same epsilon, to the digits printed


def test_the_first_command_answers_before_compiling_and_the_next_run_loads_the_compiled_kernels(tmp_path):
    """``wavecontact collide --gamma 0.6 --kappa 100`` on an empty cache prints its answer from the interpreted
    kernels, then compiles them (the notice comes after the answer); the next run loads them, the same digits."""
    command = [sys.executable, "-m", "wavecontact", "collide", "--gamma", "0.6", "--kappa", "100"]
    first = subprocess.run(command, env=_env(tmp_path), stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                           timeout=300, check=True)
    lines = first.stdout.splitlines()
    answer = next(i for i, line in enumerate(lines) if line.startswith("epsilon = "))
    assert "interpreted" in lines[answer] and "compiled after this answer" in lines[answer], first.stdout
    assert all("compiling" not in line for line in lines[:answer]), first.stdout  # no compilation before it
    cached = {path.name.split("-")[0] for path in tmp_path.rglob("*.nbi")}
    assert {"kernels._method_of_steps", "energy_split._energy_gain"} <= cached
    again = subprocess.run(command, env=_env(tmp_path), capture_output=True, text=True, timeout=300, check=True)
    assert "interpreted" not in again.stdout and "numba kernel preparation" in again.stdout, again.stdout
    assert "compiling" not in again.stderr
    assert lines[answer].split("(")[0] == again.stdout.split("(")[0]
