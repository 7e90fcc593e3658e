"""Run a script once without numba (``WAVECONTACT_PURE_PYTHON=1``) and once compiled, each in its own process."""

import os
import subprocess
import sys

import numpy as np


def pure_and_compiled_outputs(script, tmp_path, *arguments):
    """The arrays the script saves to the npz file named by its first argument, for the pure-Python run
    and for the compiled run, as two dicts; ``arguments`` follow the file name on the command line."""
    outputs = []
    for pure in ("1", "0"):
        path = tmp_path / f"run{pure}.npz"
        env = dict(os.environ, WAVECONTACT_PURE_PYTHON=pure)
        subprocess.run([sys.executable, "-c", script, str(path), *map(str, arguments)], check=True, env=env,
                       timeout=600)
        with np.load(path) as data:
            outputs.append({k: data[k] for k in data.files})
    return outputs
