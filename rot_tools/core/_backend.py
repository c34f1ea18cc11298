"""
One formula, two engines: Python floats for a single item, NumPy chunks for a batch.

Every conversion in rot_tools is written once as a *kernel*: a function of an ops namespace
and of the entries of its inputs (a matrix as ``m[row][col]``, a vector as ``v[i]``, a scalar
as itself), returning the entries of its outputs. ``apply`` runs a kernel

- on a single item with Python floats and the ``math`` module (a chain of small NumPy calls
  costs ~10× more per item than plain floats): as the kernel's function in
  rot_tools/core/_generated.py, straight-line code written from the kernel ahead of time by
  ``python -m rot_tools.core._generate`` (the same operations without the bookkeeping around
  them, results equal bit for bit), or as the kernel itself where there is none; or
- on a batch, in chunks of CHUNK items whose entries are contiguous NumPy arrays (each chunk
  transposed once on the way in and once on the way out): as the kernel's function in
  rot_tools/core/_generated_chunks.py, NumPy calls written from the kernel ahead of time into
  buffers reused chunk after chunk (the same ufuncs, so the same bits), or as the kernel
  itself on NumPy arrays where there is none. The temporaries stay in cache and the memory
  used beyond the inputs and outputs stays small.

Kernels select between branches with ``ops.where`` (both sides are evaluated), so they must
not divide by zero on the branch that is thrown away: guard divisors with ``ops.where``.
Where a result can overflow float64 for finite inputs, the kernel returns an ``in_range``
flag beside it and the caller refuses the flagged items (floating-point warnings of the
batch engine are silenced). ``ops.any(c)`` and ``ops.rare(c)`` are the only data-dependent
control flow a kernel may use (true when c holds for the item, or for any item of a chunk);
``ops.rare`` marks the unusual side — a huge or tiny vector rescaled, gimbal lock — which the
generated code leaves to the kernel itself. Python ``if`` on a value works on floats but
keeps the kernel from being generated. doc/engine.md tells the whole story.
"""

from collections import Counter
from functools import partial
from itertools import chain
import math
import sys

import numpy as np
from rot_tools.core._arrays import as_float_array, require_finite
from rot_tools.core._generated import CODE as GENERATED
from rot_tools.core._generated_chunks import CHUNKS as GENERATED_CHUNKS
from rot_tools.core.errors import FLOAT_ERRORS, RotationError

CHUNK = 8192

# An output's (trailing shape, dtype). Callers build their outputs from these and other
# module-level constants, so that apply's check of them against the generated code's is
# an identity check of each element.
MATRIX = ((3, 3), np.float64)
VECTOR = ((3,), np.float64)
SCALAR = ((), np.float64)
FLAG = ((), np.bool_)


class _FloatOps:
    """Scalar engine: Python floats."""

    atan2 = staticmethod(math.atan2)
    sqrt = staticmethod(math.sqrt)
    sin = staticmethod(math.sin)
    cos = staticmethod(math.cos)
    tan = staticmethod(math.tan)
    abs = staticmethod(abs)  # noqa: A003
    any = rare = staticmethod(bool)  # noqa: A003

    @staticmethod
    def maximum(a, b):  # NaN if either is NaN, as NumPy's (max(x, nan) is x)
        return a if a >= b or a != a else b

    @staticmethod
    def minimum(a, b):
        return a if a <= b or a != a else b

    @staticmethod
    def max_of(first, *rest):
        for x in rest:
            first = first if first >= x or first != first else x
        return first

    @staticmethod
    def where(cond, a, b):
        return a if cond else b


class _ArrayOps:
    """Batch engine: NumPy arrays (errors on the discarded branch of a where are silenced)."""

    atan2 = staticmethod(np.arctan2)
    sqrt = staticmethod(np.sqrt)
    sin = staticmethod(np.sin)
    cos = staticmethod(np.cos)
    tan = staticmethod(np.tan)
    abs = staticmethod(np.abs)  # noqa: A003
    any = rare = staticmethod(np.any)  # noqa: A003
    maximum = staticmethod(np.maximum)
    minimum = staticmethod(np.minimum)
    where = staticmethod(np.where)

    @staticmethod
    def max_of(first, *rest):
        for x in rest:
            first = np.maximum(first, x)
        return first


FLOATS = _FloatOps()
ARRAYS = _ArrayOps()


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


def apply(kernel, inputs, outputs):
    """
    Run ``kernel(ops, *entries)`` on one item or on a batch.

    inputs: sequence of (value, trailing shape, name, finite): each value is made a float64
    array with that trailing shape (RotationError naming it otherwise) and, when ``finite``,
    refused if it holds NaN/Inf; their batch shapes broadcast. outputs: sequence of
    (trailing shape, dtype). Returns a tuple of arrays of shape batch + trailing shape
    (NumPy scalars for a single item). dtype ``float`` (Python's) asks for plain Python
    floats for a single item — a float, or a flat tuple of the entries, row-major — and
    float64 arrays for a batch.

    One item runs the kernel's function in rot_tools/core/_generated.py when there is one for
    this kernel and these outputs (the same float operations as the kernel on FLOATS, so the
    same bits), else the kernel itself on FLOATS (counted in FALLBACKS). Where Python's float
    arithmetic raises (x/0, sin(inf), sqrt(−1)) the item is run as a batch of one, so that
    one item gives the inf/NaN a batch gives.
    """
    known = _CODE_OF.get(kernel)  # (outputs, function): equal at once where the caller's
    # outputs are made of the same constants (the identity of each element decides)
    one = known[1] if known is not None and known[0] == outputs else _find_code(kernel, outputs)
    if one is not None:  # (None back: not one plain item, NaN/Inf in it, or a rare case)
        count = len(inputs)  # (one or two values passed without a list built: ~0.2 µs)
        result = (one(inputs[0][0]) if count == 1 else
                  one(inputs[0][0], inputs[1][0]) if count == 2 else
                  one(*[value for value, _, _, _ in inputs]))
        if result is not None:
            return result
    return _generic(kernel, inputs, outputs)


def _generic(kernel, inputs, outputs):
    """Run apply's call without generated code: the kernel itself on FLOATS, or _batch."""
    # Plain loops: on one item the Python overhead here is a good part of the call.
    arrays, values = [], []
    for x, t, name, finite in inputs:
        a = as_float_array(x, t, name)
        arrays.append(a)
        if values is not None and a.ndim == len(t):
            v = a.tolist()
            if finite and not _all_finite(v, len(t)):
                require_finite(a, name)
            values.append(v)
        else:
            values = None
    tails = [t for _, t, _, _ in inputs]
    if values is not None:  # a single item: Python floats
        _count_fallback(kernel, tails, outputs)
        try:
            result = kernel(FLOATS, *values)
        except FLOAT_ERRORS:
            return _one_as_batch(kernel, arrays, tails, outputs)
        out = []
        for r, (t, dt) in zip(result, outputs):
            if not t:
                out.append(dt(r))
            elif dt is float:  # plain floats: a flat tuple, row-major
                out.append(tuple(flatten(r, t)))
            else:
                out.append(np.array(r, dtype=dt))
        return tuple(out)
    checks = [(i, name) for i, (_, _, name, finite) in enumerate(inputs) if finite]
    return _batch(kernel, arrays, tails, outputs, checks)


def _batch(kernel, arrays, tails, outputs, checks=()):
    """
    Return the kernel on ARRAYS, chunk by chunk, over the broadcast batch of the arrays.

    checks: (index, name) of the arrays to refuse NaN/Inf in (require_finite's error), each
    chunk's entries tested while they are in cache. A chunk runs the kernel's generated
    chunk function where there is one (_ChunkCode), else the kernel itself.
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
    code = _ChunkCode(kernel, outputs, length)
    with np.errstate(divide='ignore', invalid='ignore', over='ignore'):
        for start in range(0, n, CHUNK):
            chunk = slice(start, start + CHUNK)
            entries = [_columns(f[chunk], t, b) for f, t, b in zip(flat, tails, ins)]
            for i, name in checks:
                if not np.isfinite(entries[i]).all():
                    require_finite(arrays[i], name)
            if code.run(entries, outs, buffers, chunk):
                continue
            CHUNK_FALLBACKS[code.key] += 1
            result = kernel(ARRAYS, *(nest(list(e), t) for e, t in zip(entries, tails)))
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


class _ChunkCode:
    """
    A kernel's chunk function in rot_tools/core/_generated_chunks.py, and the buffers it works in.

    Made for one batch. ``run`` writes a chunk's outputs and returns True; it returns False
    where there is no such function for this kernel and these outputs, and where an
    ``ops.rare`` case in the chunk leaves the chunk to the kernel itself.
    """

    __slots__ = ('key', 'function', 'floats', 'bools')

    def __init__(self, kernel, outputs, length):
        self.key = kernel_key(kernel)
        code = GENERATED_CHUNKS.get(self.key)
        self.function = code[1] if code is not None and code[0] == list(outputs) else None
        if self.function is not None:
            self.floats, self.bools = _rows(code[2], length), _rows(code[3], length, np.bool_)

    def run(self, entries, outs, buffers, chunk):
        if self.function is None:
            return False
        m = entries[0].shape[1]
        targets = []
        for out, buffer in zip(outs, buffers):
            targets.extend([out[chunk, 0]] if buffer is None else buffer[:, :m])
        if not self.function([row for e in entries for row in e], targets,
                             list(self.floats[:, :m]), list(self.bools[:, :m])):
            return False
        for out, buffer in zip(outs, buffers):
            if buffer is not None:
                out[chunk] = buffer[:, :m].T
        return True


def _one_as_batch(kernel, arrays, tails, outputs):
    """One item run as a batch of one, returned as one item (the types of the float path)."""
    out = []
    for r, (t, dt) in zip(_batch(kernel, [a[None] for a in arrays], tails, outputs), outputs):
        if not t:
            out.append(dt(r[0]))
        elif dt is float:
            out.append(tuple(r[0].ravel().tolist()))
        else:
            out.append(r[0])
    return tuple(out)


_CODE_OF = {}
"""kernel object -> (outputs as last met, its generated function for them or None)."""

FALLBACKS = Counter()
"""kernel key -> one-item calls that ran the kernel itself on FLOATS (no generated function
for it, an input that is not one plain item, NaN/Inf, or an ops.rare case). The test that
every public kernel runs generated code on ordinary inputs reads it."""

CHUNK_FALLBACKS = Counter()
"""kernel key -> chunks of batches that ran on the kernel itself (no chunk code for it, or an
ops.rare case in the chunk). The test that public batches run chunk code reads it."""

RECORD = None
"""The generator's (rot_tools.core._generate): a dict it sets to collect kernel key ->
(kernel, tails, outputs) of every one-item call that runs on FLOATS."""


def kernel_key(kernel):
    """
    Return the name under which rot_tools/core/_generated.py lists a kernel object's function.

    ``module.qualname`` of a function, with the fixed arguments of a functools.partial in
    brackets; a kernel built by a helper (so3's checked kernels) carries its own
    ``rot_tools_key``, and a partial keeps its key there once made (~3 µs of reprs, which
    every batch would pay again).
    """
    key = getattr(kernel, 'rot_tools_key', None)
    if key is not None:
        return key
    if type(kernel) is partial:
        fixed = [repr(a) for a in kernel.args]
        fixed += [f'{k}={v!r}' for k, v in sorted(kernel.keywords.items())]
        kernel.rot_tools_key = key = f'{kernel_key(kernel.func)}[{", ".join(fixed)}]'
        return key
    return f'{kernel.__module__}.{kernel.__qualname__}'


def _find_code(kernel, outputs):
    """
    Return the generated function of a kernel for these outputs, or None.

    Remembered for a kernel the generated module lists (a fixed set); a kernel built per
    call (matrix_to_euler with another lock_tol) is looked up again, not kept for ever.
    """
    code = GENERATED.get(kernel_key(kernel))
    if code is None:
        return None
    one = code[1] if code[0] == list(outputs) else None
    _CODE_OF[kernel] = (outputs, one)  # (no caller changes its outputs after the call)
    return one


def _no_code(*values):
    """Take no item: the one-item function of a kernel with no generated code."""
    return None


class Conversion:
    """
    A kernel with its inputs' checks and its outputs given once: apply's arguments, bound.

    inputs: [(trailing shape, name, finite), ...]. ``conversion.one(*values)`` is the
    kernel's generated function alone: the outputs for one plain item, or None; then
    ``conversion(*values)`` takes apply's generic path (the kernel itself on one item, or a
    batch) without trying the generated function again. A public function writes
    ``c.one(x) or c(x)``: its usual item runs the generated code with nothing around it.
    """

    __slots__ = ('kernel', 'inputs', 'outputs', 'one')

    def __init__(self, kernel, inputs, outputs):
        self.kernel, self.inputs, self.outputs = kernel, inputs, outputs
        self.bind()
        _CONVERSIONS.append(self)

    def bind(self):
        """Look the generated function up (again: the generator records with none)."""
        self.one = _find_code(self.kernel, self.outputs) or _no_code

    def __call__(self, *values):
        return _generic(self.kernel, [(v, *i) for v, i in zip(values, self.inputs)],
                        self.outputs)


_CONVERSIONS = []


def bind_conversions():
    """Bind every Conversion made so far to the generated code as GENERATED now holds it."""
    for conversion in _CONVERSIONS:
        conversion.bind()


def _count_fallback(kernel, tails, outputs):
    key = kernel_key(kernel)
    FALLBACKS[key] += 1
    if RECORD is not None and key not in RECORD:
        RECORD[key] = (kernel, list(tails), list(outputs))


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
