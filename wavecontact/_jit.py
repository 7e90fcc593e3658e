"""Optional numba compilation of the hot time-stepping kernels.

Kernels are written as plain Python functions on NumPy arrays and decorated
with :func:`kernel`.  With numba installed they are compiled (and cached on
disk); without it, or with ``WAVECONTACT_PURE_PYTHON=1`` in the environment,
the same functions run as ordinary Python: correct, only much slower.
"""

from __future__ import annotations

import os

__all__ = ["NUMBA_ENABLED", "kernel"]

_FORCE_PURE = os.environ.get("WAVECONTACT_PURE_PYTHON", "") not in ("", "0")

try:  # pragma: no cover - exercised by the import itself
    if _FORCE_PURE:
        raise ImportError
    import numba as _numba

    NUMBA_ENABLED = True
except ImportError:  # pragma: no cover
    _numba = None
    NUMBA_ENABLED = False


def kernel(function=None, **options):
    """Compile ``function`` with ``numba.njit(cache=True, **options)`` when available.

    Usable as ``@kernel`` or ``@kernel(fastmath=False)``.  The pure-Python
    original stays reachable as ``compiled.py_func`` either way.
    """

    def wrap(func):
        if not NUMBA_ENABLED:
            func.py_func = func
            return func
        settings = {"cache": True, "nogil": True}
        settings.update(options)
        return _numba.njit(**settings)(func)

    if function is not None:
        return wrap(function)
    return wrap
