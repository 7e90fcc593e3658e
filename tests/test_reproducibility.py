"""Bit-identical results whatever the state of numba's kernel cache (issue: fastmath made a ring run
depend on whether its kernels had just been compiled or were loaded from the cache).

Each run is a separate process with its own ``NUMBA_CACHE_DIR``: an empty one makes numba compile every
kernel, a filled one makes it load them.  The ring is the sensitive case: it is chaotic, so a difference
in the last bit of one collision grows until whole trajectories differ.
"""

from __future__ import annotations

import os
import subprocess
import sys
import time

import numpy as np
import pytest

from wavecontact._jit import NUMBA_ENABLED
from wavecontact.studies.ring import CHECKPOINT_NAME, RingRun

ARGS = ["-m", "wavecontact", "ring", "--gamma", "0.6173", "--kappa", "4000", "--modes", "12",
        "--collisions", "300", "--checkpoint-every", "20", "--no-progress"]
pytestmark = pytest.mark.skipif(not NUMBA_ENABLED, reason="numba not installed: nothing is cached")


def _env(cache):
    env = dict(os.environ)
    env["NUMBA_CACHE_DIR"] = str(cache)
    return env


def _ring(out, cache, **kwargs):
    return subprocess.run([sys.executable, *ARGS, "--out", str(out)], env=_env(cache), capture_output=True,
                          text=True, timeout=600, **kwargs)


def _same(a: RingRun, b: RingRun):
    for name in RingRun._ARRAYS:
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)


def test_fresh_compile_and_cache_load_give_the_same_ring_and_resume_matches(tmp_path):
    cache = tmp_path / "cache"
    compiled = _ring(tmp_path / "compiled", cache)  # empty cache: every kernel compiled
    assert compiled.returncode == 0, compiled.stderr
    assert any(cache.rglob("*.nbi")), "numba wrote no cache: the test would compare two compiled runs"
    loaded = _ring(tmp_path / "loaded", cache)  # the same kernels loaded from the cache
    assert loaded.returncode == 0, loaded.stderr
    reference = RingRun.load_npz(tmp_path / "compiled" / "ring.npz")
    _same(reference, RingRun.load_npz(tmp_path / "loaded" / "ring.npz"))

    # a run started with an empty cache, stopped after a checkpoint, resumed with the cache filled
    cold = tmp_path / "cold-cache"
    stopped = tmp_path / "stopped"
    proc = subprocess.Popen([sys.executable, *ARGS, "--out", str(stopped)], env=_env(cold),
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    checkpoint = stopped / CHECKPOINT_NAME
    try:
        deadline = time.monotonic() + 600
        while not checkpoint.exists() and proc.poll() is None and time.monotonic() < deadline:
            time.sleep(0.002)
    finally:
        proc.kill()
        proc.wait()
    if (stopped / "ring.npz").exists():
        pytest.skip("the run finished before it could be stopped")
    assert checkpoint.exists()
    resumed = _ring(stopped, cold)
    assert resumed.returncode == 0, resumed.stderr
    assert "resuming from checkpoint" in resumed.stderr
    _same(reference, RingRun.load_npz(stopped / "ring.npz"))
