"""Bags written by the tests (rosbags' writer), from the real recording or message by message."""

import csv
import io
import json
from pathlib import Path

from conftest import run_cli
import numpy as np

REAL = Path(__file__).resolve().parents[1].parent / 'shared' / 'data' / 'jackal_imu_odometry.bag'
"""61 s of a Clearpath Jackal: 3,061 Imu on /imu/data, 3,060 Odometry on
/jackal_velocity_controller/odom (a ROS 1 bag; see its README)."""

IMU_TYPE, POSE_TYPE = 'sensor_msgs/msg/Imu', 'geometry_msgs/msg/PoseWithCovarianceStamped'
ODOM_TYPE = 'nav_msgs/msg/Odometry'


def decode(path=REAL):
    """
    Return {topic: {field: array}} of a bag's Imu and poses with covariance, decoded by rosbags.

    Fields: record (ns), sec, nsec, stamp (s), frame (a list), q (x, y, z, w), p (zero for an
    Imu), cov; an Imu's gyro and accel too.
    """
    from rosbags.highlevel import AnyReader
    out = {}
    with AnyReader([path]) as reader:
        for conn, record, raw in reader.messages():
            if conn.msgtype not in (IMU_TYPE, POSE_TYPE, ODOM_TYPE):
                continue
            msg = reader.deserialize(raw, conn.msgtype)
            d = out.setdefault(conn.topic, {})
            if conn.msgtype == IMU_TYPE:
                q, p, cov = msg.orientation, None, msg.orientation_covariance
                w, a = msg.angular_velocity, msg.linear_acceleration
                d.setdefault('gyro', []).append((w.x, w.y, w.z))
                d.setdefault('accel', []).append((a.x, a.y, a.z))
            else:
                q, p, cov = msg.pose.pose.orientation, msg.pose.pose.position, msg.pose.covariance
            for name, value in (('record', record), ('sec', msg.header.stamp.sec),
                                ('nsec', msg.header.stamp.nanosec),
                                ('frame', msg.header.frame_id), ('q', (q.x, q.y, q.z, q.w)),
                                ('p', (0.0, 0.0, 0.0) if p is None else (p.x, p.y, p.z)),
                                ('cov', np.array(cov, float))):
                d.setdefault(name, []).append(value)
    for d in out.values():
        d.update({k: np.array(v) for k, v in d.items() if k != 'frame'})
        d['stamp'] = d['sec'] + 1e-9 * d['nsec']
    return out


def convert_real(dst, storage, source=REAL):
    """Return the real recording (or ``source``) as a rosbag2 bag (storage 'sqlite3' or 'mcap')."""
    from rosbags.convert import convert
    convert([Path(source)], Path(dst), storage, 8, None, 'file', None, None, [], [], [], [])
    return Path(dst)


def real_excerpt(dst, count=300):
    """Return a ROS 1 bag of the real recording's first ``count`` messages, copied as recorded."""
    from rosbags.rosbag1 import Reader, Writer
    with Reader(REAL) as reader, Writer(Path(dst)) as writer:
        conns = {}
        for k, (conn, t, raw) in enumerate(reader.messages()):
            if k == count:
                break
            if conn.topic not in conns:
                conns[conn.topic] = writer.add_connection(
                    conn.topic, conn.msgtype, msgdef=conn.msgdef.data, md5sum=conn.digest)
            writer.write(conns[conn.topic], t, raw)
    return Path(dst)


def store():
    from rosbags.typesys import get_typestore, Stores
    return get_typestore(Stores.ROS2_JAZZY)


class Builder:
    """Message objects of the ROS 2 Jazzy types, as rosbags builds them."""

    def __init__(self):
        self.store = store()
        self.t = self.store.types

    def make(self, name, **fields):
        return self.t[name](**fields)

    def header(self, stamp, frame='map'):
        sec = int(np.floor(stamp))
        time = self.make('builtin_interfaces/msg/Time', sec=sec,
                         nanosec=int(round((stamp - sec) * 1e9)))
        return self.make('std_msgs/msg/Header', stamp=time, frame_id=frame)

    def vector(self, v):
        return self.make('geometry_msgs/msg/Vector3', x=float(v[0]), y=float(v[1]),
                         z=float(v[2]))

    def point(self, v):
        return self.make('geometry_msgs/msg/Point', x=float(v[0]), y=float(v[1]),
                         z=float(v[2]))

    def quaternion(self, q):
        return self.make('geometry_msgs/msg/Quaternion', x=float(q[0]), y=float(q[1]),
                         z=float(q[2]), w=float(q[3]))

    def pose(self, p, q):
        return self.make('geometry_msgs/msg/Pose', position=self.point(p),
                         orientation=self.quaternion(q))

    def pose_stamped(self, stamp, p, q, frame='map'):
        return self.make('geometry_msgs/msg/PoseStamped', header=self.header(stamp, frame),
                         pose=self.pose(p, q))

    def _covariance(self, p, q, cov=None):
        cov = np.zeros(36) if cov is None else np.asarray(cov, float).reshape(36)
        return self.make('geometry_msgs/msg/PoseWithCovariance', pose=self.pose(p, q),
                         covariance=cov)

    def pose_with_covariance_stamped(self, stamp, p, q, frame='map', cov=None):
        return self.make('geometry_msgs/msg/PoseWithCovarianceStamped',
                         header=self.header(stamp, frame), pose=self._covariance(p, q, cov))

    def odometry(self, stamp, p, q, frame='odom', child='base_link', cov=None):
        zero = self.vector((0, 0, 0))
        twist = self.make('geometry_msgs/msg/TwistWithCovariance',
                          twist=self.make('geometry_msgs/msg/Twist', linear=zero, angular=zero),
                          covariance=np.zeros(36))
        return self.make('nav_msgs/msg/Odometry', header=self.header(stamp, frame),
                         child_frame_id=child, pose=self._covariance(p, q, cov), twist=twist)

    def imu(self, stamp, q, gyro=(0, 0, 0), cov0=0.0, frame='imu', cov=None):
        """Return an Imu; its orientation_covariance ``cov`` (9 numbers), else 0 but [0] = cov0."""
        if cov is None:
            cov = np.zeros(9)
            cov[0] = cov0
        cov = np.asarray(cov, float).reshape(9)
        return self.make('sensor_msgs/msg/Imu', header=self.header(stamp, frame),
                         orientation=self.quaternion(q), orientation_covariance=cov,
                         angular_velocity=self.vector(gyro),
                         angular_velocity_covariance=np.zeros(9),
                         linear_acceleration=self.vector((0, 0, 0)),
                         linear_acceleration_covariance=np.zeros(9))

    def quaternion_stamped(self, stamp, q, frame='map'):
        return self.make('geometry_msgs/msg/QuaternionStamped',
                         header=self.header(stamp, frame), quaternion=self.quaternion(q))

    def transform_stamped(self, stamp, t, q, frame='map', child='body'):
        tf = self.make('geometry_msgs/msg/Transform', translation=self.vector(t),
                       rotation=self.quaternion(q))
        return self.make('geometry_msgs/msg/TransformStamped',
                         header=self.header(stamp, frame), child_frame_id=child, transform=tf)

    def tf_message(self, transforms):
        return self.make('tf2_msgs/msg/TFMessage', transforms=list(transforms))

    def string(self, text):
        return self.make('std_msgs/msg/String', data=text)


def write_bag(dst, messages, storage='sqlite3'):
    """Return a rosbag2 bag of [(topic, msgtype, record time ns, message object)]."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    typestore = store()
    plugin = StoragePlugin.MCAP if storage == 'mcap' else StoragePlugin.SQLITE3
    with Writer(Path(dst), version=8, storage_plugin=plugin) as writer:
        conns = {}
        for topic, msgtype, t, msg in messages:
            if topic not in conns:
                conns[topic] = writer.add_connection(topic, msgtype, typestore=typestore)
            writer.write(conns[topic], t, typestore.serialize_cdr(msg, msgtype))
    return Path(dst)


def write_ros1_bag(dst, messages):
    """Return a ROS 1 bag of [(topic, msgtype, record time ns, message object)]."""
    from rosbags.rosbag1 import Writer
    typestore = store()
    with Writer(Path(dst)) as writer:
        conns = {}
        for topic, msgtype, t, msg in messages:
            if topic not in conns:
                conns[topic] = writer.add_connection(topic, msgtype, typestore=typestore)
            writer.write(conns[topic], t, typestore.serialize_ros1(msg, msgtype))
    return Path(dst)


def tf_chain_messages(n=40, bad_at=7):
    """
    Return (messages, truth, static) of a TF tree map → odom → base_link → imu, plus odom → wheel.

    base_link → imu is on /tf_static; odom → wheel has a zero quaternion at sample ``bad_at``.
    """
    b = Builder()
    rng = np.random.default_rng(17)
    messages, truth = [], {}
    static_q = rng.normal(size=4)
    static_q /= np.linalg.norm(static_q)
    static = b.transform_stamped(0.5, (0.1, 0.0, 0.2), static_q, 'base_link', 'imu')
    messages.append(('/tf_static', 'tf2_msgs/msg/TFMessage', 500_000_000,
                     b.tf_message([static])))
    for k in range(n):
        stamp = 1.0 + 0.1 * k
        sample = {}
        transforms = []
        for parent, child in (('map', 'odom'), ('odom', 'base_link'), ('odom', 'wheel')):
            q = rng.normal(size=4)
            q /= np.linalg.norm(q)
            if child == 'wheel' and k == bad_at:
                q = np.zeros(4)
            t = rng.normal(size=3)
            sample[parent, child] = (q, t)
            transforms.append(b.transform_stamped(stamp, t, q, parent, child))
        truth[stamp] = sample
        messages.append(('/tf', 'tf2_msgs/msg/TFMessage', int(stamp * 1e9) + 1000,
                         b.tf_message(transforms)))
    return messages, truth, (static_q, np.array([0.1, 0.0, 0.2]))


def without_definitions(bag):
    """Return the rosbag2 sqlite3 bag without its message definitions, as older recorders wrote."""
    import sqlite3
    (db,) = Path(bag).glob('*.db3')
    with sqlite3.connect(db) as con:
        con.execute('DELETE FROM message_definitions')
    return Path(bag)


def run_quiet(capsys, *args):
    """Return run_cli's (status, stdout, stderr), stderr without the gyro warnings."""
    status, out, err = run_cli(capsys, *args)
    return status, out, without_gyro_warnings(err)


def summary_of(capsys, *args, run=run_cli):
    """Return the --json summary of ``run`` on these words; it must succeed, stderr empty."""
    status, out, err = run(capsys, *args, '--json')
    assert (status, err) == (0, ''), err
    return json.loads(out)


def rows_of(capsys, *args, run=run_cli):
    """Return the --csv rows of ``run`` on these words; it must succeed, stderr empty."""
    status, out, err = run(capsys, *args, '--csv', '-')
    assert (status, err) == (0, ''), err
    return list(csv.DictReader(io.StringIO(out)))


def without_gyro_warnings(err):
    """Return stderr without the warnings of an Imu whose orientation disagrees with its gyro."""
    return ''.join(line for line in err.splitlines(keepends=True)
                   if 'the orientation disagrees with the gyro' not in line)
