"""
rot-tools bag: standard deviations of roll, pitch and yaw from the recorded covariances.

Reference: σ = √diag(J·Σ·Jᵀ), J of scipy's as_euler(RPY_SEQUENCE) about the parent's fixed
axes by central differences; with ``--input-covariance rpy``, √diag(Σ).
"""

import csv
import io
import math

import bag_helpers as bh
import numpy as np
import pytest

pytest.importorskip('rosbags', reason="the 'bag' extra (rosbags) is not installed")
from rot_tools.cli import bag_covariance  # noqa: E402
from rot_tools.core.euler import RPY_SEQUENCE  # noqa: E402
from rot_tools.io import bag_read  # noqa: E402
from scipy.spatial.transform import Rotation  # noqa: E402

IMU, ODOM = '/imu/data', '/jackal_velocity_controller/odom'
STD = ['roll_std', 'pitch_std', 'yaw_std']


def cells(rows, names):
    """Return the cells as floats, NaN where empty."""
    return np.array([[float(r[n]) if r[n] else np.nan for n in names] for r in rows])


def central_difference(R, i, h):
    """Return (θ(h·e_i) − θ(−h·e_i))/2h (N, 3), θ(δ) = as_euler(RPY_SEQUENCE) of exp([δ]×)·R."""
    step = np.zeros((len(R), 3))
    step[:, i] = h
    plus = (Rotation.from_rotvec(step) * R).as_euler(RPY_SEQUENCE)
    minus = (Rotation.from_rotvec(-step) * R).as_euler(RPY_SEQUENCE)
    return (np.remainder(plus - minus + np.pi, 2 * np.pi) - np.pi) / (2 * h[:, None])


def euler_jacobian(quaternions):
    """
    dθ/dδ (N, 3, 3) at δ = 0, by central differences of step h and h/2 (Richardson).

    (4·D(h/2) − D(h))/3 cancels the h² term; h = 10⁻³·cos(pitch) keeps the step well inside
    the distance to gimbal lock, where the angles' higher derivatives grow.
    """
    R = Rotation.from_quat(quaternions)
    h = 1e-3 * np.cos(R.as_euler(RPY_SEQUENCE)[:, 1])
    J = np.empty((len(R), 3, 3))
    for i in range(3):
        J[:, :, i] = (4 * central_difference(R, i, h / 2) - central_difference(R, i, h)) / 3
    return J


def rotation_block(cov):
    """Return the rotation's 3×3 of covariances (N, 9) or (N, 36)."""
    cov = np.asarray(cov, float)
    return cov.reshape(-1, 3, 3) if cov.shape[1] == 9 else cov.reshape(-1, 6, 6)[:, 3:, 3:]


def reference_sigma(quaternions, cov, reading='rotvec'):
    """σ (N, 3) of roll, pitch, yaw (rad): √diag(J·Σ·Jᵀ), or √diag(Σ) for 'rpy'."""
    S = rotation_block(cov)
    if reading == 'rpy':
        return np.sqrt(np.diagonal(S, axis1=1, axis2=2))
    J = euler_jacobian(quaternions)
    return np.sqrt(np.einsum('nij,njk,nik->ni', J, S, J))


def decoded(path):
    """{topic: (quaternions (N, 4), covariances (N, 9 or 36))}, decoded by rosbags."""
    return {topic: (d['q'], d['cov']) for topic, d in bh.decode(path).items()}


@pytest.fixture(scope='module')
def real():
    return decoded(bh.REAL)


@pytest.fixture(scope='module')
def excerpt(tmp_path_factory):
    """Return the real recording's first 300 messages, as recorded (a ROS 1 bag)."""
    return bh.real_excerpt(tmp_path_factory.mktemp('excerpt') / 'excerpt.bag')


# The real recording


def test_real_bag_columns_and_median(capsys, real):
    rows = bh.rows_of(capsys, 'bag', bh.REAL)
    s = bh.summary_of(capsys, 'bag', bh.REAL)
    for topic in (IMU, ODOM):
        q, cov = real[topic]
        want = reference_sigma(q, cov)
        got = cells([r for r in rows if r['topic'] == topic], STD)
        np.testing.assert_allclose(got, want, rtol=2e-11, atol=5e-13)
        t = s['topics'][topic]
        assert t['covariances'] == {'reading': 'rotvec', 'good': len(q), 'unknown': 0,
                                    'bad': 0, 'gimbal_lock': 0}
        np.testing.assert_allclose([t['rpy_stddev_median'][k] for k in ('roll', 'pitch', 'yaw')],
                                   np.median(want, axis=0), rtol=2e-11, atol=5e-13)
        assert 'first_bad_covariance' not in t
    # the IMU's tilt carries some of its yaw variance into roll and pitch: not √diag
    q, cov = real[IMU]
    got = cells([r for r in rows if r['topic'] == IMU], STD)
    assert np.abs(got / reference_sigma(q, cov, 'rpy') - 1).max() > 1e-3


def test_real_bag_in_degrees(capsys, real):
    rows = bh.rows_of(capsys, 'bag', bh.REAL, '--deg', '--topic', IMU)
    q, cov = real[IMU]
    want = np.degrees(reference_sigma(q, cov))
    np.testing.assert_allclose(cells(rows, STD), want, rtol=2e-11, atol=5e-13)
    t = bh.summary_of(capsys, 'bag', bh.REAL, '--deg')['topics'][IMU]
    assert t['unit'] == 'deg'
    np.testing.assert_allclose(list(t['rpy_stddev_median'].values()), np.median(want, axis=0),
                               rtol=2e-11, atol=5e-13)


def test_real_bag_read_as_rpy(capsys, real):
    rows = bh.rows_of(capsys, 'bag', bh.REAL, '--input-covariance', 'rpy')
    s = bh.summary_of(capsys, 'bag', bh.REAL, '--input-covariance', 'rpy')
    for topic in (IMU, ODOM):
        q, cov = real[topic]
        want = reference_sigma(q, cov, 'rpy')
        got = cells([r for r in rows if r['topic'] == topic], STD)
        np.testing.assert_allclose(got, want, rtol=1e-11, atol=5e-13)  # 12 decimals
        t = s['topics'][topic]
        assert t['covariances']['reading'] == 'rpy'
        np.testing.assert_allclose(list(t['rpy_stddev_median'].values()), want[0], rtol=1e-11,
                                   atol=5e-13)
    assert s['topics'][ODOM]['rpy_stddev_median']['yaw'] == pytest.approx(math.sqrt(0.03))


@pytest.mark.parametrize('storage', ['ros1', 'sqlite3', 'mcap'])
def test_the_covariance_column_of_each_format(tmp_path, storage, excerpt):
    """The covariance column holds each message's array as rosbags decodes it, NaN and all."""
    path = excerpt if storage == 'ros1' else bh.convert_real(tmp_path / storage, storage,
                                                             excerpt)
    derived = write_derived(tmp_path / f'derived-{storage}', storage)[0]
    for source in (path, derived):
        with bag_read.open_bag(source) as reader:
            columns = bag_read.read_topics(reader, list(reader.connections))
        want = decoded(source)
        for topic, (_, cov) in want.items():
            assert columns[topic].covariance.shape == cov.shape
            np.testing.assert_array_equal(columns[topic].covariance, cov)
    assert columns['/pose'].covariance is None


# Bags written here: covariances unknown, bad, at gimbal lock


def _spd(rng, size, scale):
    A = rng.normal(size=(size, size)) * scale
    return A @ A.T


def _cases(rng, size):
    """[(name, quaternion, covariance (size²,), expected status)] of one topic."""
    q = Rotation.random(80, random_state=rng.integers(1 << 30)).as_quat()
    good = [_spd(rng, size, 0.05) for _ in range(80)]
    cases = [('good', q[k], good[k].ravel(), 'good') for k in range(80)]
    nan, asym, indefinite = good[1].copy(), good[2].copy(), good[3].copy()
    nan[-1, -2] = np.nan
    asym[-1, -2] += 1e-3 * np.abs(asym).max()
    indefinite[-3:, -3:] = np.diag([0.01, -1e-4, 0.02])
    lock = Rotation.from_euler(RPY_SEQUENCE, [0.3, np.pi / 2, -0.2]).as_quat()
    special = [('unknown', q[4], np.zeros(size * size), 'unknown'),
               ('nan', q[5], nan.ravel(), 'bad'),
               ('asymmetric', q[6], asym.ravel(), 'bad'),
               ('indefinite', q[7], indefinite.ravel(), 'bad'),
               ('lock', lock, good[8].ravel(), 'gimbal_lock'),
               ('unknown', q[9], np.zeros(size * size), 'unknown')]
    if size == 6:
        # PSD within 1e-9·max|C| of the whole (10⁶ m²), not of its rotation block alone
        whole = np.diag([1e6, 1e6, 1e6, 0.0, 0.0, 0.0])
        whole[3:5, 3:5] = [[1.0, 1.0 + 1e-5], [1.0 + 1e-5, 1.0]]
        whole[5, 5] = 0.5
        special.append(('big_position', q[10], whole.ravel(), 'good'))
    for k, case in enumerate(special):
        cases.insert(7 + 9 * k, case)
    return cases


def write_derived(path, storage, seed=3):
    """Return (bag, {topic: cases}) of an Imu, a PoseWithCovarianceStamped, an Odometry topic."""
    b, rng = bh.Builder(), np.random.default_rng(seed)
    topics = {'/imu': _cases(rng, 3), '/pose_cov': _cases(rng, 6), '/odom': _cases(rng, 6)}
    messages = []
    for topic, cases in topics.items():
        for k, (_, q, cov, _) in enumerate(cases):
            stamp = 5.0 + 0.02 * k
            p = (k, 0.5, -1.0)
            if topic == '/imu':
                msg, kind = b.imu(stamp, q, cov=cov), bh.IMU_TYPE
            elif topic == '/pose_cov':
                msg, kind = b.pose_with_covariance_stamped(stamp, p, q, cov=cov), bh.POSE_TYPE
            else:
                msg, kind = b.odometry(stamp, p, q, cov=cov), bh.ODOM_TYPE
            messages.append((topic, kind, int(stamp * 1e9), msg))
    refused = np.zeros(9)
    refused[0] = -1.0
    messages.append(('/imu', bh.IMU_TYPE, int(9e9), b.imu(9.0, (0, 0, 0, 1), cov=refused)))
    for k in range(3):
        messages.append(('/imu/none', bh.IMU_TYPE, int((6 + k) * 1e9),
                         b.imu(6.0 + k, (0, 0, 0, 1), cov=np.zeros(9))))
        messages.append(('/pose', 'geometry_msgs/msg/PoseStamped', int((6 + k) * 1e9),
                         b.pose_stamped(6.0 + k, (1, 2, 3), (0, 0, 0, 1))))
    messages.sort(key=lambda m: m[2])
    if storage == 'ros1':
        return bh.write_ros1_bag(path.with_suffix('.bag'), messages), topics
    return bh.write_bag(path, messages, storage), topics


@pytest.mark.parametrize('storage', ['ros1', 'sqlite3', 'mcap'])
def test_unknown_and_bad_covariances_leave_empty_cells(capsys, tmp_path, storage):
    path, topics = write_derived(tmp_path / 'derived', storage)
    rows = bh.rows_of(capsys, 'bag', path, run=bh.run_quiet)
    s = bh.summary_of(capsys, 'bag', path, run=bh.run_quiet)
    for topic, cases in topics.items():
        mine = [r for r in rows if r['topic'] == topic]
        assert len(mine) == len(cases)  # /imu's message without orientation is refused
        q = np.array([c[1] for c in cases])
        cov = np.array([c[2] for c in cases])
        status = np.array([c[3] for c in cases])
        got = cells(mine, STD)
        good = status == 'good'
        assert np.isnan(got[~good]).all() and not np.isnan(got[good]).any()
        want = reference_sigma(q[good], cov[good])
        np.testing.assert_allclose(got[good], want, rtol=2e-11, atol=5e-13)
        # the other columns are the message's own, whatever its covariance
        rot = Rotation.from_quat(q)
        np.testing.assert_allclose(cells(mine, ['qx', 'qy', 'qz', 'qw']),
                                   rot.as_quat(canonical=True), atol=1e-11)
        np.testing.assert_allclose(cells(mine, ['rx', 'ry', 'rz']), rot.as_rotvec(),
                                   atol=1e-10)
        t = s['topics'][topic]
        counts = {name: int((status == name).sum())
                  for name in ('good', 'unknown', 'bad', 'gimbal_lock')}
        assert counts == {'good': len(cases) - 6, 'unknown': 2, 'bad': 3, 'gimbal_lock': 1}
        assert t['covariances'] == {'reading': 'rotvec', **counts}
        assert t['accepted'] == len(cases)
        np.testing.assert_allclose(list(t['rpy_stddev_median'].values()),
                                   np.median(want, axis=0), rtol=2e-11, atol=5e-13)
        assert t['first_bad_covariance'].startswith('covariance must be finite: 1 non-finite')
    assert s['topics']['/imu']['refused']['no_orientation'] == 1
    none = s['topics']['/imu/none']
    assert none['rpy_stddev_median'] == 'unknown'
    assert none['covariances'] == {'reading': 'rotvec', 'good': 0, 'unknown': 3, 'bad': 0,
                                   'gimbal_lock': 0}
    assert 'covariances' not in s['topics']['/pose']
    assert 'rpy_stddev_median' not in s['topics']['/pose']
    assert {r[n] for r in rows if r['topic'] in ('/pose', '/imu/none') for n in STD} == {''}


def test_pitch_90_is_good_when_read_as_rpy(capsys, tmp_path):
    path, topics = write_derived(tmp_path / 'derived', 'mcap')
    rows = bh.rows_of(capsys, 'bag', path, '--input-covariance', 'rpy', '--deg', run=bh.run_quiet)
    s = bh.summary_of(capsys, 'bag', path, '--input-covariance', 'rpy', run=bh.run_quiet)
    for topic, cases in topics.items():
        mine = [r for r in rows if r['topic'] == topic]
        status = np.array([c[3] for c in cases])
        good = (status == 'good') | (status == 'gimbal_lock')
        cov = np.array([c[2] for c in cases])
        got = cells(mine, STD)
        assert np.isnan(got[~good]).all()
        np.testing.assert_allclose(got[good], np.degrees(reference_sigma(None, cov[good], 'rpy')),
                                   rtol=1e-11, atol=5e-13)
        assert s['topics'][topic]['covariances'] == {
            'reading': 'rpy', 'good': len(cases) - 5, 'unknown': 2, 'bad': 3, 'gimbal_lock': 0}


def test_runs_and_the_whole_batch_give_the_same(tmp_path, monkeypatch, excerpt):
    """Check the runs of one covariance against message_covariance's batch over every message."""
    path, _ = write_derived(tmp_path / 'derived', 'sqlite3')
    for source in (excerpt, path):
        results = {}
        for groups in (0, 10 ** 9):
            monkeypatch.setattr(bag_covariance, 'GROUPS', groups)
            for reading in ('rotvec', 'rpy'):
                _, topics = cli_analyse(source, reading)
                results[groups, reading] = {t.topic: (t.rpy_std, t.covariance_status)
                                            for t in topics if t.covariance_status is not None}
        for reading in ('rotvec', 'rpy'):
            runs, whole = results[10 ** 9, reading], results[0, reading]
            assert runs.keys() == whole.keys() and len(runs) >= 2
            for topic in runs:
                np.testing.assert_array_equal(runs[topic][1], whole[topic][1])
                np.testing.assert_allclose(runs[topic][0], whole[topic][0], rtol=1e-13,
                                           atol=0)


def cli_analyse(path, reading):
    from rot_tools.cli import bag_analysis
    return bag_analysis.analyse(path, reading=reading)


def test_parquet_null_where_the_csv_is_empty(capsys, tmp_path):
    pq = pytest.importorskip('pyarrow.parquet')
    import pyarrow as pa
    path, _ = write_derived(tmp_path / 'derived', 'sqlite3')
    status, _, err = bh.run_quiet(capsys, 'bag', path, '--parquet', tmp_path / 'pq', '--csv',
                                  tmp_path / 'rows.csv', '--deg', '--precision', '17')
    assert (status, err) == (0, '')
    (file,) = (tmp_path / 'pq').glob('*.parquet')
    table = pq.read_table(file)
    rows = list(csv.DictReader(io.StringIO((tmp_path / 'rows.csv').read_text())))
    assert table.num_rows == len(rows)
    for name in STD:
        assert table.schema.field(name).type == pa.float64()
        column = table.column(name).to_pylist()
        assert [v is None for v in column] == [r[name] == '' for r in rows]
        np.testing.assert_allclose([np.nan if v is None else v for v in column],
                                   cells(rows, [name])[:, 0], rtol=1.1e-16, atol=1.1e-17)


def test_the_option_reaches_every_bag_of_a_fleet(capsys, tmp_path):
    path, _ = write_derived(tmp_path / 'derived', 'mcap')
    data = bh.summary_of(capsys, 'bag', bh.REAL, path, '--jobs', '1', '--input-covariance', 'rpy')
    readings = {t['covariances']['reading'] for e in data['bags']
                for t in e['topics'].values() if 'covariances' in t}
    assert readings == {'rpy'} and data['fleet']['failed'] == 0


def test_an_unknown_reading_is_refused(capsys):
    status, out, err = bh.run_quiet(capsys, 'bag', bh.REAL, '--input-covariance', 'body')
    assert (status, out) == (2, '')
    assert "argument --input-covariance: invalid choice: 'body'" in err.splitlines()[-1]


# Covariances at float64's ends


def extreme_bag(path):
    """Return (bag, {topic: (quaternions, covariances)}): covariances near 1e308 and 5e-324."""
    b, rng = bh.Builder(), np.random.default_rng(11)
    q = Rotation.random(40, random_state=7).as_quat()
    huge, tiny = 1e308 * np.eye(3).ravel(), 5e-324 * np.eye(3).ravel()
    pose = np.diag([1.0, 1.0, 1.0, 1e308, 1e308, 1e308]).ravel()
    plan = {'/imu': (q[:32], [huge] * 24 + [tiny] * 8), '/odom': (q[32:], [pose] * 8)}
    messages = []
    for topic, (qs, covs) in plan.items():
        for k, (qk, cov) in enumerate(zip(qs, covs)):
            stamp = 3.0 + 0.05 * k
            msg = (b.imu(stamp, qk, cov=cov) if topic == '/imu' else
                   b.odometry(stamp, rng.normal(size=3), qk, cov=cov))
            messages.append((topic, bh.IMU_TYPE if topic == '/imu' else bh.ODOM_TYPE,
                             int(stamp * 1e9), msg))
    return bh.write_bag(path, messages), {t: (qs, np.array(c)) for t, (qs, c) in plan.items()}


def test_covariances_near_float64_s_ends_are_converted_at_the_scale_of_one(
        capsys, tmp_path, monkeypatch):
    """
    σ = √max|C|·σ(C / max|C|): 1e308·I gives σ near 1e154, 5e-324·I near 2e-162, never inf or 0.

    One beyond float64 is bad, as ~/rpy_covariance says; the table is written whole.
    """
    path, plan = extreme_bag(tmp_path / 'extreme')
    out = tmp_path / 'rows.csv'
    status, _, err = bh.run_quiet(capsys, 'bag', path, '--csv', out)
    assert (status, err) == (0, '')
    rows = list(csv.DictReader(io.StringIO(out.read_text())))
    analysed = []
    for groups in (0, 10 ** 9):  # every message in one batch, or run by run
        monkeypatch.setattr(bag_covariance, 'GROUPS', groups)
        _, topics = cli_analyse(path, 'rotvec')
        analysed.append({t.topic: (t.rpy_std, t.covariance_status) for t in topics})
    limit = np.finfo(float).max
    for topic, (q, cov) in plan.items():
        scale = np.abs(cov).max(axis=1)[:, None]
        unit = reference_sigma(q, cov / scale)
        with np.errstate(over='ignore'):
            ratio = unit ** 2 * scale / limit  # the variance against float64's largest
        expected = np.where((ratio > 1).any(axis=1)[:, None], np.nan, unit * np.sqrt(scale))
        clear = (np.abs(ratio - 1) > 1e-6).all(axis=1)
        huge = scale[:, 0] > 1
        table = cells([r for r in rows if r['topic'] == topic], STD)  # 2e-162 prints as 0
        for got in (table[huge], analysed[0][topic][0][huge], analysed[1][topic][0][huge],
                    analysed[1][topic][0][~huge]):
            assert (got[np.isfinite(got)] > 0).all()
        for got in (table[huge], *(a[topic][0] for a in analysed)):
            part = huge if len(got) < len(q) else slice(None)
            ok = clear[part]
            assert (np.isnan(got) == np.isnan(expected[part]))[ok].all(), topic
            np.testing.assert_allclose(got[ok], expected[part][ok], rtol=1e-6)
        np.testing.assert_array_equal(analysed[0][topic][1], analysed[1][topic][1])
        np.testing.assert_allclose(analysed[0][topic][0], analysed[1][topic][0], rtol=1e-13)
        assert (ratio[huge] > 1).any() and not (ratio[huge] > 1).all()
