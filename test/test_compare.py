"""rot-tools compare: evo's numbers, a time offset, a simulated mounting, bad inputs."""

import json
from pathlib import Path
import shlex
import warnings

import bag_helpers as bh
from conftest import one_error, run_cli
from doc_blocks import assert_doc_output, console_steps, doc_block
import numpy as np
import pytest
import rot_tools as rt
from rot_tools.cli import main as cli
import yaml

STATS = ('rmse', 'mean', 'median', 'std', 'min', 'max')


def turn(t):
    """Return a motion about all three axes: R(t) = exp([v(t)]×)."""
    v = np.stack([np.sin(1.3 * t), np.sin(0.7 * t + 1), np.sin(0.5 * t)], -1)
    return rt.rotvec_to_matrix(v)


def path_of(t):
    """Return the positions of a helix."""
    return np.stack([np.cos(0.3 * t), np.sin(0.3 * t), 0.05 * t], -1)


def noisy(R, degrees, rng):
    """R turned by a random rotation vector of σ = degrees per axis."""
    return R @ rt.rotvec_to_matrix(rng.normal(scale=np.radians(degrees), size=(len(R), 3)))


def write_tum(path, t, R, b):
    np.savetxt(path, np.column_stack([t, b, rt.matrix_to_quaternion(R)]), fmt='%.9f',
               header='t x y z qx qy qz qw')
    return path


def write_euroc(path, t, R, b):
    q = rt.matrix_to_quaternion(R)[:, [3, 0, 1, 2]]
    with open(path, 'w') as out:
        out.write('#timestamp [ns], p_x [m], p_y [m], p_z [m], q_w [], q_x [], q_y [], q_z []\n')
        for ns, row in zip(np.rint(t * 1e9).astype(np.int64), np.column_stack([b, q])):
            out.write(f'{ns},' + ','.join(f'{x:.9f}' for x in row) + '\n')
    return path


def write_pose_bag(path, t, R, b, topic='/est/pose'):
    builder = bh.Builder()
    q = rt.matrix_to_quaternion(R)
    messages = [(topic, 'geometry_msgs/msg/PoseStamped', int(round(s * 1e9)),
                 builder.pose_stamped(s, p, qk)) for s, p, qk in zip(t, b, q)]
    tf = [('/tf', 'tf2_msgs/msg/TFMessage', int(round(s * 1e9)),
           builder.tf_message([builder.transform_stamped(s, p, qk, 'map', 'body')]))
          for s, p, qk in zip(t, b, q)]
    return bh.write_bag(path, messages + tf)


def two_streams(rng, n_ref, n_est, duration=30.0):
    """REF and EST (noisy, its world frame turned, positions drifting) at their own rates."""
    t_ref = np.linspace(0.0, duration, n_ref)
    t_est = np.linspace(0.0, duration, n_est) + rng.uniform(-0.004, 0.004, n_est)
    t_est[0], t_est[-1] = 0.0, duration
    W = rt.rotvec_to_matrix(np.array([0.1, -0.2, 0.7]))
    R_ref, b_ref = turn(t_ref), path_of(t_ref)
    R_est = W @ noisy(turn(t_est), 0.5, rng)
    b_est = (W @ path_of(t_est)[..., None])[..., 0] + rng.normal(scale=0.01, size=(n_est, 3))
    return (t_ref, R_ref, b_ref), (np.sort(t_est), R_est, b_est)


# ---- evo's numbers ------------------------------------------------------------------------


def evo_numbers(traj_ref, traj_est):
    """APE and RPE (angle_deg, delta 1 frame) statistics as evo_ape/evo_rpe --align give them."""
    sync = pytest.importorskip('evo.core.sync', reason='evo is not installed (a test '
                               'requirement: requirements-test.txt)')
    from evo.core import metrics
    traj_ref, traj_est = sync.associate_trajectories(traj_ref, traj_est, max_diff=0.01)
    traj_est.align(traj_ref, correct_scale=False)
    out = {'pairs': traj_ref.num_poses}
    ape = metrics.APE(metrics.PoseRelation.rotation_angle_deg)
    ape.process_data((traj_ref, traj_est))
    rpe = metrics.RPE(metrics.PoseRelation.rotation_angle_deg, delta=1,
                      delta_unit=metrics.Unit.frames, all_pairs=False)
    rpe.process_data((traj_ref, traj_est))
    out['ape'], out['rpe'] = ape.get_all_statistics(), rpe.get_all_statistics()
    return out


def ours(capsys, *args):
    status, out, err = run_cli(capsys, 'compare', *args, '--match', 'nearest', '--offset', '0',
                               '--align', 'se3', '--deg', '--json', '--precision', '17')
    assert status == 0 and err == '', err
    return json.loads(out)


def assert_as_evo(mine, evo):
    assert mine['pairs'] == evo['pairs'] > 800 and mine['alignment'] == 'se3'
    for metric in ('ape', 'rpe'):
        for key in STATS:
            assert abs(mine[metric][key] - evo[metric][key]) <= 1e-6, (metric, key)


@pytest.fixture(scope='module')
def streams():
    return two_streams(np.random.default_rng(5), 3001, 901)


@pytest.mark.parametrize('longer', ['ref', 'est'])
def test_tum_files_give_evos_numbers(capsys, tmp_path, streams, longer):
    pytest.importorskip('evo', reason='evo is not installed (a test requirement)')
    from evo.tools import file_interface
    ref, est = streams if longer == 'ref' else streams[::-1]  # evo walks the shorter stream
    ref_path = write_tum(tmp_path / 'ref.tum', *ref)
    est_path = write_tum(tmp_path / 'est.tum', *est)
    mine = ours(capsys, est_path, ref_path)
    evo = evo_numbers(file_interface.read_tum_trajectory_file(ref_path),
                      file_interface.read_tum_trajectory_file(est_path))
    assert_as_evo(mine, evo)


def test_euroc_file_gives_evos_numbers(capsys, tmp_path, streams):
    pytest.importorskip('evo', reason='evo is not installed (a test requirement)')
    from evo.tools import file_interface
    ref_path = write_euroc(tmp_path / 'data.csv', *streams[0])
    est_path = write_tum(tmp_path / 'est.tum', *streams[1])
    mine = ours(capsys, est_path, ref_path)
    evo = evo_numbers(file_interface.read_euroc_csv_trajectory(ref_path),
                      file_interface.read_tum_trajectory_file(est_path))
    assert_as_evo(mine, evo)


def test_bag_topic_gives_evos_numbers_and_its_tf_the_same(capsys, tmp_path, streams):
    pytest.importorskip('rosbags', reason="the 'bag' extra (rosbags) is not installed")
    pytest.importorskip('evo', reason='evo is not installed (a test requirement)')
    from evo.tools import file_interface
    from rosbags.rosbag2 import Reader
    bag = write_pose_bag(tmp_path / 'est_bag', *streams[1])
    ref_path = write_tum(tmp_path / 'ref.tum', *streams[0])
    mine = ours(capsys, bag, ref_path, '--est-topic', '/est/pose')
    with Reader(bag) as reader:
        est = file_interface.read_bag_trajectory(reader, '/est/pose')
    evo = evo_numbers(file_interface.read_tum_trajectory_file(ref_path), est)
    assert_as_evo(mine, evo)
    by_tf = ours(capsys, bag, ref_path, '--est-tf', 'map', 'body')
    for metric in ('ape', 'rpe'):
        for key in STATS:
            assert abs(by_tf[metric][key] - mine[metric][key]) <= 1e-9


def as_they_come(path, t, R, b):
    """Write a TUM file with repeated stamps and swapped lines; return (repeated, backwards)."""
    rows = np.column_stack([t, b, rt.matrix_to_quaternion(R)])
    off = rt.matrix_to_quaternion(R @ rt.rot_x(np.radians(30)))
    lines = [f'{row[0]:.9f} ' + ' '.join(f'{x:.9f}' for x in row[1:]) for row in rows]
    out, repeated = [], 0
    for k, line in enumerate(lines):
        out.append(line)
        if k % 97 == 50:
            out.append(line.split(' ', 1)[0] + ' ' + ' '.join(
                f'{x:.9f}' for x in np.concatenate([b[k], off[k]])))
            repeated += 1
    backwards = 0
    for k in range(10, len(out) - 1, 89):
        if out[k].split(' ', 1)[0] != out[k + 1].split(' ', 1)[0]:
            out[k], out[k + 1] = out[k + 1], out[k]
            backwards += 1
    Path(path).write_text('# t x y z qx qy qz qw\n' + '\n'.join(out) + '\n')
    return repeated, backwards


def test_stamps_as_they_come_give_evos_numbers(capsys, tmp_path, streams):
    pytest.importorskip('evo', reason='evo is not installed (a test requirement)')
    from evo.tools import file_interface
    ref_path = tmp_path / 'ref.tum'
    repeated, backwards = as_they_come(ref_path, *streams[0])
    est_path = write_tum(tmp_path / 'est.tum', *streams[1])
    status, out, err = run_cli(capsys, 'compare', est_path, ref_path, '--match', 'nearest',
                               '--align', 'se3', '--deg', '--json', '--precision', '17')
    assert status == 0
    assert err == (f'warning: REF ({ref_path}): {repeated} repeated stamps dropped (the first '
                   f'of each kept), {backwards} stamps out of order sorted\n')
    mine = json.loads(out)
    assert (mine['ref']['dropped_duplicates'], mine['ref']['reordered']) == (repeated, backwards)
    assert (mine['est']['dropped_duplicates'], mine['est']['reordered']) == (0, 0)
    assert mine['ref']['poses'] == len(streams[0][0])
    evo = evo_numbers(file_interface.read_tum_trajectory_file(ref_path),  # as written
                      file_interface.read_tum_trajectory_file(est_path))
    assert_as_evo(mine, evo)


def test_strict_stamps_refuse_them_saying_which(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    t = 1311868229.576 + np.arange(0.0, 10.0, 0.05)
    R, b = turn(t), path_of(t)
    write_tum(tmp_path / 'good.tum', t, R, b)
    write_tum(tmp_path / 'twice.tum', np.insert(t, 7, t[6]), np.insert(R, 7, R[6], 0),
              np.insert(b, 7, b[6], 0))
    write_euroc(tmp_path / 'back.csv', t[[0, 1, 3, 2, 4, 5, 6]], R[:7], b[:7])
    for words, says in [
            (('twice.tum', 'good.tum'), 'twice.tum:9: duplicate stamp 1311868229.876 (as on '
             'line 8)'),
            (('good.tum', 'back.csv'), 'back.csv:5: stamp 1311868229.676 goes back from '
             '1311868229.726 on line 4')]:
        status, out, err = run_cli(capsys, 'compare', *words, '--strict-stamps')
        assert (status, out) == (2, '')
        assert err == f'rot-tools: error: compare: {says}\n'
    status, out, err = run_cli(capsys, 'compare', 'twice.tum', 'good.tum', '--json')
    assert status == 0 and err == ('warning: EST (twice.tum): 1 repeated stamp dropped (the '
                                   'first of each kept)\n')
    assert json.loads(out)['ape']['max'] == 0.0


def test_a_bag_topic_as_it_comes(capsys, tmp_path):
    pytest.importorskip('rosbags', reason="the 'bag' extra (rosbags) is not installed")
    builder = bh.Builder()
    t = 1311868229.5 + np.arange(200) / 64  # exact in nanoseconds
    R, b = turn(t), path_of(t)
    q = rt.matrix_to_quaternion(R)
    order = list(range(len(t)))
    order[10], order[11] = 11, 10  # recorded in this order: the header stamps go back
    order.insert(30, 29)  # a message stamped again (the same pose)
    bag = bh.write_bag(tmp_path / 'est', [
        ('/pose', 'geometry_msgs/msg/PoseStamped', 1_000_000_000 + n,
         builder.pose_stamped(t[k], b[k], q[k])) for n, k in enumerate(order)])
    ref = write_tum(tmp_path / 'ref.tum', t, R, b)
    status, out, err = run_cli(capsys, 'compare', bag, ref, '--json')
    assert status == 0 and err == (f'warning: EST ({bag}): 1 repeated stamp dropped (the first '
                                   'of each kept), 1 stamp out of order sorted\n')
    found = json.loads(out)
    assert found['est']['poses'] == len(t) and found['ape']['max'] < 1e-7
    status, out, err = run_cli(capsys, 'compare', bag, ref, '--strict-stamps')
    assert (status, out) == (2, '')
    assert err == ('rot-tools: error: compare: EST: /pose: stamp 1311868229.65625 goes back '
                   'from 1311868229.671875 (messages 11 and 12 as recorded)\n')


# ---- time offset, recorded -----------------------------------------------------------------


def test_offset_of_the_recorded_imu_is_recovered_within_a_sample(capsys, tmp_path):
    pytest.importorskip('rosbags', reason="the 'bag' extra (rosbags) is not installed")
    if not bh.REAL.exists():
        pytest.skip(f'the shared recording is not there: {bh.REAL}')
    from rot_tools.cli import bag_analysis
    _, (imu,) = bag_analysis.analyse(bh.REAL, ('/imu/data',))
    shift = 0.137  # s, not a multiple of the 0.02 s period
    builder = bh.Builder()
    stamps = imu.ns / 1e9 + shift
    bh.write_bag(tmp_path / 'late', [
        ('/imu/data', 'sensor_msgs/msg/Imu', int(round(s * 1e9)), builder.imu(s, q))
        for s, q in zip(stamps, imu.quaternion)])
    status, out, err = run_cli(capsys, 'compare', tmp_path / 'late', bh.REAL, '--est-topic',
                               '/imu/data', '--ref-topic', '/imu/data', '--offset', 'auto',
                               '--json')
    assert status == 0 and err == '', err
    found = json.loads(out)
    period = float(np.median(np.diff(imu.ns))) / 1e9
    assert abs(found['offset'] + shift) < period, found['offset']
    assert found['offset_correlation'] > 0.99
    assert found['ape']['rmse'] < np.radians(0.5)


def test_unrelated_streams_matched_by_a_weak_correlation_get_a_warning(capsys, tmp_path):
    """Two stretches of the IMU 30 s apart correlate only by chance: a warning."""
    pytest.importorskip('rosbags', reason="the 'bag' extra (rosbags) is not installed")
    from rot_tools.cli import bag_analysis
    _, (imu,) = bag_analysis.analyse(bh.REAL, ('/imu/data',))
    t = (imu.ns - imu.ns[0]) / 1e9
    first, later = t < 15, (t >= 30) & (t < 45)
    zero = np.zeros((len(t), 3))
    est = write_tum(tmp_path / 'est.tum', t[first], imu.R[first], zero[first])
    ref = write_tum(tmp_path / 'ref.tum', t[later] - 30, imu.R[later], zero[later])
    status, out, err = run_cli(capsys, 'compare', est, ref, '--offset', 'auto', '--max-offset',
                               '200000', '--json')
    found = json.loads(out)
    assert status == 0
    assert found['offset_correlation'] == pytest.approx(0.68, abs=0.005)  # doc/compare.md
    assert found['offset_warning'].startswith(
        'the angular speeds correlate weakly at the offset found (r = '
        f"{found['offset_correlation']:.2f} < 0.9)")
    assert err == f"warning: {found['offset_warning']}\n"


def test_csv_dash_is_the_standard_output(capsys, tmp_path, monkeypatch, streams):
    monkeypatch.chdir(tmp_path)
    est = write_tum(tmp_path / 'est.tum', *streams[1])
    ref = write_tum(tmp_path / 'ref.tum', *streams[0])
    status, out, err = run_cli(capsys, 'compare', est, ref, '--csv', '-')
    assert (status, err) == (0, '')
    run_cli(capsys, 'compare', est, ref, '--csv', 'e.csv')
    assert out == (tmp_path / 'e.csv').read_text()
    assert not (tmp_path / '-').exists()


# ---- mounting, simulated -------------------------------------------------------------------


def mounted(tmp_path, motion, X, rng):
    """Files of a REF and of an EST mounted by X (R_est = R_ref·X), noisy, at other rates."""
    t_ref, t_est = np.arange(0.0, 40.0, 0.01), np.arange(0.0, 40.0, 0.02)
    W = rt.rot_z(0.5)
    R_est = W @ noisy(motion(t_est), 0.02, rng) @ X
    ref = write_tum(tmp_path / 'ref.tum', t_ref, motion(t_ref), path_of(t_ref))
    est = write_tum(tmp_path / 'est.tum', t_est, R_est, path_of(t_est))
    return est, ref


def test_mounting_is_recovered_within_a_tenth_of_a_degree(capsys, tmp_path):
    X = rt.rotvec_to_matrix(np.array([0.3, -0.5, 1.1]))
    est, ref = mounted(tmp_path, turn, X, np.random.default_rng(8))
    status, out, err = run_cli(capsys, 'compare', est, ref, '--mounting', '--delta', '0.5',
                               '--delta-unit', 's', '--align', 'rotation', '--json', '--deg')
    assert status == 0 and err == '', err
    found = json.loads(out)
    got = rt.quaternion_to_matrix(np.array(found['mounting']['quaternion']))
    assert np.degrees(rt.rotation_distance(got, X)) < 0.1
    assert 'warning' not in found['mounting'] and found['mounting']['axes'] == 3
    assert found['ape']['rmse'] < 0.1  # EST turned by X and aligned: the noise is left


def test_motion_about_one_axis_gets_the_warning(capsys, tmp_path):
    def yaw_only(t):
        return rt.rot_z(np.sin(0.5 * t) * 2)
    X = rt.rotvec_to_matrix(np.array([0.3, -0.5, 1.1]))
    est, ref = mounted(tmp_path, yaw_only, X, np.random.default_rng(9))
    status, out, err = run_cli(capsys, 'compare', est, ref, '--mounting', '--delta', '0.5',
                               '--delta-unit', 's', '--json')
    assert status == 0
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].startswith(
        'warning: mounting: the motion turned about one axis only')
    assert 'not determined' in json.loads(out)['mounting']['warning']


# ---- interpolation ------------------------------------------------------------------------


def test_interpolated_matching_beats_nearest_at_two_rates(capsys, tmp_path):
    t_ref = np.arange(0.0, 20.0, 1 / 30)
    t_est = np.arange(0.0, 20.0, 1 / 47)
    ref = write_tum(tmp_path / 'ref.tum', t_ref, turn(t_ref), path_of(t_ref))
    est = write_tum(tmp_path / 'est.tum', t_est, turn(t_est), path_of(t_est))
    rmse = {}
    for how in ('interpolate', 'nearest'):
        status, out, err = run_cli(capsys, 'compare', est, ref, '--match', how, '--max-gap',
                                   '0.05', '--json')
        assert status == 0 and err == '', err
        rmse[how] = json.loads(out)['ape']['rmse']
    assert rmse['interpolate'] < 0.05 * rmse['nearest'], rmse


# ---- alignment ----------------------------------------------------------------------------


def test_posyaw_aligns_the_positions_by_a_yaw_and_a_shift(capsys, tmp_path):
    from scipy import optimize
    from scipy.spatial.transform import Rotation
    rng = np.random.default_rng(12)
    t = np.arange(0.0, 10.0, 0.05)
    R_ref, b_ref = turn(t), path_of(t) * 5
    yaw, shift = rt.rot_z(-2.0), np.array([3.0, 1.0, -0.5])
    tilt = rt.rot_x(np.radians(2))  # a drift of gravity the yaw does not take away
    R_est = yaw @ tilt @ noisy(R_ref, 0.2, rng)
    b_est = (b_ref + rng.normal(scale=0.02, size=b_ref.shape)) @ (yaw @ tilt).T + shift
    est = write_tum(tmp_path / 'est.tum', t, R_est, b_est)
    ref = write_tum(tmp_path / 'ref.tum', t, R_ref, b_ref)
    status, out, err = run_cli(capsys, 'compare', est, ref, '--align', 'posyaw', '--json',
                               '--precision', 17)
    assert status == 0 and err == '', err
    found = json.loads(out)
    b_est_read = np.loadtxt(est)[:, 1:4]  # as the file holds them, and so compare reads them

    def residuals(x):  # b_ref ≈ Rot_z(ψ)·b_est + t: the 4 unknowns, by scipy
        return (b_ref - Rotation.from_euler('z', x[0]).apply(b_est_read) - x[1:]).ravel()

    best = optimize.least_squares(residuals, [0.0, 0, 0, 0], xtol=1e-15, ftol=1e-15).x
    W = Rotation.from_euler('z', best[0])
    assert (W.inv() * Rotation.from_quat(found['alignment_quaternion'])).magnitude() < 1e-9
    R_est_read = rt.quaternion_to_matrix(np.loadtxt(est)[:, 4:8])
    angles = (Rotation.from_matrix(R_ref).inv() * W * Rotation.from_matrix(R_est_read)).magnitude()
    assert abs(found['ape']['rmse'] - np.sqrt(np.mean(angles ** 2))) < 1e-9
    assert abs(np.degrees(found['ape']['rmse']) - 2) < 0.5  # the tilt is left


# ---- outputs ------------------------------------------------------------------------------


def test_roll_pitch_yaw_statistics_are_of_angles_within_a_half_turn(capsys, tmp_path):
    t = np.arange(0.0, 20.0, 0.05)
    R = turn(t)
    drift = rt.rot_z(0.9 * t) @ rt.rot_x(np.radians(3) * np.sin(t))  # yaw drifts 1030°
    est = write_tum(tmp_path / 'est.tum', t, R @ drift, path_of(t))
    ref = write_tum(tmp_path / 'ref.tum', t, R, path_of(t))
    status, out, err = run_cli(capsys, 'compare', est, ref, '--deg', '--json', '--csv',
                               tmp_path / 'e.csv')
    assert status == 0 and err == '', err
    rpy = json.loads(out)['rpy']
    assert all(-180 < x <= 180 for key in ('mean', 'median', 'min', 'max') for x in rpy[key])
    assert 100 < rpy['rmse'][2] < 110  # uniform over (−180°, 180°]: 180/√3; not 600
    table = np.loadtxt(tmp_path / 'e.csv', delimiter=',', skiprows=1)
    assert (np.abs(table[:, 2:]) <= 180).all()
    assert abs(np.sqrt(np.mean(table[:, 4] ** 2)) - rpy['rmse'][2]) < 1e-6  # the same angles


def test_json_gives_matrices_as_rows_and_the_plot_names_the_alignment(capsys, tmp_path):
    pytest.importorskip('matplotlib', reason="the 'plot' extra (matplotlib) is not installed")
    from rot_tools.cli import compare
    t = np.arange(0.0, 10.0, 0.05)
    X = rt.rotvec_to_matrix(np.array([0.3, -0.5, 1.1]))
    W, shift = rt.rot_z(0.5), np.array([1.0, 2.0, 3.0])
    est = write_tum(tmp_path / 'est.tum', t, W.T @ turn(t) @ X, (path_of(t) - shift) @ W)
    ref = write_tum(tmp_path / 'ref.tum', t, turn(t), path_of(t))
    args = ['compare', est, ref, '--align', 'se3', '--mounting', '--json', '--precision', 12]
    status, out, err = run_cli(capsys, *args)
    assert status == 0 and err == '', err
    found = json.loads(out)
    assert np.abs(np.array(found['alignment_matrix']) - W).max() < 1e-6
    assert np.abs(np.array(found['alignment_translation']) - shift).max() < 1e-6
    assert np.abs(np.array(found['mounting']['matrix']) - X).max() < 1e-6
    parsed = cli.parse_args([str(a) for a in args])
    poses = [compare.read_side(name, path, None, None)
             for name, path in (('EST', est), ('REF', ref))]
    figure = compare.figure(compare.compare(*poses, parsed), parsed)
    title = figure.get_suptitle()
    assert 'se3 alignment (Umeyama on the positions)' in title, title
    assert 'EST turned by the mounting' in title, title


def test_csv_has_one_row_per_pair_and_the_plot_is_drawn(capsys, tmp_path, streams):
    ref = write_tum(tmp_path / 'ref.tum', *streams[0])
    est = write_tum(tmp_path / 'est.tum', *streams[1])
    args = ['compare', est, ref, '--align', 'se3', '--csv', tmp_path / 'e.csv', '--json']
    matplotlib = None
    try:
        import matplotlib
    except ImportError:
        pass
    if matplotlib is not None:
        args += ['--plot', tmp_path / 'e.png']
    status, out, err = run_cli(capsys, *args)
    assert status == 0 and err == '', err
    found = json.loads(out)
    rows = (tmp_path / 'e.csv').read_text().splitlines()
    assert rows[0] == 'stamp,angle,roll,pitch,yaw' and len(rows) == found['pairs'] + 1
    angles = np.array([float(r.split(',')[1]) for r in rows[1:]])
    assert abs(np.sqrt(np.mean(angles ** 2)) - found['ape']['rmse']) < 1e-9
    if matplotlib is not None:
        assert (tmp_path / 'e.png').read_bytes()[:4] == b'\x89PNG'


# ---- bad inputs ---------------------------------------------------------------------------


def bad_inputs(tmp_path):
    t = np.arange(0.0, 10.0, 0.05)
    R, b = turn(t), path_of(t)
    good = write_tum(tmp_path / 'good.tum', t, R, b)
    (tmp_path / 'seven.tum').write_text('0 1 2 3 0 0 0\n')
    (tmp_path / 'words.tum').write_text('0 1 2 3 0 0 0 one\n')
    (tmp_path / 'zero.tum').write_text('0 1 2 3 0 0 0 0\n1 1 2 3 0 0 0 1\n')
    (tmp_path / 'back.tum').write_text('1 0 0 0 0 0 0 1\n0 0 0 0 0 0 0 1\n')
    (tmp_path / 'short.csv').write_text('#t,x\n1,2,3\n')
    write_tum(tmp_path / 'later.tum', t + 1000.0, R, b)
    write_tum(tmp_path / 'two.tum', t[:2], R[:2], b[:2])
    write_tum(tmp_path / 'still.tum', t, np.broadcast_to(np.eye(3), R.shape), b)
    write_tum(tmp_path / 'imu.tum', t, R, b)
    write_tum(tmp_path / 'unix.tum', t + 1311868229.576, R, b)
    return good


@pytest.mark.parametrize('other, options, says', [
    ('seven.tum', (), '7 values, 8 expected'),
    ('words.tum', (), 'not a number'),
    ('zero.tum', (), 'quaternion of norm 0'),
    ('back.tum', ('--strict-stamps',), 'back.tum:2: stamp 0.0 goes back from 1.0 on line 1'),
    ('unix.tum unix.tum', ('--delta', '1e-7', '--delta-unit', 's'),
     'delta = 1e-07 s is within the rounding of stamps near 1311868239.526 s'),
    ('short.csv', (), '3 values, 8 or more expected'),
    ('missing.tum', (), 'cannot read it'),
    ('later.tum', (), 'no overlap in time'),
    ('two.tum', (), '2 matched pair(s)'),
    ('still.tum', ('--offset', 'auto'), 'turns at a constant speed'),
    ('still.tum', ('--mounting',), 'never turns'),
    ('good.tum', ('--delta', '1.5'), 'integer'),
    ('good.tum', ('--max-gap', '-1'), 'expected a number > 0'),
    ('good.tum', ('--offset', 'soon'), "expected 'auto' or seconds"),
    ('good.tum', ('--csv', 'good.tum'), 'would overwrite an input'),
    ('good.tum', ('--seq', 'ZYX'), 'unrecognized arguments: --seq ZYX'),
])
def test_bad_input_is_one_line_and_status_2(capsys, tmp_path, monkeypatch, other,
                                            options, says):
    bad_inputs(tmp_path)
    monkeypatch.chdir(tmp_path)
    sides = other.split() if ' ' in other else [other, 'good.tum']
    one_error(capsys, 'compare', *sides, *options, contains=says)


def hostile_files(directory):
    """Write small TUM files at float64's edges: stamps, steps and positions."""
    t = np.arange(20) / 10
    R = rt.rot_z((t * 3) ** 2)
    for name, stamps, b in [
            ('ok', t, path_of(t)), ('huge', np.linspace(-1, 1, 20) * 1e308, path_of(t)),
            ('tiny', t * 1e-319, path_of(t)), ('far', t, np.where(path_of(t) > 0, 1e308, -1e308)),
            ('unix', 1.3e9 + t, path_of(t)), ('late', 1e16 + t * 1e4, path_of(t))]:
        np.savetxt(directory / f'{name}.tum', np.column_stack(
            [stamps, b, rt.matrix_to_quaternion(R)]), fmt='%.17g')


@pytest.mark.parametrize('words, says', [
    ('huge ok --offset auto', 'stamps of R_est span -1e+308 to 1e+308 s: their differences '
     'overflow float64'),
    ('tiny ok --offset auto', 'R_est turns faster than float64 holds'),
    ('ok tiny --offset auto', 'R_ref turns faster than float64 holds'),
    ('far ok --align se3', None), ('ok far --align posyaw --match nearest', None),
    ('ok far --align posyaw', 'R0ᵀ·(b1 − b0) of screw_interpolate overflows float64'),
    ('unix ok --offset auto --max-offset 1e300', None),  # the offset is -1.3e9 s
    ('unix ok --offset auto --max-offset 1e8', 'the streams do not overlap within '
     'max_offset = 100000000.0 s: R_ref spans [0.05, 1.85] s, R_est [1300000000.05, '
     '1300000001.85] s'),
    ('unix ok --offset 1e300', 'no overlap in time: EST spans [1e+300, 1e+300] s (offset 1e+300 '
     's added), REF [0.0, 1.9] s'),
    ('ok ok --offset 1e10', 'no overlap in time: EST spans [10000000000.0, 10000000001.9] s '
     '(offset 10000000000.0 s added)'),
    ('ok late --offset 1e16', "the offset 1e+16 s swallows the steps of EST's stamps: 0.0 and "
     '0.1 s both become 1e+16 s'),
    ('ok ok --offset -1.3e9 --match nearest', 'no overlap in time: EST spans [-1300000000.0, '
     '-1299999998.1] s (offset -1300000000.0 s added), REF [0.0, 1.9] s'),
])
def test_edges_of_float64_are_one_plain_line_without_numpy_warnings(
        capsys, tmp_path, monkeypatch, words, says):
    hostile_files(tmp_path)
    monkeypatch.chdir(tmp_path)
    est, ref, *options = words.split()
    with warnings.catch_warnings():
        warnings.simplefilter('error')  # a RuntimeWarning would reach stderr
        status, out, err = run_cli(capsys, 'compare', f'{est}.tum', f'{ref}.tum', *options)
    if says is None:  # the fit scales the positions; the offset search finds -1.3e9 s
        assert status == 0 and err == '', err
        assert abs(yaml.safe_load(out)['offset'] - (-1.3e9 if est == 'unix' else 0)) < 0.01
        return
    assert (status, out) == (2, '') and err.count('\n') == 1, err
    assert err.startswith('rot-tools: error: compare: ') and says in err, err


def test_a_file_named_like_an_option_after_a_double_dash(capsys, tmp_path, monkeypatch):
    bad_inputs(tmp_path)
    monkeypatch.chdir(tmp_path)
    (tmp_path / '-x.tum').write_bytes((tmp_path / 'good.tum').read_bytes())
    for words in (['--', '-x.tum', 'good.tum'], ['good.tum', '--json', '--', '-x.tum']):
        status, out, err = run_cli(capsys, 'compare', *words)
        assert status == 0 and err == '', err
        assert '-x.tum' in out


def test_an_option_of_the_other_commands_before_compare(capsys, tmp_path, monkeypatch):
    bad_inputs(tmp_path)
    monkeypatch.chdir(tmp_path)
    status, _, err = run_cli(capsys, '--point', 1, 2, 3, 'compare', 'good.tum', 'good.tum')
    assert status == 2 and err == 'rot-tools: error: --point does not apply to compare\n'


def test_a_bag_of_several_topics_asks_for_one(capsys, tmp_path, streams):
    pytest.importorskip('rosbags', reason="the 'bag' extra (rosbags) is not installed")
    builder = bh.Builder()
    t, R, b = streams[1]
    q = rt.matrix_to_quaternion(R)
    bag = bh.write_bag(tmp_path / 'two', [
        (topic, 'geometry_msgs/msg/PoseStamped', int(s * 1e9), builder.pose_stamped(s, p, qk))
        for topic in ('/a', '/b') for s, p, qk in zip(t[:5], b, q)])
    ref = write_tum(tmp_path / 'ref.tum', *streams[0])
    status, _, err = run_cli(capsys, 'compare', bag, ref)
    assert status == 2 and err.count('\n') == 1
    assert '2 topics (/a, /b): choose one with --est-topic' in err
    status, _, err = run_cli(capsys, 'compare', bag, ref, '--est-topic', '/a', '--align', 'se3',
                             '--est-tf', 'map', 'body')
    assert status == 2 and 'not both' in err


def test_a_bare_mcap_file_is_a_bag_and_no_output_lands_in_a_bag(capsys, tmp_path):
    pytest.importorskip('rosbags', reason="the 'bag' extra (rosbags) is not installed")
    builder = bh.Builder()
    t = np.arange(0.0, 4.0, 0.05)
    R, b = turn(t), path_of(t)
    q = rt.matrix_to_quaternion(R)
    messages = [('/pose', 'geometry_msgs/msg/PoseStamped', int(s * 1e9) + 1,
                 builder.pose_stamped(s, p, qk)) for s, p, qk in zip(t, b, q)]
    folder = bh.write_bag(tmp_path / 'victim', messages, storage='mcap')
    (storage,) = folder.glob('*.mcap')
    bare = storage.rename(tmp_path / 'alone.mcap')
    bh.write_bag(tmp_path / 'victim2', messages)
    ref = write_tum(tmp_path / 'ref.tum', t, R, b)
    status, out, err = run_cli(capsys, 'compare', bare, ref, '--json', '--precision', 17)
    assert status == 0 and err == '', err
    assert json.loads(out)['pairs'] == len(t) and json.loads(out)['ape']['max'] < 1e-7
    metadata = tmp_path / 'victim2' / 'metadata.yaml'
    before = metadata.read_bytes()
    db3 = next((tmp_path / 'victim2').glob('*.db3'))
    for est, option, target in [(tmp_path / 'victim2', '--csv', metadata), (bare, '--csv', bare),
                                (db3, '--csv', metadata), (db3, '--plot', db3.parent / 'e.png')]:
        one_error(capsys, 'compare', est, ref, option, target,
                  contains='would overwrite the bag being read')
    assert metadata.read_bytes() == before and bare.stat().st_size > 0


def test_a_topic_whose_every_message_is_refused_is_one_line(capsys, tmp_path):
    pytest.importorskip('rosbags', reason="the 'bag' extra (rosbags) is not installed")
    builder = bh.Builder()
    t = np.arange(0.0, 1.0, 0.1)
    bag = bh.write_bag(tmp_path / 'zero', [('/imu', 'sensor_msgs/msg/Imu', int(s * 1e9) + 1,
                                            builder.imu(s, (0, 0, 0, 0))) for s in t])
    ref = write_tum(tmp_path / 'ref.tum', t, turn(t), path_of(t))
    assert one_error(capsys, 'compare', bag, ref).startswith(
        'rot-tools: error: compare: EST: /imu: no message to compare: all 10 refused, the first '
        'because ')


def test_se3_needs_positions(capsys, tmp_path):
    pytest.importorskip('rosbags', reason="the 'bag' extra (rosbags) is not installed")
    builder = bh.Builder()
    t = np.arange(0.0, 5.0, 0.02)
    q = rt.matrix_to_quaternion(turn(t))
    bag = bh.write_bag(tmp_path / 'imu', [('/imu', 'sensor_msgs/msg/Imu', int(s * 1e9),
                                           builder.imu(s, qk)) for s, qk in zip(t, q)])
    ref = write_tum(tmp_path / 'ref.tum', t, turn(t), path_of(t))
    status, _, err = run_cli(capsys, 'compare', bag, ref, '--align', 'se3')
    assert status == 2 and err.count('\n') == 1 and 'EST has none (an Imu)' in err


# ---- the docs' examples -------------------------------------------------------------------


def simulated_files(directory):
    """Write doc/compare.md's example: EST 0.25 s late, mounted by X, in a world turned 30°."""
    rng = np.random.default_rng(2024)
    t_ref, t_est = np.arange(0.0, 30.0, 0.01), np.arange(0.0, 30.0, 0.02)
    X = rt.rotvec_to_matrix(np.array([0.3, -0.5, 1.1]))
    R_est = rt.rot_z(np.radians(30)) @ noisy(turn(t_est + 0.25), 0.05, rng) @ X
    write_tum(directory / 'ref.tum', t_ref, turn(t_ref), path_of(t_ref))
    write_tum(directory / 'est.tum', t_est, R_est, path_of(t_est + 0.25))
    return X


def test_doc_example_is_real_output(capsys, tmp_path, monkeypatch):
    X = simulated_files(tmp_path)
    monkeypatch.chdir(tmp_path)
    ((command, _),) = console_steps(doc_block('compare-example'))
    status, out, err = run_cli(capsys, *shlex.split(command)[1:])
    assert status == 0 and err == '', err
    assert_doc_output('compare-example', f'$ {command}\n{out}')
    found = json.loads(run_cli(capsys, *shlex.split(command)[1:], '--json', '--precision', 12)[1])
    assert abs(found['offset'] - 0.25) < 0.01  # the 0.02 s period: within a sample
    got = rt.quaternion_to_matrix(np.array(found['mounting']['quaternion']))
    assert np.degrees(rt.rotation_distance(got, X)) < 0.1


def test_readme_example_is_real_output(capsys, monkeypatch):
    pytest.importorskip('rosbags', reason="the 'bag' extra (rosbags) is not installed")
    if not bh.REAL.exists():
        pytest.skip(f'the shared recording is not there: {bh.REAL}')
    monkeypatch.chdir(Path(__file__).resolve().parents[1])  # the README's commands' cwd
    ((command, _),) = console_steps(doc_block('readme-compare'))
    status, out, err = run_cli(capsys, *shlex.split(command)[1:])
    assert status == 0 and err == '', err
    assert_doc_output('readme-compare', f'$ {command}\n{out}')
