"""The two engines of rot_tools._backend and the compiled one-item engine of rot_tools._trace.

The compiled function of a kernel must give what the kernel gives on Python floats, bit for
bit, on every path through it (rescaled tiny/huge vectors, the near-π axis, gimbal lock),
and the same error for the same bad input. Each public one-item conversion is run twice on
the same adversarial items: once forced onto Python floats, once forced onto compiled code.
"""

import math
import re

import math_helpers as h
import numpy as np
import pytest
import rot_tools as rt
from rot_tools import _backend
from rot_tools._trace import compile_single, TraceError

SEQUENCES = ('ZYX', 'xyz', 'ZXZ', 'yxy', 'XZY', 'zyz')


def _rotations():
    """Rotations on every path: random, angle 0, tiny, near and at π, gimbal lock."""
    rng = np.random.default_rng(11)
    axes = rng.normal(size=(8, 3))
    axes /= np.linalg.norm(axes, axis=1)[:, None]
    angles = [0.0, 1e-300, 1e-15, 1e-8, 0.3, 1.9, h.PI - 1e-7, h.PI - 1e-12, h.PI]
    out = [rt.axis_angle_to_matrix(a, t) for a in axes for t in angles]
    out += [rt.axis_angle_to_matrix(e, t) for e in np.eye(3) for t in (h.PI, h.PI / 2, 2.0)]
    for seq in ('ZYX', 'ZXZ'):
        lock = h.singular_values(seq)
        for mid in (lock[0], lock[1], lock[1] - 1e-9, lock[1] - 1e-5):
            out.append(rt.euler_to_matrix([0.4, mid, -1.1], seq))
    return [np.array(R) for R in out]


ROTATIONS = _rotations()
VECTORS = [np.array(v, dtype=float) for v in (
    [0.0, 0.0, 0.0], [0.3, -0.2, 0.9], [1e-300, 0.0, 0.0], [0.0, 5e-324, 0.0],
    [1e300, -1e300, 1e299], [h.PI, 0.0, 0.0], [0.0, -h.PI, 0.0], [1e-9, 2e-9, -3e-9],
    [7.0, 8.0, -9.0], [-1.7e308, -1.7e308, 0.0], [1.7e308, 0.0, -1.7e308])]
BAD = [np.array(v) for v in ([np.nan, 0.0, 0.0], [0.0, np.inf, 0.0], [0.0, 0.0, -np.inf])]


def _calls():
    """(label, function of no argument): every public one-item conversion on every item."""
    calls = []
    for i, R in enumerate(ROTATIONS):
        b = VECTORS[i % len(VECTORS)]
        calls += [
            (f'axis_angle {i}', lambda R=R: rt.matrix_to_axis_angle(R)),
            (f'rotvec {i}', lambda R=R: rt.matrix_to_rotvec(R)),
            (f'quaternion {i}', lambda R=R: rt.matrix_to_quaternion(R)),
            (f'validate {i}', lambda R=R: rt.validate_rotation(R)),
            (f'is_rotation {i}', lambda R=R: rt.is_rotation(R)),
            (f'screw {i}', lambda R=R, b=b: rt.screw_from_transform(R, b)),
            (f'screw_log {i}', lambda R=R, b=b: rt.screw_log(R, b)),
            (f'unchecked screw {i}', lambda R=R, b=b: rt.screw_log(R, b, check=False)),
            (f'points {i}', lambda R=R, b=b: rt.transform_points(R, b, b[::-1])),
            (f'compose {i}', lambda R=R, b=b: rt.compose_transforms(R, b, R.T, -b)),
            (f'invert {i}', lambda R=R, b=b: rt.invert_transform(R, b)),
            (f'homogeneous {i}', lambda R=R, b=b: rt.homogeneous_to_transform(
                rt.transform_to_homogeneous(R, b))),
            (f'frame {i}', lambda R=R: rt.frame_to_matrix(R[:, 0], R[:, 1], R[:, 2]))]
        calls += [(f'{seq} {i}', lambda R=R, seq=seq: rt.matrix_to_euler(R, seq))
                  for seq in SEQUENCES]
        calls += [(f'decompose {seq} {i}', lambda R=R, b=b, seq=seq: rt.decompose(R, b, seq))
                  for seq in SEQUENCES[:2]]
    for i, v in enumerate(VECTORS + BAD):
        calls += [
            (f'rotvec_to_matrix {i}', lambda v=v: rt.rotvec_to_matrix(v)),
            (f'axis_angle_to_matrix {i}', lambda v=v: rt.axis_angle_to_matrix(v, 0.7)),
            (f'zero angle {i}', lambda v=v: rt.axis_angle_to_matrix(v, 0.0)),
            (f'quaternion_to_matrix {i}', lambda v=v: rt.quaternion_to_matrix([*v, 0.5])),
            (f'screw_exp {i}', lambda v=v: rt.screw_exp(np.concatenate([v, v[::-1]]))),
            (f'screw_exp pure {i}', lambda v=v: rt.screw_exp(np.concatenate([np.zeros(3), v]))),
            (f'transform_from_screw {i}',
             lambda v=v: rt.transform_from_screw([0.0, 0.6, 0.8], v, 1.3, -0.4))]
        calls += [(f'euler {seq} {i}', lambda v=v, seq=seq: rt.euler_to_matrix(v, seq))
                  for seq in SEQUENCES]
    for i, R in enumerate(ROTATIONS[:3]):  # NaN/Inf in R: refused, or NaN out unchecked
        for bad in (np.nan, np.inf):
            S = R.copy()
            S[1, 2] = bad
            calls += [(f'bad R {i} {bad}', lambda S=S: rt.matrix_to_rotvec(S)),
                      (f'bad R unchecked {i} {bad}',
                       lambda S=S: rt.matrix_to_axis_angle(S, check=False)),
                      (f'bad R is_rotation {i} {bad}', lambda S=S: rt.is_rotation(S))]
    return calls


def _run(call):
    """The call's result, or the type and text of the error it raised."""
    try:
        return call()
    except Exception as exc:  # compared below: the same error from both engines
        return (type(exc), str(exc))


def _bits(x):
    """Every float of a (nested) result as its IEEE bits, NaN sign aside; other values as is."""
    if isinstance(x, tuple):
        return tuple(_bits(v) for v in x)
    if isinstance(x, np.ndarray) or isinstance(x, np.generic):
        a = np.asarray(x)
        if a.dtype == np.float64:
            a = np.where(np.isnan(a), np.nan, a)  # (−x and −1·x differ only in NaN's sign)
            return (a.shape, a.tobytes())
        return (a.shape, a.dtype.str, a.tobytes())
    if isinstance(x, float):
        return _bits(np.float64(x))
    return x


@pytest.fixture
def engine(monkeypatch):
    """engine('floats') runs one-item calls on Python floats, engine('compiled') compiled."""
    def use(name):
        monkeypatch.undo()
        if name == 'floats':  # compiled code is looked up under another name: never found
            monkeypatch.setattr(_backend, '_COMPILED', '_rot_tools_test_no_code')
            monkeypatch.setattr(_backend, 'HOT_AFTER', 10**9)
        else:  # compiled on the first call (which itself runs on floats)
            monkeypatch.setattr(_backend, 'HOT_AFTER', 0)
    return use


def _compiled_run(calls):
    """Each call's result once its kernel is compiled (a first run compiles it)."""
    for call in calls:
        _run(call)
    return [_run(call) for call in calls]


def test_compiled_one_item_engine_matches_python_floats_bit_for_bit(engine):
    calls = _calls()
    engine('floats')
    floats = [_bits(_run(call)) for _, call in calls]
    engine('compiled')
    compiled = [_bits(r) for r in _compiled_run([call for _, call in calls])]
    differ = [label for (label, _), a, b in zip(calls, floats, compiled) if a != b]
    assert not differ, f'{len(differ)} of {len(calls)} differ, e.g. {differ[:5]}'
    errors = sum(isinstance(r, tuple) and len(r) == 2 and r[0] is type for r in floats)
    assert errors == 0  # (results are compared, error types are classes, never type itself)


def test_every_call_above_really_ran_compiled(engine):
    engine('compiled')
    for _, call in _calls():
        _run(call)
    kernels = [rt.euler.euler_to_matrix.__globals__['_MATRIX_KERNELS']['ZYX'],
               rt.axis_angle._rotvec_kernel, rt.so3._quaternion_kernel,
               rt.so3._checking(rt.axis_angle.axis_angle_kernel),
               rt.so3._checking(rt.decomposition._DECOMPOSE_KERNELS['xyz'])]
    for kernel in kernels:
        code = kernel.__dict__.get(_backend._COMPILED)
        assert callable(code) and 'traced' in code.__doc__, kernel


def test_errors_are_the_same_from_both_engines(engine):
    cases = [lambda: rt.rotvec_to_matrix([0.0, np.nan, 0.0]),
             lambda: rt.euler_to_matrix([np.inf, 0.0, 0.0]),
             lambda: rt.matrix_to_euler(np.diag([1.0, 1.0, -1.0])),
             lambda: rt.matrix_to_rotvec(np.eye(3) * 1.001),
             lambda: rt.axis_angle_to_matrix([0.0, 0.0, 0.0], 0.5),
             lambda: rt.quaternion_to_matrix([0.0, 0.0, 0.0, 0.0])]
    engine('floats')
    expected = [_run(c) for c in cases]
    engine('compiled')
    got = _compiled_run(cases)
    assert got == expected
    assert all(e[0] is rt.RotationError for e in expected)
    assert 'must be finite' in expected[0][1] and 'reflection' in expected[2][1]


def test_finite_guard_lets_an_overflowing_sum_through_to_the_exact_check(engine):
    # 1e308 + 1e308 overflows the guard's quick sum: the call must still succeed (exactly as
    # on floats), not be refused as non-finite.
    v = np.array([1e308, 1e308, 0.0])
    engine('floats')
    expected = rt.rotvec_to_matrix(v)
    engine('compiled')
    (got,) = _compiled_run([lambda: rt.rotvec_to_matrix(v)])
    assert got.tobytes() == expected.tobytes()
    assert rt.is_rotation(got)


def test_inputs_of_any_layout_and_type_take_a_path_that_gives_the_same_result(engine):
    engine('compiled')
    a = np.array([0.3, -0.4, 1.2])
    expected = rt.euler_to_matrix(a)
    variants = [a.tolist(), tuple(a), a.astype('>f8'), np.stack([a, a], axis=1)[:, 0],
                [np.float64(x) for x in a], [0.3, -0.4, np.float64(1.2)], a[None, :][0]]
    for v in variants:
        got = rt.euler_to_matrix(v)
        assert type(got) is np.ndarray and got.shape == (3, 3) and got.dtype == np.float64
        assert got.tobytes() == expected.tobytes()
    R = np.asfortranarray(expected)  # not C-ordered: entries must still be read row-major
    assert rt.matrix_to_rotvec(R).tobytes() == rt.matrix_to_rotvec(expected).tobytes()
    angle = rt.matrix_to_axis_angle(expected)[1]
    assert type(angle) is np.float64
    assert rt.axis_angle_to_matrix([0, 0, 1], np.float64(0.5)).tobytes() == \
        rt.axis_angle_to_matrix([0, 0, 1], 0.5).tobytes()


def test_outputs_are_fresh_arrays_and_scalars_of_the_declared_types(engine):
    engine('compiled')
    R = ROTATIONS[4]
    first = rt.matrix_to_euler(R, 'ZYX')
    second = rt.matrix_to_euler(R, 'ZYX')
    assert first[0] is not second[0]
    first[0][0] = 99.0
    assert second[0][0] != 99.0
    assert type(first[1]) is np.bool_
    assert type(rt.matrix_to_axis_angle(R)[1]) is np.float64
    assert rt.matrix_to_quaternion(R).flags.writeable


# -- the tracer itself ----------------------------------------------------------------------

def _compile(kernel, tails, outputs):
    """kernel compiled, called on plain floats (one vector input per tail)."""
    single = compile_single(kernel, _backend.FLOATS, tails, outputs)

    def call(*entries):
        inputs, start = [], 0
        for tail in tails:
            inputs.append((list(entries[start:start + tail[0]]), tail, 'v', True))
            start += tail[0]
        return single(inputs)
    call.__source__ = single.__source__
    return call


_F = ((), np.float64)


def test_two_independent_branches_become_four_paths_each_right():
    def kernel(ops, v):
        x = ops.where(v[0] > 0, v[0], -v[0])
        if ops.any(v[1] > 1.0):
            x = x * 10.0
        if ops.any(v[2] < 0):
            x = x + 0.5
        return (x,)
    f = _compile(kernel, [(3,)], [_F])
    statements = [line.strip() for line in f.__source__.splitlines()]
    branches = [line for line in statements if line.startswith('if ') and not re.search(
        r'type\(|len\(|\* 0\.0', line)]  # (not the checks of the inputs)
    assert len(branches) == 1 + 2  # the second branch is written once under each way
    for v in ([2.0, 0.0, 1.0], [-2.0, 5.0, 1.0], [2.0, 0.0, -1.0], [-3.0, 2.0, -1.0]):
        assert f(*v) == kernel(_backend.FLOATS, v)


def test_a_branch_taken_on_a_condition_decides_its_wheres():
    def kernel(ops, v):
        big = v[0] > 1.0
        y = v[1] * 2.0
        if ops.any(big):
            y = ops.where(big, y, -y)  # inside the branch big is known to be true
        return (y,)
    f = _compile(kernel, [(2,)], [_F])
    assert ' if t0 else ' not in f.__source__
    assert f(3.0, 1.5) == (3.0,) and f(0.5, 1.5) == (3.0,)


def test_sign_products_and_repeated_expressions_are_simplified_exactly():
    def kernel(ops, v):
        return ((1.0 * v[0]) * (-1.0 * v[1]) + ops.sin(v[0]) * ops.sin(v[0]),)
    f = _compile(kernel, [(2,)], [_F])
    assert '1.0' not in f.__source__ and f.__source__.count('_op_sin') == 1
    for v in ([0.3, -0.7], [-0.0, 2.0], [1e308, 2.0]):
        assert f(*v)[0] == kernel(_backend.FLOATS, v)[0]


def test_untraceable_kernels_are_refused_and_run_on_floats():
    def branching(ops, v):
        return (v[0] if v[1] > 0 else v[2],)  # Python if on a value

    def as_float(ops, v):
        return (math.floor(v[0]),)

    for kernel in (branching, as_float):
        with pytest.raises(TraceError):
            _compile(kernel, [(3,)], [_F])
        for _ in range(_backend.HOT_AFTER + 2):
            out = _backend.apply(kernel, [(np.array([1.5, 2.0, 3.0]), (3,), 'v', True)], [_F])
        assert out == (1.5,) if kernel is branching else out == (1.0,)
        assert kernel.__dict__[_backend._CALLS] is False
        assert _backend._COMPILED not in kernel.__dict__


def test_a_kernel_is_compiled_only_once_it_is_hot():
    def kernel(ops, v):
        return ([v[1], v[0]],)

    spec = [((2,), np.float64)]
    for n in range(_backend.HOT_AFTER):
        assert _backend.apply(kernel, [(np.array([1.0, 2.0]), (2,), 'v', True)], spec)[0] \
            .tolist() == [2.0, 1.0]
        assert kernel.__dict__[_backend._CALLS] == n + 1
        assert _backend._COMPILED not in kernel.__dict__
    _backend.apply(kernel, [(np.array([1.0, 2.0]), (2,), 'v', True)], spec)
    assert callable(kernel.__dict__[_backend._COMPILED])
    out = _backend.apply(kernel, [(np.array([3.0, 4.0]), (2,), 'v', True)], spec)
    assert out[0].tolist() == [4.0, 3.0]


def test_generated_source_shows_in_tracebacks():
    def kernel(ops, v):
        return (v[0] / v[1],)
    f = _compile(kernel, [(2,)], [_F])
    with pytest.raises(ZeroDivisionError) as info:
        f(1.0, 0.0)
    assert 'a0 / a1' in str(info.traceback[-1])
    assert f(3.0, 2.0) == (1.5,)
    assert f(3.0, np.inf) is None  # NaN/Inf: left to the generic path's checks


def test_values_read_once_are_folded_into_their_reader():
    def kernel(ops, v):
        once = v[0] * v[1]
        twice = v[0] + v[1]
        below = v[0] - v[1]  # read only inside the branch: stays a variable before it
        out = once + twice * twice
        if ops.any(v[2] > 0):
            out = out + below
        return (out,)
    f = _compile(kernel, [(3,)], [_F])
    assignments = [line.strip() for line in f.__source__.splitlines() if ' = ' in line
                   and line.strip().startswith('t')]
    assert any(re.fullmatch(r't\d+ = a0 \+ a1', line) for line in assignments)  # read twice
    assert any(re.fullmatch(r't\d+ = a0 - a1', line) for line in assignments)  # in a branch
    assert not any(re.fullmatch(r't\d+ = a0 \* a1', line) for line in assignments)  # once:
    assert any('(a0 * a1) + ' in line for line in assignments)  # folded into its reader
    for v in ([0.3, -2.0, 1.0], [0.3, -2.0, -1.0], [1e154, -3.0, 1.0]):
        assert f(*v) == kernel(_backend.FLOATS, v)


def test_float_outputs_are_plain_floats_for_one_item_and_arrays_for_a_batch():
    def kernel(ops, m, a):
        return [[m[0][0] * a, m[0][1]], [m[1][0], m[1][1] + a]], [a, -a], a * a
    outputs = [((2, 2), float), ((2,), float), ((), float)]
    m = np.array([[1.0, 2.0], [3.0, 4.0]])

    def run(m, a):
        return _backend.apply(kernel, [(m, (2, 2), 'm', True), (a, (), 'a', True)], outputs)
    expected = ((2.0, 2.0, 3.0, 6.0), (2.0, -2.0), 4.0)
    for _ in range(_backend.HOT_AFTER + 2):  # on floats, then compiled
        got = run(m, 2.0)
        assert got == expected and all(type(x) is float for x in got[0] + got[1] + got[2:])
    assert callable(kernel.__dict__[_backend._COMPILED])
    batch = run(np.stack([m, m]), np.array([2.0, 3.0]))
    assert batch[0].shape == (2, 2, 2) and batch[0].dtype == np.float64
    assert batch[0][1].tolist() == [[3.0, 2.0], [3.0, 7.0]] and batch[2].tolist() == [4.0, 9.0]


def _batch_calls():
    """(label, call) of every public batch conversion on the adversarial items at once."""
    R = np.stack(ROTATIONS)
    b = np.stack([VECTORS[i % len(VECTORS)] for i in range(len(R))])
    v = np.stack(VECTORS)
    calls = [('axis_angle', lambda: rt.matrix_to_axis_angle(R)),
             ('rotvec', lambda: rt.matrix_to_rotvec(R)),
             ('quaternion', lambda: rt.matrix_to_quaternion(R)),
             ('validate', lambda: rt.validate_rotation(R)),
             ('is_rotation', lambda: rt.is_rotation(R)),
             ('screw', lambda: rt.screw_from_transform(R, b)),
             ('screw_log', lambda: rt.screw_log(R, b)),
             ('points', lambda: rt.transform_points(R, b, b[::-1])),
             ('compose', lambda: rt.compose_transforms(R, b, R[::-1], b)),
             ('invert', lambda: rt.invert_transform(R, b)),
             ('values', lambda: rt.decomposition.decompose_values(R, b, 'zyx')),
             ('rotvec_to_matrix', lambda: rt.rotvec_to_matrix(v)),
             ('axis_angle_to_matrix', lambda: rt.axis_angle_to_matrix(v[1:], 0.7)),
             ('quaternion_to_matrix', lambda: rt.quaternion_to_matrix(
                 np.concatenate([v[1:], np.full((len(v) - 1, 1), 0.5)], axis=1))),
             ('screw_exp', lambda: rt.screw_exp(np.concatenate([v, v[::-1]], axis=1)))]
    calls += [(f'{seq}', lambda seq=seq: rt.matrix_to_euler(R, seq)) for seq in SEQUENCES]
    calls += [(f'decompose {seq}', lambda seq=seq: rt.decompose(R, b, seq))
              for seq in SEQUENCES[:2]]
    calls += [(f'euler {seq}', lambda seq=seq: rt.euler_to_matrix(v, seq)) for seq in SEQUENCES]
    return calls


def _tree_bits(x):
    if isinstance(x, tuple):
        return tuple(_tree_bits(v) for v in x)
    return _bits(x)


def test_compiled_batch_code_matches_the_array_engine_bit_for_bit(monkeypatch):
    calls = _batch_calls()
    monkeypatch.setattr(_backend, '_batch_code', lambda *args: None)
    arrays = [_tree_bits(_run(call)) for _, call in calls]
    monkeypatch.undo()
    monkeypatch.setattr(_backend, 'BATCH_AFTER', 0)
    compiled = [_tree_bits(_run(call)) for _, call in calls]
    differ = [label for (label, _), a, c in zip(calls, arrays, compiled) if a != c]
    assert not differ, differ
    kernel = rt.so3._checking(rt.euler._ANGLES_KERNELS['ZYX'])
    code = kernel.__dict__[_backend._BATCH]
    assert callable(code) and 'a batch' in code.__doc__


def test_batch_code_takes_both_ways_of_an_any(monkeypatch):
    monkeypatch.setattr(_backend, 'BATCH_AFTER', 0)

    def kernel(ops, v):
        out = v[0] * 2.0
        if ops.any(v[1] > 0):
            out = ops.where(v[1] > 0, out + 1.0, out)  # not settled by the branch: a batch
        return (out,)
    spec = [((), np.float64)]
    x = np.array([[1.0, -1.0], [2.0, 1.0], [3.0, -5.0]])
    assert _backend.apply(kernel, [(x, (2,), 'v', True)], spec)[0].tolist() == [2.0, 5.0, 6.0]
    assert _backend.apply(kernel, [(x[[0, 2]], (2,), 'v', True)], spec)[0].tolist() == [
        2.0, 6.0]
    assert '_op_any(' in kernel.__dict__[_backend._BATCH].__source__
