"""NumPy's per-sample random streams, many at once: ``default_rng(SeedSequence(seed, spawn_key=(j,)))``.

An ensemble's sample ``j`` draws its bath from
``numpy.random.default_rng(numpy.random.SeedSequence(seed).spawn(n)[j]).standard_normal(...)``.
Building a ``SeedSequence`` and a ``Generator`` per sample costs about 10 us of Python work,
as much as the hard-core collision itself.  This module computes the same numbers without
those objects:

* :func:`spawned_states` hashes the entropy of ``SeedSequence(seed, spawn_key=(j,))`` for a
  whole range of ``j`` with NumPy ``uint32`` arithmetic (the algorithm of
  ``numpy.random.SeedSequence``: ``mix_entropy`` and ``generate_state(4, uint64)``) and
  returns the four 64-bit words that seed ``PCG64``;
* :func:`standard_normals` seeds NumPy's ``PCG64`` (XSL-RR 128/64) from those words and
  draws ``Generator.standard_normal``'s numbers with NumPy's ziggurat, in a compiled
  kernel, row by row.

The results are the numbers NumPy's own objects give, bit for bit (tested against
``default_rng`` for many seeds, including the ziggurat's rare tail and wedge branches).
The kernel is written in ``uint64`` arithmetic that wraps modulo ``2**64`` both compiled and
as plain Python (NumPy scalars, overflow warnings silenced), so ``WAVECONTACT_PURE_PYTHON=1``
gives the same numbers.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from .._jit import kernel
from ..errors import InvalidParameterError, require_integer

__all__ = ["SpawnedSeeds", "seed_states", "spawned_states", "standard_normals"]

# numpy.random.SeedSequence's hash constants (numpy/random/bit_generator.pyx)
_INIT_A = 0x43B0D7E5
_MULT_A = 0x931E8875
_INIT_B = 0x8B51F9DD
_MULT_B = 0x58F38DED
_MIX_MULT_L = 0xCA01F9DD
_MIX_MULT_R = 0x4973F715
_XSHIFT = 16
_POOL_SIZE = 4
_MASK32 = 0xFFFFFFFF

# PCG64's 128-bit LCG multiplier (numpy/random/src/pcg64/pcg64.h), high and low words
_MULT_HI = np.uint64(2549297995355413924)
_MULT_LO = np.uint64(4865540595714422341)
_LOW32 = np.uint64(0xFFFFFFFF)
_U1 = np.uint64(1)
_U8 = np.uint64(8)
_U11 = np.uint64(11)
_U32 = np.uint64(32)
_U58 = np.uint64(58)
_U63 = np.uint64(63)
_U64 = np.uint64(64)
_BYTE = np.uint64(0xFF)
_MANTISSA = np.uint64(0x000FFFFFFFFFFFFF)
_ZERO = np.uint64(0)


def _ziggurat_tables():
    """NumPy's ziggurat tables for the standard normal (as numba ports them from NumPy's C source)."""
    from numba.np.random import _constants as c

    return (np.array(c.ki_double, dtype=np.uint64), np.array(c.wi_double, dtype=np.float64),
            np.array(c.fi_double, dtype=np.float64), float(c.ziggurat_nor_r), float(c.ziggurat_nor_inv_r))


_KI, _WI, _FI, _NOR_R, _NOR_INV_R = _ziggurat_tables()


def _uint32_words(value: int) -> list:
    """``value`` as little-endian 32-bit words (``SeedSequence``'s ``_int_to_uint32_array``)."""
    words = [value & _MASK32]
    value >>= 32
    while value:
        words.append(value & _MASK32)
        value >>= 32
    return words


def _mix_pool(columns: list) -> list:
    """``SeedSequence.mix_entropy``: the 4-word pool from entropy words (uint32 scalars or arrays, which broadcast)."""
    hash_const = _INIT_A

    def hashmix(value):
        nonlocal hash_const
        value = value ^ np.uint32(hash_const)
        hash_const = (hash_const * _MULT_A) & _MASK32
        value = value * np.uint32(hash_const)
        return value ^ (value >> np.uint32(_XSHIFT))

    def mix(x, y):
        result = np.uint32(_MIX_MULT_L) * x - np.uint32(_MIX_MULT_R) * y
        return result ^ (result >> np.uint32(_XSHIFT))

    pool = [hashmix(columns[i] if i < len(columns) else np.uint32(0)) for i in range(_POOL_SIZE)]
    for i_src in range(_POOL_SIZE):
        for i_dst in range(_POOL_SIZE):
            if i_src != i_dst:
                pool[i_dst] = mix(pool[i_dst], hashmix(pool[i_src]))
    for i_src in range(_POOL_SIZE, len(columns)):
        for i_dst in range(_POOL_SIZE):
            pool[i_dst] = mix(pool[i_dst], hashmix(columns[i_src]))
    return pool


def _pcg_words(pool: list, count: int) -> np.ndarray:
    """``SeedSequence.generate_state(4, uint64)`` from the pools (uint32 arrays): ``(count, 4)`` uint64."""
    hash_const = _INIT_B
    words = []
    for i_dst in range(8):
        value = pool[i_dst % _POOL_SIZE] ^ np.uint32(hash_const)
        hash_const = (hash_const * _MULT_B) & _MASK32
        value = value * np.uint32(hash_const)
        words.append(np.broadcast_to(value ^ (value >> np.uint32(_XSHIFT)), (count,)).astype(np.uint64))
    return np.stack([words[2 * i] | (words[2 * i + 1] << np.uint64(32)) for i in range(4)], axis=1)


def spawned_states(seed: int, start: int, stop: int) -> np.ndarray:
    """PCG64 seed words of ``SeedSequence(seed, spawn_key=(j,))`` for ``j`` from ``start`` to ``stop - 1``.

    Parameters
    ----------
    seed : int
        The ensemble's seed (>= 0).
    start, stop : int
        Child indices ``0 <= start <= stop``.

    Returns
    -------
    ndarray (stop - start, 4) of uint64
        ``SeedSequence(seed, spawn_key=(j,)).generate_state(4, numpy.uint64)`` per row, the
        words with which ``PCG64`` seeds itself.
    """
    seed, start, stop = int(seed), int(start), int(stop)
    count = stop - start
    with np.errstate(over="ignore"):
        run = _uint32_words(seed)
        run += [0] * (_POOL_SIZE - len(run))  # SeedSequence pads the entropy when it has a spawn key
        if stop <= 2**32:
            child = [np.arange(start, stop, dtype=np.uint64).astype(np.uint32)]
        else:  # keys of several words: the general path, one SeedSequence per child
            return seed_states([np.random.SeedSequence(seed, spawn_key=(j,)) for j in range(start, stop)])
        columns = [np.uint32(word) for word in run] + child  # the seed's words are the same for every child
        return _pcg_words(_mix_pool(columns), count)


class SpawnedSeeds(Sequence):
    """The children ``SeedSequence(seed).spawn(stop)[start:stop]`` as a sequence, without building them.

    Item ``i`` is ``SeedSequence(seed, spawn_key=(start + i,))`` (built on access);
    :func:`seed_states` hashes the whole range at once.
    """

    def __init__(self, seed: int, start: int, stop: int):
        seed = require_integer("seed", seed, 0, allowed="a non-negative integer")
        if not 0 <= int(start) <= int(stop):
            raise InvalidParameterError(f"sample range must satisfy 0 <= start <= stop, got {start}..{stop}")
        self.seed, self.start, self.stop = int(seed), int(start), int(stop)

    def __len__(self) -> int:
        return self.stop - self.start

    def __getitem__(self, index):
        if isinstance(index, slice):
            first, last, step = index.indices(len(self))
            if step != 1:
                return [self[i] for i in range(first, last, step)]
            return SpawnedSeeds(self.seed, self.start + first, self.start + max(first, last))
        if not -len(self) <= index < len(self):
            raise IndexError(index)
        return np.random.SeedSequence(self.seed, spawn_key=(self.start + index % len(self),))


def seed_states(seeds) -> np.ndarray:
    """PCG64 seed words ``(len(seeds), 4)`` of seeds (ints, ``SeedSequence`` objects, or :class:`SpawnedSeeds`).

    ``SeedSequence(s).generate_state(4, numpy.uint64)`` per seed (what ``default_rng(s)``
    seeds its ``PCG64`` with); a :class:`SpawnedSeeds` range goes through
    :func:`spawned_states` at once.
    """
    if isinstance(seeds, SpawnedSeeds):
        return spawned_states(seeds.seed, seeds.start, seeds.stop)
    states = np.empty((len(seeds), 4), dtype=np.uint64)
    for j, seed in enumerate(seeds):
        sequence = seed if isinstance(seed, np.random.SeedSequence) else np.random.SeedSequence(seed)
        states[j] = sequence.generate_state(4, np.uint64)
    return states


@kernel(inline="always")
def _mulhi(a, b):
    """High 64 bits of the 128-bit product of two uint64."""
    a_lo = a & _LOW32
    a_hi = a >> _U32
    b_lo = b & _LOW32
    b_hi = b >> _U32
    p0 = a_lo * b_lo
    p1 = a_lo * b_hi
    p2 = a_hi * b_lo
    mid = (p0 >> _U32) + (p1 & _LOW32) + (p2 & _LOW32)
    return a_hi * b_hi + (p1 >> _U32) + (p2 >> _U32) + (mid >> _U32)


@kernel(inline="always")
def _step(hi, lo, inc_hi, inc_lo):
    """One LCG step ``state * MULT + inc`` modulo 2**128; returns the new ``(hi, lo)``."""
    product_lo = lo * _MULT_LO
    product_hi = hi * _MULT_LO + lo * _MULT_HI + _mulhi(lo, _MULT_LO)
    new_lo = product_lo + inc_lo
    carry = _U1 if new_lo < product_lo else _ZERO
    return product_hi + inc_hi + carry, new_lo


@kernel(inline="always")
def _output(hi, lo):
    """PCG's XSL-RR output of a 128-bit state."""
    value = hi ^ lo
    rotation = hi >> _U58
    return (value >> rotation) | (value << ((_U64 - rotation) & _U63))


@kernel
def _normals_row(words, out, ki, wi, fi, nor_r, nor_inv_r):
    """Seed PCG64 from ``words`` (4 uint64) and fill ``out`` (1-D) with ``standard_normal`` draws."""
    # pcg64_set_seed: state = (words[0], words[1]), increment from (words[2], words[3])
    init_hi, init_lo = words[0], words[1]
    inc_hi = (words[2] << _U1) | (words[3] >> _U63)
    inc_lo = (words[3] << _U1) | _U1
    hi, lo = _step(_ZERO, _ZERO, inc_hi, inc_lo)
    lo_sum = lo + init_lo
    carry = _U1 if lo_sum < lo else _ZERO
    hi, lo = _step(hi + init_hi + carry, lo_sum, inc_hi, inc_lo)
    for n in range(out.shape[0]):
        while True:
            hi, lo = _step(hi, lo, inc_hi, inc_lo)
            r = _output(hi, lo)
            idx = int(r & _BYTE)
            r = r >> _U8
            rabs = (r >> _U1) & _MANTISSA
            x = float(rabs) * wi[idx]
            if r & _U1:
                x = -x
            if rabs < ki[idx]:
                break
            if idx == 0:
                while True:
                    hi, lo = _step(hi, lo, inc_hi, inc_lo)
                    u = float(_output(hi, lo) >> _U11) * (1.0 / 9007199254740992.0)
                    xx = -nor_inv_r * np.log1p(-u)
                    hi, lo = _step(hi, lo, inc_hi, inc_lo)
                    u = float(_output(hi, lo) >> _U11) * (1.0 / 9007199254740992.0)
                    yy = -np.log1p(-u)
                    if yy + yy > xx * xx:
                        break
                x = -(nor_r + xx) if (rabs >> _U8) & _U1 else nor_r + xx
                break
            hi, lo = _step(hi, lo, inc_hi, inc_lo)
            u = float(_output(hi, lo) >> _U11) * (1.0 / 9007199254740992.0)
            if (fi[idx - 1] - fi[idx]) * u + fi[idx] < np.exp(-0.5 * x * x):
                break
        out[n] = x


@kernel
def _normals_rows(states, out, ki, wi, fi, nor_r, nor_inv_r):
    for j in range(states.shape[0]):
        _normals_row(states[j], out[j], ki, wi, fi, nor_r, nor_inv_r)


def standard_normals(states: np.ndarray, count: int, out: np.ndarray | None = None) -> np.ndarray:
    """``default_rng(s).standard_normal(count)`` for every seed ``s`` whose PCG64 words are a row of ``states``.

    Parameters
    ----------
    states : ndarray (n, 4) of uint64
        From :func:`spawned_states` or :func:`seed_states`.
    count : int
        Draws per row.
    out : ndarray (n, count) of float64, optional
        Filled in place (C-contiguous rows).

    Returns
    -------
    ndarray (n, count)
        Row ``j`` holds the first ``count`` standard normals of row ``j``'s stream.
    """
    states = np.ascontiguousarray(states, dtype=np.uint64)
    if out is None:
        out = np.empty((states.shape[0], int(count)))
    with np.errstate(over="ignore"):
        _normals_rows(states, out, _KI, _WI, _FI, _NOR_R, _NOR_INV_R)
    return out
