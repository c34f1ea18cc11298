"""rot_tools: rotations and rigid motions without quaternions, for one item or a batch.

Plain NumPy (no ROS import anywhere in this package's math). Angles are radians, arrays
float64, ``...`` any leading batch shape. Invalid input raises RotationError (a ValueError).
"""

from rot_tools.axis_angle import (
    axis_angle_to_matrix, matrix_to_axis_angle, matrix_to_rotvec, rotvec_to_matrix)
from rot_tools.errors import RotationError
from rot_tools.euler import (
    EULER_SEQUENCES, GIMBAL_LOCK_TOL, euler_to_matrix, matrix_to_euler)
from rot_tools.report import Decomposition, decompose
from rot_tools.screw import (
    PURE_TRANSLATION_ANGLE, Screw, screw_exp, screw_from_transform, screw_interpolate,
    screw_log, transform_from_screw)
from rot_tools.so3 import (
    ROTATION_TOL, is_rotation, nearest_rotation, quaternion_to_matrix, rot_x, rot_y, rot_z,
    skew, validate_rotation)

__all__ = [
    'EULER_SEQUENCES', 'GIMBAL_LOCK_TOL', 'PURE_TRANSLATION_ANGLE', 'ROTATION_TOL',
    'Decomposition', 'RotationError', 'Screw', 'axis_angle_to_matrix', 'decompose',
    'euler_to_matrix', 'is_rotation', 'matrix_to_axis_angle', 'matrix_to_euler',
    'matrix_to_rotvec', 'nearest_rotation', 'quaternion_to_matrix', 'rot_x', 'rot_y', 'rot_z',
    'rotvec_to_matrix', 'screw_exp', 'screw_from_transform', 'screw_interpolate', 'screw_log',
    'skew', 'transform_from_screw', 'validate_rotation',
]
