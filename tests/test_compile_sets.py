"""What a README command compiles on an empty numba cache: the kernels its runs execute, not the contact
schemes and laws it never calls (docs/performance.md, compile time of a first run).

The FE loop ``advance`` takes the contact scheme as an argument, None for the force scheme, and both it and
the lattice ``advance_lattice`` take ``general_law``, None for the exponential law; numba prunes the branches
of a None argument before typing, so a force-scheme run compiles neither the splitting and interface flows
nor any law's flow or gap solutions, and an exponential-law run of the other schemes only the exponential
law's.  Each compiled kernel leaves one index file in the cache, named ``module.function-line...nbi``, so the
cache lists what the command compiled.  (The ring command's set is checked in tests/test_reproducibility.py,
on the runs that test makes anyway.)
"""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from wavecontact._jit import NUMBA_ENABLED

pytestmark = pytest.mark.skipif(not NUMBA_ENABLED, reason="numba not installed: nothing is compiled")

# the README's converge line at two meshes: 50 elements in the flat layout, 100 in the interleaved one
CONVERGE = ["converge", "--gamma", "0.6", "--kappa", "20", "--order", "1", "2", "--mass", "lumped", "consistent",
            "--elements", "50", "100"]


def _compiled_on_an_empty_cache(arguments, cache) -> set:
    """Run ``wavecontact ARGUMENTS`` with numba's cache in ``cache``; the kernels the cache then holds."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache))
    env.pop("WAVECONTACT_PURE_PYTHON", None)
    done = subprocess.run([sys.executable, "-m", "wavecontact", *arguments], env=env, capture_output=True,
                          text=True, timeout=900, check=False)
    assert done.returncode == 0, done.stderr
    return {path.name.split("-")[0] for path in cache.rglob("*.nbi")}


# the kernels of the general laws (penalty, hard, overlap laws) and of their dispatch
GENERAL_LAWS = {"contact_flows.contact_flow", "contact_flows.interface_gap", "contact_kernels.law_flow",
                "contact_kernels.law_gap", "contact_kernels.hard_gap", "contact_kernels.penalty_gap",
                "contact_kernels.overlap_gap", "contact_kernels.hard_elastic_flow", "contact_kernels.penalty_flow",
                "contact_kernels.overlap_flow"}


def test_exponential_runs_compile_no_other_law_and_force_runs_no_other_scheme(tmp_path):
    compiled = _compiled_on_an_empty_cache(CONVERGE, tmp_path)
    ran = {"kernels.advance", "lattice.advance_lattice", "contact_flows.exponential_gap_quartic",
           "interleaved_step.step_condensed_loaded", "explicit_step.step_flat", "kernels._method_of_steps"}
    assert ran <= compiled, f"the cache misses {sorted(ran - compiled)}: the command ran other kernels than assumed"
    # no splitting flow; the lattice's gap equation is pruned_gap's exponential branch
    not_run = GENERAL_LAWS | {"contact_kernels.exponential_flow", "contact_flows.pruned_flow"}
    assert not compiled & not_run, f"the converge command compiled {sorted(compiled & not_run)}"
    # P2 consistent at 40 elements does not resolve the contact: the massless-end interface, whose loop compiles
    # the splitting and interface flows of the exponential law alone (the same cache: advance's new specialisation)
    interface = ["collide", "--solver", "fem", "--gamma", "0.6", "--kappa", "100", "--order", "2", "--mass",
                 "consistent", "--elements", "40", "--json"]
    compiled = _compiled_on_an_empty_cache(interface, tmp_path)
    assert {"contact_flows.pruned_gap", "contact_flows.pruned_flow", "contact_kernels.exponential_flow"} <= compiled
    assert not compiled & GENERAL_LAWS, f"an exponential interface run compiled {sorted(compiled & GENERAL_LAWS)}"
