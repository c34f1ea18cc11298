"""
The engine: kernels run by rot_tools.core._backend.apply, and their generated one-item code.

The generated function of a kernel (rot_tools/core/_generated.py) must give what the kernel
gives on Python floats, bit for bit (rescaled tiny/huge vectors, the near-π axis and gimbal
lock run the kernel itself), with the same errors. It must be what the kernels give today
(regenerated in memory and compared), run from the first call on, for every public function
and rotation_node's per-message path, with no compilation at call time; the results must not
depend on call history; one item must fail as a batch does; and a traceback through it must
name a real file.
"""

import inspect
import math
from pathlib import Path
import re
import subprocess
import sys
import textwrap
import traceback
from types import SimpleNamespace

import math_helpers as h
import numpy as np
import pytest
import rot_tools as rt
from rot_tools.core import (_backend, _generate, _generated, _generated_chunks, _trace_batch,
                            decomposition)
from rot_tools.core._trace import compile_kernel, TraceError
from rot_tools.core._trace_batch import chunk_source
from rot_tools.io import boundary

REPO = Path(__file__).resolve().parent.parent

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
    """Return the call's result, or the type and text of the error it raised."""
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
    """
    Switch one-item calls between the kernels themselves and the generated code.

    engine('floats'): the kernels on Python floats; engine('generated'): as rot_tools runs
    them, through rot_tools/core/_generated.py.
    """
    def use(name):
        monkeypatch.undo()
        monkeypatch.setattr(_backend, '_CODE_OF', {})  # (forget the functions found so far)
        if name == 'floats':
            monkeypatch.setattr(_backend, 'GENERATED', {})
    return use


@pytest.fixture
def fallbacks():
    """Return the FALLBACKS counter, emptied: what ran on the kernels themselves from now on."""
    _backend.FALLBACKS.clear()
    yield _backend.FALLBACKS
    _backend.FALLBACKS.clear()


def test_generated_code_matches_the_kernels_on_python_floats_bit_for_bit(engine, fallbacks):
    calls = _calls()
    engine('floats')
    floats = [_bits(_run(call)) for _, call in calls]
    engine('generated')
    fallbacks.clear()
    generated = [_bits(_run(call)) for _, call in calls]
    differ = [label for (label, _), a, b in zip(calls, floats, generated) if a != b]
    assert not differ, f'{len(differ)} of {len(calls)} differ, e.g. {differ[:5]}'
    errors = sum(isinstance(r, tuple) and len(r) == 2 and r[0] is type for r in floats)
    assert errors == 0  # (results are compared, error types are classes, never type itself)
    # Most of these adversarial items ran generated code; the rare ones (tiny/huge vectors,
    # gimbal lock, NaN/Inf) ran the kernel itself, and so did the bad inputs.
    assert sum(fallbacks.values()) < len(calls) / 2


def test_the_checked_in_generated_modules_are_what_the_kernels_give():
    for path, text in _generate.sources().items():
        current = path.read_text(encoding='utf-8')
        assert current == text, (
            f'rot_tools/{path.name} is stale: run {_generate.COMMAND} and commit the result')
        assert current.startswith(f'# flake8: noqa\n"""\nGenerated by ``{_generate.COMMAND}``')
        assert current.count('\n') < 12_000  # a budget: the common path of each kernel only
    # Every kernel with one-item code has its chunk code too.
    assert set(_generated_chunks.CHUNKS) == set(_generated.CODE)


def _batch_inputs(tail, n, rng):
    """
    Return n items of one trailing shape, for chunks of 16.

    The first and last chunks hold ordinary values (rotations for a matrix); the middle one
    also the adversarial rotations and vectors (tiny, huge, zero: ops.rare cases).
    """
    x = rng.normal(size=(n, *tail))
    if tail == (3, 3):
        x = rt.random_rotations(n, rng=rng)
        x[16:32] = ROTATIONS[:16]
    elif tail == (3,):
        x[16:16 + len(VECTORS)] = VECTORS
    elif tail == ():
        x[16:20] = [0.0, h.PI, -h.PI, 1e-300]
    else:
        x[16] = 0.0
    return x


def test_chunk_code_matches_the_kernels_on_arrays_bit_for_bit(monkeypatch):
    rng = np.random.default_rng(23)
    monkeypatch.setattr(_backend, 'CHUNK', 16)
    ran = 0
    for name, key, kernel, tails, outputs in _generate.record():
        arrays = [_batch_inputs(t, 40, rng) for t in tails]
        _backend.CHUNK_FALLBACKS.clear()
        chunked = _bits(_backend._batch(kernel, arrays, tails, outputs))
        ran += _backend.CHUNK_FALLBACKS[key] < 3  # (a chunk ran its chunk code)
        with monkeypatch.context() as m:
            m.setattr(_backend, 'GENERATED_CHUNKS', {})
            assert _bits(_backend._batch(kernel, arrays, tails, outputs)) == chunked, name
    assert ran == len(_generated_chunks.CHUNKS)


# Public functions that run no kernel (plain NumPy): every other public function must be in
# _generate.ordinary_calls, so that a new conversion cannot be forgotten there. (Classes
# are not checked: a class whose methods run kernels needs calls there too.)
NO_KERNEL = {'rot_x', 'rot_y', 'rot_z', 'skew', 'nearest_rotation', 'mean_rotation',
             'align_vectors', 'random_rotations'}


def _ordinary_items(n=60):
    """Return n random rotations (every angle, both sides of π/2), translations, angles."""
    rng = np.random.default_rng(5)
    R = rt.random_rotations(n, rng=rng)
    b = rng.uniform(-3.0, 3.0, (n, 3))
    e = rng.uniform(-1.5, 1.5, (n, 3))
    return list(R), list(b), list(e)


def test_every_public_function_and_the_node_path_run_generated_code(fallbacks):
    calls = _generate.ordinary_calls()
    public = {name for name in rt.__all__ if inspect.isfunction(getattr(rt, name))}
    covered = {name for _, name, _ in calls}
    assert public - NO_KERNEL <= covered, public - NO_KERNEL - covered
    fallbacks.clear()
    for _, _, call in calls:
        call()
    Rs, bs, es = _ordinary_items()
    for R, b, e in zip(Rs, bs, es):
        q = rt.matrix_to_quaternion(R)
        for seq in rt.EULER_SEQUENCES:
            # rotation_node's per-message path: a message's fields in (the boundary imports
            # no ROS), its numbers out
            settings = SimpleNamespace(quaternion_tolerance=1e-6, euler_sequence=seq,
                                       degrees=False)
            for fields, convert in (((*b.tolist(), *q.tolist()), boundary.pose_fields_to_rt),
                                    (tuple(e.tolist()), boundary.euler_fields_to_rt)):
                R1, b1 = convert(fields, settings)
                decomposition.decompose_values(R1, b1, seq)
            rt.matrix_to_euler(R, seq)
            rt.decompose(R, b, seq)
        rt.quaternion_to_matrix(tuple(q.tolist()))
        rt.quaternion_to_matrix(q)
        rt.matrix_to_rotvec(R, check=False)
        rt.rotvec_to_matrix(rt.matrix_to_rotvec(R))
        rt.axis_angle_to_matrix(*rt.matrix_to_axis_angle(R))
        rt.screw_exp(rt.screw_log(R, b))
        rt.transform_from_screw(*rt.screw_from_transform(R, b)[:2], 0.5, 0.1)
        rt.compose_transforms(*rt.invert_transform(R, b), R, b)
        rt.transform_points(R, b, e)
        rt.homogeneous_to_transform(rt.transform_to_homogeneous(R, b))
        rt.rotation_distance(R, Rs[0])
        rt.frame_to_matrix(*R.T)
        rt.is_rotation(R)
    assert not fallbacks, f'ran the kernel itself, not generated code: {dict(fallbacks)}'


def test_every_public_batch_runs_chunk_code(monkeypatch):
    monkeypatch.setattr(_backend, 'CHUNK', 16)  # (four chunks, the last one short)
    Rs, bs, es = (np.array(x) for x in _ordinary_items())
    q = rt.matrix_to_quaternion(Rs)
    _backend.CHUNK_FALLBACKS.clear()
    for seq in rt.EULER_SEQUENCES:
        rt.euler_to_matrix(es, seq)
        for check in (True, False):
            rt.matrix_to_euler(Rs, seq, check=check)
            rt.decompose(Rs, bs, seq, check=check)
        decomposition.decompose_values(Rs, bs, seq)
    for check in (True, False):
        rt.matrix_to_rotvec(Rs, check=check)
        rt.matrix_to_axis_angle(Rs, check=check)
        rt.matrix_to_quaternion(Rs, check=check)
        rt.screw_from_transform(Rs, bs, check=check)
        rt.screw_exp(rt.screw_log(Rs, bs, check=check))
        rt.compose_transforms(*rt.invert_transform(Rs, bs, check=check), Rs, bs, check=check)
        rt.transform_points(Rs, bs, es, check=check)
        rt.homogeneous_to_transform(rt.transform_to_homogeneous(Rs, bs, check=check))
        rt.rotation_distance(Rs, Rs[::-1], check=check)
        rt.screw_interpolate(Rs, bs, Rs[::-1], -bs, 0.25, check=check)
    rt.quaternion_to_matrix(q)
    rt.rotvec_to_matrix(rt.matrix_to_rotvec(Rs))
    rt.axis_angle_to_matrix(*rt.matrix_to_axis_angle(Rs))
    rt.transform_from_screw(*rt.screw_from_transform(Rs, bs)[:2], 0.5, 0.1)
    rt.frame_to_matrix(Rs[..., 0], Rs[..., 1], Rs[..., 2])
    rt.is_rotation(Rs)
    rt.validate_rotation(Rs)
    assert not _backend.CHUNK_FALLBACKS, (
        f'chunks ran the kernel itself, not chunk code: {dict(_backend.CHUNK_FALLBACKS)}')


def test_a_kernel_missing_from_the_generated_module_is_noticed(monkeypatch, fallbacks):
    # The silent cliff: without its generated function a kernel still gives the right
    # answer, slower; FALLBACKS (which the test above reads) says so.
    table = dict(_backend.GENERATED)
    key = _backend.kernel_key(rt.so3._checking(rt.axis_angle._rotvec_of_matrix_kernel))
    del table[key]
    monkeypatch.setattr(_backend, 'GENERATED', table)
    monkeypatch.setattr(_backend, '_CODE_OF', {})
    R = ROTATIONS[4]
    expected = rt.matrix_to_rotvec(R).tobytes()
    assert fallbacks == {key: 1}
    monkeypatch.undo()
    assert rt.matrix_to_rotvec(R).tobytes() == expected
    assert fallbacks == {key: 1}


def test_every_conversion_is_bound_to_its_generated_function():
    # c.one(x) or c(x): a Conversion without its generated function would still answer
    # through apply (slower, and no FALLBACKS would show it).
    for name in rt.__all__:  # (rot_tools imports its modules on first use of a name)
        getattr(rt, name)
    unbound = [_backend.kernel_key(c.kernel) for c in _backend._CONVERSIONS
               if c.one is not _backend.GENERATED[_backend.kernel_key(c.kernel)][1]]
    assert len(_backend._CONVERSIONS) >= 56 and not unbound, unbound


def test_public_names_become_plain_module_attributes_on_first_access():
    # A module with __getattr__ gets no cached attribute look-ups from CPython: the hook
    # loads every public name on the first access of one, then goes.
    script = textwrap.dedent("""
        import sys
        import rot_tools as rt
        assert '__getattr__' in vars(rt) and 'numpy' not in sys.modules
        rt.rotvec_to_matrix
        assert '__getattr__' not in vars(rt)
        assert set(rt.__all__) <= set(vars(rt))
        try:
            rt.no_such_name
        except AttributeError as exc:
            print('ok', exc)
    """)
    done = subprocess.run([sys.executable, '-c', script], capture_output=True, text=True,
                          timeout=120, cwd=REPO)
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith("ok module 'rot_tools' has no attribute 'no_such_name'")


def test_no_compilation_or_tracing_happens_at_call_time():
    # A fresh process: import rot_tools, then forbid compile and exec, then make the first
    # call of every ordinary call (the node's path included). The tracer is never imported.
    script = textwrap.dedent("""
        import builtins, sys
        import numpy as np
        import rot_tools as rt
        from rot_tools.core import _backend, _generate
        calls = _generate.ordinary_calls()
        for name in rt.__all__:  # (rot_tools imports its modules on first use of a name)
            getattr(rt, name)
        assert 'rot_tools.core._trace' not in sys.modules
        def forbidden(*args, **kwargs):
            raise AssertionError('compile or exec at call time')
        builtins.compile = builtins.exec = forbidden
        for label, name, call in calls:
            call()
        assert 'rot_tools.core._trace' not in sys.modules
        assert not _backend.FALLBACKS, dict(_backend.FALLBACKS)
        print('ok', len(calls))
    """)
    done = subprocess.run([sys.executable, '-c', script], capture_output=True, text=True,
                          timeout=120, cwd=REPO)
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith('ok ')


def test_results_do_not_depend_on_call_history():
    R, b = ROTATIONS[5], VECTORS[1]
    calls = [lambda: rt.matrix_to_euler(R, 'zyx'), lambda: rt.matrix_to_axis_angle(R),
             lambda: decomposition.decompose_values(R, b, 'XYZ'), lambda: rt.screw_log(R, b),
             lambda: rt.euler_to_matrix([0.1, 0.2, 0.3]), lambda: rt.decompose(R, b),
             lambda: rt.quaternion_to_matrix((0.0, 0.0, 0.0, 0.0))]
    first = [_bits(_run(c)) for c in calls]
    types = [type(_run(c)) for c in calls]
    for _ in range(200):
        for c in calls:
            _run(c)
    assert [_bits(_run(c)) for c in calls] == first
    assert [type(_run(c)) for c in calls] == types
    assert not [n for n in dir(_backend) if 'HOT' in n or 'BATCH' in n or 'CALLS' in n]


def test_kernels_built_per_call_are_not_kept():
    # matrix_to_euler with another lock_tol builds its kernel per call: the engine must not
    # keep each one (a node or a loop calling it would grow without bound).
    R = ROTATIONS[5]
    rt.matrix_to_euler(R, 'ZYX', lock_tol=1e-5)
    before = len(_backend._CODE_OF)
    for _ in range(50):
        rt.matrix_to_euler(R, 'ZYX', lock_tol=1e-5)
        rt.matrix_to_euler(R, 'zxz', lock_tol=2e-5, check=False)
    assert len(_backend._CODE_OF) <= before + 1


def test_apply_follows_its_outputs_argument_on_every_call():
    # (Once hot, the old engine returned the outputs of the first call's spec.)
    kernel = rt.axis_angle._rotvec_kernel
    inputs = [((0.3, -1.0, 0.5), (3,), 'rotation vector', True)]
    arrays = [((3, 3), np.float64), ((), np.bool_)]
    floats = [((3, 3), float), ((), np.bool_)]
    for _ in range(40):
        a = _backend.apply(kernel, inputs, arrays)
        f = _backend.apply(kernel, inputs, floats)
        assert type(a[0]) is np.ndarray and a[0].shape == (3, 3)
        assert type(f[0]) is tuple and len(f[0]) == 9 and type(f[0][0]) is float
        assert a[0].ravel().tolist() == list(f[0])


def test_one_item_gives_what_a_batch_gives_where_float_arithmetic_would_raise():
    def kernel(ops, v):
        return (v[0] / v[1], ops.sqrt(v[0]), ops.sin(v[2] * 1e308 * 10.0))
    outputs = [((), np.float64)] * 3
    item = np.array([-1.0, 0.0, 1.0])
    one = _backend.apply(kernel, [(item, (3,), 'v', True)], outputs)
    batch = _backend.apply(kernel, [(item[None], (3,), 'v', True)], outputs)
    assert [type(x) for x in one] == [np.float64] * 3
    assert one[0] == -math.inf and math.isnan(one[1]) and math.isnan(one[2])
    assert _bits(one) == _bits(tuple(x[0] for x in batch))
    # A generated function meets the raise itself and leaves the item to apply (None).
    compiled = compile_kernel(kernel, _backend.FLOATS, [(3,)], outputs)
    assert compiled(item) is None
    assert compiled(np.array([1.0, 2.0, 0.0])) == (0.5, 1.0, 0.0)


def _weird_items():
    """Finite and non-finite extremes: every public function, one item and a batch of one."""
    rng = np.random.default_rng(3)
    values = [0.0, -0.0, 1.0, -1.0, 1e-300, 1e300, 1.7e308, -1.7e308, 5e-324, 3.0, 0.5]
    mats = [rng.choice(values, size=(3, 3)) for _ in range(40)]
    mats += [np.full((3, 3), x) for x in (np.inf, np.nan, 0.0, 1e308)]
    vecs = [rng.choice(values, size=9) for _ in range(40)] + [np.zeros(9)]
    return mats, vecs


def _fail_alike_calls():
    mats, vecs = _weird_items()
    calls = []
    for i, (m, v) in enumerate(zip(mats, vecs)):
        b = v[:3]  # (one item; the batch of one gets m[None], v[None])
        calls += [
            (f'axis_angle {i}', lambda m, v, b=b: rt.matrix_to_axis_angle(m, check=False), m),
            (f'rotvec {i}', lambda m, v: rt.matrix_to_rotvec(m, check=False), m),
            (f'quaternion {i}', lambda m, v: rt.matrix_to_quaternion(m, check=False), m),
            (f'euler {i}', lambda m, v: rt.matrix_to_euler(m, 'zxz', check=False), m),
            (f'screw {i}', lambda m, v, b=b: rt.screw_from_transform(m, b, check=False), m),
            (f'log {i}', lambda m, v, b=b: rt.screw_log(m, b, check=False), m),
            (f'decompose {i}', lambda m, v, b=b: rt.decompose(m, b, 'YXZ', check=False), m),
            (f'values {i}', lambda m, v, b=b: decomposition.decompose_values(m, b, 'xyz'), m),
            (f'points {i}', lambda m, v, b=b: rt.transform_points(m, b, b, check=False), m),
            (f'compose {i}', lambda m, v, b=b: rt.compose_transforms(m, b, m, b, check=False),
             m),
            (f'invert {i}', lambda m, v, b=b: rt.invert_transform(m, b, check=False), m),
            (f'distance {i}', lambda m, v: rt.rotation_distance(m, m, check=False), m),
            (f'is_rotation {i}', lambda m, v: rt.is_rotation(m), m),
            (f'validate {i}', lambda m, v: rt.validate_rotation(m), m),
            (f'checked rotvec {i}', lambda m, v: rt.matrix_to_rotvec(m), m)]
        calls += [
            (f'rotvec_to_matrix {i}', lambda m, v: rt.rotvec_to_matrix(v[..., :3]), v),
            (f'axis_angle_to_matrix {i}',
             lambda m, v: rt.axis_angle_to_matrix(v[..., :3], v[..., 3]), v),
            (f'quaternion_to_matrix {i}', lambda m, v: rt.quaternion_to_matrix(v[..., :4]), v),
            (f'screw_exp {i}', lambda m, v: rt.screw_exp(v[..., :6]), v),
            (f'transform_from_screw {i}', lambda m, v: rt.transform_from_screw(
                v[..., :3], v[..., 3:6], v[..., 6], v[..., 7]), v),
            (f'euler_to_matrix {i}', lambda m, v: rt.euler_to_matrix(v[..., :3], 'ZYX'), v),
            (f'frame {i}', lambda m, v: rt.frame_to_matrix(
                v[..., :3], v[..., 3:6], v[..., 6:9]), v)]
    return mats, vecs, calls


def _outcome(call, m, v, batch=False):
    try:
        return call(m, v)
    except rt.RotationError as exc:
        text = re.sub(r',? \(?(worst |first )?at item \(0,\)\)?| \(item \(0,\)\)', '',
                      str(exc))
        if batch:  # the batch's index of a value has the item first
            text = text.replace('at index (0, ', 'at index (')
        return rt.RotationError, text


def _same(one, batch):
    """Tell whether the batch-of-one result is the one-item result (NaN = NaN)."""
    if isinstance(one, tuple) and one and one[0] is rt.RotationError:
        return batch == one
    if isinstance(one, tuple) and not all(type(x) is float for x in one):
        return isinstance(batch, tuple) and len(one) == len(batch) and all(
            _same(a, b) for a, b in zip(one, batch))
    a, b = np.asarray(one), np.asarray(batch)[0]
    if a.dtype == bool or b.dtype == bool:
        return a.shape == b.shape and (a == b).all()
    exact = ~np.isfinite(a) | ~np.isfinite(b)
    # Finite values to rounding, relative to the largest of the output: libm's and NumPy's
    # tan, sin, ... may differ in the last bit, and a cancellation of entries near 1e308
    # turns that into ~1e292 (NumPy 1.26's tan in screw_from_transform).
    scale = np.abs(a[~exact]).max(initial=0.0)
    return a.shape == b.shape and np.array_equal(a[exact], b[exact], equal_nan=True) and \
        np.allclose(a[~exact], b[~exact], rtol=1e-12, atol=1e-12 * scale)


def test_one_item_and_a_batch_fail_alike_for_every_public_function():
    # Each call on one item and on a batch of that one item: the same values (NaN and inf
    # where the other has them) or the same RotationError (the batch naming item (0,)); never
    # ZeroDivisionError or "math domain error" on one side only.
    mats, vecs, calls = _fail_alike_calls()
    differ = []
    for label, call, _ in calls:
        m, v = mats[int(label.split()[-1])], vecs[int(label.split()[-1])]
        one = _outcome(call, m, v)
        batch = _outcome(call, m[None], v[None], batch=True)
        if not _same(one, batch):
            differ.append((label, one, batch))
    assert not differ, differ[:3]


def test_a_traceback_through_generated_code_names_a_line_of_a_real_file(monkeypatch):
    def broken(*args):
        raise RuntimeError('broken sqrt')
    monkeypatch.setattr(_generated, '_op_sqrt', broken)
    with pytest.raises(RuntimeError) as info:
        rt.matrix_to_rotvec(ROTATIONS[4])
    frames = traceback.extract_tb(info.value.__traceback__)
    assert all(Path(f.filename).is_file() for f in frames), [f.filename for f in frames]
    last = frames[-2]  # (the last is `broken` above)
    assert Path(last.filename).resolve() == REPO / 'rot_tools' / '_generated.py'
    assert '_op_sqrt(' in last.line
    assert last.name == 'axis_angle__rotvec_of_matrix_kernel_checked'
    text = Path(last.filename).read_text(encoding='utf-8').splitlines()[last.lineno - 1]
    assert text.strip() == last.line


def test_a_refused_conversion_traceback_names_real_files_only():
    with pytest.raises(rt.RotationError) as info:
        rt.matrix_to_rotvec(np.eye(3) * 1.001)
    frames = traceback.extract_tb(info.value.__traceback__)
    assert all(Path(f.filename).is_file() for f in frames)
    assert 'rot_tools' in frames[-1].filename


def test_errors_are_the_same_from_both_engines(engine):
    cases = [lambda: rt.rotvec_to_matrix([0.0, np.nan, 0.0]),
             lambda: rt.euler_to_matrix([np.inf, 0.0, 0.0]),
             lambda: rt.matrix_to_euler(np.diag([1.0, 1.0, -1.0])),
             lambda: rt.matrix_to_rotvec(np.eye(3) * 1.001),
             lambda: rt.axis_angle_to_matrix([0.0, 0.0, 0.0], 0.5),
             lambda: rt.quaternion_to_matrix([0.0, 0.0, 0.0, 0.0])]
    engine('floats')
    expected = [_run(c) for c in cases]
    engine('generated')
    got = [_run(c) for c in cases]
    assert got == expected
    assert all(e[0] is rt.RotationError for e in expected)
    assert 'must be finite' in expected[0][1] and 'reflection' in expected[2][1]


def test_finite_guard_lets_an_overflowing_sum_through_to_the_exact_check(engine):
    # 1e308 + 1e308 overflows the generated code's quick sum: the call must still succeed
    # (exactly as on floats), not be refused as non-finite.
    v = np.array([1e308, 1e308, 0.0])
    engine('floats')
    expected = rt.rotvec_to_matrix(v)
    engine('generated')
    got = rt.rotvec_to_matrix(v)
    assert got.tobytes() == expected.tobytes()
    assert rt.is_rotation(got)


def test_inputs_of_any_layout_and_type_take_a_path_that_gives_the_same_result():
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


def test_outputs_are_fresh_arrays_and_scalars_of_the_declared_types():
    R = ROTATIONS[4]
    first = rt.matrix_to_euler(R, 'ZYX')
    second = rt.matrix_to_euler(R, 'ZYX')
    assert first[0] is not second[0]
    first[0][0] = 99.0
    assert second[0][0] != 99.0
    assert type(first[1]) is np.bool_
    assert type(rt.matrix_to_axis_angle(R)[1]) is np.float64
    assert rt.matrix_to_quaternion(R).flags.writeable
    values = decomposition.decompose_values(R, VECTORS[1], 'zyx')
    assert all(type(x) is float for field in values for x in field)


# -- the tracer itself ----------------------------------------------------------------------

def _compile(kernel, tails, outputs):
    """Return the kernel traced and compiled, called on plain floats."""
    single = compile_kernel(kernel, _backend.FLOATS, tails, outputs)

    def call(*entries):
        values, start = [], 0
        for tail in tails:
            values.append(list(entries[start:start + tail[0]]))
            start += tail[0]
        return single(*values)
    call.__source__ = single.__source__
    return call


_F = ((), np.float64)


def test_a_rare_branch_is_left_to_the_kernel_itself():
    def kernel(ops, v):
        x = ops.where(v[0] > 0, v[0], -v[0])
        big = v[1] > 1.0
        if ops.rare(big):
            x = ops.where(big, x * 10.0, x)
        return (x + ops.where(big, 1.0, 0.5),)  # past the guard big is known false
    f = _compile(kernel, [(2,)], [_F])
    assert 'return None  # rare' in f.__source__ and ' if t' not in f.__source__.split(
        'return None  # rare')[1].split('return (')[0].replace(' if t0 else', '')
    assert f(2.0, 0.0) == (2.5,) and f(-3.0, 1.0) == (3.5,)
    assert f(2.0, 5.0) is None  # the rare case: apply then runs the kernel
    assert kernel(_backend.FLOATS, [2.0, 5.0]) == (21.0,)


def test_sign_products_and_repeated_expressions_are_simplified_exactly():
    def kernel(ops, v):
        return ((1.0 * v[0]) * (-1.0 * v[1]) + ops.sin(v[0]) * ops.sin(v[0]),)
    f = _compile(kernel, [(2,)], [_F])
    body = f.__source__.split('def traced')[1]
    assert '1.0' not in body and body.count('_op_sin') == 1
    for v in ([0.3, -0.7], [-0.0, 2.0], [1e308, 2.0]):
        assert f(*v)[0] == kernel(_backend.FLOATS, v)[0]


def test_untraceable_kernels_are_refused_and_run_on_floats(fallbacks):
    def branching(ops, v):
        return (v[0] if v[1] > 0 else v[2],)  # Python if on a value

    def as_float(ops, v):
        return (math.floor(v[0]),)

    for kernel in (branching, as_float):
        with pytest.raises(TraceError):
            _compile(kernel, [(3,)], [_F])
        for _ in range(3):
            out = _backend.apply(kernel, [(np.array([1.5, 2.0, 3.0]), (3,), 'v', True)], [_F])
        assert out == (1.5,) if kernel is branching else out == (1.0,)
        assert fallbacks[_backend.kernel_key(kernel)] == 3


def _chunk_function(kernel, tails, outputs):
    """Return the kernel written out for a chunk, compiled, and its numbers of buffers."""
    text, floats, bools, ufuncs = chunk_source('chunk', kernel, _backend.ARRAYS, tails, outputs)
    names = {'_np': np}
    source = '\n'.join([_trace_batch.PRELUDE, *_trace_batch.ufunc_lines(ufuncs), text])
    exec(compile(source, '<test chunk>', 'exec'), names)  # noqa: S102
    return names['chunk'], floats, bools, text


def test_chunk_code_reuses_buffers_and_leaves_rare_chunks_to_the_kernel():
    def kernel(ops, v):
        n2 = v[0] * v[0] + v[1] * v[1]
        if ops.rare(n2 > 1e300):
            n2 = ops.where(n2 > 1e300, 1e300, n2)
        s = ops.sqrt(n2)
        return [s * v[0], s * v[1] + 1.0], n2 == 0.0
    outputs = [((2,), np.float64), ((), np.bool_)]
    f, floats, bools, text = _chunk_function(kernel, [(2,)], outputs)
    assert floats <= 3 and bools <= 1  # five float values, at most three alive at once
    assert 'return None  # rare' in text and text.count('out=o') == 3  # outputs written direct
    a = [np.array([3.0, 0.0, -1e-300]), np.array([4.0, 0.0, 2.0])]
    o = [np.empty(3), np.empty(3), np.empty(3, bool)]
    assert f(a, o, list(np.empty((floats, 3))), list(np.empty((bools, 3), bool)))
    want = kernel(_backend.ARRAYS, a)
    assert all(np.array_equal(x, y) for x, y in zip(o, [*want[0], want[1]]))
    a[0][1] = 1e200  # a rare item: the chunk is the kernel's
    with np.errstate(over='ignore'):
        assert f(a, o, list(np.empty((floats, 3))), list(np.empty((bools, 3), bool))) is None


def test_kernels_the_chunk_writer_cannot_write_are_refused():
    def arithmetic_on_a_condition(ops, v):
        return ((v[0] > 0) * 2.0,)

    def integer_output(ops, v):
        return (v[0] + v[1],)

    with pytest.raises(TraceError, match='condition'):
        _chunk_function(arithmetic_on_a_condition, [(2,)], [_F])
    with pytest.raises(TraceError, match='dtype'):
        _chunk_function(integer_output, [(2,)], [((), np.int64)])


def test_values_read_once_are_folded_into_their_reader():
    def kernel(ops, v):
        once = v[0] * v[1]
        twice = v[0] + v[1]
        out = once + twice * twice
        return (out,)
    f = _compile(kernel, [(3,)], [_F])
    assignments = [line.strip() for line in f.__source__.splitlines() if ' = ' in line
                   and line.strip().startswith('t')]
    assert any(re.fullmatch(r't\d+ = a0 \+ a1', line) for line in assignments)  # read twice
    assert not any(re.fullmatch(r't\d+ = a0 \* a1', line) for line in assignments)  # once:
    assert '(a0 * a1) + ' in f.__source__  # folded into its reader
    for v in ([0.3, -2.0, 1.0], [1e154, -3.0, 1.0]):
        assert f(*v) == kernel(_backend.FLOATS, v)


def test_float_outputs_are_plain_floats_for_one_item_and_arrays_for_a_batch():
    def kernel(ops, m, a):
        return [[m[0][0] * a, m[0][1]], [m[1][0], m[1][1] + a]], [a, -a], a * a
    outputs = [((2, 2), float), ((2,), float), ((), float)]
    m = np.array([[1.0, 2.0], [3.0, 4.0]])

    def run(m, a):
        return _backend.apply(kernel, [(m, (2, 2), 'm', True), (a, (), 'a', True)], outputs)
    expected = ((2.0, 2.0, 3.0, 6.0), (2.0, -2.0), 4.0)
    got = run(m, 2.0)
    assert got == expected and all(type(x) is float for x in got[0] + got[1] + got[2:])
    batch = run(np.stack([m, m]), np.array([2.0, 3.0]))
    assert batch[0].shape == (2, 2, 2) and batch[0].dtype == np.float64
    assert batch[0][1].tolist() == [[3.0, 2.0], [3.0, 7.0]] and batch[2].tolist() == [4.0, 9.0]
    compiled = compile_kernel(kernel, _backend.FLOATS, [(2, 2), ()], outputs)
    assert compiled(m, 2.0) == expected


def _unindented(text):
    return '\n'.join(line.strip() for line in text.splitlines())


def test_doc_engine_shows_real_code_and_names():
    doc = (REPO / 'doc' / 'engine.md').read_text(encoding='utf-8')
    blocks = [_unindented(b) for b in re.findall(r'```python\n(.*?)```', doc, re.S)]
    sources = [_unindented(p.read_text(encoding='utf-8'))
               for p in (REPO / 'rot_tools').glob('*.py')]
    assert len(blocks) == 2 and all(any(b in s for s in sources) for b in blocks), blocks
    assert 'python -m rot_tools.core._generate ' in doc and _generate.COMMAND.endswith(
        'python -m rot_tools.core._generate')
    ops = {n for n in dir(_backend.FLOATS) if not n.startswith('_')}
    table = doc.split('## 2. The ops namespace')[1].split('\n## ')[0]
    assert ops - {'any'} <= set(re.findall(r'\b(\w+)\b', table)), ops
