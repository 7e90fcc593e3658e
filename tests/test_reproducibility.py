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
        "--collisions", "300", "--checkpoint-every", "100", "--no-progress"]
pytestmark = pytest.mark.skipif(not NUMBA_ENABLED, reason="numba not installed: nothing is cached")


def _env(cache):
    env = dict(os.environ)
    env["NUMBA_CACHE_DIR"] = str(cache)
    return env


def _ring(out, cache, **kwargs):
    return subprocess.run([sys.executable, *ARGS, "--out", str(out)], check=False, env=_env(cache),
                          capture_output=True,
                          text=True, timeout=600, **kwargs)


def _same(a: RingRun, b: RingRun):
    for name in RingRun._ARRAYS:
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)


def test_fresh_compile_and_cache_load_give_the_same_ring_and_resume_matches(tmp_path):
    """One process compiles every kernel (empty cache) and is stopped after its first checkpoint
    (collision 100; the fastmath kernels first differed at collision 16); a second resumes it with
    the cache that the first filled; a third runs uninterrupted on that cache.  The first 100
    collisions thus come from freshly compiled kernels in one run and cached ones in the other, and
    the rest from a resumed run in one and a straight run in the other: all must agree bit for bit."""
    cache = tmp_path / "cache"
    stopped = tmp_path / "stopped"
    proc = subprocess.Popen([sys.executable, *ARGS, "--out", str(stopped)], env=_env(cache),
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
    assert any(cache.rglob("*.nbi")), "numba wrote no cache: the runs below would compile again"
    resumed = _ring(stopped, cache)
    assert resumed.returncode == 0, resumed.stderr
    assert "resuming from checkpoint" in resumed.stderr and "after collision 100" in resumed.stderr
    straight = _ring(tmp_path / "straight", cache)
    assert straight.returncode == 0, straight.stderr
    _same(RingRun.load_npz(tmp_path / "straight" / "ring.npz"), RingRun.load_npz(stopped / "ring.npz"))
    # The three processes filled the cache with every kernel the ring command compiles (one index file per
    # kernel, named module.function-line): its free flights compile the splitting kernel without its stepping,
    # rotation tables and contact law, and the exponential collision no general law (docs/performance.md,
    # compile time of a first run); any of these in the cache means a ring run compiles them again.
    compiled = {path.name.split("-")[0] for path in cache.rglob("*.nbi")}
    assert "kernels.run_episode" in compiled and "contact_kernels.exponential_response" in compiled
    not_needed = {"kernels.rotation_tables", "kernels._update_forces", "kernels._rotate", "kernels._kick_deferred",
                  "contact_kernels.law_response", "contact_kernels.series_response", "contact_kernels.contact_response",
                  "contact_kernels.law_force", "collocation._force"}
    assert not compiled & not_needed, f"the ring command compiled {sorted(compiled & not_needed)}"
