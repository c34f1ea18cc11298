"""One item and a batch give the same values and failures, for every public function."""

import importlib
import math
from pathlib import Path
import pkgutil
import re
import subprocess
import sys
import textwrap
import traceback
from typing import NamedTuple

from api_sweep import assert_sweeps_every_public_function, TIME_SERIES
from hypothesis import example, given, settings, strategies as st
import math_helpers as h
import numpy as np
import pytest
import rot_tools as rt
from rot_tools.core import engine, euler, so3
from rot_tools.core.decomposition import decompose_one
from rot_tools.core.euler import GIMBAL_LOCK_TOL, RPY_SEQUENCE

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


def _covariance(R):
    """Return a covariance of three angles: diag(0.01, 0.02, 0.03) turned by R."""
    return R @ np.diag([0.01, 0.02, 0.03]) @ np.swapaxes(R, -1, -2)


def _pose_covariance(cov):
    """Return a 6 × 6 pose covariance with ``cov`` on both diagonal blocks."""
    cov6 = np.zeros(cov.shape[:-2] + (6, 6))
    cov6[..., :3, :3] = cov6[..., 3:, 3:] = cov
    return cov6


def _public_calls():
    """(label, function of one item or a batch, items): every public function of items."""
    R = np.array(ROTATIONS)
    b = np.array([VECTORS[i % len(VECTORS)] for i in range(len(R))])
    v = np.array(VECTORS)
    calls = [
        ('matrix_to_axis_angle', lambda R, b: rt.matrix_to_axis_angle(R)),
        ('matrix_to_rotvec', lambda R, b: rt.matrix_to_rotvec(R)),
        ('matrix_to_quaternion', lambda R, b: rt.matrix_to_quaternion(R)),
        ('matrix_to_rodrigues', lambda R, b: rt.matrix_to_rodrigues(R)),
        ('is_rotation', lambda R, b: rt.is_rotation(R)),
        ('validate_rotation', lambda R, b: rt.validate_rotation(R)),
        ('nearest_rotation', lambda R, b: rt.nearest_rotation(R)),
        ('screw_from_transform', lambda R, b: rt.screw_from_transform(R, b)),
        ('screw_log', lambda R, b: rt.screw_log(R, b)),
        ('screw_interpolate', lambda R, b: rt.screw_interpolate(
            R, b, np.swapaxes(R, -1, -2), -b, 0.3)),
        ('transform_points', lambda R, b: rt.transform_points(R, b, b[..., ::-1])),
        ('compose_transforms', lambda R, b: rt.compose_transforms(R, b, R, -b)),
        ('invert_transform', lambda R, b: rt.invert_transform(R, b)),
        ('transform_to_homogeneous', lambda R, b: rt.transform_to_homogeneous(R, b)),
        ('homogeneous_to_transform', lambda R, b: rt.homogeneous_to_transform(
            h.homogeneous(R, b))),
        ('frame_to_matrix', lambda R, b: rt.frame_to_matrix(R[..., 0], R[..., 1], R[..., 2])),
        ('rotation_distance', lambda R, b: rt.rotation_distance(R, R[..., ::-1, :].swapaxes(
            -1, -2) @ R, check=False)),
        ('mean_rotation', lambda R, b: rt.mean_rotation(
            np.stack([R, np.swapaxes(R, -1, -2), R @ R], -3))),
        ('align_vectors', lambda R, b: rt.align_vectors(R, R[..., ::-1, :])),
        ('change_covariance_frame', lambda R, b: rt.change_covariance_frame(
            _covariance(R), R)),
        ('rotvec_covariance_to_euler', lambda R, b: rt.rotvec_covariance_to_euler(
            R, _covariance(R))),
        ('transform_pose_covariance', lambda R, b: rt.transform_pose_covariance(
            R, b, _pose_covariance(_covariance(R)))),
        ('decompose yxz unchecked', lambda R, b: rt.decompose(R, b, 'yxz', check=False))]
    calls += [(f'matrix_to_euler {s}', lambda R, b, s=s: rt.matrix_to_euler(R, s))
              for s in SEQUENCES]
    calls += [(f'decompose {s}', lambda R, b, s=s: rt.decompose(R, b, s)) for s in SEQUENCES[:2]]
    out = [(label, call, (R, b)) for label, call in calls]
    vector_calls = [
        ('rotvec_to_matrix', lambda v: rt.rotvec_to_matrix(v)),
        ('rodrigues_to_matrix', lambda v: rt.rodrigues_to_matrix(v)),
        ('axis_angle_to_matrix', lambda v: rt.axis_angle_to_matrix(v[..., ::-1] + 1.0, v[..., 0])),
        ('quaternion_to_matrix', lambda v: rt.quaternion_to_matrix(
            np.concatenate([v, np.ones(v.shape[:-1] + (1,))], axis=-1))),
        ('screw_exp', lambda v: rt.screw_exp(np.concatenate([v * 1e-300, v[..., ::-1]], -1))),
        ('transform_from_screw', lambda v: rt.transform_from_screw(
            [0.0, 0.6, 0.8], v * 1e-300, 1.3, -0.4)),
        ('rot_x', lambda v: rt.rot_x(v[..., 0])),
        ('rot_y', lambda v: rt.rot_y(v[..., 1])),
        ('rot_z', lambda v: rt.rot_z(v[..., 2])),
        ('skew', lambda v: rt.skew(v)),
        ('euler_covariance_to_rotvec', lambda v: rt.euler_covariance_to_rotvec(
            v * 1e-300, np.diag([0.01, 0.02, 0.03])))]
    vector_calls += [(f'euler_to_matrix {s}', lambda v, s=s: rt.euler_to_matrix(v * 1e-300, s))
                     for s in SEQUENCES]
    out += [(label, lambda v, b, call=call: call(v), (v, v)) for label, call in vector_calls]
    return out


NOT_ITEMS = dict(TIME_SERIES, random_rotations='draws rotations: takes a count, not items')
"""The public functions the sweeps over items and batches cannot call, and why."""


def test_the_sweep_of_items_and_batches_calls_every_public_function():
    labels = [label for label, _, _ in _public_calls()]
    assert_sweeps_every_public_function({label.split()[0] for label in labels}, NOT_ITEMS)


SUBNORMAL_STEPS = 4 * 5e-324


def _close(one, batch):
    """Tell whether one item's result is the batch's to rounding (NaN = NaN, inf exactly)."""
    if isinstance(one, tuple):
        return len(one) == len(batch) and all(_close(a, b) for a, b in zip(one, batch))
    a, b = np.asarray(one), np.asarray(batch)
    if a.dtype == bool or b.dtype == bool:
        return a.shape == b.shape and bool((a == b).all())
    exact = ~np.isfinite(a) | ~np.isfinite(b)
    scale = np.abs(a[~exact]).max(initial=0.0)
    return a.shape == b.shape and np.array_equal(a[exact], b[exact], equal_nan=True) and \
        np.allclose(a[~exact], b[~exact], rtol=1e-12, atol=1e-12 * scale + SUBNORMAL_STEPS)


def _outcome(call, *args):
    try:
        return call(*args)
    except rt.RotationError as exc:
        return rt.RotationError, re.sub(r',? \(?(worst |first )?at item \(\d+,\)\)?'
                                        r'| \(item \(\d+,\)\)', '', str(exc))


def _item_of(result, i):
    if isinstance(result, tuple) and result and result[0] is rt.RotationError:
        return result
    if hasattr(result, '_fields'):
        return type(result)(*(_item_of(r, i) for r in result))
    if isinstance(result, tuple):
        return tuple(_item_of(r, i) for r in result)
    return np.asarray(result)[i]


def _refused(outcome):
    return isinstance(outcome, tuple) and bool(outcome) and outcome[0] is rt.RotationError


def _locked_covariance(one, batch_item):
    """Tell whether one item is refused at gimbal lock where its batch item is flagged, NaN."""
    return (_refused(one) and 'gimbal lock' in one[1] and not _refused(batch_item)
            and bool(batch_item.degenerate) and np.isnan(batch_item.cov).all())


PUBLIC_CALLS = _public_calls()


@pytest.mark.parametrize('label, call, items', PUBLIC_CALLS, ids=[c[0] for c in PUBLIC_CALLS])
def test_every_public_function_gives_one_item_what_a_batch_gives(label, call, items,
                                                                 monkeypatch):
    # One item runs a kernel on FLOATS, the batch on ARRAYS in chunks of 16: the same result.
    monkeypatch.setattr(engine, 'CHUNK', 16)
    first, second = items
    batch = _outcome(call, first, second)
    for i in range(len(first)):
        one = _outcome(call, first[i], second[i])
        # (where some item is refused, each item against a batch of itself alone)
        expected = _outcome(call, first[i:i + 1], second[i:i + 1]) if _refused(batch) else batch
        if _refused(one) and _refused(expected):
            assert expected == one, (label, i)
        elif not _locked_covariance(one, _item_of(expected, 0 if _refused(batch) else i)):
            assert _close(one, _item_of(expected, 0 if _refused(batch) else i)), (label, i, one)


def test_chunk_boundaries_do_not_change_results(monkeypatch):
    rng = np.random.default_rng(23)
    R = rt.random_rotations(100, rng=rng)
    R[40:40 + 16] = ROTATIONS[:16]
    b = rng.normal(size=(100, 3))
    whole = rt.decompose(R, b, 'zxz')
    for chunk in (1, 7, 16, 99, 100):
        monkeypatch.setattr(engine, 'CHUNK', chunk)
        parts = rt.decompose(R, b, 'zxz')
        for x, y in zip(whole, parts):
            for u, w in zip(x if isinstance(x, tuple) else (x,), y if isinstance(y, tuple)
                            else (y,)):
                assert _close(u, w)


def test_nan_and_inf_are_refused_per_chunk_with_the_first_index(monkeypatch):
    monkeypatch.setattr(engine, 'CHUNK', 16)
    v = np.ones((50, 3))
    v[37, 1] = np.nan
    v[45, 0] = np.inf
    with pytest.raises(rt.RotationError, match=re.escape(
            'rotation vector must be finite: 2 non-finite value(s), first nan at index '
            '(37, 1)')):
        rt.rotvec_to_matrix(v)
    R = np.broadcast_to(np.eye(3), (40, 3, 3)).copy()
    R[33, 2, 2] = -np.inf
    with pytest.raises(rt.RotationError, match=re.escape('first -inf at index (33, 2, 2)')):
        rt.matrix_to_euler(R)


def test_overflow_flags_name_the_first_item(monkeypatch):
    monkeypatch.setattr(engine, 'CHUNK', 4)
    b = np.zeros((10, 3))
    b[6] = [1.7e308, 1.7e308, 0.0]
    with pytest.raises(rt.RotationError, match=r'overflows float64 .* first at item \(6,\)'):
        rt.transform_points(np.eye(3), b, b)


def _weird_items():
    """Finite and non-finite extremes: every public function, one item and a batch of one."""
    rng = np.random.default_rng(3)
    values = [0.0, -0.0, 1.0, -1.0, 1e-300, 1e300, 1.7e308, -1.7e308, 5e-324, 3.0, 0.5]
    mats = [rng.choice(values, size=(3, 3)) for _ in range(40)]
    mats += [np.full((3, 3), x) for x in (np.inf, np.nan, 0.0, 1e308)]
    vecs = [rng.choice(values, size=9) for _ in range(40)] + [np.zeros(9)]
    return mats, vecs


def _fail_alike_calls():
    """(label, call of a matrix m and a vector v of 9): every public function of items."""
    I3 = np.eye(3)
    return [
        ('matrix_to_axis_angle', lambda m, v: rt.matrix_to_axis_angle(m, check=False)),
        ('matrix_to_rotvec', lambda m, v: rt.matrix_to_rotvec(m, check=False)),
        ('matrix_to_quaternion', lambda m, v: rt.matrix_to_quaternion(m, check=False)),
        ('matrix_to_rodrigues', lambda m, v: rt.matrix_to_rodrigues(m, check=False)),
        ('matrix_to_euler', lambda m, v: rt.matrix_to_euler(m, 'zxz', check=False)),
        ('screw_from_transform', lambda m, v: rt.screw_from_transform(m, v[..., :3],
                                                                      check=False)),
        ('screw_log', lambda m, v: rt.screw_log(m, v[..., :3], check=False)),
        ('screw_interpolate', lambda m, v: rt.screw_interpolate(
            m, v[..., :3], I3, v[..., 3:6], v[..., 6], check=False)),
        ('decompose', lambda m, v: rt.decompose(m, v[..., :3], 'YXZ', check=False)),
        ('transform_points', lambda m, v: rt.transform_points(m, v[..., :3], v[..., :3],
                                                              check=False)),
        ('compose_transforms', lambda m, v: rt.compose_transforms(
            m, v[..., :3], m, v[..., :3], check=False)),
        ('invert_transform', lambda m, v: rt.invert_transform(m, v[..., :3], check=False)),
        ('transform_to_homogeneous', lambda m, v: rt.transform_to_homogeneous(
            m, v[..., :3], check=False)),
        ('homogeneous_to_transform', lambda m, v: rt.homogeneous_to_transform(
            h.homogeneous(m, v[..., :3]), check=False)),
        ('rotation_distance', lambda m, v: rt.rotation_distance(m, m, check=False)),
        ('mean_rotation', lambda m, v: rt.mean_rotation(
            np.stack([m, np.broadcast_to(I3, m.shape)], -3), check=False)),
        ('nearest_rotation', lambda m, v: rt.nearest_rotation(m)),
        ('is_rotation', lambda m, v: rt.is_rotation(m)),
        ('validate_rotation', lambda m, v: rt.validate_rotation(m)),
        ('matrix_to_rotvec checked', lambda m, v: rt.matrix_to_rotvec(m)),
        ('matrix_to_rodrigues checked', lambda m, v: rt.matrix_to_rodrigues(m)),
        ('matrix_to_euler checked', lambda m, v: rt.matrix_to_euler(m, 'XYZ')),
        ('align_vectors', lambda m, v: rt.align_vectors(
            m, v[..., :9].reshape(v.shape[:-1] + (3, 3)))),
        ('change_covariance_frame', lambda m, v: rt.change_covariance_frame(m, m)),
        ('rotvec_covariance_to_euler', lambda m, v: rt.rotvec_covariance_to_euler(m, m)),
        ('euler_covariance_to_rotvec', lambda m, v: rt.euler_covariance_to_rotvec(
            v[..., :3], m)),
        ('transform_pose_covariance', lambda m, v: rt.transform_pose_covariance(
            m, v[..., :3], _pose_covariance(m))),
        ('rotvec_to_matrix', lambda m, v: rt.rotvec_to_matrix(v[..., :3])),
        ('rodrigues_to_matrix', lambda m, v: rt.rodrigues_to_matrix(v[..., :3])),
        ('axis_angle_to_matrix', lambda m, v: rt.axis_angle_to_matrix(v[..., :3], v[..., 3])),
        ('quaternion_to_matrix', lambda m, v: rt.quaternion_to_matrix(v[..., :4])),
        ('screw_exp', lambda m, v: rt.screw_exp(v[..., :6])),
        ('transform_from_screw', lambda m, v: rt.transform_from_screw(
            v[..., :3], v[..., 3:6], v[..., 6], v[..., 7])),
        ('euler_to_matrix', lambda m, v: rt.euler_to_matrix(v[..., :3], 'ZYX')),
        ('frame_to_matrix', lambda m, v: rt.frame_to_matrix(v[..., :3], v[..., 3:6],
                                                            v[..., 6:9])),
        ('rot_x', lambda m, v: rt.rot_x(v[..., 0])),
        ('rot_y', lambda m, v: rt.rot_y(v[..., 1])),
        ('rot_z', lambda m, v: rt.rot_z(v[..., 2])),
        ('skew', lambda m, v: rt.skew(v[..., 3:6]))]


def test_the_sweep_of_extremes_calls_every_public_function():
    labels = {label.split()[0] for label, _ in _fail_alike_calls()}
    assert_sweeps_every_public_function(labels, NOT_ITEMS)


def _fail_outcome(call, m, v, batch=False):
    result = _outcome(call, m, v)
    if batch and _refused(result):
        return result[0], result[1].replace('at index (0, ', 'at index (').replace(
            'at index (0,)', 'at index ()')
    return result


def test_one_item_and_a_batch_fail_alike_for_every_public_function():
    # The same values (NaN and inf alike) or the same RotationError, never another exception.
    mats, vecs = _weird_items()
    differ = []
    for label, call in _fail_alike_calls():
        for i, (m, v) in enumerate(zip(mats, vecs)):
            with np.errstate(all='ignore'):
                one = _fail_outcome(call, m, v)
                batch = _fail_outcome(call, m[None], v[None], batch=True)
            same = one == batch if _refused(one) else _close(one, _item_of(batch, 0))
            if not same:
                differ.append((label, i, one, batch))
    assert not differ, differ[:3]


class _Three(NamedTuple):
    quotient: float
    root: float
    sine: float


def test_one_item_gives_what_a_batch_gives_where_float_arithmetic_would_raise():
    def kernel(ops, v):
        return _Three(quotient=v[0] / v[1], root=ops.sqrt(v[0]),
                      sine=ops.sin(v[2] * 1e308 * 10.0))
    outputs = _Three(quotient=engine.SCALAR, root=engine.SCALAR, sine=engine.SCALAR)
    item = np.array([-1.0, 0.0, 1.0])
    one = engine.apply(kernel, [(item, (3,), 'v', True)], outputs)
    batch = engine.apply(kernel, [(item[None], (3,), 'v', True)], outputs)
    assert type(one) is _Three and [type(x) for x in one] == [np.float64] * 3
    assert one.quotient == -math.inf and math.isnan(one.root) and math.isnan(one.sine)
    assert np.array_equal(np.array(one), np.array([x[0] for x in batch]), equal_nan=True)


def test_apply_to_one_gives_the_numbers_of_apply_as_python_numbers():
    # apply_to_one's Python floats are apply's numbers; a batch is refused.
    def kernel(ops, v):
        return _Three(quotient=v[0] / v[1], root=ops.sqrt(v[0]),
                      sine=ops.sin(v[2] * 1e308 * 10.0))
    outputs = _Three(quotient=engine.SCALAR, root=engine.SCALAR, sine=engine.SCALAR)
    for item in ([4.0, 2.0, 1e-310], [-1.0, 0.0, 1.0]):
        numpy = engine.apply(kernel, [(np.array(item), (3,), 'v', True)], outputs)
        for taken in (np.array(item), tuple(item), item):
            one = engine.apply_to_one(kernel, [(taken, (3,), 'v', True)], outputs)
            assert type(one) is _Three and [type(x) for x in one] == [float] * 3
            assert np.array_equal(np.array(one), np.array(numpy), equal_nan=True)
    with pytest.raises(rt.RotationError, match=r'one item only: v of shape \(3,\)'):
        engine.apply_to_one(kernel, [(np.ones((2, 3)), (3,), 'v', True)], outputs)
    with pytest.raises(rt.RotationError, match='v must be finite'):
        engine.apply_to_one(kernel, [((1.0, math.nan, 0.0), (3,), 'v', True)], outputs)


def _python_numbers(value):
    """Tell whether a result holds only Python floats and bools, in lists and NamedTuples."""
    if isinstance(value, (tuple, list)):
        return all(map(_python_numbers, value))
    return type(value) in (float, bool)


@pytest.mark.parametrize('seq', SEQUENCES)
def test_decompose_one_gives_the_numbers_of_decompose(seq):
    # rotation_node's decomposition: every field of decompose(check=False), bit for bit, as
    # Python numbers; the same refusal where the screw overflows float64.
    for R in ROTATIONS:
        for b in VECTORS:
            one = _outcome(lambda R, b: decompose_one(R, b, seq), R, b)
            arrays = _outcome(lambda R, b: rt.decompose(R, b, seq, check=False), R, b)
            if isinstance(arrays, tuple) and arrays[0] is rt.RotationError:
                assert one == arrays
                continue
            assert type(one) is type(arrays) and _python_numbers(one), one
            assert np.array(_leaves(one)).tobytes() == np.array(_leaves(arrays)).tobytes(), (
                R, b)
    with pytest.raises(rt.RotationError, match=r'one item only: R of shape \(3, 3\)'):
        decompose_one(np.array(ROTATIONS[:2]), VECTORS[1], seq)


def _leaves(result):
    """Return the numbers of a decomposition, in order, flat."""
    if isinstance(result, (tuple, list, np.ndarray)):
        return [x for part in result for x in _leaves(part)]
    return [float(result)]


class _Pose(NamedTuple):
    matrix: list
    vector: list
    scalar: float


class _Other(NamedTuple):
    matrix: list
    vector: list
    scalar: float


def test_outputs_come_back_in_the_kernels_named_tuple_by_name():
    # The kernel's NamedTuple, built by keyword in any order, comes back by name.
    def kernel(ops, m, a):
        return (_Pose(scalar=a * a, vector=[a, -a], matrix=[[m[0][0] * a, m[0][1]],
                                                            [m[1][0], m[1][1] + a]]),
                a > 2.5)
    outputs = (_Pose(matrix=engine.Spec((2, 2)), vector=engine.Spec((2,)),
                     scalar=engine.SCALAR), engine.FLAG)
    m = np.array([[1.0, 2.0], [3.0, 4.0]])

    def run(m, a):
        return engine.apply(kernel, [(m, (2, 2), 'm', True), (a, (), 'a', True)], outputs)
    (pose, flag) = run(m, 2.0)
    assert type(pose) is _Pose and type(flag) is np.bool_ and not flag
    assert pose.matrix.tolist() == [[2.0, 2.0], [3.0, 6.0]] and pose.vector.tolist() == [
        2.0, -2.0] and pose.scalar == 4.0 and type(pose.scalar) is np.float64
    pose, flag = run(np.stack([m, m]), np.array([2.0, 3.0]))
    assert pose.matrix.shape == (2, 2, 2) and pose.vector.shape == (2, 2)
    assert pose.matrix[1].tolist() == [[3.0, 2.0], [3.0, 7.0]]
    assert pose.scalar.tolist() == [4.0, 9.0] and flag.tolist() == [False, True]


@pytest.mark.parametrize('batch', [False, True])
def test_an_output_of_another_form_is_refused_not_misread(batch):
    # Another NamedTuple (even of the same fields), a plain tuple or a wrong shape: TypeError.
    outputs = _Pose(matrix=engine.Spec((2, 2)), vector=engine.Spec((2,)), scalar=engine.SCALAR)
    v = np.array([[1.0, 2.0]] * 2) if batch else np.array([1.0, 2.0])
    kernels = [lambda ops, v: _Other(matrix=[v, v], vector=v, scalar=v[0]),
               lambda ops, v: ([v, v], v, v[0]),
               lambda ops, v: _Pose(matrix=v, vector=[v, v], scalar=v[0]),
               lambda ops, v: _Pose(matrix=[v, v], vector=[v[0], v[1], v[0]], scalar=v[0])]
    for kernel in kernels:
        with pytest.raises(TypeError, match='kernel'):
            engine.apply(kernel, [(v, (2,), 'v', True)], outputs)


# -- one item and a batch of one: the same formula --------------------------------------------

ONE_ITEM = {
    'euler_to_matrix': lambda a, s: rt.euler_to_matrix(a, s),
    'matrix_to_euler': lambda R, s: rt.matrix_to_euler(R, s),
    'matrix_to_euler unchecked': lambda R, s: rt.matrix_to_euler(R, s, check=False),
    'matrix_to_axis_angle': lambda R, s: rt.matrix_to_axis_angle(R),
    'matrix_to_rotvec': lambda R, s: rt.matrix_to_rotvec(R),
    'matrix_to_quaternion': lambda R, s: rt.matrix_to_quaternion(R),
    'quaternion_to_matrix': lambda q, s: rt.quaternion_to_matrix(q),
    'axis_angle_to_matrix': lambda v, s: rt.axis_angle_to_matrix(v[:3], float(v[3])),
    'rotvec_to_matrix': lambda v, s: rt.rotvec_to_matrix(v),
}

_EDGE_ANGLES = [0.0, 5e-324, 1e-300, 1e-15, 1e-8, math.pi / 2, math.pi - 1e-12, math.pi - 1e-7,
                math.pi, -math.pi, 2.0]
_angle = st.one_of(st.sampled_from(_EDGE_ANGLES), st.floats(-4.0, 4.0))
_size = st.one_of(st.sampled_from([0.0, 5e-324, 1e-300, 1e-160, 1.0, 1e160, 1e300, 1.7e308]),
                  st.floats(0.0, 10.0))
_sequence = st.sampled_from(('ZYX', 'zyx', 'XYZ', 'ZXZ', 'yxy', 'XZY', 'zyz', 'yzx'))


def _long_enough(a):
    return 0.1 < math.hypot(*a)


def _first(pair):
    return pair[0]


# (named functions, not lambdas, in strategies: Hypothesis may look up a lambda's source for
# every example it draws)
@st.composite
def _axes(draw):
    axis = draw(st.tuples(*[st.floats(-1.0, 1.0)] * 3).filter(_long_enough))
    return np.array(axis) / np.linalg.norm(axis)


@st.composite
def _rotation(draw):
    """Draw a rotation: random axis and edge angles, or Euler angles at or near gimbal lock."""
    if draw(st.booleans()):
        return rt.axis_angle_to_matrix(draw(_axes()), draw(_angle))
    seq = draw(_sequence)
    lock = h.singular_values(seq)[draw(st.integers(0, 1))]
    near = draw(st.sampled_from([0.0, 1e-12, -1e-9, 1e-7, -1e-6, 2e-6, 1e-3]))
    middle = lock + near if abs(lock) > 1 or lock + near >= 0 else lock - near
    return rt.euler_to_matrix([draw(_angle), middle, draw(_angle)], seq)


def _same_as_batch(name, x, seq):
    """Compare the public function's result on one item with the batch formula's on [x]."""
    one = _outcome(ONE_ITEM[name], x, seq)
    batch = _outcome(ONE_ITEM[name], x[None], seq) if name != 'axis_angle_to_matrix' else \
        _outcome(rt.axis_angle_to_matrix, x[None, :3], x[None, 3])
    if isinstance(one, tuple) and one and one[0] is rt.RotationError:
        assert batch == one, (name, x)
    else:
        assert _close(one, _item_of(batch, 0)), (name, x, one, batch)


@settings(max_examples=150, deadline=None)
@given(rotation=_rotation(), seq=_sequence)
def test_one_item_from_a_matrix_gives_the_batch_formula(rotation, seq):
    for name in ('matrix_to_axis_angle', 'matrix_to_rotvec', 'matrix_to_quaternion'):
        _same_as_batch(name, rotation, seq)


def _wrapped_difference(a, b):
    """Return max |a − b| of angles, ±π and a hair inside counted as the same angle."""
    d = np.abs(np.asarray(a) - np.asarray(b))
    return float(np.minimum(d, 2 * math.pi - d).max())


@st.composite
def _euler_rotation(draw):
    """(R, seq): any of the 24 sequences, its middle angle at, or 1e-9..1e-5 from, a lock."""
    seq = draw(st.sampled_from(rt.EULER_SEQUENCES))
    lock = h.singular_values(seq)[draw(st.integers(0, 1))]
    near = draw(st.one_of(st.just(0.0), st.sampled_from([1e-9, 1e-7, 1e-6, 1e-5]),
                          st.floats(1e-9, 1e-5)))
    middle = lock - near if lock > 0 else lock + near  # (inside the range: θ2 is returned)
    if draw(st.integers(0, 3)) == 0:  # also rotations far from any lock
        middle = draw(st.floats(*h.middle_range(seq)))
    return rt.euler_to_matrix([draw(_angle), middle, draw(_angle)], seq), seq


_lock_tol = st.one_of(st.just(None), st.sampled_from([0.0, 1e-9, 1e-7, 1e-6, 1e-5, 1e-3]),
                      st.floats(0.0, 0.78))


@settings(max_examples=600, deadline=None)
@given(rotation=_euler_rotation(), lock_tol=_lock_tol, check=st.booleans())
@example(rotation=(rt.euler_to_matrix([0.4, h.PI / 2, -1.1], 'zyx'), 'zyx'), lock_tol=None,
         check=True)
@example(rotation=(rt.euler_to_matrix([2.0, 0.0, -1.1], 'XZX'), 'XZX'), lock_tol=0.0,
         check=False)
@example(rotation=(np.eye(3), 'ZYX'), lock_tol=None, check=True)  # (θ2 = atan2(−0.0, 1))
@example(rotation=(np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]]), 'ZYX'),
         lock_tol=0.0, check=True)  # (θ2 = π/2 exactly: locked at lock_tol 0)
@example(rotation=(np.diag([1.0, -1.0, -1.0]), 'zxz'), lock_tol=0.0, check=True)  # (θ2 = π)
def test_one_item_of_matrix_to_euler_gives_the_batch_formula(rotation, lock_tol, check):
    # One item (on floats) and a batch of one (on arrays): the same lock flag and angles.
    R, seq = rotation
    options = {'check': check} if lock_tol is None else {'check': check, 'lock_tol': lock_tol}
    angles, lock = rt.matrix_to_euler(R, seq, **options)
    angles_b, lock_b = rt.matrix_to_euler(R[None], seq, **options)
    assert type(angles) is np.ndarray and angles.shape == (3,) and type(lock) is np.bool_
    on_floats = euler.angles_kernel(engine.FLOATS, R.tolist(), euler.parse_sequence(seq),
                                    GIMBAL_LOCK_TOL if lock_tol is None else lock_tol)
    assert angles.tobytes() == np.array(on_floats.angles).tobytes(), on_floats
    assert lock == on_floats.degenerate
    if lock != lock_b[0]:  # θ2 a last bit from the lock's edge: libm's and NumPy's atan2 differ
        edge = (math.pi / 2 - abs(angles[1]) if seq.upper() in h.TAIT_BRYAN else
                min(angles[1], math.pi - angles[1]))
        assert abs(edge - (GIMBAL_LOCK_TOL if lock_tol is None else lock_tol)) <= 1e-15
        return
    assert _wrapped_difference(angles, angles_b[0]) <= 1e-15, (angles, angles_b[0])
    assert -math.pi < angles[0] <= math.pi and -math.pi < angles[2] <= math.pi
    if lock:
        assert angles[2] == 0.0


@settings(max_examples=150, deadline=None)
@given(a=st.tuples(_angle, _angle, _angle), seq=_sequence)
def test_one_item_of_euler_to_matrix_gives_the_batch_formula(a, seq):
    _same_as_batch('euler_to_matrix', np.array(a), seq)


@settings(max_examples=150, deadline=None)
@given(axis=_axes(), size=_size, angle=_angle)
@example(axis=np.array([0.0, 0.0, 1.0]), size=0.0, angle=0.0)
def test_one_item_to_a_matrix_gives_the_batch_formula(axis, size, angle):
    # (the fast path _plain_rodrigues for ordinary sizes, apply for the edges drawn here)
    v = axis * size
    _same_as_batch('rotvec_to_matrix', axis * (abs(angle) * min(size, 1.0)), None)
    _same_as_batch('quaternion_to_matrix', np.append(v, angle), None)
    _same_as_batch('axis_angle_to_matrix', np.append(v, angle), None)


@settings(max_examples=300, deadline=None)
@given(rotation=st.one_of(_rotation(), _euler_rotation().map(_first)), axis=_axes(),
       size=_size, seq=st.sampled_from(rt.EULER_SEQUENCES))
@example(rotation=np.eye(3), axis=np.array([1.0, 0.0, 0.0]), size=1e100, seq='ZYX')
@example(rotation=rt.axis_angle_to_matrix([0.0, 0.0, 1.0], 1e-12), axis=np.array([1.0, 0.0, 0.0]),
         size=1e100, seq='ZYX')
@example(rotation=rt.axis_angle_to_matrix([0.0, 0.0, 1.0], 1e-11), axis=np.array([1.0, 0.0, 0.0]),
         size=1e300, seq='zxz')  # (the screw overflows: refused)
@example(rotation=np.array([[-1.0, 0.0, 1.00021137e-12], [1.00021137e-18, 1.0, 1e-06],
                           [-1.00021137e-12, 1e-06, -1.0]]),
         axis=np.array([0.0, 0.0, 1.0]), size=0.0, seq='ZXZ')  # (θ2 at the lock's edge)
@example(rotation=np.array([[0.9364566872907963, -1.2246467991473532e-16, 0.35078322768961984],
                           [-1.1468286846308076e-16, -1.0, -4.295855569846701e-17],
                           [0.35078322768961984, 0.0, -0.9364566872907963]]),
         axis=np.array([0.0, 0.0, 1.0]), size=0.0, seq='XYX')  # (θ1 a last bit from −π)
def test_decompose_of_one_item_gives_the_batch_formula(rotation, axis, size, seq):
    # One item and a batch of one: the same numbers in every field, or the same refusal.
    b = axis * size
    one = _outcome(lambda R, b: rt.decompose(R, b, seq, check=False), rotation, b)
    batch = _outcome(lambda R, b: rt.decompose(R, b, seq, check=False), rotation[None], b[None])
    if isinstance(one, tuple) and one and one[0] is rt.RotationError:
        assert batch == one
        return
    for field in one._fields:
        a, c = getattr(one, field), _item_of(getattr(batch, field), 0)
        if field in ('euler', 'rpy', 'degenerate') and _same_angles(a, c):
            continue  # (outer angles a last bit from ±π may land on either side of the seam)
        if field in ('euler', 'rpy', 'degenerate'):
            # θ2 a last bit from the lock's edge: libm's and NumPy's atan2 differ there, and
            # one side takes the lock's form (θ3 = 0) where the other does not
            s, angles = (RPY_SEQUENCE, a) if field == 'rpy' else (seq, one.euler)
            edge = (math.pi / 2 - abs(angles[1]) if s.upper() in h.TAIT_BRYAN else
                    min(angles[1], math.pi - angles[1]))
            assert abs(edge - GIMBAL_LOCK_TOL) <= 1e-15, (field, a, c)
            continue
        assert _close(a, c), (field, a, c)


def _same_angles(a, c):
    """Equal flags, or angles equal to rounding (±π and a hair inside counted alike)."""
    if np.asarray(a).dtype == bool:
        return a == c
    return _wrapped_difference(a, c) <= 1e-15


CHECKED = [('validate_rotation', rt.validate_rotation),
           ('matrix_to_euler', lambda R: rt.matrix_to_euler(R, 'zxz')),
           ('matrix_to_quaternion', rt.matrix_to_quaternion),
           ('decompose', lambda R: rt.decompose(R, np.zeros(3)))]


def _takes(call, R):
    try:
        call(R)
    except rt.RotationError:
        return False
    return True


@settings(max_examples=200, deadline=None)
@given(rotation=_rotation(), entry=st.integers(0, 8),
       error=st.sampled_from([0.0, 1e-10, 9e-10, 1.1e-9, 1e-6, -2.0, math.nan]))
def test_checked_conversions_take_what_validate_rotation_takes(rotation, entry, error):
    # One item and a batch of one take exactly the matrices validate_rotation takes.
    R = rotation.copy()
    R.flat[entry] += error
    valid = _takes(rt.validate_rotation, R)
    for name, call in CHECKED:
        assert _takes(call, R) == _takes(call, R[None]) == valid, name


def _straddling_the_tolerance():
    """Matrices s·Q with s a few ulps either side of where their defect reaches ROTATION_TOL."""
    tol = so3.ROTATION_TOL
    out = []
    for q in [np.eye(3)] + ROTATIONS[::6]:
        for edge in (math.sqrt(1 + tol), math.sqrt(1 - tol), (1 + tol) ** (1 / 3),
                     (1 - tol) ** (1 / 3)):
            s = edge
            for _ in range(24):
                s = math.nextafter(s, 0.0)
            for _ in range(48):
                out.append(s * q)
                s = math.nextafter(s, 2.0)
    return out


def test_checked_conversions_take_what_validate_rotation_takes_at_the_tolerance():
    # A few floats either side of 1 ± tol: taken exactly where validate_rotation takes them.
    taken = []
    for R in _straddling_the_tolerance():
        valid = _takes(rt.validate_rotation, R)
        for name, call in CHECKED[1:]:
            assert _takes(call, R) == _takes(call, R[None]) == valid, (name, R)
        taken.append(valid)
    assert 0.2 < sum(taken) / len(taken) < 0.8  # (both sides of the edge were met)


def _at_the_edge(target):
    """Return [[c, −v, 0], [v, c, 0], [0, 0, 1]] with squared column norms and det ``target``."""
    for v in (0.0, 2.0 ** -27, math.sqrt(2.0 ** -53), 2.0 ** -26):
        c = math.sqrt(target)
        for _ in range(8):
            m = [[c, -v, 0.0], [v, c, 0.0], [0.0, 0.0, 1.0]]
            if c * c + v * v + 0.0 * 0.0 == target == so3.defects_kernel(engine.FLOATS, m).det:
                return np.array(m)
            c = math.nextafter(c, 0.0 if c * c > target else 2.0)
    raise AssertionError(f'no matrix found with squared norm {target!r}')


def test_the_rotation_check_takes_the_last_float_at_the_tolerance():
    # Columns' squared norms and det R exactly at 1 ∓ tol (the last float with |s − 1| ≤ tol:
    # taken) and one float beyond (refused), in each column (P·R·Pᵀ, P cyclic).
    tol = so3.ROTATION_TOL
    low, high = 1.0 - tol, 1.0 + tol
    low = low if 1.0 - low <= tol else math.nextafter(low, 2.0)
    high = high if high - 1.0 <= tol else math.nextafter(high, 0.0)
    shift = np.roll(np.eye(3), 1, axis=0)
    for target, valid in ((low, True), (high, True), (math.nextafter(low, 0.0), False),
                          (math.nextafter(high, 2.0), False)):
        R = _at_the_edge(target)
        for _ in range(3):
            for name, call in CHECKED:
                assert _takes(call, R) == _takes(call, R[None]) == valid, (name, target, R)
            R = shift @ R @ shift.T


# -- the public names and their results ----------------------------------------------------

def test_public_names_are_plain_module_attributes():
    # `import rot_tools` imports every public name from its module: no import hook.
    script = textwrap.dedent("""
        import rot_tools as rt
        assert '__getattr__' not in vars(rt) and set(rt.__all__) <= set(vars(rt))
        try:
            rt.no_such_name
        except AttributeError as exc:
            print('ok', exc)
    """)
    done = subprocess.run([sys.executable, '-c', script], capture_output=True, text=True,
                          timeout=120, cwd=REPO)
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith("ok module 'rot_tools' has no attribute 'no_such_name'")


def test_the_public_names_are_those_of_the_core_modules_all():
    # A public name is written once, in its core module's __all__; rot_tools imports them all.
    modules = [importlib.import_module('rot_tools.core.' + m.name)
               for m in pkgutil.iter_modules(rt.core.__path__)]
    assert sorted(rt.__all__) == sorted(
        name for module in modules for name in getattr(module, '__all__', ()))


def test_results_do_not_depend_on_call_history():
    R, b = ROTATIONS[5], VECTORS[1]
    calls = [lambda: rt.matrix_to_euler(R, 'zyx'), lambda: rt.matrix_to_axis_angle(R),
             lambda: rt.decompose(R, b, 'XYZ'), lambda: rt.screw_log(R, b),
             lambda: rt.euler_to_matrix([0.1, 0.2, 0.3]), lambda: rt.decompose(R, b),
             lambda: rt.quaternion_to_matrix((0.0, 0.0, 0.0, 0.0))]
    first = [repr(_outcome(c)) for c in calls]
    for _ in range(200):
        for c in calls:
            _outcome(c)
    assert [repr(_outcome(c)) for c in calls] == first


def test_inputs_of_any_layout_and_type_give_the_same_result():
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
    assert type(rt.matrix_to_axis_angle(expected)[1]) is np.float64
    assert rt.axis_angle_to_matrix([0, 0, 1], np.float64(0.5)).tobytes() == \
        rt.axis_angle_to_matrix([0, 0, 1], 0.5).tobytes()


def test_outputs_are_fresh_arrays_a_caller_may_change():
    R = ROTATIONS[4]
    first = rt.matrix_to_euler(R, 'ZYX')
    second = rt.matrix_to_euler(R, 'ZYX')
    first[0][0] = 99.0
    assert second[0][0] != 99.0
    assert rt.matrix_to_quaternion(R).flags.writeable


def test_outputs_are_arrays_and_scalars_of_the_declared_types():
    R = ROTATIONS[4]
    assert type(rt.matrix_to_euler(R, 'ZYX')[1]) is np.bool_
    d = rt.decompose(R, VECTORS[1], 'zyx')
    assert type(d.angle) is np.float64 and type(d.degenerate) is np.bool_
    assert all(type(x) is np.ndarray for x in (d.axis, d.rotvec, d.euler, d.rpy, d.twist))


def test_a_failing_conversion_traceback_names_the_kernel_line(monkeypatch):
    def broken(*args):
        raise RuntimeError('broken sqrt')
    monkeypatch.setattr(engine.FLOATS, 'sqrt', broken)
    with pytest.raises(RuntimeError) as info:
        rt.matrix_to_rotvec(ROTATIONS[4])
    frames = traceback.extract_tb(info.value.__traceback__)
    assert all(Path(f.filename).is_file() for f in frames), [f.filename for f in frames]
    assert any(f.filename.endswith('engine.py') and 'ops.sqrt(' in f.line for f in frames)
