"""TransformTree: lookups across a tree of frames, at any time, and its refusals."""

import math
from pathlib import Path
import re

from doc_blocks import assert_doc_output
from hypothesis import given, settings
from hypothesis import strategies as st
import math_helpers as h
import numpy as np
import pytest
import rot_tools
from rot_tools import RotationError, TransformLookupError, TransformTree, TransformTreeError
from scipy.linalg import expm, logm
from scipy.spatial.transform import Rotation

TOL = 1e-12  # products of a few 4×4 matrices, translations of order 1–10
INTERP_TOL = 1e-11  # against scipy's expm/logm of 4×4 matrices


def hom(R, b):
    """4×4 homogeneous matrix of p ↦ R·p + b."""
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = R, b
    return T


def random_transform(seed, scale=3.0):
    R = Rotation.random(random_state=seed).as_matrix()
    b = np.random.default_rng(seed).normal(size=3) * scale
    return R, b


def ref_interpolate(T0, T1, s):
    """Return the constant-screw motion by scipy's matrix exponential and logarithm."""
    return T0 @ expm(s * np.real(logm(np.linalg.inv(T0) @ T1)))


def ref_pose(edges, frame):
    """T_root_frame: the product of the edges' 4×4 matrices from the root down to frame."""
    T = np.eye(4)
    while frame in edges:
        parent, T_edge = edges[frame]
        T = T_edge @ T
        frame = parent
    return T


def ref_lookup(edges, reference, body):
    """T_reference_body = T_root_reference⁻¹ · T_root_body (both frames in one tree)."""
    return np.linalg.inv(ref_pose(edges, reference)) @ ref_pose(edges, body)


def assert_transform(result, T, tol=TOL):
    R, b = result[0], result[1]
    assert h.max_abs(R - T[..., :3, :3]) <= tol
    assert h.max_abs(b - T[..., :3, 3]) <= tol * (1 + h.max_abs(T[..., :3, 3]))


# A tree:        map
#                 |  (static)
#                odom
#                 |  (dynamic)
#               base_link
#               /         \  (static)
#          camera        lidar
#             |  (dynamic)
#          optical
STATIC = {'odom': 'map', 'camera': 'base_link', 'lidar': 'base_link'}
DYNAMIC = {'base_link': 'odom', 'optical': 'camera'}
FRAMES = ('map', 'odom', 'base_link', 'camera', 'lidar', 'optical')


def motion(child, t):
    """Return a smooth made-up motion of each dynamic edge (the samples' values at time t)."""
    seed = FRAMES.index(child)
    R0, b0 = random_transform(seed)
    R = R0 @ h.ref_elementary('z', 0.4 * t) @ h.ref_elementary('x', 0.1 * t * (seed + 1))
    return R, b0 + np.array([0.5 * t, np.sin(t), 0.1 * t * t])


def make_tree(stamps=np.arange(0.0, 5.01, 0.5), **kwargs):
    """Return the tree above, its dynamic edges sampled at ``stamps``; returns (tree, statics)."""
    tree = TransformTree(**kwargs)
    statics = {}
    for i, (child, parent) in enumerate(sorted(STATIC.items())):
        R, b = random_transform(100 + i)
        statics[child] = (parent, hom(R, b))
        tree.set_transform(parent, child, R, b, 0.25, static=True)
    for child, parent in DYNAMIC.items():
        for t in stamps:
            tree.set_transform(parent, child, *motion(child, t), t)
    return tree, statics


def ref_edges_at(statics, t, stamps):
    """Return every edge's reference 4×4 at time t, dynamic ones by T0·expm(s·logm(T0⁻¹T1))."""
    edges = dict(statics)
    for child, parent in DYNAMIC.items():
        i = int(np.searchsorted(stamps, t))
        if stamps[i] == t:
            T = hom(*motion(child, t))
        else:
            t0, t1 = stamps[i - 1], stamps[i]
            T = ref_interpolate(hom(*motion(child, t0)), hom(*motion(child, t1)),
                                (t - t0) / (t1 - t0))
        edges[child] = (parent, T)
    return edges


STAMPS = np.arange(0.0, 5.01, 0.5)


# Exports and the shape of the tree


def test_exported_with_errors_that_are_rotation_errors():
    assert rot_tools.TransformTree is TransformTree
    assert issubclass(TransformLookupError, TransformTreeError)
    assert issubclass(TransformTreeError, RotationError)
    assert issubclass(TransformLookupError, ValueError)
    assert {'TransformTree', 'TransformLookupError', 'TransformTreeError'} <= set(
        rot_tools.__all__)


def test_chain_up_down_and_across_through_the_common_ancestor():
    tree, _ = make_tree()
    assert tree.chain('map', 'optical') == ['map', 'odom', 'base_link', 'camera', 'optical']
    assert tree.chain('optical', 'map') == ['optical', 'camera', 'base_link', 'odom', 'map']
    assert tree.chain('lidar', 'optical') == ['lidar', 'base_link', 'camera', 'optical']
    assert tree.chain('camera', 'camera') == ['camera']
    assert tree.frames == sorted(FRAMES)
    assert tree.parent('optical') == 'camera'
    assert tree.parent('map') is None


# Lookups against products of 4×4 matrices


def test_static_tree_every_pair_against_4x4_products():
    tree = TransformTree()
    edges = {}
    for i, (child, parent) in enumerate([('b', 'a'), ('c', 'b'), ('d', 'b'), ('e', 'd'),
                                         ('f', 'a')]):
        R, b = random_transform(i)
        edges[child] = (parent, hom(R, b))
        tree.set_transform(parent, child, R, b, 1.0 + i, static=True)
    for reference in 'abcdef':
        for body in 'abcdef':
            result = tree.lookup(reference, body)
            assert_transform(result, ref_lookup(edges, reference, body))
            # Any time: static edges hold at every time, and the stamp asked is echoed.
            at = tree.lookup(reference, body, -123.5)
            assert_transform(at, ref_lookup(edges, reference, body))
            assert at[2] == -123.5


@pytest.mark.parametrize('reference, body', [
    ('map', 'optical'), ('optical', 'map'), ('lidar', 'optical'), ('optical', 'lidar'),
    ('odom', 'camera'), ('base_link', 'base_link'), ('camera', 'odom')])
@pytest.mark.parametrize('t', [0.0, 0.5, 1.7, 2.25, 3.999, 5.0])
def test_static_and_dynamic_mix_at_a_time_against_products_and_expm(reference, body, t):
    tree, statics = make_tree()
    R, b, stamp = tree.lookup(reference, body, t)
    assert stamp == t and isinstance(stamp, float)
    assert R.shape == (3, 3) and b.shape == (3,)
    expected = ref_lookup(ref_edges_at(statics, t, STAMPS), reference, body)
    assert_transform((R, b), expected, INTERP_TOL)


def test_a_sample_stamp_gives_the_sample_exactly():
    tree, _ = make_tree()
    R, b = motion('base_link', 1.5)
    got = tree.lookup('odom', 'base_link', 1.5)
    assert np.array_equal(got[0], R) and np.array_equal(got[1], b)


def test_interpolation_is_the_constant_screw_motion_not_lerp_and_slerp():
    # A quarter turn about z with the child 1 m off the axis: half-way, the screw motion
    # keeps the child on the circle of radius 1 about the axis (tf2's lerp would put it at
    # distance cos 45° from it).
    tree = TransformTree()
    tree.set_transform('world', 'arm', np.eye(3), [1.0, 0.0, 0.0], 0.0)
    tree.set_transform('world', 'arm', h.ref_elementary('z', np.pi / 2), [0.0, 1.0, 0.0], 1.0)
    R, b, _ = tree.lookup('world', 'arm', 0.5)
    assert h.max_abs(R - h.ref_elementary('z', np.pi / 4)) <= TOL
    assert h.max_abs(b - [np.cos(np.pi / 4), np.sin(np.pi / 4), 0.0]) <= TOL


@settings(**h.HYPOTHESIS_SETTINGS)
@given(seed=st.integers(0, 2**31 - 1), s=st.floats(0.0, 1.0), gap=st.floats(1e-3, 1e3),
       angle=st.floats(0.0, 3.0), start=st.floats(-1e4, 1e4))
def test_one_edge_between_two_samples_against_expm_logm(seed, s, gap, angle, start):
    R0, b0 = random_transform(seed)
    rng = np.random.default_rng(seed)
    axis = rng.normal(size=3)
    step = Rotation.from_rotvec(angle * axis / np.linalg.norm(axis)).as_matrix()
    R1, b1 = R0 @ step, b0 + rng.normal(size=3)
    tree = TransformTree(cache_seconds=2e3)
    end = start + gap  # the stamps as floats hold them: s is measured between those
    tree.set_transform('p', 'c', R0, b0, start)
    tree.set_transform('p', 'c', R1, b1, end)
    t = min(max(start + s * gap, start), end)
    expected = ref_interpolate(hom(R0, b0), hom(R1, b1), (t - start) / (end - start))
    assert_transform(tree.lookup('p', 'c', t), expected, INTERP_TOL)
    # And the same edge walked down: the inverse.
    assert_transform(tree.lookup('c', 'p', t), np.linalg.inv(expected), INTERP_TOL)


@settings(**h.HYPOTHESIS_SETTINGS)
@given(parents=st.lists(st.integers(0, 100), min_size=1, max_size=8),
       pair=st.tuples(st.integers(0, 8), st.integers(0, 8)), seed=st.integers(0, 10**6))
def test_random_trees_against_4x4_products(parents, pair, seed):
    # Frame k + 1 hangs from one of the frames 0..k: every tree shape, every pair.
    tree, edges = TransformTree(), {}
    for k, p in enumerate(parents):
        parent, child = f'f{p % (k + 1)}', f'f{k + 1}'
        R, b = random_transform(seed + k)
        edges[child] = (parent, hom(R, b))
        tree.set_transform(parent, child, R, b, 0.0, static=bool(k % 2))
    reference, body = (f'f{i % (len(parents) + 1)}' for i in pair)
    got = tree.lookup(reference, body)
    assert_transform(got, ref_lookup(edges, reference, body))
    back = tree.lookup(body, reference)
    product = hom(*got[:2]) @ hom(*back[:2])
    assert h.max_abs(product - np.eye(4)) <= 1e-11


# Batches of stamps


def test_a_batch_of_stamps_equals_one_lookup_per_stamp():
    tree, statics = make_tree()
    times = np.array([[0.0, 0.3, 1.0], [2.71, 4.99, 5.0]])
    R, b, stamps = tree.lookup('lidar', 'optical', times)
    assert R.shape == (2, 3, 3, 3) and b.shape == (2, 3, 3) and stamps.shape == (2, 3)
    assert np.array_equal(stamps, times)
    for index in np.ndindex(times.shape):
        one = tree.lookup('lidar', 'optical', float(times[index]))
        assert h.max_abs(R[index] - one[0]) <= 1e-14
        assert h.max_abs(b[index] - one[1]) <= 1e-14
        expected = ref_lookup(ref_edges_at(statics, times[index], STAMPS), 'lidar', 'optical')
        assert_transform((R[index], b[index]), expected, INTERP_TOL)


def test_a_batch_of_samples_equals_one_sample_at_a_time():
    one, _ = make_tree()
    many = TransformTree()
    for i, (child, parent) in enumerate(sorted(STATIC.items())):
        many.set_transform(parent, child, *random_transform(100 + i), 0.25, static=True)
    for child, parent in DYNAMIC.items():
        values = [motion(child, t) for t in STAMPS[::-1]]  # given in reverse order
        stored = many.set_transform(parent, child, np.array([v[0] for v in values]),
                                    np.array([v[1] for v in values]), STAMPS[::-1])
        assert stored == len(STAMPS)
    times = np.linspace(0.0, 5.0, 17)
    a, b = one.lookup('map', 'optical', times), many.lookup('map', 'optical', times)
    assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])
    # At equal stamps the last sample given wins, within a batch and over stored samples.
    R = np.stack([h.ref_elementary('z', a) for a in (0.1, 0.2, 0.3)])
    b = np.array([[1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [3.0, 0.0, 0.0]])
    assert many.set_transform('odom', 'base_link', R, b, [1.0, 1.0, 2.0]) == 2
    for t, k in [(1.0, 1), (2.0, 2)]:
        got = many.lookup('odom', 'base_link', t)
        assert np.array_equal(got[0], R[k]) and np.array_equal(got[1], b[k])


# Time: the latest common time, extrapolation, the cache


def test_latest_common_time_is_the_oldest_newest_stamp_of_the_dynamic_edges():
    tree, statics = make_tree()
    tree.set_transform('camera', 'optical', *motion('optical', 5.5), 5.5)  # optical ahead
    assert tree.latest_common_time('map', 'optical') == 5.0  # base_link's newest
    R, b, stamp = tree.lookup('map', 'optical')
    assert stamp == 5.0
    stamps = {'base_link': STAMPS, 'optical': np.append(STAMPS, 5.5)}
    edges = dict(statics)
    for child, parent in DYNAMIC.items():
        t0, t1 = (5.0, 5.0) if child == 'base_link' else (5.0, 5.5)
        edges[child] = (parent, hom(*motion(child, t0)))
    assert stamps and t1  # the interpolation at 5.0 is the sample at 5.0 for both edges
    assert_transform((R, b), ref_lookup(edges, 'map', 'optical'))
    # Only the chain's edges count: optical is not on the chain lidar → odom.
    assert tree.latest_common_time('lidar', 'odom') == 5.0
    assert tree.lookup('camera', 'optical')[2] == 5.5
    assert tree.time_range('map', 'optical') == (0.0, 5.0)


def test_latest_time_of_a_static_chain_and_of_a_frame_in_itself():
    tree, _ = make_tree()
    tree.set_transform('map', 'marker', np.eye(3), [1.0, 2.0, 3.0], 7.5, static=True)
    # All-static chain: the newest stamp its static edges were set with.
    assert tree.lookup('odom', 'marker')[2] == 7.5
    assert tree.lookup('marker', 'map')[2] == 7.5
    assert tree.time_range('odom', 'marker') == (-math.inf, math.inf)
    # A frame in itself: the identity, at the newest stamp of its own edge (0 for a root).
    R, b, stamp = tree.lookup('base_link', 'base_link')
    assert np.array_equal(R, np.eye(3)) and np.array_equal(b, np.zeros(3)) and stamp == 5.0
    assert tree.lookup('map', 'map')[2] == 0.0
    assert tree.lookup('lidar', 'lidar')[2] == 0.25


def assert_extrapolation(excinfo, edge, seconds):
    exc = excinfo.value
    assert exc.reason == 'extrapolation'
    assert exc.edge == edge
    assert exc.seconds == pytest.approx(seconds, abs=1e-9)
    text = str(exc)
    assert repr(edge[0]) in text and repr(edge[1]) in text
    assert h.mentions_magnitude(text, seconds, 1.0001)


@pytest.mark.parametrize('t, seconds, side', [
    (5.75, 0.75, 'after the newest'), (-0.125, 0.125, 'before the oldest'),
    (1e4, 1e4 - 5.0, 'after the newest')])
def test_extrapolation_both_sides_names_the_edge_and_the_seconds(t, seconds, side):
    tree, _ = make_tree()
    with pytest.raises(TransformLookupError, match=side) as excinfo:
        tree.lookup('map', 'base_link', t)
    assert_extrapolation(excinfo, ('odom', 'base_link'), seconds)
    # A batch with one stamp out of range is refused by its worst stamp.
    with pytest.raises(TransformLookupError) as excinfo:
        tree.lookup('map', 'base_link', [1.0, t, 2.0])
    assert_extrapolation(excinfo, ('odom', 'base_link'), seconds)


def test_latest_common_time_out_of_another_edges_cache_is_extrapolation():
    tree = TransformTree(cache_seconds=2.0)
    for t in np.arange(0.0, 10.01, 0.5):
        tree.set_transform('a', 'b', np.eye(3), [t, 0.0, 0.0], t)
    tree.set_transform('b', 'c', np.eye(3), [0.0, 1.0, 0.0], 3.0)  # stopped at 3.0
    # The common time is 3.0, but a→b only holds 8.0..10.0 by now: 5 s before its data.
    with pytest.raises(TransformLookupError) as excinfo:
        tree.lookup('a', 'c')
    assert_extrapolation(excinfo, ('a', 'b'), 5.0)


def test_a_dynamic_edge_with_one_sample_answers_only_at_its_stamp():
    tree = TransformTree()
    R, b = random_transform(7)
    tree.set_transform('a', 'b', R, b, 2.0)
    got = tree.lookup('a', 'b', 2.0)
    assert np.array_equal(got[0], R) and np.array_equal(got[1], b)
    assert tree.lookup('a', 'b')[2] == 2.0
    with pytest.raises(TransformLookupError, match='one sample') as excinfo:
        tree.lookup('a', 'b', 2.5)
    assert_extrapolation(excinfo, ('a', 'b'), 0.5)


def test_cache_expiry_keeps_the_last_cache_seconds():
    tree = TransformTree(cache_seconds=1.0)
    for k in range(400):  # more than the arrays' first capacity: they grow and slide
        t = 0.01 * k
        tree.set_transform('a', 'b', h.ref_elementary('z', t), [t, 0.0, 0.0], t)
    newest = 0.01 * 399
    first, last = tree.time_range('a', 'b')
    assert last == newest and newest - 1.0 <= first <= newest - 1.0 + 0.01
    with pytest.raises(TransformLookupError) as excinfo:
        tree.lookup('a', 'b', newest - 1.5)
    assert_extrapolation(excinfo, ('a', 'b'), first - (newest - 1.5))
    # Inside the window every sample is still exact.
    for k in range(300, 400):
        R, b, _ = tree.lookup('a', 'b', 0.01 * k)
        assert np.array_equal(b, [0.01 * k, 0.0, 0.0])
        assert np.array_equal(R, h.ref_elementary('z', 0.01 * k))
    # Data older than the window is not stored.
    assert tree.set_transform('a', 'b', np.eye(3), [0.0, 0.0, 0.0], 0.5) == 0
    assert tree.time_range('a', 'b') == (first, last)


def test_the_sample_count_is_capped_keeping_the_newest():
    tree = TransformTree(cache_seconds=math.inf, max_samples=50)
    for k in range(1000):
        tree.set_transform('a', 'b', np.eye(3), [k, 0.0, 0.0], float(k))
    assert tree.time_range('a', 'b') == (950.0, 999.0)
    many = TransformTree(cache_seconds=math.inf, max_samples=50)
    stamps = np.arange(1000.0)
    assert many.set_transform('a', 'b', np.broadcast_to(np.eye(3), (1000, 3, 3)),
                              np.stack([stamps, 0 * stamps, 0 * stamps], -1), stamps) == 50
    assert many.time_range('a', 'b') == (950.0, 999.0)


def test_the_frame_count_is_capped():
    tree = TransformTree(max_frames=4)
    tree.set_transform('a', 'b', np.eye(3), [0.0, 0.0, 0.0], 0.0)
    tree.set_transform('b', 'c', np.eye(3), [0.0, 0.0, 0.0], 0.0, static=True)
    with pytest.raises(TransformTreeError, match='max_frames = 4') as excinfo:
        tree.set_transform('x', 'y', np.eye(3), [0.0, 0.0, 0.0], 0.0)  # two more: 5
    assert excinfo.value.reason == 'too_many_frames'
    assert tree.frames == ['a', 'b', 'c']
    tree.set_transform('c', 'd', np.eye(3), [0.0, 0.0, 0.0], 0.0)  # the fourth
    tree.set_transform('a', 'c', np.eye(3), [0.0, 0.0, 0.0], 1.0)  # re-parented: no new frame
    with pytest.raises(TransformTreeError, match='too_many_frames|max_frames'):
        tree.set_transform('d', 'e', np.eye(3), [0.0, 0.0, 0.0], 0.0)
    with pytest.raises(RotationError, match='max_frames'):
        TransformTree(max_frames=1)


def test_samples_out_of_order_and_repeated_stamps():
    in_order, shuffled = TransformTree(), TransformTree()
    stamps = np.arange(0.0, 3.0, 0.1)
    for t in stamps:
        in_order.set_transform('a', 'b', *motion('base_link', t), t)
    for t in np.random.default_rng(3).permutation(stamps):
        shuffled.set_transform('a', 'b', *motion('optical', t), t)  # wrong values first
    for t in np.random.default_rng(4).permutation(stamps):
        assert shuffled.set_transform('a', 'b', *motion('base_link', t), t) == 1  # replaced
    times = np.linspace(0.0, 2.9, 23)
    a, b = in_order.lookup('a', 'b', times), shuffled.lookup('a', 'b', times)
    assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])


# Refusals


def test_unknown_frame():
    tree, _ = make_tree()
    for reference, body in [('map', 'nowhere'), ('nowhere', 'map'), ('', 'map')]:
        with pytest.raises(TransformLookupError, match="'nowhere'|''") as excinfo:
            tree.lookup(reference, body)
        assert excinfo.value.reason == 'unknown_frame'
        assert excinfo.value.edge is None and excinfo.value.seconds is None
    with pytest.raises(TransformLookupError, match='unknown'):
        tree.chain('map', 'nowhere')
    with pytest.raises(TransformLookupError, match='unknown'):
        TransformTree().lookup('a', 'a')


def test_frames_in_two_trees_are_not_connected():
    tree, _ = make_tree()
    tree.set_transform('moon', 'rover', np.eye(3), [0.0, 0.0, 0.0], 1.0, static=True)
    for reference, body in [('optical', 'rover'), ('moon', 'map')]:
        with pytest.raises(TransformLookupError, match='not connected') as excinfo:
            tree.lookup(reference, body)
        assert excinfo.value.reason == 'not_connected'
        assert 'moon' in str(excinfo.value) and 'map' in str(excinfo.value)
    with pytest.raises(TransformLookupError):
        tree.time_range('rover', 'lidar')


@pytest.mark.parametrize('parent, child', [('optical', 'map'), ('optical', 'base_link'),
                                           ('camera', 'camera'), ('lidar', 'odom')])
def test_a_loop_is_refused_and_the_tree_is_unchanged(parent, child):
    tree, _ = make_tree()
    before = {f: tree.parent(f) for f in FRAMES}
    lookup = tree.lookup('map', 'optical', 2.2)
    with pytest.raises(TransformTreeError, match='loop') as excinfo:
        tree.set_transform(parent, child, np.eye(3), [0.0, 0.0, 0.0], 2.0, static=True)
    assert excinfo.value.reason == 'loop'
    assert repr(child) in str(excinfo.value)
    assert {f: tree.parent(f) for f in FRAMES} == before
    again = tree.lookup('map', 'optical', 2.2)
    assert np.array_equal(again[0], lookup[0]) and np.array_equal(again[1], lookup[1])


def test_a_frame_re_parented_replaces_its_old_edge():
    tree, statics = make_tree()
    R, b = random_transform(42)
    tree.set_transform('lidar', 'camera', R, b, 1.0, static=True)  # camera moves under lidar
    assert tree.parent('camera') == 'lidar'
    assert tree.chain('base_link', 'optical') == ['base_link', 'lidar', 'camera', 'optical']
    edges = ref_edges_at(statics, 2.5, STAMPS)
    edges['camera'] = ('lidar', hom(R, b))
    assert_transform(tree.lookup('map', 'optical', 2.5),
                     ref_lookup(edges, 'map', 'optical'), INTERP_TOL)
    # A dynamic edge re-parented forgets the old parent's samples.
    tree.set_transform('map', 'base_link', np.eye(3), [1.0, 2.0, 3.0], 9.0)
    assert tree.chain('odom', 'base_link') == ['odom', 'map', 'base_link']
    assert tree.time_range('map', 'base_link') == (9.0, 9.0)
    # A static edge turned dynamic (same parent) replaces it too.
    tree.set_transform('base_link', 'lidar', np.eye(3), [0.0, 0.0, 1.0], 3.0)
    with pytest.raises(TransformLookupError, match='before the oldest') as excinfo:
        tree.lookup('base_link', 'lidar', 2.0)
    assert_extrapolation(excinfo, ('base_link', 'lidar'), 1.0)


@pytest.mark.parametrize('R, b, stamp, what', [
    (np.full((3, 3), np.nan), [0.0, 0.0, 0.0], 1.0, 'R'),
    (np.eye(3), [0.0, np.inf, 0.0], 1.0, 'translation b'),
    (np.eye(3), [0.0, 0.0, 0.0], math.nan, 'stamp'),
    (np.eye(3), [0.0, 0.0, 0.0], -math.inf, 'stamp')])
@pytest.mark.parametrize('static', [False, True])
def test_nan_and_inf_are_refused(R, b, stamp, what, static):
    tree, _ = make_tree()
    with pytest.raises(TransformTreeError, match=re.escape(what)) as excinfo:
        tree.set_transform('odom', 'base_link', R, b, stamp, static=static)
    assert excinfo.value.reason == 'non_finite'
    assert tree.time_range('odom', 'base_link') == (0.0, 5.0)


REFUSED_EDGES = {
    'scaled R': ('a', 'b', 1.001 * np.eye(3), [0, 0, 0], 0.0, 'not_rotation', 'not orthogonal'),
    'reflection': ('a', 'b', -np.eye(3), [0, 0, 0], 0.0, 'not_rotation', 'reflection'),
    'empty parent': ('', 'b', np.eye(3), [0, 0, 0], 0.0, 'bad_frame', 'non-empty string'),
    'empty child': ('a', '', np.eye(3), [0, 0, 0], 0.0, 'bad_frame', 'non-empty string'),
    'no parent': (None, 'b', np.eye(3), [0, 0, 0], 0.0, 'bad_frame', 'non-empty string'),
    'a number child': ('a', 3, np.eye(3), [0, 0, 0], 0.0, 'bad_frame', 'non-empty string'),
    'a 4×4 R': ('a', 'b', np.eye(4), [0, 0, 0], 0.0, 'bad_value', None),
    'two entries in b': ('a', 'b', np.eye(3), [0, 0], 0.0, 'bad_value', None),
    'two stamps': ('a', 'b', np.eye(3), [0, 0, 0], [0.0, 1.0], 'bad_value', None),
    'a word for a stamp': ('a', 'b', np.eye(3), [0, 0, 0], 'now', 'bad_value', None),
    'two static transforms': ('a', 'b', np.stack([np.eye(3)] * 2), np.zeros((2, 3)), [0.0, 1.0],
                              'bad_value', 'static edge takes one'),
}
"""set_transform(parent, child, R, b, stamp) refused, its reason and message."""


@pytest.mark.parametrize('case', REFUSED_EDGES)
def test_an_edge_that_is_not_a_transform_is_refused_and_the_tree_stays_empty(case):
    parent, child, R, b, stamp, reason, message = REFUSED_EDGES[case]
    tree = TransformTree()
    with pytest.raises(TransformTreeError, match=message) as excinfo:
        tree.set_transform(parent, child, R, b, stamp, static=case == 'two static transforms')
    assert excinfo.value.reason == reason
    assert tree.frames == []


@pytest.mark.parametrize('options, message', [
    ({'cache_seconds': 0.0}, 'cache_seconds'), ({'cache_seconds': -1.0}, 'cache_seconds'),
    ({'cache_seconds': math.nan}, 'cache_seconds'), ({'cache_seconds': 'ten'}, 'cache_seconds'),
    ({'max_samples': 1}, 'max_samples')])
def test_a_tree_refuses_a_bad_cache(options, message):
    with pytest.raises(RotationError, match=message):
        TransformTree(**options)


def test_a_lookup_at_a_non_finite_stamp_is_refused():
    tree, _ = make_tree()
    with pytest.raises(RotationError, match='finite'):
        tree.lookup('map', 'optical', math.nan)


def test_values_numpy_cannot_take_are_rotation_errors():
    # A Python int beyond float64, an empty batch of stamps, batch shapes that do not
    # broadcast: each a RotationError saying what, never NumPy's or Python's own exception.
    with pytest.raises(RotationError, match="cache_seconds is beyond float64's range"):
        TransformTree(cache_seconds=10**400)
    tree, _ = make_tree()
    for empty in (np.empty(0), np.empty((2, 0))):
        with pytest.raises(RotationError, match=re.escape(f'empty (shape {empty.shape})')):
            tree.lookup('map', 'optical', empty)
    R = np.broadcast_to(np.eye(3), (2, 3, 3))
    with pytest.raises(RotationError, match=r'do not broadcast together: \(2,\), \(2,\), '
                                            r'\(3,\), \(3,\), \(\)'):
        rot_tools.screw_interpolate(R, np.zeros((2, 3)), np.broadcast_to(np.eye(3), (3, 3, 3)),
                                    np.zeros((3, 3)), 0.5)
    with pytest.raises(RotationError, match='do not broadcast'):  # two items, three fractions
        rot_tools.screw_interpolate(R, np.zeros((2, 3)), np.eye(3), np.ones(3), [0.1, 0.2, 0.3])


def test_long_frame_names_are_refused_and_every_message_shows_names_cut_short():
    tree = TransformTree()
    long_name = 'x' * 10**6
    with pytest.raises(TransformTreeError) as excinfo:
        tree.set_transform('odom', long_name, np.eye(3), np.zeros(3), 0.0)
    assert excinfo.value.reason == 'bad_frame'
    assert 'has 1,000,000 characters, at most MAX_FRAME_NAME = 256' in str(excinfo.value)
    assert len(str(excinfo.value)) < 200
    # Names at the limit are taken; the unknown-frame message lists 20 of them, each cut.
    for k in range(30):
        tree.set_transform('odom', f'{k:03d}' + 'y' * 253, np.eye(3), np.zeros(3), 0.0)
    with pytest.raises(TransformLookupError, match='unknown') as excinfo:
        tree.lookup('odom', 'z' * 256)
    text = str(excinfo.value)
    assert len(text) < 20 * 45 + 100 and text.count('…') == 21
    with pytest.raises(TransformTreeError, match='loop') as excinfo:
        tree.set_transform('000' + 'y' * 253, 'odom', np.eye(3), np.zeros(3), 0.0)
    assert len(str(excinfo.value)) < 300


def test_a_forgotten_frame_is_unknown_and_frees_its_place():
    tree = TransformTree(max_frames=4)
    tree.set_transform('a', 'b', np.eye(3), np.zeros(3), 0.0)
    tree.set_transform('b', 'c', np.eye(3), np.zeros(3), 0.0)
    tree.set_transform('a', 'd', np.eye(3), np.zeros(3), 0.0, static=True)
    with pytest.raises(TransformTreeError, match='max_frames'):
        tree.set_transform('a', 'e', np.eye(3), np.zeros(3), 0.0)
    tree.forget('b')  # b still names c's parent: it stays, as a root
    assert tree.frames == ['a', 'b', 'c', 'd'] and tree.parent('b') is None
    tree.forget('c')  # now b and c are named by no edge
    assert tree.frames == ['a', 'd']
    with pytest.raises(TransformLookupError) as excinfo:
        tree.lookup('a', 'c')
    assert excinfo.value.reason == 'unknown_frame'
    tree.set_transform('a', 'e', np.eye(3), np.zeros(3), 0.0)
    tree.forget('nowhere')  # nothing to forget: nothing happens
    tree.forget('d')
    assert tree.frames == ['a', 'e']


def test_an_edges_memory_is_bounded_by_max_samples_and_given_back():
    import tracemalloc
    tree = TransformTree(cache_seconds=10.0, max_samples=10_000)
    tracemalloc.start()
    try:
        for k in range(12_000):  # 1 kHz for 12 s: the newest 10,000 kept
            tree.set_transform('a', 'b', np.eye(3), np.zeros(3), k * 1e-3)
        full = tracemalloc.get_traced_memory()[0]
        # 104 bytes a sample (stamp, R, b): at most max_samples + 1 of them, not 16,384.
        assert full <= 10_001 * 104 + 20_000
        for k in range(20):  # then 1 Hz: 10 samples in the window
            tree.set_transform('a', 'b', np.eye(3), np.zeros(3), 12.0 + k)
        assert tracemalloc.get_traced_memory()[0] <= 20_000
    finally:
        tracemalloc.stop()
    assert tree.time_range('a', 'b') == (21.0, 31.0)


# The user documentation's example


def test_the_example_of_doc_tf_md_prints_what_the_page_shows(capsys):
    page = (Path(__file__).resolve().parents[1] / 'doc' / 'tf.md').read_text(encoding='utf-8')
    example = page[page.index('### Example'):]
    code = re.search(r'```python\n(.*?)```', example, re.S).group(1)
    exec(compile(code, 'doc/tf.md', 'exec'), {})
    assert_doc_output('tf-tree-example', capsys.readouterr().out)


# A recording followed through the tree


def recording(samples):
    """Return Transforms of samples [(parent, child, R, b, stamp, static)], as recorded."""
    from rot_tools.core.transform_tree import Transforms
    parent, child, R, b, stamp, static = zip(*samples)
    return Transforms(list(parent), list(child), np.array(R), np.array(b), np.array(stamp),
                      np.array(static))


def test_follow_looks_up_at_every_stamp_of_the_dynamic_edges():
    """Two dynamic edges sampled at different times and a static one: every stamp of both."""
    stamps = {'odom': np.arange(0.0, 2.01, 0.5), 'base_link': np.arange(0.25, 2.3, 0.4)}
    samples = [('base_link', 'camera', *random_transform(7), 0.1, True)]
    for child, parent in (('odom', 'map'), ('base_link', 'odom')):
        samples += [(parent, child, *motion('base_link' if child == 'odom' else 'optical', t),
                     t, False) for t in stamps[child]]
    samples.sort(key=lambda s: s[4])  # as recorded: in time order
    tree = TransformTree(math.inf, max_samples=100)
    followed = tree.follow('map', 'camera', recording(samples))
    want = np.unique(np.concatenate(list(stamps.values())))
    want = want[(want >= 0.25) & (want <= 2.0)]  # where both dynamic edges have data
    np.testing.assert_array_equal(followed.stamp, want)
    assert followed.chains == [['map', 'odom', 'base_link', 'camera']] and not followed.refused
    tree = TransformTree(math.inf)  # the same samples fed at once: the same lookups
    for parent, child, R, b, t, static in samples:
        tree.set_transform(parent, child, R, b, t, static=static)
    R, b, _ = tree.lookup('map', 'camera', want)
    assert h.max_abs(followed.R - R) == 0 and h.max_abs(followed.b - b) == 0


def test_follow_uses_a_re_parented_frame_under_each_parent():
    """base_link under odom until 1.0 s, then under map: each time under the parent it had."""
    samples, truth = [], {}
    for k, t in enumerate(np.arange(0.0, 2.01, 0.25)):
        samples.append(('map', 'odom', *random_transform(k), t, False))
        parent = 'odom' if t <= 1.0 else 'map'
        samples.append((parent, 'base_link', *random_transform(50 + k), t, False))
        T = hom(*random_transform(50 + k))
        truth[t] = hom(*random_transform(k)) @ T if parent == 'odom' else T
    tree = TransformTree(math.inf, max_samples=100)
    followed = tree.follow('map', 'base_link', recording(samples))
    np.testing.assert_array_equal(followed.stamp, list(truth))
    assert followed.chains == [['map', 'odom', 'base_link'], ['map', 'base_link']]
    want = np.array(list(truth.values()))
    assert_transform((followed.R, followed.b), want)


def test_follow_counts_a_refused_run_and_goes_on():
    """A loop (x under y, y under x) and an empty frame name are refused; the chain is not."""
    R, b = np.eye(3), np.zeros(3)
    samples = [('map', 'odom', R, b, t, False) for t in (1.0, 2.0)]
    samples += [('x', 'y', R, b, 1.5, False), ('y', 'x', R, b, 1.6, False),
                ('odom', '', R, b, 1.7, False)]
    followed = TransformTree(math.inf).follow('map', 'odom', recording(samples))
    assert {k: e.reason for k, e in followed.refused.items()} == {3: 'loop', 4: 'bad_frame'}
    np.testing.assert_array_equal(followed.stamp, [1.0, 2.0])


def test_follow_a_static_chain_once_and_refuse_what_cannot_be_looked_up():
    R, b = random_transform(3)
    tree = TransformTree(math.inf)
    followed = tree.follow('a', 'b', recording([('a', 'b', R, b, 4.0, True)] * 3))
    assert followed.stamp.tolist() == [4.0] and h.max_abs(followed.R[0] - R) == 0
    with pytest.raises(TransformLookupError, match="frame 'c' is unknown") as caught:
        TransformTree(math.inf).follow('a', 'c', recording([('a', 'b', R, b, 4.0, False)]))
    assert caught.value.reason == 'unknown_frame'
    disjoint = [('a', 'b', R, b, 1.0, False), ('a', 'b', R, b, 2.0, False),
                ('a', 'c', R, b, 3.0, False), ('a', 'c', R, b, 4.0, False)]
    with pytest.raises(TransformLookupError, match='no time at which every edge'):
        TransformTree(math.inf).follow('b', 'c', recording(disjoint))
