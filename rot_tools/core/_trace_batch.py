"""
The tracer's second writer: a kernel written out as NumPy calls on one chunk, ahead of time.

Run on ARRAYS, a kernel makes a fresh array of the chunk's length for every operation, and a
chunk's temporaries together outgrow the processor's cache. ``chunk_source`` writes the trace
of rot_tools.core._trace (the kernel run once on symbols, here with ARRAYS' functions) as one
NumPy ufunc call per operation, each writing into a buffer the caller owns (its ``out``),
each buffer reused once its value is dead, and each output entry written straight into the
caller's row for it: the same ufuncs on the same values in the same order as
``kernel(ARRAYS, ...)``, so the same bits, in a few buffers that stay in cache.

``ops.where(c, a, b)`` stays NumPy's where (a fresh array: it has no ``out``); ops.maximum
and ops.minimum are their ufuncs; ``ops.rare(c)`` becomes ``if c.any(): return None``, and
the caller then runs that chunk on the kernel itself.
"""

import math

import numpy as np
from rot_tools.core._trace import _GUARD, _live, _run, PICKS, TraceError, WHERE

_UFUNC_OF_TEMPLATE = {
    '{} + {}': 'add', '{} - {}': 'subtract', '{} * {}': 'multiply', '{} / {}': 'divide',
    '{} // {}': 'floor_divide', '{} % {}': 'remainder', '{} ** {}': 'power',
    '-{}': 'negative', '+{}': 'positive', 'abs({})': 'absolute',
    '{} < {}': 'less', '{} <= {}': 'less_equal', '{} > {}': 'greater',
    '{} >= {}': 'greater_equal', '{} == {}': 'equal', '{} != {}': 'not_equal',
    # (conditions: the operators & | ^ ~ that ARRAYS applies to boolean arrays)
    '{} and {}': 'bitwise_and', '{} & {}': 'bitwise_and', '{} or {}': 'bitwise_or',
    '{} | {}': 'bitwise_or', '{} ^ {}': 'bitwise_xor', '~{}': 'invert',
}
_COMPARISONS = {'less', 'less_equal', 'greater', 'greater_equal', 'equal', 'not_equal'}
_LOGICAL = {'bitwise_and', 'bitwise_or', 'bitwise_xor', 'invert'}  # (of conditions only)
_UFUNC_OF_PICK = {template: name for name, template in PICKS.items()}  # maximum, minimum
_FLOAT, _BOOL = 'f', 'b'


def _kind_of_constant(text):
    """'b' for a bool constant, 'f' for a number (an int is a float to every ufunc here)."""
    return _BOOL if text in ('True', 'False') else _FLOAT


class _Writer:
    """The statements of one chunk function, with its buffers given out and taken back."""

    def __init__(self, arrays):
        self.arrays = arrays
        self.lines = []
        self.kind = {}  # source name -> 'f' or 'b'
        self.place = {}  # source name -> the variable holding it
        self.free = {_FLOAT: [], _BOOL: []}
        self.count = {_FLOAT: 0, _BOOL: 0}
        self.ufuncs = set()

    def kind_of(self, text):
        return self.kind[text] if text in self.kind else _kind_of_constant(text)

    def buffer(self, kind):
        if self.free[kind]:
            return self.free[kind].pop()
        self.count[kind] += 1
        return f'{kind}{self.count[kind] - 1}'

    def release(self, name):
        held = self.place.get(name, '')
        if held[:1] in (_FLOAT, _BOOL) and held[1:].isdigit():
            self.free[held[0]].append(held)

    def call(self, ufunc, args, target):
        self.ufuncs.add(ufunc)
        self.lines.append(f'_np_{ufunc}({", ".join(args)}, out={target})')

    def statement(self, name, template, sources, target):
        """Write one operation into ``target`` (None: a new buffer); (its kind, its place)."""
        args = [self.place.get(s, s) for s in sources]
        kinds = [self.kind_of(s) for s in sources]
        if template == WHERE:  # (a fresh array: NumPy's where has no out)
            a, cond, b = args
            kind = kinds[0]
            if kinds[2] != kind or kinds[1] != _BOOL:
                raise TraceError('ops.where on a condition and values of two kinds')
            self.lines.append(f'{name} = _where({cond}, {a}, {b})')
            return kind, name
        if template in _UFUNC_OF_PICK:
            ufunc, args, kinds = _UFUNC_OF_PICK[template], [args[0], args[2]], [kinds[0], kinds[2]]
        elif template.startswith('_op_'):
            op = template[4:template.index('(')]
            ufunc = getattr(self.arrays, op)
            if not isinstance(ufunc, np.ufunc):
                raise TraceError(f'ops.{op} is not a NumPy ufunc')
            ufunc = ufunc.__name__
        elif template in _UFUNC_OF_TEMPLATE:
            ufunc = _UFUNC_OF_TEMPLATE[template]
        else:
            raise TraceError(f'no ufunc for the operation {template!r}')
        wanted = _BOOL if ufunc in _LOGICAL else _FLOAT
        if any(k != wanted for k in kinds):
            raise TraceError(f'{ufunc} of a {"float" if wanted is _BOOL else "condition"}')
        kind = _BOOL if ufunc in _LOGICAL or ufunc in _COMPARISONS else _FLOAT
        target = target or self.buffer(kind)
        self.call(ufunc, args, target)
        return kind, target


def chunk_source(name, kernel, arrays, tails, outputs):
    """
    Return the source of ``def name(a, o, f, b)``, its numbers of buffers and its ufuncs.

    a: the chunk's input entries (contiguous arrays of m, inputs flattened row-major, in
    order); o: one array of m per output entry (outputs flattened likewise, of the outputs'
    dtypes); f, b: lists of float64 and bool arrays of m, as many as the numbers returned
    (floats, bools). The function fills o and returns True, or returns None where an
    ``ops.rare`` condition holds for an item of the chunk (o then half written).
    Returns (source, floats, bools, names of the ufuncs it calls); raises TraceError when the
    kernel cannot be written so.
    """
    trace, flat = _run(kernel, arrays, tails, outputs)
    live = _live(trace, flat)
    statements = [(n, text) for n, text, _ in trace.statements if n is _GUARD or n in live]
    entries = [trace.source(x) for out in flat for x in out]
    entry_kinds = []
    for tail, dtype in outputs:
        kind = {'f': _FLOAT, 'b': _BOOL}.get(np.dtype(dtype).kind)
        if kind is None:
            raise TraceError(f'an output of dtype {np.dtype(dtype)}')
        entry_kinds += [kind] * math.prod(tail)
    last, uses = {}, {}
    for i, (n, text) in enumerate(statements):
        for s in [text] if n is _GUARD else trace.forms[n][1]:
            last[s], uses[s] = i, uses.get(s, 0) + 1
    for s in entries:
        last[s], uses[s] = len(statements), uses.get(s, 0) + 1
    direct = {s: f'o{j}' for j, s in enumerate(entries)
              if uses[s] == 1 and s in trace.forms and trace.forms[s][0] != WHERE}
    w = _Writer(arrays)
    inputs = sum(math.prod(t) for t in tails)
    w.kind.update({f'a{i}': _FLOAT for i in range(inputs)})
    for i, (n, text) in enumerate(statements):
        if n is _GUARD:
            w.lines.append(f'if {w.place.get(text, text)}.any():')
            w.lines.append('    return None  # rare: the caller runs the chunk on the kernel')
            sources = [text]
        else:
            template, sources = trace.forms[n]
            w.kind[n], w.place[n] = w.statement(n, template, sources, direct.get(n))
        for s in dict.fromkeys(sources):  # (in order: the file must not vary by run)
            if last[s] == i:
                w.release(s)
    for j, (s, kind) in enumerate(zip(entries, entry_kinds)):
        if s in direct:
            if w.kind[s] != kind:
                raise TraceError(f'output entry {j} is of another kind than its output')
            continue
        w.lines.append(f'_copyto(o{j}, {w.place.get(s, s)})')
    head = [f'def {name}(a, o, f, b):']
    for var, prefix, number in (('a', 'a', inputs), ('o', 'o', len(entries)),
                                ('f', _FLOAT, w.count[_FLOAT]), ('b', _BOOL, w.count[_BOOL])):
        if number:
            head.append(f'    {", ".join(f"{prefix}{i}" for i in range(number))}, = {var}')
    body = ['    ' + line for line in w.lines + ['return True']]
    return '\n'.join(head + body) + '\n', w.count[_FLOAT], w.count[_BOOL], w.ufuncs


PRELUDE = """\
_copyto, _where = _np.copyto, _np.where
_float, _float64, _bool = float, _np.float64, _np.bool_
_inf, _nan = float('inf'), float('nan')
"""
"""The names every chunk function may use, besides _np_<ufunc>."""


def ufunc_lines(ufuncs):
    """Write module lines binding ``_np_<name>`` to each NumPy ufunc the chunk functions call."""
    return [f'_np_{u} = _np.{u}' for u in sorted(ufuncs)]
