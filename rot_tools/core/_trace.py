"""
The tracer: a kernel written out as straight-line Python source, ahead of time.

A kernel (see _backend) is one formula, run by ``apply`` on Python floats for one item. Run
that way it pays, on every call, for each ``ops.*`` attribute look-up, helper call, list and
tuple it builds around the arithmetic. ``function_source`` removes that cost without a second
copy of the formula: it runs the kernel once with *symbolic* entries, records every
arithmetic operation, comparison and ``ops.*`` call as one assignment, in the order the kernel
evaluates them, and writes the recording out as a Python function of apply's inputs. The
function does the same float operations in the same order as ``kernel(FLOATS, ...)``, so its
results are the same bit for bit; it only leaves out the bookkeeping (and work whose result
nothing uses). rot_tools.core._generate writes these functions into rot_tools/core/_generated.py;
nothing is traced or compiled while a program runs.

Branches: ``ops.rare(c)`` is the only one. The tracer follows the usual way (c false) and
writes ``if c: return None``, so that apply runs an item where c holds on the kernel itself
(the same bits, no compilation). Everything else is one straight line: ``ops.where`` becomes
``a if c else b``. Anything the tracer cannot represent — ``if`` on a value, ``float(x)``,
an ``ops`` function that returns a container — raises TraceError.
"""

from collections import Counter
import math
import re

import numpy as np
from rot_tools.core._backend import flatten, nest


class TraceError(Exception):
    """The kernel does something the tracer cannot turn into straight-line code."""


class _Sym:
    """
    A value known only at run time: the variable that will hold it.

    ``real``: it is surely a float (an input entry, or arithmetic on floats), not a bool.
    """

    __slots__ = ('trace', 'name', 'real')
    __hash__ = None  # == builds an expression

    def __init__(self, trace, name, real):
        self.trace = trace
        self.name = name
        self.real = real

    def __bool__(self):
        raise TraceError('the kernel branches on a value (use ops.where / ops.rare)')

    def _refuse(self, *args):
        raise TraceError('the kernel uses a value as a number, index or container')

    __float__ = __int__ = __index__ = __iter__ = __len__ = __getitem__ = _refuse
    __complex__ = __round__ = __trunc__ = __floor__ = __ceil__ = _refuse

    def __mul__(self, other):
        # x·1 = x and x·(−1) = −x exactly in IEEE arithmetic (kernels multiply by signs ±1)
        if self.real and type(other) is float and abs(other) == 1.0:
            return self if other == 1.0 else self.trace.emit('-{}', self)
        return self.trace.emit('{} * {}', self, other)

    def __rmul__(self, other):
        if self.real and type(other) is float and abs(other) == 1.0:
            return self if other == 1.0 else self.trace.emit('-{}', self)
        return self.trace.emit('{} * {}', other, self)


def _real(x):
    """Tell whether x is a float (or int) that arithmetic keeps a float."""
    if type(x) is _Sym:
        return x.real
    return type(x) is int or isinstance(x, float)


def _operator(template, reflected=False, logical=False):
    real = False if logical else None
    if reflected:
        return lambda self, other: self.trace.emit(template, other, self, real=real)
    return lambda self, other: self.trace.emit(template, self, other, real=real)


for _name, _symbol in (('add', '+'), ('sub', '-'), ('truediv', '/'), ('floordiv', '//'),
                       ('mod', '%'), ('pow', '**')):
    setattr(_Sym, f'__{_name}__', _operator(f'{{}} {_symbol} {{}}'))
    setattr(_Sym, f'__r{_name}__', _operator(f'{{}} {_symbol} {{}}', reflected=True))


def _condition(word, symbol, reflected=False):
    """
    Combine conditions with ``and`` / ``or``.

    ``a & b`` / ``a | b`` of conditions, written ``a and b`` / ``a or b``: on the bools of
    one item the same value, and the right side is skipped when the left decides (a guard's
    ``rare & nonzero`` costs one comparison on an ordinary item).
    """
    def op(self, other):
        a, b = (other, self) if reflected else (self, other)
        template = f'{{}} {word} {{}}' if not (_real(a) or _real(b)) else f'{{}} {symbol} {{}}'
        return self.trace.emit(template, a, b, real=False)
    return op


for _name, _word, _symbol in (('and', 'and', '&'), ('or', 'or', '|')):
    setattr(_Sym, f'__{_name}__', _condition(_word, _symbol))
    setattr(_Sym, f'__r{_name}__', _condition(_word, _symbol, reflected=True))
_Sym.__xor__ = _operator('{} ^ {}', logical=True)
_Sym.__rxor__ = _operator('{} ^ {}', reflected=True, logical=True)
for _name, _symbol in (('lt', '<'), ('le', '<='), ('gt', '>'), ('ge', '>='), ('eq', '=='),
                       ('ne', '!=')):
    setattr(_Sym, f'__{_name}__', _operator(f'{{}} {_symbol} {{}}', logical=True))
_Sym.__neg__ = lambda self: self.trace.emit('-{}', self)
_Sym.__pos__ = lambda self: self.trace.emit('+{}', self)
_Sym.__invert__ = lambda self: self.trace.emit('~{}', self, real=False)
_Sym.__abs__ = lambda self: self.trace.emit('abs({})', self)

_GUARD = None
"""The name of a statement that is a guard (``if cond: return None``), not an assignment."""

WHERE = '{} if {} else {}'
"""The template of ops.where(c, a, b) (arguments a, c, b); rot_tools.core._trace_batch reads it."""
PICKS = {'maximum': '{} if {} >= {} or {} != {} else {}',  # (arguments a, a, b, a, a, b)
         'minimum': '{} if {} <= {} or {} != {} else {}'}
"""The templates of ops.maximum and ops.minimum as the float engine computes them."""


class _Trace:
    """One run of a kernel on symbols: its statements, in the order it evaluates them."""

    def __init__(self):
        self.statements = []  # (name or _GUARD, source text, names it reads)
        self.known = {}  # condition name -> False once a guard has left its items out
        self.seen = {}  # source text -> its symbol: each expression is computed once
        self.forms = {}  # name -> (template, its arguments' source texts): for other writers

    def source(self, x):
        if type(x) is _Sym:
            if x.trace is not self:
                raise TraceError('a symbol from another trace')
            return x.name
        if isinstance(x, (bool, np.bool_)):
            return repr(bool(x))
        if type(x) is int or isinstance(x, float):
            x = x if type(x) is int else float(x)
            if math.isfinite(x):
                return repr(x)
            return '_nan' if math.isnan(x) else '_inf' if x > 0 else '(-_inf)'
        raise TraceError(f'the kernel mixes a {type(x).__name__} into its arithmetic')

    def emit(self, template, *args, real=None):
        """Return a new variable holding template filled with args (real if all args are)."""
        sources = [self.source(a) for a in args]
        text = template.format(*sources)
        if text in self.seen:  # every operation is pure: reuse the earlier result
            return self.seen[text]
        name = f't{len(self.statements)}'
        self.statements.append((name, text, {a.name for a in args if type(a) is _Sym}))
        self.forms[name] = (template, sources)
        sym = self.seen[text] = _Sym(self, name, all(map(_real, args)) if real is None else real)
        return sym

    def guard(self, condition):
        """
        Return False, after a guard.

        Return False, after a guard that leaves the items where ``condition`` holds to
        the kernel itself (ops.rare).

        Past the guard the condition is known to be false, so later wheres on it are
        settled (on one item ops.rare is bool(condition)).
        """
        name = self.source(condition)
        if name not in self.known:
            self.statements.append((_GUARD, name, {name}))
            self.known[name] = False
        return False


class _TraceOps:
    """The ops namespace of a trace: an engine's functions, recorded instead of called."""

    def __init__(self, trace, engine):
        self._trace = trace
        self._engine = engine

    def where(self, cond, a, b):
        if type(cond) is not _Sym:
            return a if cond else b  # known now: as the engines do it
        known = self._trace.known.get(cond.name)
        if known is not None:  # inside a branch taken on cond
            return a if known else b
        if a is b:
            return a
        return self._trace.emit(WHERE, a, cond, b, real=_real(a) and _real(b))

    def maximum(self, a, b):  # written out as the float engine computes them
        return self._pick(a, b, 'maximum', self._engine.maximum)

    def minimum(self, a, b):
        return self._pick(a, b, 'minimum', self._engine.minimum)

    def max_of(self, first, *rest):
        for x in rest:
            first = self.maximum(first, x)
        return first

    def _pick(self, a, b, name, fn):
        if type(a) is not _Sym and type(b) is not _Sym:
            return fn(a, b)
        return self._trace.emit(PICKS[name], a, a, b, a, a, b, real=_real(a) and _real(b))

    def rare(self, cond):
        if type(cond) is not _Sym:
            return bool(cond)
        return self._trace.guard(cond)

    any = rare  # (the older name of ops.rare)  # noqa: A003

    def __getattr__(self, name):
        fn = getattr(self._engine, name)
        trace = self._trace

        def recorded(*args):
            if not any(type(a) is _Sym for a in args):
                return fn(*args)  # every argument known: the engine's own result
            return trace.emit(f'_op_{name}(' + ', '.join(['{}'] * len(args)) + ')', *args)
        return recorded


def _symbols(trace, prefix, tail, start):
    """Symbols prefix<start>, prefix<start + 1>, ... nested as a kernel takes them."""
    return nest([_Sym(trace, f'{prefix}{start + i}', True) for i in range(math.prod(tail))],
                tail)


def _entries_of(value, tail):
    """flatten(value, tail), refusing an output of another shape."""
    rows = [value] if len(tail) == 2 else []
    if (tail and len(value) != tail[0]) or any(len(row) != tail[1] for r in rows for row in r):
        raise TraceError(f'an output is not of shape {tail}')
    return flatten(value, tail)


def _run(kernel, engine, tails, outputs):
    """Trace kernel: (trace, flat symbolic outputs per output)."""
    trace = _Trace()
    args, start = [], 0
    for tail in tails:
        args.append(_symbols(trace, 'a', tail, start))
        start += math.prod(tail)
    result = kernel(_TraceOps(trace, engine), *args)
    if len(result) != len(outputs):
        raise TraceError(f'the kernel returns {len(result)} outputs, expected {len(outputs)}')
    flat = [_entries_of(r, t) for r, (t, _) in zip(result, outputs)]
    return trace, flat


def _live(trace, flat):
    """Names whose values the outputs or the guards need."""
    live = {x.name for out in flat for x in out if type(x) is _Sym}
    for name, _, reads in reversed(trace.statements):
        if name is _GUARD or name in live:
            live |= reads
    return live


DTYPE_NAMES = {float: '_float', np.float64: '_float64', np.bool_: '_bool'}
"""The names under which the generated module knows each output dtype (see PRELUDE)."""
_ARRAY_DTYPES = {np.dtype(np.float64): ('d', '_f64'), np.dtype(np.bool_): ('?', '_b1')}


def _result_lines(values, outputs, packers):
    """
    Write the statements that build and return the outputs.

    Statements that build the output arrays / scalars from their entries' source texts
    (``values``, one list per output) and return them; packers collects the struct formats
    (e.g. '9d') whose pack_into the module must define.
    """
    lines, results = [], []
    for k, (text, (tail, dtype)) in enumerate(zip(values, outputs)):
        if not tail:
            if dtype not in DTYPE_NAMES:
                raise TraceError(f'no scalar output for dtype {dtype}')
            if dtype is np.bool_:  # (NumPy's two bools are singletons: np.bool_(c) is one)
                known = {'True': '_True', 'False': '_False'}.get(text[0])
                results.append(known or f'(_True if {text[0]} else _False)')
            else:
                results.append(f'{DTYPE_NAMES[dtype]}({text[0]})')
            continue
        if dtype is float:  # plain Python floats: a flat tuple of the entries
            results.append(f'({", ".join(text)},)')
            continue
        code = _ARRAY_DTYPES.get(np.dtype(dtype))
        if code is None:
            raise TraceError(f'no packed output for dtype {dtype}')
        fmt = f'{len(text)}{code[0]}'
        packers.add(fmt)
        dtype_arg = '' if code[1] == '_f64' else f', {code[1]}'  # float64: np.empty's default
        lines.append(f'o{k} = _empty({tail!r}{dtype_arg})')
        lines.append(f'_pack_{fmt}(o{k}, 0, {", ".join(text)})')
        results.append(f'o{k}')
    lines.append(f'return ({", ".join(results)},)')
    return lines


_TEMPORARY = re.compile(r'\bt\d+\b')


def _fold(statements, tails):
    """
    Fold each temporary read once into the expression that reads it.

    statements: [(name, text)] in order (guards included, never folded); tails: the texts
    after them that read names (the output entries). Returns both rewritten. Every
    operation is pure, so computing a value where it is used instead of where it was
    defined changes no result; it only saves storing and loading a local. (A value defined
    before a guard and folded below it is then not computed for the items the guard
    leaves out, which changes nothing either.)
    """
    uses = Counter(_TEMPORARY.findall(' '.join([t for _, t in statements] + tails)))
    folded, kept = {}, []

    def expand(text):
        return _TEMPORARY.sub(lambda m: folded.pop(m.group(), m.group()), text)

    for name, text in statements:
        text = expand(text)
        if name is not _GUARD and uses[name] == 1:
            folded[name] = f'({text})'
        else:
            kept.append((name, text))
    return kept, [expand(t) for t in tails]


def _statement_lines(statements, pad):
    """Write assignments, and guards written ``if cond: return None``."""
    lines = []
    for name, text in statements:
        if name is _GUARD:
            lines += [f'{pad}if {text}:', f'{pad}    return None  # rare: apply runs the kernel']
        else:
            lines.append(f'{pad}{name} = {text}')
    return lines


def _body(trace, flat, outputs, packers):
    """Source lines of the traced kernel: its live statements, then the outputs built."""
    live = _live(trace, flat)
    statements = [(name, text) for name, text, _ in trace.statements
                  if name is _GUARD or name in live]
    values = [[trace.source(x) for x in out] for out in flat]
    sizes = [len(v) for v in values]
    statements, texts = _fold(statements, [t for v in values for t in v])
    values = [texts[sum(sizes[:k]):sum(sizes[:k + 1])] for k in range(len(sizes))]
    return _statement_lines(statements, '        ') + [
        '        ' + line for line in _result_lines(values, outputs, packers)]


def _input_lines(index, tail, first):
    """
    Return the statements that read input ``index`` into a<first>, a<first + 1>, ...

    They take one item of ``tail``, or return None from the function (apply's generic path
    then deals with the input).
    """
    x, n = f'x{index}', math.prod(tail)
    names = [f'a{first + i}' for i in range(n)]
    if not tail:
        return [f'if type({x}) is float:', f'    {names[0]} = {x}',
                f'elif type({x}) is _float64:', f'    {names[0]} = _float({x})',
                'else:', '    return None']
    array = f'type({x}) is _ndarray and {x}.dtype is _f64 and {x}.shape == {tail!r}'
    if len(tail) == 2:
        rows = ', '.join('(' + ', '.join(names[r * tail[1]:(r + 1) * tail[1]]) + ',)'
                         for r in range(tail[0]))
        return [f'if not ({array}):', '    return None', f'{rows}, = {x}.tolist()']
    entries = ', '.join(names) + ','
    floats = ' and '.join(f'type({a}) is float' for a in names)
    return [f'if {array}:', f'    {entries} = {x}.tolist()',
            f'elif (type({x}) is tuple or type({x}) is list) and len({x}) == {n}:',
            f'    {entries} = {x}', f'    if not ({floats}):', '        return None',
            'else:', '    return None']


def function_source(name, kernel, floats, tails, outputs, packers):
    """
    Source of ``def name(x0, x1, ...)``: the kernel for one item, straight-line.

    The function takes one value per input, with the trailing shapes ``tails``, and returns
    the outputs — arrays of the shapes of ``outputs`` ((tail, dtype) each), dtype scalars for
    tail (), flat tuples of floats for dtype float — when every value is one item given as a
    float64 ndarray of exactly its tail, a float (a scalar) or a tuple / list of floats (a
    vector), and holds no NaN/Inf, no ops.rare condition holds and Python's float arithmetic
    raises nothing (x/0, sqrt(−1): NumPy gives inf/NaN there). Otherwise it returns None and
    the caller takes apply's generic path, which coerces, checks and runs the kernel itself
    (the NaN/Inf test is a quick sum that can also fire when the sum overflows, and never
    misses one). The names it uses besides its own are PRELUDE's, ``_op_<name>`` for each
    function of ``floats``, and ``_pack_<fmt>`` for each format added to ``packers``.
    Raises TraceError when the kernel cannot be traced.
    """
    trace, flat = _run(kernel, floats, tails, outputs)
    body, count = [], 0
    for i, tail in enumerate(tails):
        body += _input_lines(i, tail, count)
        count += math.prod(tail)
    if count:
        body += [f'if ({" + ".join(f"a{i}" for i in range(count))}) * 0.0 != 0.0:',
                 '    return None']
    lines = [f'def {name}({", ".join(f"x{i}" for i in range(len(tails)))}):']
    lines += ['    ' + line for line in body + ['try:']] + _body(trace, flat, outputs, packers)
    lines += ['    except _FLOAT_ERRORS:', '        return None']
    return '\n'.join(lines) + '\n'


PRELUDE = """\
import math as _math
from struct import Struct as _Struct

import numpy as _np
from rot_tools.core.errors import FLOAT_ERRORS as _FLOAT_ERRORS

_empty, _ndarray = _np.empty, _np.ndarray
_f64, _b1 = _np.dtype(_np.float64), _np.dtype(_np.bool_)
_float, _float64, _bool = float, _np.float64, _np.bool_
_inf, _nan = _math.inf, _math.nan
_True, _False = _np.True_, _np.False_
"""
"""The names every generated function may use, besides _op_* and _pack_*."""


def op_lines(floats):
    """Write module lines binding ``_op_<name>`` to each function of the float engine."""
    lines = []
    for attr in sorted(dir(floats)):
        if attr.startswith('_') or attr in vars(_TraceOps):
            continue  # (written out as Python by the tracer: where, rare, maximum, ...)
        fn = getattr(floats, attr)
        module = getattr(fn, '__module__', None)
        if module == 'math':
            lines.append(f'_op_{attr} = _math.{fn.__name__}')
        elif module == 'builtins':
            lines.append(f'_op_{attr} = {fn.__name__}')
        else:
            raise TraceError(f'ops.{attr} of the float engine is neither math nor builtin')
    return lines


def packer_lines(packers):
    """Write module lines binding ``_pack_<fmt>`` for each struct format in packers."""
    return [f'_pack_{fmt} = _Struct({fmt!r}).pack_into' for fmt in sorted(packers)]


def compile_kernel(kernel, floats, tails, outputs):
    """
    Return the function of function_source, compiled in a namespace of its own.

    Return the function of function_source, compiled in a namespace of its own (for tests and
    for trying a kernel out; rot_tools itself only runs rot_tools/core/_generated.py).
    """
    packers = set()
    body = function_source('traced', kernel, floats, tails, outputs, packers)
    source = '\n'.join([PRELUDE, *op_lines(floats), *packer_lines(packers), '', body])
    names = {}
    exec(compile(source, '<rot_tools.core._trace.compile_kernel>', 'exec'), names)  # noqa: S102
    function = names['traced']
    function.__source__ = source
    return function
