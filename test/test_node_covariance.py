"""
rotation_node's ~/rpy_covariance and describe's rpy_stddev / rpy_correlation, over real DDS.

The expected covariance is J·Σ·Jᵀ, J by central differences of scipy's ``as_euler('xyz')``.
"""

import math
import warnings

import conftest
from doc_blocks import assert_doc_output
from geometry_msgs.msg import PoseWithCovarianceStamped
import numpy as np
import pytest
from rclpy.parameter import Parameter
from rot_tools.ros.node.rotation_node import RotationNode
from scipy.spatial.transform import Rotation
from test_node import imu, odometry, pose_with_covariance, quat, Rig, set_one, xyz

H = 1e-5
RPY = (0.3, -0.5, 1.1)
"""Roll, pitch, yaw of the test rotation (rad): far from gimbal lock and from ±π."""
Q = Rotation.from_euler('xyz', RPY).as_quat()
P = (1.5, -2.0, 0.25)

BUILD = {
    'imu': lambda cov, q=Q: imu(q, frame='map', covariance=cov),
    'pose_with_covariance': lambda cov, q=Q: pose_with_covariance(q, P, covariance=cov),
    'odometry': lambda cov, q=Q: odometry(q, P, frame='map', covariance=cov),
}
SIZE = {'imu': 3, 'pose_with_covariance': 6, 'odometry': 6}


def spd(n, seed, scale=(0.1, 0.05, 0.02, 0.035, 0.02, 0.01)):
    """Return a correlated n×n covariance (position ≤ 0.1 m, rotations ≤ 2°)."""
    A = np.linalg.qr(np.random.default_rng(seed).standard_normal((n, n)))[0]
    C = A @ np.diag(np.array(scale[-n:]) ** 2) @ A.T
    return 0.5 * (C + C.T)


def rpy_jacobian(q):
    """∂(roll, pitch, yaw)/∂δ at δ = 0, R_true = exp([δ]×)·R, by scipy and central differences."""
    R = Rotation.from_quat(q)

    def rpy(delta):
        return (Rotation.from_rotvec(delta) * R).as_euler('xyz')
    return np.stack([(rpy(H * e) - rpy(-H * e)) / (2 * H) for e in np.eye(3)], axis=-1)


def expected_covariance(q, cov):
    """Return the 6×6 ~/rpy_covariance of an input with orientation q and covariance cov."""
    cov = np.asarray(cov, dtype=float)
    T = np.eye(cov.shape[0])
    T[-3:, -3:] = rpy_jacobian(q)
    out = np.zeros((6, 6))
    out[6 - len(T):, 6 - len(T):] = T @ cov @ T.T
    return out


@pytest.fixture(scope='module')
def rig(ros_context, tester_context):
    """One RotationNode for the module, and a tester matched with it."""
    tester = conftest.Tester(tester_context, name='covariance_tester')
    node = RotationNode(context=ros_context, namespace=f'/{conftest.RUN}/covariance',
                        parameter_overrides=[Parameter('publish_markers', value=False)])
    try:
        yield Rig(tester, node)
    finally:
        tester.remove_node(node)
        node.destroy_node()
        tester.close()


@pytest.fixture(autouse=True)
def defaults(rig):
    """Each test starts from the defaults of the parameters the module changes."""
    yield
    assert set_one(rig.node, 'angle_unit', 'rad').successful
    assert set_one(rig.node, 'input_covariance', 'rotvec').successful


def served(rig, kind, msg):
    """Send msg; wait for its outputs (not ~/rpy_covariance); return its stamp."""
    stamp = rig.send(kind, msg)
    rig.outputs(stamp, marker=False)
    return stamp


def assert_no_covariance(rig, kind, stamp):
    """Check ~/rpy_covariance has nothing for ``stamp``: a good input sent after it has one."""
    later = served(rig, kind, BUILD[kind](np.eye(SIZE[kind]) * 1e-4))
    rig.output_of('rpy_covariance', later)
    assert [m for m in rig.received('rpy_covariance') if m.header.stamp.sec == stamp] == []


def refused(rig):
    return rig.report_or_note()['refused']  # (before any input too)


@pytest.mark.parametrize('kind', BUILD)
def test_each_input_publishes_its_rpy_covariance(rig, kind):
    cov = spd(SIZE[kind], seed=len(kind))
    stamp = served(rig, kind, BUILD[kind](cov))
    msg = rig.output_of('rpy_covariance', stamp)
    assert isinstance(msg, PoseWithCovarianceStamped) and msg.header.frame_id == 'map'
    assert quat(msg.pose.pose.orientation).tolist() == Q.tolist()
    assert xyz(msg.pose.pose.position).tolist() == (list(P) if SIZE[kind] == 6 else [0.0] * 3)
    expected = expected_covariance(Q, cov)
    got = np.reshape(msg.pose.covariance, (6, 6))
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-9 * np.abs(expected).max())
    np.testing.assert_array_equal(got, got.T)
    if SIZE[kind] == 6:
        np.testing.assert_array_equal(got[:3, :3], cov[:3, :3])  # the position block as sent
    report = rig.report()
    assert report['rpy_covariance_of'] == {'source': rig.topic(kind),
                                           'stamp': {'sec': stamp, 'nanosec': 0}}
    s = np.sqrt(np.diag(expected)[3:])
    stddev = report['rpy_stddev']
    assert list(stddev) == ['roll', 'pitch', 'yaw', 'unit'] and stddev['unit'] == 'rad'
    np.testing.assert_allclose([stddev[k] for k in ('roll', 'pitch', 'yaw')], s, rtol=1e-8)
    np.testing.assert_allclose(report['rpy_correlation'], expected[3:, 3:] / np.outer(s, s),
                               rtol=0, atol=1e-8)


def test_describe_gives_the_standard_deviations_in_angle_unit(rig):
    assert set_one(rig.node, 'angle_unit', 'deg').successful
    cov = np.diag([1e-4, 4e-4, 9e-4])
    stamp = served(rig, 'imu', BUILD['imu'](cov))
    expected = expected_covariance(Q, cov)
    got = np.reshape(rig.output_of('rpy_covariance', stamp).pose.covariance, (6, 6))  # always rad²
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-9 * np.abs(expected).max())
    stddev = rig.report()['rpy_stddev']
    assert stddev['unit'] == 'deg'
    np.testing.assert_allclose([stddev[k] for k in ('roll', 'pitch', 'yaw')],
                               np.degrees(np.sqrt(np.diag(expected)[3:])), rtol=1e-8)
    assert xyz(rig.received('rpy')[-1].vector) == pytest.approx(np.degrees(RPY), abs=1e-12)


def test_the_documented_describe_of_a_covariance(rig):
    """Check doc/node.md's example: at pitch 60°, 0.5° about fixed X and Y is 1° of roll."""
    assert set_one(rig.node, 'angle_unit', 'deg').successful
    q = Rotation.from_euler('xyz', [5.0, 60.0, 30.0], degrees=True).as_quat()
    cov = np.diag(np.radians([0.5, 0.5, 2.0]) ** 2)
    served(rig, 'imu', BUILD['imu'](cov, q))
    text = rig.describe().message
    shown = text[text.index('rpy_covariance_of:'):text.index('refused:')]
    assert_doc_output('node-describe-covariance', shown.replace(rig.prefix, '/rot_tools'))
    assert rig.report()['rpy_stddev']['roll'] == pytest.approx(1.0, abs=0.05)


def test_an_unknown_covariance_publishes_nothing_and_is_said_unknown(rig):
    before = refused(rig)
    stamp = served(rig, 'odometry', BUILD['odometry'](np.zeros((6, 6))))
    report = rig.report()
    assert report['rpy_stddev'] == report['rpy_correlation'] == 'unknown'
    assert report['rpy_covariance_of']['stamp']['sec'] == stamp
    assert report['refused'] == before
    assert_no_covariance(rig, 'odometry', stamp)


def test_input_covariance_rpy_passes_the_block_through(rig):
    assert set_one(rig.node, 'input_covariance', 'rpy').successful
    for kind in ('odometry', 'imu'):
        cov = spd(SIZE[kind], seed=11)
        got = rig.output_of('rpy_covariance', served(rig, kind, BUILD[kind](cov))).pose.covariance
        expected = np.zeros((6, 6))
        expected[6 - len(cov):, 6 - len(cov):] = cov
        np.testing.assert_array_equal(np.reshape(got, (6, 6)), expected)


def test_input_covariance_is_validated(rig):
    result = set_one(rig.node, 'input_covariance', 'euler')
    assert not result.successful
    assert result.reason == "input_covariance 'euler' is not 'rotvec' or 'rpy'"
    assert rig.node.get_parameter('input_covariance').value == 'rotvec'
    descriptor = rig.node.describe_parameter('input_covariance')
    assert descriptor.description and descriptor.additional_constraints == "'rotvec' or 'rpy'"


def test_gimbal_lock_publishes_nothing_and_describe_says_so(rig):
    before = refused(rig)
    q = Rotation.from_euler('xyz', [0.2, math.pi / 2, 0.0]).as_quat()
    stamp = served(rig, 'imu', BUILD['imu'](np.eye(3) * 1e-4, q))
    report = rig.report()
    assert report['rpy_stddev'] == report['rpy_correlation'] == (
        'none at gimbal lock (pitch ±90°)')
    assert report['refused'] == before  # not a refusal of the input
    assert_no_covariance(rig, 'imu', stamp)
    assert set_one(rig.node, 'input_covariance', 'rpy').successful  # given as roll/pitch/yaw
    got = rig.output_of('rpy_covariance', served(rig, 'imu', BUILD['imu'](np.eye(3) * 1e-4, q)))
    np.testing.assert_array_equal(np.reshape(got.pose.covariance, (6, 6))[3:, 3:],
                                  np.eye(3) * 1e-4)


NON_SYMMETRIC = np.eye(6) * 0.01
NON_SYMMETRIC[0, 4] = 0.5
NOT_PSD = np.diag([1e-4, -2e-4, 1e-4])
NAN = np.eye(6) * 0.01
NAN[5, 5] = math.nan
INF = np.eye(3) * 1e-4
INF[1, 2] = -math.inf
BIG = 1.7976931348623157e308

BAD = [  # (kind, covariance, the refusal's sentence)
    ('pose_with_covariance', NON_SYMMETRIC,
     'pose.covariance is not symmetric: max|C − Cᵀ| = 0.5 > 1e-09·max|C| = 5e-10'),
    ('imu', NOT_PSD, 'orientation_covariance is not positive semi-definite: its lowest '
     'eigenvalue is -0.0002, below -1e-09·max|C| = -2e-13'),
    ('odometry', NAN, 'pose.covariance must be finite: 1 non-finite value(s), first nan at '
     'index (5, 5)'),
    ('imu', INF, 'orientation_covariance must be finite: 1 non-finite value(s), first -inf at '
     'index (1, 2)'),
    ('imu', BIG * np.eye(3), 'orientation_covariance: its covariance of roll, pitch, yaw '
     'overflows float64 (beyond ±1.8e308)'),  # a covariance, but not its roll, pitch, yaw
]


def test_bad_covariances_are_refused_one_after_the_other(rig):
    """Each bad covariance is counted and said; the input's other outputs are published."""
    before = refused(rig)
    for k, (kind, cov, why) in enumerate(BAD, start=1):
        stamp = served(rig, kind, BUILD[kind](cov))
        assert rig.received('rpy')[-1].header.stamp.sec == stamp
        report = rig.report()
        assert report['refused']['bad_covariance'] == before['bad_covariance'] + k
        assert report['refused']['total'] == before['total'] + k
        assert report['last_refusals']['bad_covariance'] == {
            'source': rig.topic(kind), 'stamp': {'sec': stamp, 'nanosec': 0}, 'message': why}
        assert report['rpy_stddev'] == 'refused (bad_covariance)'
        assert report['source'] == rig.topic(kind)  # the input itself was accepted
        assert_no_covariance(rig, kind, stamp)


def test_huge_and_subnormal_covariances_are_published_as_they_are(rig):
    """1e308·I is finite (no .inf, no RuntimeWarning); 5e-324·I is not all zeros (unknown)."""
    huge = np.diag([1e308, 2e307, 1e307, 1e308, 1e308, 1e308])
    with warnings.catch_warnings(record=True) as caught:  # the node runs in this thread
        warnings.simplefilter('always')
        stamp = served(rig, 'odometry', BUILD['odometry'](huge))
        got = np.reshape(rig.output_of('rpy_covariance', stamp).pose.covariance, (6, 6))
        stamp = served(rig, 'imu', BUILD['imu'](5e-324 * np.eye(3)))
        tiny = rig.output_of('rpy_covariance', stamp)
    assert not [w for w in caught if issubclass(w.category, RuntimeWarning)]
    expected = expected_covariance(Q, huge / 1e308) * 1e308  # linear in the covariance
    assert np.isfinite(got).all()
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-9 * np.abs(expected).max())
    np.testing.assert_array_equal(got[:3, :3], huge[:3, :3])
    rpy = np.reshape(tiny.pose.covariance, (6, 6))[3:, 3:]
    J = rpy_jacobian(Q)  # diag(J·Jᵀ) ≥ 1 (the Euler-rate columns are unit vectors)
    np.testing.assert_array_equal(np.diag(rpy), 5e-324 * np.round(np.diag(J @ J.T)))


def test_near_gimbal_lock_describe_notes_what_the_standard_deviations_mean(rig):
    """1.7e-6 rad from the lock, 0.57° of error: a roll and yaw of 5,700 rad, and a note."""
    q = Rotation.from_euler('xyz', [0.2, math.pi / 2 - 1.7e-6, 0.1]).as_quat()
    served(rig, 'imu', BUILD['imu'](np.eye(3) * 1e-4, q))
    report = rig.report()
    assert report['rpy_stddev']['roll'] > 5000
    assert report['rpy_note'].startswith(
        'pitch is 1.7e-06 rad from gimbal lock (pitch = ±90°), within 3 of its standard '
        'deviations (0.01 rad)'), report['rpy_note']
    served(rig, 'imu', BUILD['imu'](np.eye(3) * 1e-4))
    assert 'rpy_note' not in rig.report()
