"""The one-item engine compiled: a kernel traced once into straight-line Python source.

A kernel (see _backend) is one formula, run by ``apply`` on Python floats for one item. Run
that way it pays, on every call, for each ``ops.*`` attribute look-up, helper call, list and
tuple it builds around the arithmetic. ``compile_single`` removes that cost without a second
copy of the formula: it runs the kernel once with *symbolic* entries, records every
arithmetic operation, comparison and ``ops.*`` call as one assignment, in the order the kernel
evaluates them, and compiles the recording into a Python function of the flat entries. The
function does the same float operations in the same order as ``kernel(FLOATS, ...)``, so its
results are the same bit for bit; it only leaves out the bookkeeping (and work whose result
nothing uses).

``ops.any`` is the kernels' only data-dependent control flow (the rare branches: rescaling a
huge or tiny vector, the near-π axis). The tracer follows each way through every ``ops.any``
— the kernel is traced once per path — and writes the paths as nested if/else blocks.

Anything the tracer cannot represent — ``if`` on a value, ``float(x)``, an ``ops`` function
that returns a container, too many paths — raises TraceError, and the kernel keeps running
on Python floats. The generated source is kept on the function (``__source__``) and shown in
tracebacks.
"""

from collections import Counter
import linecache
import math
import re
import struct

import numpy as np

MAX_PATHS = 64
"""More ways through a kernel's ops.any than this and it is not compiled."""


class TraceError(Exception):
    """The kernel does something the tracer cannot turn into straight-line code."""


class _Sym:
    """A value known only at run time: the variable that will hold it.

    ``real``: it is surely a float (an input entry, or arithmetic on floats), not a bool.
    """

    __slots__ = ('trace', 'name', 'real')
    __hash__ = None  # == builds an expression

    def __init__(self, trace, name, real):
        self.trace = trace
        self.name = name
        self.real = real

    def __bool__(self):
        raise TraceError('the kernel branches on a value (use ops.where / ops.any)')

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
    """True for a float (or int) that arithmetic keeps a float: a real symbol or a number."""
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
for _name, _symbol in (('and', '&'), ('or', '|'), ('xor', '^')):
    setattr(_Sym, f'__{_name}__', _operator(f'{{}} {_symbol} {{}}', logical=True))
    setattr(_Sym, f'__r{_name}__', _operator(f'{{}} {_symbol} {{}}', reflected=True, logical=True))
for _name, _symbol in (('lt', '<'), ('le', '<='), ('gt', '>'), ('ge', '>='), ('eq', '=='),
                       ('ne', '!=')):
    setattr(_Sym, f'__{_name}__', _operator(f'{{}} {_symbol} {{}}', logical=True))
_Sym.__neg__ = lambda self: self.trace.emit('-{}', self)
_Sym.__pos__ = lambda self: self.trace.emit('+{}', self)
_Sym.__invert__ = lambda self: self.trace.emit('~{}', self, real=False)
_Sym.__abs__ = lambda self: self.trace.emit('abs({})', self)


class _Trace:
    """One run of a kernel on symbols, following ``decisions`` at its ops.any branches."""

    def __init__(self, decisions, single=True):
        self.decisions = decisions
        self.single = single  # one item (ops.any is bool), else a batch (np.any)
        self.statements = []  # (name, source text, names it reads)
        self.branches = []  # (statement index, condition name, decision taken)
        self.constants = {}  # global name -> value, for what repr cannot write
        self.known = {}  # condition name -> the value a branch taken on it implies
        self.seen = {}  # source text -> its symbol: each expression is computed once

    def source(self, x):
        if type(x) is _Sym:
            if x.trace is not self:
                raise TraceError('a symbol from another trace')
            return x.name
        if isinstance(x, (bool, np.bool_)):
            return repr(bool(x))
        if type(x) is int or isinstance(x, float):  # (np.float64 from the batch engine)
            x = x if type(x) is int else float(x)
            if math.isfinite(x):
                return repr(x)
            name = f'_c{len(self.constants)}'  # inf, nan
            self.constants[name] = x
            return name
        raise TraceError(f'the kernel mixes a {type(x).__name__} into its arithmetic')

    def emit(self, template, *args, real=None):
        """Return a new variable holding template filled with args (real if all args are)."""
        text = template.format(*map(self.source, args))
        if text in self.seen:  # every operation is pure: reuse the earlier result
            return self.seen[text]
        name = f't{len(self.statements)}'
        self.statements.append((name, text, {a.name for a in args if type(a) is _Sym}))
        sym = self.seen[text] = _Sym(self, name, all(map(_real, args)) if real is None else real)
        return sym

    def branch(self, condition):
        """Take the next decision of this path at an ops.any.

        On one item ops.any is bool(condition), so a branch taken on a condition also
        settles every later where on it (``known``); on a batch it is np.any and does not.
        """
        name = self.source(condition)
        if name in self.known:
            return self.known[name]
        k = len(self.branches)
        taken = self.decisions[k] if k < len(self.decisions) else False
        self.branches.append((len(self.statements), name, taken))
        if self.single:
            self.known[name] = taken
        return taken


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
        real = _real(a) and _real(b)
        if self._trace.single:
            return self._trace.emit('{} if {} else {}', a, cond, b, real=real)
        return self._trace.emit('_op_where({}, {}, {})', cond, a, b, real=real)

    def any(self, cond):
        if type(cond) is not _Sym:
            return bool(cond)
        return self._trace.branch(cond)

    def __getattr__(self, name):
        fn = getattr(self._engine, name)
        trace = self._trace

        def recorded(*args):
            if not any(type(a) is _Sym for a in args):
                return fn(*args)  # every argument known: the engine's own result
            return trace.emit(f'_op_{name}(' + ', '.join(['{}'] * len(args)) + ')', *args)
        return recorded


def nest(entries, tail):
    """Flat entries → a kernel's argument: the scalar, a list (vector) or a list of rows."""
    if not tail:
        return entries[0]
    if len(tail) == 1:
        return list(entries)
    return [list(entries[r * tail[1]:(r + 1) * tail[1]]) for r in range(tail[0])]


def flatten(value, tail):
    """A kernel's output → its entries as a flat list (a matrix row-major)."""
    if not tail:
        return [value]
    if len(tail) == 1:
        return list(value)
    return [x for row in value for x in row]


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


def _run(kernel, engine, single, tails, outputs, decisions):
    """Trace kernel along decisions: (trace, flat symbolic outputs per output)."""
    trace = _Trace(decisions, single)
    args, start = [], 0
    for tail in tails:
        args.append(_symbols(trace, 'a', tail, start))
        start += math.prod(tail)
    result = kernel(_TraceOps(trace, engine), *args)
    if len(result) != len(outputs):
        raise TraceError(f'the kernel returns {len(result)} outputs, expected {len(outputs)}')
    flat = [_entries_of(r, t) for r, (t, _) in zip(result, outputs)]
    return trace, flat


def _all_paths(kernel, engine, single, tails, outputs):
    """Every way through the kernel's ops.any: a list of (trace, outputs)."""
    done, todo = [], [[]]
    while todo:
        trace, flat = _run(kernel, engine, single, tails, outputs, todo.pop())
        done.append((trace, flat))
        if len(done) > MAX_PATHS:
            raise TraceError(f'more than {MAX_PATHS} ways through the kernel')
        taken = [d for _, _, d in trace.branches]
        for k in range(len(trace.decisions), len(taken)):  # branches first met on this path
            todo.append(taken[:k] + [True])
    return done


def _live(trace, flat):
    """Names whose values the outputs or the branch conditions of this path need."""
    live = {x.name for out in flat for x in out if type(x) is _Sym}
    live.update(cond for _, cond, _ in trace.branches)
    for name, _, reads in reversed(trace.statements):
        if name in live:
            live |= reads
    return live


_PACK_CODES = {np.dtype(np.float64): 'd', np.dtype(np.bool_): '?'}


def _result_lines(values, outputs, names):
    """Statements that build the output arrays / scalars from their entries' source texts
    (``values``, one list per output) and return them."""
    lines, results = [], []
    for k, (text, (tail, dtype)) in enumerate(zip(values, outputs)):
        if not tail:
            results.append(f'_dt{k}({text[0]})')
            names[f'_dt{k}'] = dtype
            continue
        if dtype is float:  # plain Python floats: a flat tuple of the entries
            results.append(f'({", ".join(text)},)')
            continue
        code = _PACK_CODES.get(np.dtype(dtype))
        if code is None:
            raise TraceError(f'no packed output for dtype {dtype}')
        names[f'_pack{k}'] = struct.Struct(f'{len(text)}{code}').pack_into
        names[f'_shape{k}'] = tail
        names[f'_odt{k}'] = np.dtype(dtype)
        lines.append(f'o{k} = _empty(_shape{k}, _odt{k})')
        lines.append(f'_pack{k}(o{k}, 0, {", ".join(text)})')
        results.append(f'o{k}')
    lines.append(f'return ({", ".join(results)},)')
    return lines


_TEMPORARY = re.compile(r'\bt\d+\b')


def _fold(statements, tails, keep):
    """Fold each temporary read once in its block into the expression that reads it.

    statements: [(name, text)] of one straight-line block, in order; tails: the texts after
    them that read names (the branch condition, or the output entries); keep: names read
    below the block, which stay variables. Returns both rewritten. Every operation is pure,
    so computing a value where it is used instead of where it was defined changes no result;
    it only saves storing and loading a local.
    """
    uses = Counter(_TEMPORARY.findall(' '.join([t for _, t in statements] + tails)))
    folded, kept = {}, []

    def expand(text):
        return _TEMPORARY.sub(lambda m: folded.pop(m.group(), m.group()), text)

    for name, text in statements:
        text = expand(text)
        if uses[name] == 1 and name not in keep:
            folded[name] = f'({text})'
        else:
            kept.append((name, text))
    return kept, [expand(t) for t in tails]


def _block(paths, depth, start, outputs, names, indent):
    """Source lines of the paths that agree on their first ``depth`` decisions."""
    trace, flat = paths[0]
    live = set().union(*(_live(t, f) for t, f in paths))
    pad = '    ' * indent
    leaf = len(trace.branches) == depth
    end = len(trace.statements) if leaf else trace.branches[depth][0]
    statements = [(name, text) for name, text, _ in trace.statements[start:end] if name in live]
    if leaf:
        names.update(trace.constants)
        values = [[trace.source(x) for x in out] for out in flat]
        sizes = [len(v) for v in values]
        statements, texts = _fold(statements, [t for v in values for t in v], set())
        lines = [f'{pad}{name} = {text}' for name, text in statements]
        if not trace.single:  # a batch: every entry, flat, for apply to write
            return lines + [f'{pad}return ({", ".join(texts)},)']
        values = [texts[sum(sizes[:k]):sum(sizes[:k + 1])] for k in range(len(sizes))]
        return lines + [pad + line for line in _result_lines(values, outputs, names)]
    below = set()
    for t, f in paths:
        below.update(*(reads for _, _, reads in t.statements[end:]))
        below.update(x.name for out in f for x in out if type(x) is _Sym)
        below.update(cond for _, cond, _ in t.branches[depth + 1:])
    statements, (cond,) = _fold(statements, [trace.branches[depth][1]], below)
    lines = [f'{pad}{name} = {text}' for name, text in statements]
    ways = {True: [], False: []}
    for path in paths:
        ways[path[0].branches[depth][2]].append(path)
    lines.append(f'{pad}if {cond}:' if trace.single else f'{pad}if _op_any({cond}):')
    lines += _block(ways[True], depth + 1, end, outputs, names, indent + 1)
    lines.append(f'{pad}else:')
    lines += _block(ways[False], depth + 1, end, outputs, names, indent + 1)
    return lines


def _input_lines(index, tail, first):
    """Return the statements that read input ``index`` into a<first>, a<first + 1>, ...

    They take one item of ``tail``, or return None from the function (the caller's generic
    path then deals with the input).
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


def compile_single(kernel, floats, tails, outputs):
    """Compile ``kernel`` for one item: f(inputs) → tuple of outputs, or None.

    f takes apply's inputs, ((value, tail, name, finite), ...), with the trailing shapes
    ``tails``, and returns the outputs — arrays of the shapes of ``outputs`` ((tail, dtype)
    each), or dtype scalars for tail () — when every value is one item given as a float64
    ndarray of exactly its tail, a float (a scalar) or a tuple / list of floats (a vector),
    and holds no NaN/Inf. Otherwise it returns None and the caller takes the generic path,
    which coerces and checks (the NaN/Inf test is a quick sum that can also fire when the
    sum overflows, and never misses one). Raises TraceError when the kernel cannot be traced.
    """
    paths = _all_paths(kernel, floats, True, tails, outputs)
    names = {'_empty': np.empty, '_ndarray': np.ndarray, '_f64': np.dtype(np.float64),
             '_float64': np.float64, '_float': float}
    xs = ''.join(f'(x{i}, _, _, _), ' for i in range(len(tails)))
    body = [f'if len(inputs) != {len(tails)}:', '    return None', f'{xs}= inputs']
    count = 0
    for i, tail in enumerate(tails):
        body += _input_lines(i, tail, count)
        count += math.prod(tail)
    if count:
        body += [f'if ({" + ".join(f"a{i}" for i in range(count))}) * 0.0 != 0.0:',
                 '    return None']
    return _function('single', 'inputs', body, paths, kernel, floats, outputs, names,
                     'one item')


def compile_batch(kernel, arrays, tails, outputs):
    """Compile ``kernel`` for a chunk of items: f(*entries) → every output entry, flat.

    f takes the entries of the inputs (contiguous arrays of the chunk's items, a matrix's
    row-major) and returns those of the outputs, each an array or a constant, as
    kernel(arrays, ...) computes them (the same NumPy operations, less the ones whose result
    nothing uses, and x·1, x·(−1), repeated expressions: exact). Raises TraceError when the
    kernel cannot be traced.
    """
    paths = _all_paths(kernel, arrays, False, tails, outputs)
    params = ', '.join(f'a{i}' for i in range(sum(math.prod(t) for t in tails)))
    return _function('batch', params, [], paths, kernel, arrays, outputs, {}, 'a batch')


def _function(name, params, body, paths, kernel, engine, outputs, names, what):
    """Compile ``def name(params): body + the paths' code`` with the engine's functions."""
    for attr in dir(engine):
        if not attr.startswith('_'):
            names[f'_op_{attr}'] = getattr(engine, attr)
    label = getattr(kernel, '__qualname__', None) or getattr(
        getattr(kernel, 'func', None), '__qualname__', 'kernel')
    lines = [f'def {name}({params}):', f'    """{label}, traced: {what}, straight-line."""']
    lines += ['    ' + line for line in body] + _block(paths, 0, 0, outputs, names, 1)
    source = '\n'.join(lines) + '\n'
    filename = f'<rot_tools traced {label} {what} {id(kernel):x}>'
    exec(compile(source, filename, 'exec'), names)  # noqa: S102 - our own generated code
    linecache.cache[filename] = (len(source), None, source.splitlines(True), filename)
    function = names[name]
    function.__source__ = source
    return function
