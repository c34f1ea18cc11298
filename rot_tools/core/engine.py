"""
One formula, two ways to run it: Python floats for a single item, NumPy chunks for a batch.

A conversion is written once as a kernel of an ops namespace and its inputs' entries;
``apply`` runs it on FLOATS for one item or on ARRAYS chunk by chunk for a batch, and gives
its outputs back by name (a NamedTuple). doc/engine.md tells the rules a kernel follows and
how to add a conversion.
"""

from dataclasses import dataclass
from itertools import chain
import math
import sys
from types import SimpleNamespace
from typing import Any, NamedTuple

import numpy as np
from rot_tools.core._arrays import as_float_array, require_finite
from rot_tools.core.errors import FLOAT_ERRORS, RotationError

CHUNK = 8192


@dataclass(frozen=True)
class Spec:
    """One output of a kernel: its trailing shape and its dtype (np.float64 or np.bool_)."""

    tail: tuple
    dtype: type = np.float64


MATRIX = Spec((3, 3))
VECTOR = Spec((3,))
SCALAR = Spec(())
FLAG = Spec((), np.bool_)


class InRange(NamedTuple):
    """A result that can leave float64's range for finite inputs, and where it did not."""

    value: Any
    fits: Any


class Unit(NamedTuple):
    """A 3-vector's direction v/|v| and its length |v| (see :func:`unit`)."""

    direction: list
    norm: Any


def _maximum(a, b):
    """max(a, b) of floats, NaN if either is NaN, as np.maximum (max(x, nan) is x)."""
    return a if a >= b or a != a else b


def _minimum(a, b):
    """min(a, b) of floats, NaN if either is NaN, as np.minimum."""
    return a if a <= b or a != a else b


def _max_of(first, *rest):
    """Return the largest of the floats, NaN if one is NaN."""
    for x in rest:
        first = first if first >= x or first != first else x
    return first


def _where(cond, a, b):
    """Return a if cond else b (both already evaluated, as np.where's)."""
    return a if cond else b


def _array_max_of(first, *rest):
    """np.maximum of several arrays."""
    for x in rest:
        first = np.maximum(first, x)
    return first


# The two ops namespaces (plain attributes: a kernel looks one up for every operation).
FLOATS = SimpleNamespace(
    atan2=math.atan2, sqrt=math.sqrt, sin=math.sin, cos=math.cos, tan=math.tan, abs=abs,
    maximum=_maximum, minimum=_minimum, max_of=_max_of, where=_where, rare=bool)
"""One item: Python floats and the math module."""

ARRAYS = SimpleNamespace(
    atan2=np.arctan2, sqrt=np.sqrt, sin=np.sin, cos=np.cos, tan=np.tan, abs=np.abs,
    maximum=np.maximum, minimum=np.minimum, max_of=_array_max_of, where=np.where,
    rare=np.any)
"""A batch chunk: NumPy arrays (errors on the discarded side of a where are silenced)."""

FLOAT64 = np.dtype(np.float64)


def apply(kernel, inputs, outputs, params=()):
    """
    Run ``kernel(ops, *entries, *params)`` on one item or on a batch.

    inputs: sequence of (value, trailing shape, name, finite): each value is made a float64
    array with that trailing shape (RotationError naming it otherwise) and, when ``finite``,
    refused if it holds NaN/Inf; their batch shapes broadcast. outputs: a Spec when the
    kernel returns one output, or the NamedTuple the kernel returns with a Spec (or another
    such NamedTuple, or a plain tuple of them) in each field. params: fixed arguments after
    the entries (an Euler sequence's axes). Returns the kernel's output in the same form,
    each Spec's value an array of shape batch + trailing shape (a NumPy scalar or array for
    a single item).

    A single item runs on FLOATS; where Python's float arithmetic raises (x/0, sin(inf),
    sqrt(−1)) it is run as a batch of one instead, so that it gives the inf/NaN a batch
    gives.
    """
    values = _entries_of_one_item(inputs)
    if values is None:
        return _apply_to_batch(kernel, inputs, outputs, params)
    try:
        result = kernel(FLOATS, *values, *params)
    except FLOAT_ERRORS:
        return _apply_to_batch(kernel, inputs, outputs, params, one=True)
    return _one_item(result, outputs)


def apply_to_one(kernel, inputs, outputs, params=()):
    """
    Return apply's result for one item as Python numbers: the kernel's output on FLOATS.

    The same numbers as apply gives, in the same NamedTuple, but as the kernel gives them:
    a float (a bool for a flag), a list for a vector, a list of rows for a matrix. For a
    caller that uses them as Python numbers (rotation_node writes them into its messages),
    which apply would have made into NumPy values first. inputs, outputs and params as
    apply's; every input is one item (RotationError for a batch).
    """
    values = _entries_of_one_item(inputs)
    if values is None:
        raise RotationError('one item only: ' + ', '.join(
            f'{name} of shape {tail}' for _, tail, name, _ in inputs))
    try:
        return kernel(FLOATS, *values, *params)
    except FLOAT_ERRORS:
        result = _apply_to_batch(kernel, inputs, outputs, params, one=True)
        return _rebuild(outputs, iter([x.tolist() for x in _leaves(result, outputs)]))


def _entries_of_one_item(inputs):
    """
    Return the kernel's entries of apply's inputs when they are one item, else None.

    Each input as Python floats: a float, a list (vector) or a list of rows (matrix); NaN/Inf
    refused in the inputs marked finite.
    """
    values = []
    for x, tail, name, finite in inputs:
        if type(x) is np.ndarray and x.shape == tail and x.dtype is FLOAT64:
            v = x.tolist()  # (the usual one item: no array made, no shape to check)
        elif type(x) is float and not tail:
            v = x
        elif type(x) in (tuple, list) and len(tail) == 1 and len(x) == tail[0] and all(
                type(c) is float for c in x):
            v = list(x)  # (a vector of Python floats, as a message's fields give it)
        else:
            a = as_float_array(x, tail, name)
            if a.ndim != len(tail):
                return None
            v = a.tolist()
        if finite and not _all_finite(v, len(tail)):
            require_finite(np.asarray(v), name)
        values.append(v)
    return values


def _one_item(value, spec):
    """One item's outputs from the kernel's: NumPy scalars and arrays, in spec's form."""
    if type(spec) is Spec:
        if not spec.tail:
            return spec.dtype(value)
        out = np.array(value, spec.dtype)
        if out.shape != spec.tail:
            raise TypeError(f'a kernel gave an output of shape {out.shape}, declared '
                            f'{spec.tail}')
        return out
    _require_form(value, spec)
    return _make(spec, [_one_item(v, s) for v, s in zip(value, spec)])


def _require_form(value, spec):
    """Refuse a kernel's output that is not the NamedTuple (or tuple) that apply was told."""
    if type(value) is not type(spec) or type(value) is tuple and len(value) != len(spec):
        raise TypeError(f'a kernel returned {type(value).__name__} of {len(value)} where '
                        f'apply was told {type(spec).__name__} of {len(spec)}')


def _make(spec, parts):
    """Return a tuple of spec's type (a NamedTuple's, or tuple) of the iterable parts."""
    return tuple.__new__(type(spec), parts)


def _leaves(value, spec):
    """Return the values at the Specs of ``spec``, in order, from an output of its form."""
    if type(spec) is Spec:
        return [value]
    _require_form(value, spec)
    return [leaf for v, s in zip(value, spec) for leaf in _leaves(v, s)]


def _rebuild(spec, leaves):
    """Return the form of ``spec`` filled with the values of the iterator ``leaves``."""
    if type(spec) is Spec:
        return next(leaves)
    return _make(spec, [_rebuild(s, leaves) for s in spec])


def _apply_to_batch(kernel, inputs, outputs, params, one=False):
    """Run apply's call as a batch (one: a single item run as a batch of one)."""
    arrays = [as_float_array(x, t, name) for x, t, name, _ in inputs]
    tails = [t for _, t, _, _ in inputs]
    if one:
        result = batch(kernel, [a[None] for a in arrays], tails, outputs, params)
        firsts = [x[0] if s.tail else s.dtype(x[0])
                  for x, s in zip(_leaves(result, outputs), _leaves(outputs, outputs))]
        return _rebuild(outputs, iter(firsts))
    checks = [(i, name) for i, (_, _, name, finite) in enumerate(inputs) if finite]
    return batch(kernel, arrays, tails, outputs, params, checks)


def batch(kernel, arrays, tails, outputs, params=(), checks=()):
    """
    Return the kernel on ARRAYS, chunk by chunk, over the broadcast batch of the arrays.

    outputs as apply's. checks: (index, name) of the arrays to refuse NaN/Inf in
    (require_finite's error, which names the first bad index), each chunk's entries tested
    while they are in cache.
    """
    batches = [a.shape[:a.ndim - len(t)] for a, t in zip(arrays, tails)]
    try:
        shape = np.broadcast_shapes(*batches)
    except ValueError:
        raise RotationError(f'batch shapes {" and ".join(map(str, batches))} do not broadcast'
                            ) from None
    flat = [np.broadcast_to(a, shape + t).reshape((-1,) + t) for a, t in zip(arrays, tails)]
    n = flat[0].shape[0]
    length = min(n, CHUNK)
    specs = _leaves(outputs, outputs)
    sizes = [math.prod(s.tail) for s in specs]
    outs = [np.empty((n, size), dtype=s.dtype) for size, s in zip(sizes, specs)]
    # One buffer per input and output for all chunks (a fresh one per chunk costs page faults).
    ins = [_rows(math.prod(t), length) if t else None for t in tails]
    buffers = [_rows(size, length, s.dtype) if size > 1 else None
               for size, s in zip(sizes, specs)]
    with np.errstate(divide='ignore', invalid='ignore', over='ignore'):
        for start in range(0, n, CHUNK):
            chunk = slice(start, start + CHUNK)
            entries = [_columns(f[chunk], t, b) for f, t, b in zip(flat, tails, ins)]
            for i, name in checks:
                if not np.isfinite(entries[i]).all():
                    require_finite(arrays[i], name)
            result = kernel(ARRAYS, *(nest(list(e), t) for e, t in zip(entries, tails)),
                            *params)
            for out, size, buffer, value, spec in zip(outs, sizes, buffers,
                                                      _leaves(result, outputs), specs):
                _write_columns(out[chunk], flatten(value, spec.tail), buffer)
    return _rebuild(outputs, iter([out.reshape(shape + s.tail) for out, s in zip(outs, specs)]))


def _rows(count, length, dtype=np.float64):
    """
    Return an empty (count, length) array whose rows are 64 bytes apart, not adjacent.

    NumPy may take an output that ends where an input begins, or begins where it ends, for
    an overlap and run arctan2 (and others) in its scalar loop instead of its SIMD one,
    which rounds differently: with rows apart, a chunk's results do not depend on which rows
    its buffers happened to get.
    """
    pad = 64 // np.dtype(dtype).itemsize
    return np.empty((count, length + pad), dtype)[:, :length]


def _columns(arr, tail, buffer):
    """
    Return the entries of a chunk (m,) + tail as the rows of a (size, m) array.

    A matrix's entries row-major, copied once, transposed, into ``buffer`` (size, ≥ m): an
    entry read straight from (m, 3, 3) is strided (one float in every 72 bytes), and a kernel
    reads each entry several times. A scalar's chunk is its only row, as it is.
    """
    if not tail:
        return arr[None]
    block = buffer[:, :arr.shape[0]]
    block[...] = arr.reshape(arr.shape[0], -1).T
    return block


def _write_columns(out, entries, buffer):
    """
    Write the flat entries of one output into its chunk out (m, size).

    Through ``buffer`` (size, ≥ m), the entries contiguous, and one transposing copy.
    """
    if len(entries) == 1:
        out[:, 0] = entries[0]
        return
    cols = buffer[:, :out.shape[0]]
    for k, entry in enumerate(entries):
        cols[k] = entry
    out[...] = cols.T


def nest(entries, tail):
    """Flat entries → a kernel's argument: the scalar, a list (vector) or a list of rows."""
    if not tail:
        return entries[0]
    if len(tail) == 1:
        return list(entries)
    return [list(entries[r * tail[1]:(r + 1) * tail[1]]) for r in range(tail[0])]


def flatten(value, tail):
    """Return a kernel's output → its entries as a flat list (a matrix row-major)."""
    rows = value if len(tail) == 2 else [value]
    if len(tail) == 2 and not all(type(row) in (list, tuple) for row in rows):
        raise TypeError(f'a kernel gave an output of shape {tail} without rows')
    entries = [x for row in rows for x in row] if tail else [value]
    if len(entries) != math.prod(tail) or any(type(x) in (list, tuple) for x in entries):
        raise TypeError(f'a kernel gave an output of another shape than {tail}')
    return entries


def _all_finite(values, rank):
    """Tell whether every float of a nested list (rank 0, 1 or 2) is finite."""
    if rank == 0:
        return math.isfinite(values)
    if rank == 1:
        return all(map(math.isfinite, values))
    return all(map(math.isfinite, chain.from_iterable(values)))


# -- pieces of kernels ----------------------------------------------------------------------

def dot(u, v):
    """u·v of two 3-vectors given as entry lists."""
    return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]


def cross(u, v):
    """Return u × v of two 3-vectors given as entry lists."""
    return [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]


def _rare(v, n2):
    """Where |v|² = n2 has overflowed or lost digits to underflow (v ≠ 0)."""
    nonzero = (v[0] != 0) | (v[1] != 0) | (v[2] != 0)
    return ((n2 < 1e-290) & nonzero) | (n2 > 1e290)


class _Scaled(NamedTuple):
    """A 3-vector v as largest = max |v_i| times vector = v / max |v_i|."""

    largest: Any
    vector: list


def _scaled(ops, v):
    """Write v as largest·vector, |vector|² in [1, 3] (safe to square; v as is for v = 0)."""
    big = ops.maximum(ops.maximum(ops.abs(v[0]), ops.abs(v[1])), ops.abs(v[2]))
    safe = ops.where(big > 0, big, 1.0)
    # (vi / big, not vi * (1 / big): 1 / big overflows for a tiny big)
    return _Scaled(largest=big, vector=[vi / safe for vi in v])


def _rescaled_norm(ops, v):
    """|v| = max |v_i|·|v / max |v_i||: inf only where |v| itself is beyond 1.8e308."""
    scaled = _scaled(ops, v)
    return scaled.largest * ops.sqrt(dot(scaled.vector, scaled.vector))


def norm(ops, v):
    """|v| of a 3-vector entry list, without overflow or underflow of |v|² for any finite v."""
    n2 = dot(v, v)
    if ops.rare(_rare(v, n2)):
        return _rescaled_norm(ops, v)
    return ops.sqrt(n2)


_LARGEST = sys.float_info.max


def unit(ops, v):
    """
    Unit(direction v/|v|, norm |v|) of a 3-vector entry list; (0, 0, 1) for the zero vector.

    Where |v|² overflows or underflows, v/|v| is taken from v scaled by max |v_i|: |v| itself
    may be inf (beyond 1.8e308) or a subnormal with few digits, the direction is exact.
    """
    n2 = dot(v, v)
    rare = _rare(v, n2)
    n = size = ops.sqrt(n2)
    if ops.rare(rare):
        scaled = _scaled(ops, v)
        m = ops.sqrt(dot(scaled.vector, scaled.vector))
        n = scaled.largest * m
        v = [ops.where(rare, s, vi) for s, vi in zip(scaled.vector, v)]
        size = ops.where(rare, m, n)
    zero = n == 0  # (then every v_i is ±0: v_i / 1 + 0.0 is +0.0; + 0.0 also makes −0.0 +0)
    safe = ops.where(zero, 1.0, size)
    return Unit(direction=[v[0] / safe + 0.0, v[1] / safe + 0.0,
                           ops.where(zero, 1.0, v[2] / safe)], norm=n)


def in_range(ops, values):
    """
    Tell where every entry of the flat list ``values`` is finite (±inf and NaN fail).

    Kernels return it beside results that can overflow float64 for finite inputs, and the
    caller refuses the flagged items (see _arrays.refuse_overflow).
    """
    ok = ops.abs(values[0]) <= _LARGEST
    for x in values[1:]:
        ok = ok & (ops.abs(x) <= _LARGEST)
    return ok


def linear_in_range(ops, linear, *vectors):
    """
    InRange(linear(*vectors), fits) of a function linear in its 3-vector entry lists.

    Its partial sums may overflow float64 where the result fits (R·b beyond 1.8e308 with a
    translation bringing it back): such items are computed again on the inputs scaled by 1/4
    and scaled back by 4 — exact in binary, and room enough for the few terms bounded by
    max|v_i| that a rigid motion sums. Items that fit at once keep their bits.
    """
    out = linear(*vectors)
    fits = in_range(ops, out)
    if ops.rare(ops.where(fits, False, True)):
        quarter = linear(*([0.25 * x for x in v] for v in vectors))
        out = [ops.where(fits, x, 4.0 * y) for x, y in zip(out, quarter)]
        fits = in_range(ops, out)
    return InRange(value=out, fits=fits)
