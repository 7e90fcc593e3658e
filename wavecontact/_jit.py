"""Optional numba compilation of the hot time-stepping kernels.

Kernels are written as plain Python functions on NumPy arrays and decorated
with :func:`kernel`.  With numba installed they are compiled (and cached on
disk); without it, or with ``WAVECONTACT_PURE_PYTHON=1`` in the environment,
the same functions run as ordinary Python: correct, only much slower.

numba checks a cached kernel only against the file that defines it, not
against helpers it inlines from other modules, so an edit to such a helper
alone would leave the old compiled code in use.  On import, the cached
kernels of the whole package are therefore dropped whenever any of its
sources changed (:func:`refresh_kernel_cache`).

A command's first answer need not wait for numba: inside :func:`answer_first`, :func:`prefer_interpreted`
runs a kernel as plain Python (the same bits) when its caller bounds the call to about a second and numba
has no compiled code for it in memory or on disk; :func:`compile_deferred` then compiles it for the next
runs.
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import os
import sys
import threading
import time
import types
from itertools import chain
from pathlib import Path

__all__ = ["NUMBA_ENABLED", "CompileClock", "announce_compilation", "answer_first", "compile_deferred", "deferred_count",
           "interpreted", "interpreted_call_count", "kernel", "kernel_digest", "prefer_interpreted",
           "prepared_kernel_count", "refresh_kernel_cache", "row_view"]

_STAMP_NAME = "wavecontact-sources.sha1"

_FORCE_PURE = os.environ.get("WAVECONTACT_PURE_PYTHON", "") not in ("", "0")

try:  # pragma: no cover - exercised by the import itself
    if _FORCE_PURE:
        raise ImportError
    import numba as _numba

    NUMBA_ENABLED = True
except ImportError:  # pragma: no cover
    _numba = None
    NUMBA_ENABLED = False


def _sources_digest(root: Path) -> str:
    digest = hashlib.sha1()
    for path in sorted(root.rglob("*.py")):
        digest.update(path.relative_to(root).as_posix().encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()


def kernel_digest() -> str:
    """SHA-256 of the source of every module of the package that defines a compiled kernel.

    Two builds with the same digest run the same kernels, so a checkpoint
    written by one resumes bit for bit in the other; a different digest means
    the arithmetic may differ (:mod:`wavecontact.io.checkpoint` refuses it).
    """
    root = Path(__file__).resolve().parent
    digest = hashlib.sha256()
    for path in sorted(root.rglob("*.py")):
        text = path.read_bytes()
        if b"@kernel" in text and path.name != "_jit.py":
            digest.update(path.relative_to(root).as_posix().encode())
            digest.update(text)
    return digest.hexdigest()


def refresh_kernel_cache(root=None) -> bool:
    """Delete numba's cached kernels below ``root`` if a source there changed since they were cached.

    Parameters
    ----------
    root : path, optional
        Package directory (default: this package).  The digest of its
        ``*.py`` files is kept in ``root/__pycache__``; cache files in a
        ``NUMBA_CACHE_DIR`` elsewhere are not touched.

    Returns
    -------
    bool
        True if the digest changed (and the ``*.nbi``/``*.nbc`` files were
        deleted); False if it did not, or if the directory is read-only.
    """
    root = Path(root) if root is not None else Path(__file__).resolve().parent
    try:
        current = _sources_digest(root)
        stamp = root / "__pycache__" / _STAMP_NAME
        if stamp.is_file() and stamp.read_text() == current:
            return False
        for cached in chain(root.rglob("*.nbi"), root.rglob("*.nbc")):
            cached.unlink(missing_ok=True)
        stamp.parent.mkdir(exist_ok=True)
        stamp.write_text(current)
        return True
    except OSError:  # read-only installation: numba then cannot cache there either
        return False


if NUMBA_ENABLED:
    refresh_kernel_cache()


_KERNELS = []  # every compiled kernel, to tell a first (compiling or cache-loading) call from a warm one
_OVERLOADS = []  # their ``overloads`` dicts (numba creates each once and only fills or clears it)


def prepared_kernel_count() -> int:
    """How many (kernel, signature) pairs numba has compiled or loaded from its cache in this process.

    A solve during which this number grows paid a one-time cost (compilation,
    or loading from the on-disk cache) on top of its own work.  Always 0
    without numba.
    """
    # ``overloads`` is numba's dict of compiled signatures; its length is cheap (``signatures``
    # builds a list per kernel, a tenth of a millisecond over all kernels on every solve), and
    # mapping len over the dicts themselves spares a Python-level loop (a few us per solve)
    return sum(map(len, _OVERLOADS))


def kernel(function=None, *, internal: bool = False, **options):
    """Compile ``function`` with ``numba.njit(cache=True, **options)`` when available.

    Usable as ``@kernel`` or ``@kernel(fastmath=False)``.  The pure-Python
    original stays reachable as ``compiled.py_func`` either way.

    ``internal=True`` marks a kernel that the package calls only from other compiled kernels: numba then
    builds neither its CPython wrapper (the code that unboxes every argument from Python objects) nor its
    C wrapper, which are about a sixth of the compile time of a first run (the FE ``converge`` command:
    29 s to 24 s of CPU).  The compiled code of the kernel itself is the same.  A call from Python (a
    test, a benchmark) still works: it goes to a twin of the kernel compiled with its wrappers, once per
    signature (cached on disk under its own name, ``<name>__from_python``).
    """

    def wrap(func):
        if not NUMBA_ENABLED:
            func.py_func = func
            return func
        settings = {"cache": True, "nogil": True}
        settings.update(options)
        if internal:
            compiled = _internal_dispatcher(func, settings)
        else:
            compiled = _numba.njit(**settings)(func)
        _KERNELS.append(compiled)
        _OVERLOADS.append(compiled.overloads)
        return compiled

    if function is not None:
        return wrap(function)
    return wrap


def _internal_dispatcher(func, settings: dict):
    """numba's dispatcher of ``func`` without wrappers, whose calls from Python go to :func:`_python_twin`."""
    options = {key: value for key, value in settings.items() if key != "cache"}
    options.update(no_cpython_wrapper=True, no_cfunc_wrapper=True)
    dispatcher = _InternalDispatcher(py_func=func, locals={}, targetoptions=options)
    dispatcher.twin_settings = settings
    if settings.get("cache"):
        dispatcher.enable_caching()
    return dispatcher


if NUMBA_ENABLED:
    from numba.core.registry import CPUDispatcher as _CPUDispatcher

    class _InternalDispatcher(_CPUDispatcher):
        """A kernel compiled for calls from compiled code only (numba gives it no entry point from Python)."""

        def __call__(self, *args, **kwargs):
            twin = self.__dict__.get("python_twin")
            if twin is None:
                settings = self.__dict__.get("twin_settings")
                if settings is None:  # rebuilt from a pickle: the options less the two wrapper flags
                    settings = {key: value for key, value in self.targetoptions.items()
                                if key not in ("no_cpython_wrapper", "no_cfunc_wrapper")}
                twin = self.python_twin = _python_twin(self.py_func, settings)
            return twin(*args, **kwargs)


def _python_twin(func, settings: dict):
    """``func`` compiled with its wrappers, for calls from Python: a copy of the function under the name
    ``<qualname>__from_python``, so that numba's disk cache keeps it apart from the wrapper-less kernel."""
    copy = types.FunctionType(func.__code__, func.__globals__, func.__name__, func.__defaults__, func.__closure__)
    copy.__qualname__ = func.__qualname__ + "__from_python"
    copy.__module__ = func.__module__
    copy.__doc__ = func.__doc__
    twin = _numba.njit(**settings)(copy)
    _KERNELS.append(twin)
    _OVERLOADS.append(twin.overloads)
    return twin


# --- small calls run interpreted instead of compiling -------------------------------------------------

_INTERPRETED = {}  # original function -> its interpreted clone
_PYTHON_EQUIVALENTS = {}  # kernels whose source is not plain Python (an intrinsic) -> their Python version
_UNCACHED = set()  # (kernel, argument types) known to have no compiled code on disk
_INTERPRETED_CALLS = [0]
_ANSWER_FIRST = [False]  # inside answer_first(): small calls without compiled code run interpreted
_DEFERRED = {}  # (kernel, argument types) run interpreted, to compile after the answer


def interpreted(compiled):
    """``compiled`` (a kernel) as plain Python, the kernels it calls interpreted too.

    The kernel's function is cloned with a copy of its module's globals in which every kernel is replaced
    by its own interpreted clone (built once, recursively), so that nothing in the call tree compiles.
    Plain Python and numba (no fastmath) do the same IEEE double operations in the same order, so the
    results are the same bits (tests/test_jit_interpreted.py, tests/test_delay_kernels.py,
    tests/test_delay_hardcore.py).
    """
    func = getattr(compiled, "py_func", compiled)
    if compiled in _PYTHON_EQUIVALENTS:
        return _PYTHON_EQUIVALENTS[compiled]
    clone = _INTERPRETED.get(func)
    if clone is not None:
        return clone
    names = dict(func.__globals__)
    clone = types.FunctionType(func.__code__, names, func.__name__, func.__defaults__, func.__closure__)
    clone.__qualname__ = func.__qualname__
    clone.__doc__ = func.__doc__
    _INTERPRETED[func] = clone  # before the callees: a kernel may call itself through its module
    kernels = _kernel_set()
    for name, value in func.__globals__.items():
        if _hashable(value) and value in kernels:
            names[name] = interpreted(value)
    return clone


def _hashable(value) -> bool:
    try:
        hash(value)
    except TypeError:
        return False
    return True


def _kernel_set() -> set:
    return set(_KERNELS) | set(_PYTHON_EQUIVALENTS)


def _compiled_without_compiling(compiled, args) -> bool:
    """Whether ``compiled(*args)`` runs compiled code without compiling: a specialisation for these
    argument types in memory, or in numba's disk cache (which the call then loads)."""
    try:
        signature = tuple(compiled.typeof_pyval(value) for value in args)
    except (ValueError, TypeError):  # an argument numba cannot type: let the call itself say so
        return True
    if signature in compiled.overloads:
        return True
    key = (compiled, signature)
    if key in _UNCACHED:
        return False
    cache = getattr(compiled, "_cache", None)
    try:
        found = cache is not None and cache.load_overload(signature, compiled.targetctx) is not None
    except (OSError, EOFError, ValueError):  # an unreadable cache entry: numba's own call recompiles it
        found = False
    if not found:
        _UNCACHED.add(key)
    return found


def prefer_interpreted(compiled, args, small: bool, compile_later: bool = False):
    """The callable to run ``compiled(*args)`` with: the kernel itself, or its interpreted version.

    A command's first answer should not wait seconds for numba to compile a kernel that runs for
    milliseconds.  Inside :func:`answer_first` (the CLI's ``collide``), a call its caller declares ``small``
    (at most about a second of plain Python, bounded before the call) whose compiled code is neither in
    memory nor in numba's disk cache runs interpreted (:func:`interpreted`, the same bits).  Everywhere
    else (the Python API, studies, benchmarks) and without numba, the call runs the kernel itself,
    compiling it if needed, as it always did.

    Parameters
    ----------
    compiled : numba dispatcher
        A kernel of this package.
    args : tuple
        The call's arguments (their numba types pick the specialisation looked for).
    small : bool
        The caller's bound: this call takes at most about a second as plain Python.
    compile_later : bool
        Record the specialisation for :func:`compile_deferred` (compiled code is much faster: the next
        runs load it); False where the interpreted call is about as fast as loading compiled code.
    """
    if (not NUMBA_ENABLED or not small or not _ANSWER_FIRST[0]
            or compiled.overloads  # compiled already in this process: one dict's length, no typing
            or _compiled_without_compiling(compiled, args)):
        return compiled
    if compile_later:
        _DEFERRED[(compiled, tuple(compiled.typeof_pyval(value) for value in args))] = None
    return functools.partial(_run_interpreted, compiled)


@contextlib.contextmanager
def answer_first():
    """Inside: small calls without compiled code run interpreted (:func:`prefer_interpreted`), for a
    command's first answer; call :func:`compile_deferred` once the answer is out."""
    before = _ANSWER_FIRST[0]
    _ANSWER_FIRST[0] = True
    try:
        yield
    finally:
        _ANSWER_FIRST[0] = before


def deferred_count() -> int:
    """How many kernel specialisations ran interpreted for a first answer and wait to be compiled."""
    return len(_DEFERRED)


def compile_deferred() -> int:
    """Compile (and cache on disk) every specialisation that ran interpreted for a first answer; their count."""
    pending = list(_DEFERRED)
    _DEFERRED.clear()
    for compiled, signature in pending:
        compiled.compile(signature)
    return len(pending)


def _run_interpreted(compiled, *args):
    import numpy as np

    _INTERPRETED_CALLS[0] += 1
    with np.errstate(all="ignore"):  # compiled code raises no floating-point warnings (an overflow to inf)
        return interpreted(compiled)(*args)


def interpreted_call_count() -> int:
    """How many kernel calls :func:`prefer_interpreted` has run interpreted in this process."""
    return _INTERPRETED_CALLS[0]


if NUMBA_ENABLED:
    from numba.core.event import Listener as _Listener
else:  # pragma: no cover
    _Listener = object

COMPILE_NOTICE = "wavecontact: compiling numba kernels (first run only; cached afterwards)..."


class CompileClock(_Listener):
    """Wall and CPU time numba spends compiling (not loading from its cache) while it is installed.

    Counts each outermost compilation once (the kernels it compiles on the way are inside it).
    ``on_threshold``, if given, is called once, from a timer thread, as soon as the compilations
    together have lasted ``threshold`` seconds (while the one that crosses it still runs).
    Use as a context manager; without numba it measures nothing.
    """

    def __init__(self, threshold: float = float("inf"), on_threshold=None):
        self.wall_s = 0.0
        self.cpu_s = 0.0
        self.compilations = 0
        self._threshold = threshold
        self._on_threshold = on_threshold
        self._fired = False
        self._depth = 0
        self._started = (0.0, 0.0)
        self._timer = None
        self._lock = threading.Lock()

    def on_start(self, event):
        self._depth += 1
        if self._depth > 1:
            return
        self._started = (time.perf_counter(), time.process_time())
        self.compilations += 1
        if self._on_threshold is not None and not self._fired:
            self._timer = threading.Timer(max(self._threshold - self.wall_s, 0.0), self._fire)
            self._timer.daemon = True
            self._timer.start()

    def on_end(self, event):
        self._depth -= 1
        if self._depth > 0:
            return
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
        self.wall_s += time.perf_counter() - self._started[0]
        self.cpu_s += time.process_time() - self._started[1]
        if self._on_threshold is not None and self.wall_s >= self._threshold:
            self._fire()  # crossed while the timer thread had no turn: say it now

    def _fire(self):
        with self._lock:
            if self._fired:
                return
            self._fired = True
        self._on_threshold()

    def __enter__(self):
        if NUMBA_ENABLED:
            from numba.core import event

            event.register("numba:compile", self)
        return self

    def __exit__(self, *exc):
        if NUMBA_ENABLED:
            from numba.core import event

            event.unregister("numba:compile", self)
        if self._timer is not None:
            self._timer.cancel()
        return False


@contextlib.contextmanager
def announce_compilation(stream=None, after: float = 1.0, message: str = COMPILE_NOTICE):
    """Say once on ``stream`` (default stderr) when numba has been compiling for ``after`` seconds.

    A first run on an empty cache compiles for seconds before it prints anything; this tells the
    user why.  Loading kernels from numba's cache is not compiling and is not announced.
    """

    def say():
        print(message, file=stream if stream is not None else sys.stderr, flush=True)

    with CompileClock(after, say) as clock:
        yield clock


def _row_view_compiled():
    """:func:`row_view` for compiled kernels: a view made from the row's data pointer, owning no reference."""
    from numba.core import types
    from numba.extending import intrinsic

    @intrinsic
    def data_pointer(typingctx, array):
        signature = types.CPointer(array.dtype)(array)

        def codegen(context, builder, sig, args):
            return context.make_array(sig.args[0])(context, builder, args[0]).data

        return signature, codegen

    @kernel(inline="always")
    def row_view(table, row):
        return _numba.carray(data_pointer(table[row]), (table.shape[1],))

    return row_view


def _row_view_python(table, row):
    return table[row]


if NUMBA_ENABLED:
    row_view = _row_view_compiled()
    _PYTHON_EQUIVALENTS[row_view] = _row_view_python
else:
    row_view = _row_view_python
row_view.__doc__ = """Row ``row`` of the C-contiguous 2-D array ``table`` as a 1-D view, inside a compiled kernel without
reference counting.

numba counts the references of every array view a kernel makes, with an atomic increment and decrement
per view and per call that passes it on; a step of the interleaved layout makes some twenty views of its
table and passes them through eight calls, which cost about 30 ns per call (measured: a call passing nine
views of a table, 43 ns with counted views, 12 ns with these; docs/fem.md section 7).  The view made here
holds the row's data pointer only, so it is valid only while ``table`` itself is alive: use it inside a
kernel for arrays its caller holds, never return it.  Without numba it is ``table[row]``.
"""
