"""rotation_client play republishes every field as recorded, from ROS 1 and rosbag2 bags."""

from pathlib import Path

from conftest import TIMEOUT
import numpy as np
import pytest

COUNT = 2
"""Messages recorded on each topic."""


class Messages:
    """Message objects of one rosbags typestore (ROS 1 Noetic's or ROS 2 Jazzy's)."""

    def __init__(self, store):
        from rosbags.typesys import get_typestore, Stores
        self.ros1 = store == 'ros1'
        self.store = get_typestore(Stores.ROS1_NOETIC if self.ros1 else Stores.ROS2_JAZZY)
        self.t = self.store.types

    def make(self, msgtype, **fields):
        return self.t[msgtype](**fields)

    def header(self, k, frame='map'):
        stamp = self.make('builtin_interfaces/msg/Time', sec=1_700_000_000 + k,
                          nanosec=123_456_789 + k)
        seq = {'seq': 40 + k} if self.ros1 else {}
        return self.make('std_msgs/msg/Header', **seq, stamp=stamp, frame_id=frame)

    def point(self, x, y, z):
        return self.make('geometry_msgs/msg/Point', x=x, y=y, z=z)

    def quaternion(self, x, y, z, w):
        return self.make('geometry_msgs/msg/Quaternion', x=x, y=y, z=z, w=w)

    def vector(self, x, y, z):
        return self.make('geometry_msgs/msg/Vector3', x=x, y=y, z=z)

    def octets(self, values):
        """Bytes as rosbags holds them: ROS 1 byte is int8 (and so is its ROS 2 reading)."""
        return np.asarray(values, dtype=np.uint8).view(np.int8)

    def layout(self):
        dim = self.make('std_msgs/msg/MultiArrayDimension', label='rows', size=2, stride=8)
        return self.make('std_msgs/msg/MultiArrayLayout', dim=[dim], data_offset=3)

    def diagnostics(self, k):
        statuses = [self.make('diagnostic_msgs/msg/DiagnosticStatus', level=level,
                              name=f'rot_tools: check {level}', message='all is well ✓',
                              hardware_id=f'imu_{k}', values=[
                                  self.make('diagnostic_msgs/msg/KeyValue', key='rate',
                                            value=f'{100 + level} msg/s')])
                    for level in (0, 1, 2, 3)]
        return self.make('diagnostic_msgs/msg/DiagnosticArray', header=self.header(k),
                         status=statuses)

    def image(self, k):
        data = ((np.arange(48) * 37 + k) % 256).astype(np.uint8)
        return self.make('sensor_msgs/msg/Image', header=self.header(k, 'camera'), height=4,
                         width=4, encoding='rgb8', is_bigendian=0, step=12, data=data)

    def point_cloud(self, k):
        fields = [self.make('sensor_msgs/msg/PointField', name=name, offset=4 * i,
                            datatype=7, count=1) for i, name in enumerate('xyz')]
        data = np.frombuffer(np.array([[0.5, -1.0, 2.0 + k], [1e-30, 3e30, -0.0]],
                                      dtype='<f4').tobytes(), dtype=np.uint8)
        return self.make('sensor_msgs/msg/PointCloud2', header=self.header(k, 'lidar'),
                         height=1, width=2, fields=fields, is_bigendian=False, point_step=12,
                         row_step=24, data=data, is_dense=True)

    def imu(self, k):
        cov = np.arange(9, dtype=np.float64) * 0.1 + k
        return self.make('sensor_msgs/msg/Imu', header=self.header(k, 'imu'),
                         orientation=self.quaternion(0.0, 0.0, 0.6, 0.8),
                         orientation_covariance=cov, angular_velocity=self.vector(0.1, -0.2, k),
                         angular_velocity_covariance=-cov,
                         linear_acceleration=self.vector(0.0, 0.0, 9.81),
                         linear_acceleration_covariance=cov * 1e-300)

    def byte_array(self, k):
        return self.make('std_msgs/msg/ByteMultiArray', layout=self.layout(),
                         data=self.octets([0, 1, 127, 128, 254, 255, k]))

    def char(self, k):
        return self.make('std_msgs/msg/Char', data=200 + k)

    def byte(self, k):
        return self.make('std_msgs/msg/Byte', data=self.octets([0xFE - k])[0])

    def polygon(self, k):
        points = [self.make('geometry_msgs/msg/Point32', x=float(np.float32(0.1 * i)),
                            y=-1.5, z=float(np.float32(3.3e38))) for i in range(3 + k)]
        return self.make('geometry_msgs/msg/PolygonStamped', header=self.header(k),
                         polygon=self.make('geometry_msgs/msg/Polygon', points=points))

    def occupancy_grid(self, k):
        pose = self.make('geometry_msgs/msg/Pose', position=self.point(-10.0, -5.0, 0.0),
                         orientation=self.quaternion(0.0, 0.0, 0.0, 1.0))
        info = self.make('nav_msgs/msg/MapMetaData', map_load_time=self.header(k).stamp,
                         resolution=float(np.float32(0.05)), width=3, height=2, origin=pose)
        return self.make('nav_msgs/msg/OccupancyGrid', header=self.header(k), info=info,
                         data=np.array([-1, 0, 100, 50, -1, k], dtype=np.int8))

    def nav_sat_fix(self, k):
        status = self.make('sensor_msgs/msg/NavSatStatus', status=-1, service=0xFFFF - k)
        return self.make('sensor_msgs/msg/NavSatFix', header=self.header(k, 'gps'),
                         status=status, latitude=48.8566, longitude=2.3522, altitude=-1e-9,
                         position_covariance=np.full(9, 1e300), position_covariance_type=2)

    def joint_state(self, k):
        return self.make('sensor_msgs/msg/JointState', header=self.header(k),
                         name=['shoulder', 'élbow', ''], position=np.array([0.1, -0.2, k]),
                         velocity=np.array([]), effort=np.array([np.inf, -np.inf, 5e-324]))

    def joy(self, k):
        return self.make('sensor_msgs/msg/Joy', header=self.header(k),
                         axes=np.array([0.5, -1.0, k], dtype=np.float32),
                         buttons=np.array([0, 1, -2**31, 2**31 - 1], dtype=np.int32))

    def int64_array(self, k):
        return self.make('std_msgs/msg/Int64MultiArray', layout=self.layout(),
                         data=np.array([-2**63, 2**63 - 1, k], dtype=np.int64))

    def uint64(self, k):
        return self.make('std_msgs/msg/UInt64', data=2**64 - 1 - k)

    def solid(self, k):
        fields = {} if self.ros1 else {'polygon': self.make('geometry_msgs/msg/Polygon',
                                                            points=[])}
        return self.make('shape_msgs/msg/SolidPrimitive', type=1,
                         dimensions=np.array([1.0, 2.0, 3.0 + k]), **fields)

    def mesh(self, k):
        triangle = self.make('shape_msgs/msg/MeshTriangle',
                             vertex_indices=np.array([0, 1, 2**32 - 1 - k], dtype=np.uint32))
        return self.make('shape_msgs/msg/Mesh', triangles=[triangle], vertices=[
            self.point(0.0, 0.0, 0.0), self.point(1.0, 0.0, k)])

    def by_topic(self, k):
        """Return {topic name: (type, message)} of sample ``k``."""
        return {name: (make(k).__msgtype__, make(k)) for name, make in (
            ('diagnostics', self.diagnostics), ('image', self.image),
            ('cloud', self.point_cloud), ('imu', self.imu), ('bytes', self.byte_array),
            ('char', self.char), ('byte', self.byte), ('polygon', self.polygon),
            ('map', self.occupancy_grid), ('fix', self.nav_sat_fix),
            ('joints', self.joint_state), ('joy', self.joy), ('int64', self.int64_array),
            ('uint64', self.uint64), ('solid', self.solid), ('mesh', self.mesh))}


def write(path, store, namespace):
    """Write the bag of Messages(store), its topics in ``namespace``, latched; return it."""
    messages = Messages(store)
    if store == 'ros1':
        from rosbags.rosbag1 import Writer
        qos = {'latching': 1}
        path = path.with_suffix('.bag')
    else:
        from rosbags.interfaces import (Qos, QosDurability, QosHistory, QosLiveliness,
                                        QosReliability, QosTime)
        from rosbags.rosbag2 import Writer
        never = QosTime(sec=0, nsec=0)
        qos = {'offered_qos_profiles': [Qos(
            QosHistory.KEEP_LAST, 10, QosReliability.RELIABLE, QosDurability.TRANSIENT_LOCAL,
            never, never, QosLiveliness.AUTOMATIC, never, False)]}
    with Writer(path, **({} if store == 'ros1' else {'version': 8})) as writer:
        connections = {}
        for k in range(COUNT):
            for name, (msgtype, msg) in messages.by_topic(k).items():
                if name not in connections:
                    connections[name] = writer.add_connection(
                        f'{namespace}/{name}', msgtype, typestore=messages.store, **qos)
                raw = (messages.store.serialize_ros1 if messages.ros1
                       else messages.store.serialize_cdr)(msg, msgtype)
                writer.write(connections[name], 1_000_000_000 + 10_000_000 * k, raw)
    return Path(path)


@pytest.mark.parametrize('store', ['ros1', 'ros2'])
def test_every_field_is_played_as_recorded(here, tester, namespace, tmp_path, store):
    from rclpy.qos import DurabilityPolicy, QoSProfile
    from rclpy.serialization import deserialize_message
    from rot_tools.ros.message_types import message_class
    bag = write(tmp_path / 'fields', store, namespace)
    jazzy = Messages('ros2')
    expected = {name: [] for name in jazzy.by_topic(0)}
    for k in range(COUNT):
        for name, (msgtype, msg) in jazzy.by_topic(k).items():
            raw = bytes(jazzy.store.serialize_cdr(msg, msgtype))
            expected[name].append(deserialize_message(raw, message_class(msgtype)))
    latched = QoSProfile(depth=COUNT, durability=DurabilityPolicy.TRANSIENT_LOCAL)
    for name, (msgtype, _) in jazzy.by_topic(0).items():
        tester.subscribe(f'{namespace}/{name}', message_class(msgtype), latched)
    result = here('play', bag, '--rate', 10)
    assert (result.returncode, result.stderr) == (0, '')
    for name, messages in expected.items():
        assert tester.wait_messages(f'{namespace}/{name}', COUNT, TIMEOUT) == messages
