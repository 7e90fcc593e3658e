"""The kernel cache is dropped when any source of the package changes (numba only checks the
defining file, not the helpers a kernel inlines from other modules)."""

from wavecontact._jit import refresh_kernel_cache


def test_cached_kernels_are_dropped_when_any_source_changes(tmp_path):
    package = tmp_path / "pkg"
    (package / "sub" / "__pycache__").mkdir(parents=True)
    (package / "kernels.py").write_text("def f():\n    return 1\n")
    (package / "sub" / "helpers.py").write_text("def g():\n    return 2\n")
    cached = [package / "sub" / "__pycache__" / "kernels.f-1.py311.nbi",
              package / "sub" / "__pycache__" / "kernels.f-1.py311.1.nbc"]
    for path in cached:
        path.write_bytes(b"old")
    assert refresh_kernel_cache(package)  # no digest yet: caches of unknown origin go
    assert not any(path.exists() for path in cached)

    for path in cached:
        path.write_bytes(b"new")
    assert not refresh_kernel_cache(package)  # nothing changed: the cache stays
    assert all(path.exists() for path in cached)

    (package / "sub" / "helpers.py").write_text("def g():\n    return 3\n")  # only a helper module
    assert refresh_kernel_cache(package)
    assert not any(path.exists() for path in cached)
    assert not refresh_kernel_cache(package)


def test_first_call_reports_kernel_preparation_and_a_warm_call_does_not():
    import subprocess
    import sys

    import wavecontact as wc
    from wavecontact._jit import NUMBA_ENABLED

    code = "import wavecontact as wc; print(wc.collide(0.6, 100).diagnostics['includes_kernel_preparation'])"
    first = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    assert first == str(NUMBA_ENABLED)  # a fresh process loads (or compiles) the delay kernels
    wc.collide(0.6, 100)
    assert wc.collide(0.6, 100).diagnostics["includes_kernel_preparation"] is False


def test_row_view_reads_and_writes_the_row_it_names_in_compiled_and_plain_kernels():
    """``row_view`` inside a kernel is the table's row itself (writes land in the table), compiled or not."""
    import numpy as np

    from wavecontact._jit import kernel, row_view

    def scale_row(table, row, factor):
        view = row_view(table, row)
        for i in range(view.size):
            view[i] *= factor
        return view[0] + view[view.size - 1]

    compiled = kernel(scale_row)
    for function in (compiled, compiled.py_func):
        table = np.arange(24.0).reshape(4, 6)
        expected = table.copy()
        expected[2] *= 3.0
        assert function(table, 2, 3.0) == expected[2, 0] + expected[2, -1]
        np.testing.assert_array_equal(table, expected)  # only row 2 changed


def test_an_internal_kernel_gives_the_same_result_from_a_kernel_and_from_python():
    """``kernel(internal=True)`` builds no wrappers; a call from Python goes to a twin compiled with them."""
    import numpy as np

    from wavecontact._jit import NUMBA_ENABLED, kernel

    def doubled_sum(x):
        total = 0.0
        for value in x:
            total += value
        return 2.0 * total

    inner = kernel(doubled_sum, internal=True, cache=False)

    def plus_one(x):
        return inner(x) + 1.0

    outer = kernel(plus_one, cache=False)
    x = np.array([0.1, 0.2, 0.3])
    expected = 2.0 * (0.1 + 0.2 + 0.3)
    assert outer(x) == expected + 1.0
    assert inner(x) == expected  # from Python: the twin with wrappers
    if NUMBA_ENABLED:
        assert inner.targetoptions["no_cpython_wrapper"] and inner.targetoptions["no_cfunc_wrapper"]
        assert inner.python_twin.py_func.__qualname__.endswith("__from_python")  # its own cache entry
        assert not inner.python_twin.targetoptions.get("no_cpython_wrapper", False)
