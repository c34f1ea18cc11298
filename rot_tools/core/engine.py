"""
One formula, two engines: Python floats for a single item, NumPy chunks for a batch.

Every conversion in rot_tools is written once as a *kernel*: a function of an ops namespace
and of the entries of its inputs (a matrix as ``m[row][col]``, a vector as ``v[i]``, a scalar
as itself), returning the entries of its outputs, as scipy's ``_rotation_xp.py`` writes its
formulas against ``xp``. ``apply`` runs a kernel

- on a single item as ``kernel(FLOATS, ...)``: Python floats and the ``math`` module (a
  chain of small NumPy calls costs ~10× more per item than plain floats); or
- on a batch as ``kernel(ARRAYS, ...)``, chunk by chunk (CHUNK items whose entries are
  contiguous NumPy arrays), so that the temporaries stay small and in cache.

Kernels select between branches with ``ops.where`` (both sides are evaluated), so they must
not divide by zero on the branch that is thrown away: guard divisors with ``ops.where``.
Where a result can overflow float64 for finite inputs, the kernel returns an ``in_range``
flag beside it and the caller refuses the flagged items (floating-point warnings of the
batch engine are silenced). ``ops.rare(c)`` is the only data-dependent branch a kernel may
take (true when c holds for the item, or for any item of a chunk): work that an item or a
chunk without c skips — a huge or tiny vector rescaled, gimbal lock. doc/engine.md tells
how to add a conversion.
"""

from itertools import chain
import math
import sys
from types import SimpleNamespace

import numpy as np
from rot_tools.core._arrays import as_float_array, require_finite
from rot_tools.core.errors import FLOAT_ERRORS, RotationError

CHUNK = 8192

# An output's (trailing shape, dtype). dtype ``float`` (Python's) asks for plain Python
# floats for a single item (a float, or a flat tuple of the entries, row-major).
MATRIX = ((3, 3), np.float64)
VECTOR = ((3,), np.float64)
SCALAR = ((), np.float64)
FLAG = ((), np.bool_)


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


def apply(kernel, inputs, outputs, params=()):
    """
    Run ``kernel(ops, *entries, *params)`` on one item or on a batch.

    inputs: sequence of (value, trailing shape, name, finite): each value is made a float64
    array with that trailing shape (RotationError naming it otherwise) and, when ``finite``,
    refused if it holds NaN/Inf; their batch shapes broadcast. outputs: sequence of
    (trailing shape, dtype). params: fixed arguments after the entries (an Euler
    sequence's axes). Returns a tuple of arrays of shape batch + trailing shape (NumPy
    scalars for a single item, or Python floats where the dtype is ``float``).

    A single item runs on FLOATS; where Python's float arithmetic raises (x/0, sin(inf),
    sqrt(−1)) it is run as a batch of one instead, so that it gives the inf/NaN a batch
    gives.
    """
    values = []
    for x, tail, name, finite in inputs:
        if type(x) is np.ndarray and x.shape == tail and x.dtype == FLOAT64:
            v = x.tolist()  # (the usual one item: no array made, no shape to check)
        else:
            a = as_float_array(x, tail, name)
            if a.ndim != len(tail):
                return _apply_to_batch(kernel, inputs, outputs, params)
            v = a.tolist()
        if finite and not _all_finite(v, len(tail)):
            require_finite(np.asarray(v), name)
        values.append(v)
    try:
        result = kernel(FLOATS, *values, *params)
    except FLOAT_ERRORS:
        return _apply_to_batch(kernel, inputs, outputs, params, one=True)
    return tuple([_item(r, t, dt) for r, (t, dt) in zip(result, outputs)])


FLOAT64 = np.dtype(np.float64)


def plain_item(x, tail):
    """
    Return x's entries as Python floats (nested as a kernel takes them), or None.

    Not None only where x is one finite item of trailing shape ``tail`` ((n,) or (3, 3)): a
    float64 array, or for a vector a list or tuple of Python floats. The fast paths of the
    public functions run their kernel on FLOATS straight on it; anything else (a batch,
    another type, NaN/Inf) takes apply, which converts, refuses and raises as it always does.
    """
    if type(x) is np.ndarray and x.dtype is FLOAT64 and x.shape == tail:
        v = x.tolist()
    elif type(x) in (list, tuple) and len(tail) == 1 and len(x) == tail[0] and all(
            type(e) is float for e in x):
        v = list(x)
    else:
        return None
    # 0·Σ is 0 for finite entries, NaN where one is NaN/Inf or where the sum overflowed
    # (finite entries near 1.8e308: those then take apply, which tells them apart).
    total = sum(v) if len(tail) < 2 else sum(v[0] + v[1] + v[2])  # (a matrix: 3 rows)
    return v if 0.0 * total == 0.0 else None


def _apply_to_batch(kernel, inputs, outputs, params, one=False):
    """Run apply's call as a batch (one: a single item run as a batch of one, one_as_batch)."""
    arrays = [as_float_array(x, t, name) for x, t, name, _ in inputs]
    tails = [t for _, t, _, _ in inputs]
    if one:
        return one_as_batch(kernel, arrays, tails, outputs, params)
    checks = [(i, name) for i, (_, _, name, finite) in enumerate(inputs) if finite]
    return batch(kernel, arrays, tails, outputs, params, checks)


def _item(value, tail, dtype):
    """One item's output from a kernel's value: a NumPy scalar or array, or Python floats."""
    if not tail:
        return dtype(value)
    if dtype is float:  # plain floats: a flat tuple, row-major
        return tuple(flatten(value, tail))
    return np.array(value, dtype=dtype)


def one_as_batch(kernel, arrays, tails, outputs, params=()):
    """One item run as a batch of one, returned as one item (the types of the float path)."""
    out = []
    result = batch(kernel, [a[None] for a in arrays], tails, outputs, params)
    for r, (t, dt) in zip(result, outputs):
        if not t:
            out.append(dt(r[0]))
        elif dt is float:
            out.append(tuple(r[0].ravel().tolist()))
        else:
            out.append(r[0])
    return tuple(out)


def batch(kernel, arrays, tails, outputs, params=(), checks=()):
    """
    Return the kernel on ARRAYS, chunk by chunk, over the broadcast batch of the arrays.

    checks: (index, name) of the arrays to refuse NaN/Inf in (require_finite's error, which
    names the first bad index), each chunk's entries tested while they are in cache.
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
    sizes = [math.prod(t) for t, _ in outputs]
    outs = [np.empty((n, size), dtype=dt) for size, (_, dt) in zip(sizes, outputs)]
    # One buffer per input and output for all chunks (a fresh one per chunk costs page faults).
    ins = [_rows(math.prod(t), length) if t else None for t in tails]
    buffers = [_rows(size, length, dt) if size > 1 else None
               for size, (_, dt) in zip(sizes, outputs)]
    with np.errstate(divide='ignore', invalid='ignore', over='ignore'):
        for start in range(0, n, CHUNK):
            chunk = slice(start, start + CHUNK)
            entries = [_columns(f[chunk], t, b) for f, t, b in zip(flat, tails, ins)]
            for i, name in checks:
                if not np.isfinite(entries[i]).all():
                    require_finite(arrays[i], name)
            result = kernel(ARRAYS, *(nest(list(e), t) for e, t in zip(entries, tails)),
                            *params)
            values = [x for r, (t, _) in zip(result, outputs) for x in flatten(r, t)]
            k = 0
            for out, size, buffer in zip(outs, sizes, buffers):
                _write_columns(out[chunk], values[k:k + size], buffer)
                k += size
    return tuple(out.reshape(shape + t) for out, (t, _) in zip(outs, outputs))


def _rows(count, length, dtype=np.float64):
    """
    Return an empty (count, length) array whose rows are 64 bytes apart, not adjacent.

    NumPy 1.26 takes an output that ends where an input begins, or begins where it ends, for
    an overlap and runs arctan2 (and others) in its scalar loop instead of its SIMD one,
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
    if not tail:
        return [value]
    if len(tail) == 1:
        return list(value)
    return [x for row in value for x in row]


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


def _scaled(ops, v):
    """(max |v_i|, v / max |v_i|): the second has |·|² in [1, 3], safe to square."""
    big = ops.maximum(ops.maximum(ops.abs(v[0]), ops.abs(v[1])), ops.abs(v[2]))
    safe = ops.where(big > 0, big, 1.0)
    return big, [vi / safe for vi in v]  # (not vi * (1 / big): 1 / big overflows if tiny)


def _rescaled_norm(ops, v):
    """|v| = max |v_i|·|v / max |v_i||: inf only where |v| itself is beyond 1.8e308."""
    big, scaled = _scaled(ops, v)
    return big * ops.sqrt(dot(scaled, scaled))


def norm(ops, v):
    """|v| of a 3-vector entry list, without overflow or underflow of |v|² for any finite v."""
    n2 = dot(v, v)
    if ops.rare(_rare(v, n2)):
        return _rescaled_norm(ops, v)
    return ops.sqrt(n2)


def norm_in_range(ops, v):
    """
    (|v|, in_range flag) of a 3-vector entry list: |v| is 0 where the flag is false.

    Only a rescaled |v| can overflow (|v|² ≤ 1e290 off the rare path): the flag is True
    there, without a test.
    """
    n2 = dot(v, v)
    if ops.rare(_rare(v, n2)):
        n = _rescaled_norm(ops, v)
        fits = in_range(ops, [n])
        return ops.where(fits, n, 0.0), fits
    return ops.sqrt(n2), True


_LARGEST = sys.float_info.max


def unit(ops, v):
    """
    (v/|v|, |v|) of a 3-vector entry list, with (0, 0, 1) for the zero vector.

    Where |v|² overflows or underflows, v/|v| is taken from v scaled by max |v_i|: |v| itself
    may be inf (beyond 1.8e308) or a subnormal with few digits, the direction is exact.
    """
    n2 = dot(v, v)
    rare = _rare(v, n2)
    n = size = ops.sqrt(n2)
    if ops.rare(rare):
        big, scaled = _scaled(ops, v)
        m = ops.sqrt(dot(scaled, scaled))
        n = big * m
        v = [ops.where(rare, s, vi) for s, vi in zip(scaled, v)]
        size = ops.where(rare, m, n)
    zero = n == 0  # (then every v_i is ±0: v_i / 1 + 0.0 is +0.0; + 0.0 also makes −0.0 +0)
    safe = ops.where(zero, 1.0, size)
    return [v[0] / safe + 0.0, v[1] / safe + 0.0, ops.where(zero, 1.0, v[2] / safe)], n


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
    (linear(*vectors), in_range flag) of a function linear in its 3-vector entry lists.

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
    return out, fits
