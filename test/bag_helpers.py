"""Bags written by the tests (rosbags' writer), from the real recording or message by message."""

from pathlib import Path

import numpy as np

REAL = Path(__file__).resolve().parents[1].parent / 'shared' / 'data' / 'jackal_imu_odometry.bag'
"""61 s of a Clearpath Jackal: 3,061 Imu on /imu/data, 3,060 Odometry on
/jackal_velocity_controller/odom (a ROS 1 bag; see its README)."""


def convert_real(dst, storage):
    """The real recording as a rosbag2 bag (storage 'sqlite3' or 'mcap'), by rosbags."""
    from rosbags.convert import convert
    convert([REAL], Path(dst), storage, 8, None, 'file', None, None, [], [], [], [])
    return Path(dst)


def store():
    from rosbags.typesys import get_typestore, Stores
    return get_typestore(Stores.ROS2_JAZZY)


class Builder:
    """Message objects of the ROS 2 Jazzy types, as rosbags builds them."""

    def __init__(self):
        self.store = store()
        self.t = self.store.types

    def _type(self, name):
        return self.t[name]

    def header(self, stamp, frame='map'):
        Time = self._type('builtin_interfaces/msg/Time')
        sec = int(np.floor(stamp))
        return self._type('std_msgs/msg/Header')(
            stamp=Time(sec=sec, nanosec=int(round((stamp - sec) * 1e9))), frame_id=frame)

    def vector(self, v):
        return self._type('geometry_msgs/msg/Vector3')(x=float(v[0]), y=float(v[1]),
                                                        z=float(v[2]))

    def point(self, v):
        return self._type('geometry_msgs/msg/Point')(x=float(v[0]), y=float(v[1]),
                                                      z=float(v[2]))

    def quaternion(self, q):
        return self._type('geometry_msgs/msg/Quaternion')(
            x=float(q[0]), y=float(q[1]), z=float(q[2]), w=float(q[3]))

    def pose(self, p, q):
        return self._type('geometry_msgs/msg/Pose')(position=self.point(p),
                                                     orientation=self.quaternion(q))

    def pose_stamped(self, stamp, p, q, frame='map'):
        return self._type('geometry_msgs/msg/PoseStamped')(header=self.header(stamp, frame),
                                                            pose=self.pose(p, q))

    def pose_with_covariance_stamped(self, stamp, p, q, frame='map'):
        cov = self._type('geometry_msgs/msg/PoseWithCovariance')(
            pose=self.pose(p, q), covariance=np.zeros(36))
        return self._type('geometry_msgs/msg/PoseWithCovarianceStamped')(
            header=self.header(stamp, frame), pose=cov)

    def odometry(self, stamp, p, q, frame='odom', child='base_link'):
        cov = self._type('geometry_msgs/msg/PoseWithCovariance')(
            pose=self.pose(p, q), covariance=np.zeros(36))
        twist = self._type('geometry_msgs/msg/TwistWithCovariance')(
            twist=self._type('geometry_msgs/msg/Twist')(linear=self.vector((0, 0, 0)),
                                                        angular=self.vector((0, 0, 0))),
            covariance=np.zeros(36))
        return self._type('nav_msgs/msg/Odometry')(header=self.header(stamp, frame),
                                                   child_frame_id=child, pose=cov, twist=twist)

    def imu(self, stamp, q, gyro=(0, 0, 0), cov0=0.0, frame='imu'):
        cov = np.zeros(9)
        cov[0] = cov0
        return self._type('sensor_msgs/msg/Imu')(
            header=self.header(stamp, frame), orientation=self.quaternion(q),
            orientation_covariance=cov, angular_velocity=self.vector(gyro),
            angular_velocity_covariance=np.zeros(9), linear_acceleration=self.vector((0, 0, 0)),
            linear_acceleration_covariance=np.zeros(9))

    def quaternion_stamped(self, stamp, q, frame='map'):
        return self._type('geometry_msgs/msg/QuaternionStamped')(
            header=self.header(stamp, frame), quaternion=self.quaternion(q))

    def transform_stamped(self, stamp, t, q, frame='map', child='body'):
        tf = self._type('geometry_msgs/msg/Transform')(translation=self.vector(t),
                                                        rotation=self.quaternion(q))
        return self._type('geometry_msgs/msg/TransformStamped')(
            header=self.header(stamp, frame), child_frame_id=child, transform=tf)

    def tf_message(self, transforms):
        return self._type('tf2_msgs/msg/TFMessage')(transforms=list(transforms))

    def string(self, text):
        return self._type('std_msgs/msg/String')(data=text)


def write_bag(dst, messages, storage='sqlite3'):
    """A rosbag2 bag of [(topic, msgtype, record time ns, message object)] (in that order)."""
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
