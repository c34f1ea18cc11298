"""
Math benchmark: rot_tools against scipy, transforms3d and pytransform3d, as ratios.

Three tables, each measured side by side in one run (repetitions interleaved, medians):

1. Batch throughput on N (default 1,000,000) random inputs against
   scipy.spatial.transform.Rotation (and the screw log against pytransform3d's batch
   exponential coordinates), with the largest difference between the results.
2. Peak memory of each rot_tools batch conversion (tracemalloc; NumPy reports its buffers
   to it): the peak of what the call allocates, output included, divided by the bytes of its
   input and output arrays. scipy's figure is shown for comparison.
3. Single-call latency: one rotation through the same public functions, Python call
   overhead included, against scipy (the goal), with transforms3d (which checks nothing) as
   an informative column where it has the conversion, and decompose (informative: nine
   fields) beside scipy's four conversions of the same rotation (rotvec, Euler angles,
   roll-pitch-yaw, quaternion).

Both libraries get their defaults: rot_tools validates every matrix (check=True), scipy's
from_matrix runs with assume_valid=False and pytransform3d's single-transform function with
check=True.

Run: ``.venv/bin/python bench/bench_math.py`` (options: --help).
"""

import argparse
import gc
import timeit
import tracemalloc
import warnings

import benchlib
import numpy as np
import pytransform3d.trajectories as pt_trajectories
import pytransform3d.transformations as pt_transformations
import rot_tools as rt
from scipy.spatial.transform import Rotation
import transforms3d.axangles as t3d_axangles
import transforms3d.euler as t3d_euler
import transforms3d.quaternions as t3d_quaternions

BATCH_GOAL_QUATERNION_ROUTE = 0.25  # scipy routes Euler / matrix conversions via quaternions
BATCH_GOAL_DIRECT = 1.5  # rotvec, axis-angle, quaternion → matrix: scipy's one direct formula
SINGLE_GOAL_SCIPY = 0.5  # every single conversion
MEMORY_GOAL = 2.0
TOL = 1e-12


# -- inputs -------------------------------------------------------------------------------

def make_inputs(n, seed=20261121):
    """Random inputs: uniform rotations, Euler angles in their ranges, transforms."""
    rng = np.random.default_rng(seed)
    q = rng.standard_normal((n, 4))
    q /= np.linalg.norm(q, axis=1)[:, None]
    R = np.ascontiguousarray(Rotation.from_quat(q).as_matrix())
    pi = np.pi
    e_tb = np.column_stack([rng.uniform(-pi, pi, n), rng.uniform(-pi / 2, pi / 2, n),
                            rng.uniform(-pi, pi, n)])
    e_proper = np.column_stack([rng.uniform(-pi, pi, n), rng.uniform(0.0, pi, n),
                                rng.uniform(-pi, pi, n)])
    axis = rng.standard_normal((n, 3))
    axis /= np.linalg.norm(axis, axis=1)[:, None]
    angle = rng.uniform(0.0, pi, n)
    rotvec = axis * angle[:, None]
    b = rng.uniform(-2.0, 2.0, (n, 3))
    T = np.zeros((n, 4, 4))
    T[:, :3, :3] = R
    T[:, :3, 3] = b
    T[:, 3, 3] = 1.0
    return {'R': R, 'e_tb': e_tb, 'e_proper': e_proper, 'axis': axis, 'angle': angle,
            'rotvec': rotvec, 'b': b, 'T': T, 'q': q}


# -- result comparisons (max difference to the reference) ---------------------------------

def _wrapped(d):
    """Angle differences mapped to [−π, π] (θ1, θ3 = ±π are the same angle)."""
    return np.abs((d + np.pi) % (2 * np.pi) - np.pi)


def diff_plain(a, b):
    return float(np.max(np.abs(np.asarray(a) - np.asarray(b))))


def diff_euler(rt_out, ref, seq, R):
    """Angles compared where both are regular; matrices compared where rot_tools flags lock."""
    angles, degenerate = rt_out
    d = _wrapped(angles - ref).max(axis=-1)
    if np.any(degenerate):  # scipy's gimbal convention differs: compare the rotations
        lock = np.asarray(degenerate)
        d[lock] = np.abs(rt.euler_to_matrix(angles[lock], seq) - R[lock]).max(axis=(-2, -1))
    return float(d.max())


def screw_note(twist, ref, R, b):
    """
    Where rot_tools' and pytransform3d's twists differ most, and which one is right.

    Both twists are mapped back with rot_tools.screw_exp (exact Rodrigues) and compared with
    the (R, b) they came from; the difference is also given with θ within 1e-4 of π left out.
    """
    d = np.abs(twist - ref).max(axis=-1)
    theta = np.linalg.norm(twist[:, :3], axis=-1)
    worst = int(np.argmax(d))
    away = theta < np.pi - 1e-4
    sample = np.argsort(d)[-1000:]
    errs = []
    for tw in (twist, ref):
        R2, b2 = rt.screw_exp(tw[sample])
        errs.append(max(np.abs(R2 - R[sample]).max(), np.abs(b2 - b[sample]).max()))
    return (f'screw_log vs pytransform3d: largest difference {d[worst]:.1e} at θ = '
            f'{theta[worst]:.7f} (π − θ = {np.pi - theta[worst]:.1e}); with θ < π − 1e-4: '
            f'{d[away].max():.1e}. Round trip screw_exp(twist) − (R, b) on the 1000 most '
            f'different items: rot_tools {errs[0]:.1e}, pytransform3d {errs[1]:.1e}, so the '
            "difference is pytransform3d's error near π (its axis from the symmetric part).")


def diff_quaternion(a, b):
    """
    Compare quaternions up to sign.

    Quaternions: both canonical (w > 0, at w = 0 the first non-zero positive), but at
    w ≈ 0 rounding may pick opposite signs, so ±q count as equal.
    """
    return float(np.minimum(np.abs(a - b).max(axis=-1), np.abs(a + b).max(axis=-1)).max())


def diff_rotvec(a, b):
    """Rotation vectors; at θ = π the sign is free, so ±v count as equal there."""
    d = np.abs(a - b).max(axis=-1)
    at_pi = np.linalg.norm(a, axis=-1) > np.pi - 1e-9
    d[at_pi] = np.minimum(d[at_pi], np.abs(a[at_pi] + b[at_pi]).max(axis=-1))
    return float(d.max())


# -- 1. batch throughput ------------------------------------------------------------------

def batch_cases(x):
    """
    Return the batch cases as tuples.

    Each is (name, rot_tools call, reference name, reference call, goal, compare, input
    arrays, note or None).
    """
    R, T = x['R'], x['T']
    return [
        ('Euler ZYX -> matrix', lambda: rt.euler_to_matrix(x['e_tb'], 'ZYX'),
         'scipy', lambda: Rotation.from_euler('ZYX', x['e_tb']).as_matrix(),
         BATCH_GOAL_QUATERNION_ROUTE, diff_plain, [x['e_tb']], None),
        ('Euler ZXZ -> matrix', lambda: rt.euler_to_matrix(x['e_proper'], 'ZXZ'),
         'scipy', lambda: Rotation.from_euler('ZXZ', x['e_proper']).as_matrix(),
         BATCH_GOAL_QUATERNION_ROUTE, diff_plain, [x['e_proper']], None),
        ('matrix -> rotvec', lambda: rt.matrix_to_rotvec(R),
         'scipy', lambda: Rotation.from_matrix(R).as_rotvec(),
         BATCH_GOAL_QUATERNION_ROUTE, diff_rotvec, [R], None),
        ('matrix -> Euler ZYX', lambda: rt.matrix_to_euler(R, 'ZYX'),
         'scipy', lambda: Rotation.from_matrix(R).as_euler('ZYX'),
         BATCH_GOAL_QUATERNION_ROUTE, lambda a, b: diff_euler(a, b, 'ZYX', R), [R], None),
        ('matrix -> Euler ZXZ', lambda: rt.matrix_to_euler(R, 'ZXZ'),
         'scipy', lambda: Rotation.from_matrix(R).as_euler('ZXZ'),
         BATCH_GOAL_QUATERNION_ROUTE, lambda a, b: diff_euler(a, b, 'ZXZ', R), [R], None),
        ('matrix -> quaternion', lambda: rt.matrix_to_quaternion(R),
         'scipy', lambda: Rotation.from_matrix(R).as_quat(canonical=True),
         BATCH_GOAL_QUATERNION_ROUTE, diff_quaternion, [R], None),
        ('rotvec -> matrix', lambda: rt.rotvec_to_matrix(x['rotvec']),
         'scipy', lambda: Rotation.from_rotvec(x['rotvec']).as_matrix(),
         BATCH_GOAL_DIRECT, diff_plain, [x['rotvec']], None),
        ('axis, angle -> matrix', lambda: rt.axis_angle_to_matrix(x['axis'], x['angle']),
         'scipy (rotvec)', lambda: Rotation.from_rotvec(x['rotvec']).as_matrix(),
         BATCH_GOAL_DIRECT, diff_plain, [x['axis'], x['angle']], None),
        ('quaternion -> matrix', lambda: rt.quaternion_to_matrix(x['q']),
         'scipy', lambda: Rotation.from_quat(x['q']).as_matrix(),
         BATCH_GOAL_DIRECT, diff_plain, [x['q']], None),
        ('screw_log (R, b) -> twist', lambda: rt.screw_log(R, x['b']),
         'pytransform3d', lambda: pt_trajectories.exponential_coordinates_from_transforms(T),
         None, diff_plain, [R, x['b']], lambda a, p: screw_note(a, p, R, x['b'])),
    ]


def _nbytes(out):
    if isinstance(out, tuple):
        return sum(np.asarray(o).nbytes for o in out)
    return np.asarray(out).nbytes


def run_batch(x, repeats):
    results = []
    for name, rt_call, ref_name, ref_call, goal, compare, inputs, note in batch_cases(x):
        with warnings.catch_warnings():
            warnings.simplefilter('ignore')  # scipy's gimbal-lock warning
            rt_out, ref_out = rt_call(), ref_call()  # warm-up and the results to compare
            times = benchlib.interleaved({'rt': rt_call, 'ref': ref_call}, repeats)
        t_rt, t_ref = benchlib.median(times['rt']), benchlib.median(times['ref'])
        results.append({
            'operation': name, 'reference': ref_name, 'rot_tools_s': t_rt, 'reference_s': t_ref,
            'ratio': t_rt / t_ref, 'goal': goal, 'max_diff': compare(rt_out, ref_out),
            'note': note(rt_out, ref_out) if note else None,
            'in_bytes': sum(a.nbytes for a in inputs), 'out_bytes': _nbytes(rt_out),
            'ref_call': ref_call, 'rt_call': rt_call})
        del rt_out, ref_out
        gc.collect()
    return results


def _equal_verdict(r):
    # The goal "results equal to scipy's within 1e-12" is scipy's; against pytransform3d the
    # difference is shown with a note on which side is off (see screw_note).
    if not r['reference'].startswith('scipy'):
        return '-'
    return 'yes' if r['max_diff'] <= TOL else 'NO'


def print_batch(results, n):
    rows = [[r['operation'], r['reference'], f"{r['rot_tools_s'] * 1e3:.1f} ms",
             f"{r['reference_s'] * 1e3:.1f} ms", f"{r['ratio']:.3f}", benchlib.fmt_goal(r['goal']),
             benchlib.verdict(r['ratio'], r['goal']), f"{r['max_diff']:.1e}",
             _equal_verdict(r)]
            for r in results]
    benchlib.print_table(
        f'Batch throughput, {n:,} items (medians of interleaved repetitions)',
        ['operation', 'reference', 'rot_tools', 'reference', 'ratio', 'goal', 'met?',
         'max |diff|', f'<= {TOL:g}?'], rows)
    for r in results:
        if r['note']:
            print(f"  note: {r['note']}")


# -- 2. peak memory -----------------------------------------------------------------------

def peak_allocated(call):
    """Peak bytes allocated while call() runs (its result included), via tracemalloc."""
    gc.collect()
    tracemalloc.start()
    try:
        base = tracemalloc.get_traced_memory()[0]
        tracemalloc.reset_peak()
        with warnings.catch_warnings():
            warnings.simplefilter('ignore')
            out = call()
        peak = tracemalloc.get_traced_memory()[1] - base
    finally:
        tracemalloc.stop()
    del out
    gc.collect()
    return peak


def run_memory(results):
    for r in results:
        r['rt_peak'] = peak_allocated(r['rt_call'])
        r['ref_peak'] = peak_allocated(r['ref_call'])
        r['memory_ratio'] = r['rt_peak'] / (r['in_bytes'] + r['out_bytes'])
        r['ref_memory_ratio'] = r['ref_peak'] / (r['in_bytes'] + r['out_bytes'])


def _ref_peak(r):
    # scipy 1.17 builds some results in compiled code whose buffers tracemalloc never sees
    # (a traced peak below the output's own size): say so rather than print a wrong figure.
    if r['ref_peak'] < 0.5 * r['out_bytes']:
        return 'not traced'
    return f"{r['ref_peak'] / 1e6:.0f} MB ({r['ref_memory_ratio']:.2f})"


def print_memory(results):
    rows = [[r['operation'], f"{r['in_bytes'] / 1e6:.0f} MB", f"{r['out_bytes'] / 1e6:.0f} MB",
             f"{r['rt_peak'] / 1e6:.0f} MB", f"{r['memory_ratio']:.2f}",
             benchlib.fmt_goal(MEMORY_GOAL), benchlib.verdict(r['memory_ratio'], MEMORY_GOAL),
             _ref_peak(r)]
            for r in results]
    benchlib.print_table(
        'Peak memory of the batch conversions (tracemalloc): peak allocated by the call, '
        'output included, / (input + output bytes)',
        ['operation', 'input', 'output', 'rot_tools peak', 'ratio', 'goal', 'met?',
         'reference peak (ratio)'], rows)


# -- 3. single-call latency ---------------------------------------------------------------

def _scipy_representations(R, seq):
    """Return decompose's rotation fields the usual way: scipy, one conversion each."""
    r = Rotation.from_matrix(R)
    return r.as_rotvec(), r.as_euler(seq), r.as_euler('xyz'), r.as_quat(canonical=True)


def single_cases():
    """(operation, {candidate: statement}, [(reference, goal)]) and the globals they use."""
    a_tb = np.array([0.3, -0.4, 1.2])
    a_pr = np.array([0.3, 1.1, -2.0])
    R = rt.euler_to_matrix(a_tb, 'ZYX')
    axis, angle = rt.matrix_to_axis_angle(R)
    axis, angle = np.array(axis), float(angle)
    rotvec = rt.matrix_to_rotvec(R)
    q = rt.matrix_to_quaternion(R)
    b = np.array([0.4, -1.0, 2.5])
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = R, b
    g = {'rt': rt, 'Rotation': Rotation, 'e': t3d_euler, 'aa': t3d_axangles, 'tq': t3d_quaternions,
         'pt': pt_transformations, 'a_tb': a_tb, 'a_pr': a_pr, 'f_tb': [float(v) for v in a_tb],
         'f_pr': [float(v) for v in a_pr], 'R': R, 'axis': axis, 'angle': angle, 'rotvec': rotvec,
         'b': b, 'T': T, 'q': q, 'q_wxyz': np.roll(q, 1), 'scipy_all': _scipy_representations}
    sc, t3 = ('scipy', SINGLE_GOAL_SCIPY), ('transforms3d', None)  # (t3: informative)
    sc_rotvec = ('scipy (rotvec)', SINGLE_GOAL_SCIPY)
    return g, [
        ('Euler ZYX -> matrix', {
            'rot_tools': "rt.euler_to_matrix(a_tb, 'ZYX')",
            'scipy': "Rotation.from_euler('ZYX', a_tb).as_matrix()",
            'transforms3d': "e.euler2mat(*f_tb, axes='rzyx')"}, [sc, t3]),
        ('Euler ZXZ -> matrix', {
            'rot_tools': "rt.euler_to_matrix(a_pr, 'ZXZ')",
            'scipy': "Rotation.from_euler('ZXZ', a_pr).as_matrix()",
            'transforms3d': "e.euler2mat(*f_pr, axes='rzxz')"}, [sc, t3]),
        ('matrix -> Euler ZYX', {
            'rot_tools': "rt.matrix_to_euler(R, 'ZYX').angles",
            'scipy': "Rotation.from_matrix(R).as_euler('ZYX')",
            'transforms3d': "e.mat2euler(R, axes='rzyx')"}, [sc, t3]),
        ('matrix -> Euler zxz', {
            'rot_tools': "rt.matrix_to_euler(R, 'zxz').angles",
            'scipy': "Rotation.from_matrix(R).as_euler('zxz')",
            'transforms3d': "e.mat2euler(R, axes='szxz')"}, [sc, t3]),
        ('matrix -> rotvec', {
            'rot_tools': 'rt.matrix_to_rotvec(R)',
            'scipy': 'Rotation.from_matrix(R).as_rotvec()'}, [sc]),
        ('matrix -> axis, angle', {
            'rot_tools': 'rt.matrix_to_axis_angle(R)',
            'scipy (rotvec)': 'Rotation.from_matrix(R).as_rotvec()',
            'transforms3d': 'aa.mat2axangle(R)'}, [sc_rotvec, t3]),
        ('rotvec -> matrix', {
            'rot_tools': 'rt.rotvec_to_matrix(rotvec)',
            'scipy': 'Rotation.from_rotvec(rotvec).as_matrix()'}, [sc]),
        ('axis, angle -> matrix', {
            'rot_tools': 'rt.axis_angle_to_matrix(axis, angle)',
            'scipy (rotvec)': 'Rotation.from_rotvec(rotvec).as_matrix()',
            'transforms3d': 'aa.axangle2mat(axis, angle)'}, [sc_rotvec, t3]),
        ('quaternion -> matrix', {
            'rot_tools': 'rt.quaternion_to_matrix(q)',
            'scipy': 'Rotation.from_quat(q).as_matrix()',
            'transforms3d': 'tq.quat2mat(q_wxyz)'}, [sc, t3]),
        ('matrix -> quaternion', {
            'rot_tools': 'rt.matrix_to_quaternion(R)',
            'scipy': 'Rotation.from_matrix(R).as_quat(canonical=True)',
            'transforms3d': 'tq.mat2quat(R)'}, [sc, t3]),
        ('screw_log (R, b) -> twist', {
            'rot_tools': 'rt.screw_log(R, b)',
            'pytransform3d': 'pt.exponential_coordinates_from_transform(T)'},
         [('pytransform3d', None)]),
        ('decompose (R, b) ZYX', {
            'rot_tools': "rt.decompose(R, b, 'ZYX')",
            'scipy (4 conversions)': "scipy_all(R, 'ZYX')"},
         [('scipy (4 conversions)', None)]),  # (informative: 9 fields against 4)
    ]


def _single_diff(operation, name, out):
    """Flatten one single-call result, so each reference can be compared with rot_tools."""
    if operation.startswith('decompose'):
        if name == 'rot_tools':
            out = (out.rotvec, out.euler, out.rpy, out.quaternion)
        return np.concatenate([np.ravel(x) for x in out])
    if operation == 'matrix -> axis, angle':
        if name == 'scipy (rotvec)':  # θ·l̂ → (l̂, θ)
            return np.concatenate([out / np.linalg.norm(out), [np.linalg.norm(out)]])
        return np.concatenate([np.ravel(out[0]), [out[1]]])
    if name == 'transforms3d' and operation.endswith('-> quaternion'):
        return np.roll(out, -1) * np.sign(out[0])  # (w, x, y, z) → (x, y, z, w), w > 0
    if name == 'transforms3d' and isinstance(out, tuple):  # mat2euler
        return np.array(out)
    return np.ravel(out)


def run_single(repeats, target_s=0.02):
    g, cases = single_cases()
    results = []
    for operation, stmts, refs in cases:
        outs = {k: _single_diff(operation, k, eval(s, g))  # noqa: S307
                for k, s in stmts.items()}
        timers = {k: timeit.Timer(s, globals=g) for k, s in stmts.items()}
        number = {}
        for k, t in timers.items():  # calibrate: about target_s per sample
            per = min(t.repeat(3, 200)) / 200
            number[k] = max(100, int(target_s / per))
        times = benchlib.interleaved(
            {k: (lambda t=t, n=number[k]: t.timeit(n)) for k, t in timers.items()}, repeats)
        per_call = {k: benchlib.median(v) / number[k] for k, v in times.items()}
        for ref, goal in refs:
            results.append({'operation': operation, 'reference': ref,
                            'rot_tools_us': per_call['rot_tools'] * 1e6,
                            'reference_us': per_call[ref] * 1e6,
                            'ratio': per_call['rot_tools'] / per_call[ref], 'goal': goal,
                            'max_diff': diff_plain(outs['rot_tools'], outs[ref])})
    return results


def print_single(results):
    rows = [[r['operation'], r['reference'], f"{r['rot_tools_us']:.2f} us",
             f"{r['reference_us']:.2f} us", f"{r['ratio']:.3f}", benchlib.fmt_goal(r['goal']),
             benchlib.verdict(r['ratio'], r['goal']), f"{r['max_diff']:.1e}"]
            for r in results]
    benchlib.print_table(
        'Single-call latency, one rotation through the public functions '
        '(medians of interleaved repetitions)',
        ['operation', 'reference', 'rot_tools', 'reference', 'ratio', 'goal', 'met?',
         'max |diff|'], rows)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--n', type=int, default=1_000_000, help='batch size (1,000,000)')
    parser.add_argument('--repeats', type=int, default=5,
                        help='interleaved repetitions of each batch timing (5)')
    parser.add_argument('--single-repeats', type=int, default=9,
                        help='interleaved samples of each single-call timing (9)')
    parser.add_argument('--skip', choices=['batch', 'memory', 'single'], action='append',
                        default=[], help='leave a table out (repeatable)')
    parser.add_argument('--json', metavar='PATH', help='also write the figures as JSON')
    args = parser.parse_args(argv)

    print(f'bench_math: {benchlib.machine_line()}')
    payload = {}
    if 'batch' not in args.skip or 'memory' not in args.skip:
        x = make_inputs(args.n)
        batch = run_batch(x, args.repeats if 'batch' not in args.skip else 1)
        if 'batch' not in args.skip:
            print_batch(batch, args.n)
        if 'memory' not in args.skip:
            run_memory(batch)
            print_memory(batch)
        payload['batch'] = [{k: v for k, v in r.items() if not k.endswith('_call')}
                            for r in batch]
        payload['n'] = args.n
        del x
        gc.collect()
    if 'single' not in args.skip:
        single = run_single(args.single_repeats)
        print_single(single)
        payload['single'] = single
    benchlib.write_json(args.json, payload)


if __name__ == '__main__':
    main()
