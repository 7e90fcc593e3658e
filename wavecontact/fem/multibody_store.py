"""The store of the multi-body loop (:mod:`wavecontact.fem.multibody_kernel`): every body's arrays in one float array.

A list of arrays per rod (numba's typed list) costs the loop a call into numba's list helper and a counted
reference (an atomic increment and decrement) per lookup, some thirty lookups per step; and every array a
compiled call receives costs such a pair again.  On a 3-rod chain at 200 elements per rod that fixed cost
was about twice the rods' own step.  Here every array of every body lies in one float array, the *store*,
at offsets given by the rod layout (the ``G_*`` columns, one row per rod); the loop makes its views of it
with :func:`segment` and :func:`block`, array structures built in place from the store's data pointer (like
``numba.carray``: no call, no reference), and reads a contact side's end node, a rigid body or a wall as one
index in the store.

:func:`build_store` lays out the store; each rod's arrays start on a 64-byte boundary (the interleaved
layout's tables want whole cache lines, :func:`~wavecontact.fem.interleaved_step.aligned_table`).
"""

from __future__ import annotations

import numpy as np

from .._jit import NUMBA_ENABLED
from .interleaved_step import L_SHAPE, L_U, L_V

__all__ = ["ROD_FIELDS", "block", "borrowed", "build_store", "segment"]

# rod layout: where each rod's arrays lie in the store (offsets in doubles) and their shapes
G_NODES = 0  # nodes n
G_FLAT_U, G_FLAT_V, G_SCRATCH, G_WEIGHTS = 1, 2, 3, 4  # n each: displacements, velocities, scratch, lumped masses
G_BANDS, G_BAND_ROWS = 5, 6  # stiffness bands, (rows, n)
G_TABLE, G_TABLE_ROWS, G_TABLE_COLS = 7, 8, 9  # the mass solve's table
G_STEPPED_U, G_STEPPED_V, G_STEPPED_SIZE = 10, 11, 12  # the arrays the loop steps (the flat ones or table rows)
G_KIND = 13  # mass-solve kind
G_CHUNK_ROWS = 14  # rows per chunk of the interleaved layout (0: flat layout)
ROD_FIELDS = 15


def _store_views():
    """:func:`segment`, :func:`block` and :func:`borrowed` for compiled kernels: array views built in place
    (like ``numba.carray``) from a data pointer, with no reference to count."""
    from numba.core import cgutils, types
    from numba.extending import intrinsic

    def view(context, builder, source_type, source, result_type, offset, shape, strides=None):
        array = context.make_array(source_type)(context, builder, source)
        out = context.make_array(result_type)(context, builder)
        itemsize = context.get_constant(types.intp, context.get_abi_sizeof(context.get_data_type(source_type.dtype)))
        if strides is None:  # C order
            strides, step = [], itemsize
            for extent in reversed(shape):
                strides.insert(0, step)
                step = builder.mul(step, extent)
        data = array.data if offset is None else builder.gep(array.data, [offset])
        context.populate_array(out, data=data, shape=cgutils.pack_array(builder, shape),
                               strides=cgutils.pack_array(builder, strides), itemsize=itemsize, meminfo=None)
        return out._getvalue()

    @intrinsic
    def segment(typingctx, store, offset, size):
        result = types.Array(store.dtype, 1, "C")

        def codegen(context, builder, sig, args):
            return view(context, builder, sig.args[0], args[0], result, args[1], [args[2]])

        return result(store, types.int64, types.int64), codegen

    @intrinsic
    def block(typingctx, store, offset, rows, cols):
        result = types.Array(store.dtype, 2, "C")

        def codegen(context, builder, sig, args):
            return view(context, builder, sig.args[0], args[0], result, args[1], [args[2], args[3]])

        return result(store, types.int64, types.int64, types.int64), codegen

    @intrinsic
    def borrowed(typingctx, array):
        def codegen(context, builder, sig, args):
            source = context.make_array(sig.args[0])(context, builder, args[0])
            shape = cgutils.unpack_tuple(builder, source.shape, array.ndim)
            strides = cgutils.unpack_tuple(builder, source.strides, array.ndim)
            return view(context, builder, sig.args[0], args[0], array, None, shape, strides)

        return array(array), codegen

    return segment, block, borrowed


def _segment_python(store, offset, size):
    return store[offset:offset + size]


def _block_python(store, offset, rows, cols):
    return store[offset:offset + rows * cols].reshape(rows, cols)


def _borrowed_python(array):
    return array


if NUMBA_ENABLED:
    segment, block, borrowed = _store_views()
else:
    segment, block, borrowed = _segment_python, _block_python, _borrowed_python
segment.__doc__ = """``store[offset:offset + size]`` (C-contiguous, 1-D) inside a compiled kernel: an address computation.

Like :func:`~wavecontact._jit.row_view` the view holds the data pointer only, no reference: valid while
``store`` is alive, never returned.  Without numba it is the slice.
"""
block.__doc__ = """``store[offset:offset + rows * cols].reshape(rows, cols)`` inside a compiled kernel (see :func:`segment`)."""
borrowed.__doc__ = """A C-contiguous array as a view that counts no references, inside a compiled kernel (see :func:`segment`).

numba counts a reference (an atomic increment and decrement) for every array argument of a compiled call it
does not inline, on entry and for every tuple it unpacks; handed a view made here, each is a test of a null
pointer.  Valid while ``array`` is alive; never returned.  Without numba it is ``array``.
"""


def aligned(size: int) -> np.ndarray:
    """A zero float array of ``size`` entries starting on a 64-byte boundary."""
    buffer = np.zeros(size + 8)
    start = (-buffer.ctypes.data % 64) // 8
    return buffer[start:start + size]


def build_store(rods, us, vs, solves, ru, rv) -> tuple:
    """Every body's arrays in one float array, with the values given: ``(store, layout, rigid)``.

    Parameters
    ----------
    rods : list of :class:`~wavecontact.fem.discretization.RodDiscretization`
    us, vs : lists of arrays, one per rod
        Displacements (length) and velocities (length/time), node by node.
    solves : list of ``(kind, table)``, one per rod
        The mass solves of :func:`~wavecontact.fem.explicit_step.prepare_mass`.
    ru, rv : arrays
        Displacement and velocity of each rigid body.

    Returns
    -------
    store : float array
        Per rod: displacements, velocities, a scratch array, lumped masses, stiffness bands, mass-solve
        table (each from a 64-byte boundary); then ``ru``, ``rv`` and one entry that stays 0.
    layout : int array (n_rods, ROD_FIELDS)
        The ``G_*`` offsets and shapes; the arrays the loop steps (``G_STEPPED_*``) are the flat
        displacements and velocities, or for a rod in the interleaved layout the rows of its table.
    rigid : tuple
        Offsets of ``ru``, ``rv`` and of the entry that stays 0 (a wall's displacement and velocity).
    """
    layout = np.zeros((len(rods), ROD_FIELDS), dtype=np.int64)
    blocks = []  # (offset, array) copied in
    size = 0

    def place(array) -> int:
        nonlocal size
        offset = size
        blocks.append((offset, array))
        size += -(-array.size // 8) * 8
        return offset

    for row, d, u, v, (kind, table) in zip(layout, rods, us, vs, solves):
        n = d.n_nodes
        bands = np.ascontiguousarray(d.stiffness_bands)
        row[G_NODES] = n
        row[G_FLAT_U], row[G_FLAT_V] = place(u), place(v)
        row[G_SCRATCH] = place(np.zeros(n))
        row[G_WEIGHTS] = place(d.lumped_mass)
        row[G_BANDS], row[G_BAND_ROWS] = place(bands), bands.shape[0]
        row[G_TABLE] = place(table)
        row[G_TABLE_ROWS], row[G_TABLE_COLS] = table.shape
        row[G_KIND] = kind
        row[G_CHUNK_ROWS] = int(table[L_SHAPE, 0])
        if row[G_CHUNK_ROWS]:
            columns = table.shape[1]
            row[G_STEPPED_U] = row[G_TABLE] + L_U * columns
            row[G_STEPPED_V] = row[G_TABLE] + L_V * columns
            row[G_STEPPED_SIZE] = columns
        else:
            row[G_STEPPED_U], row[G_STEPPED_V], row[G_STEPPED_SIZE] = row[G_FLAT_U], row[G_FLAT_V], n
    rigid = (place(ru), place(rv), place(np.zeros(1)))
    store = aligned(size)
    for offset, array in blocks:
        store[offset:offset + array.size] = array.ravel()
    return store, layout, rigid
