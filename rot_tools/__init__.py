"""
rot_tools: rotations and rigid motions without quaternions, for one item or a batch.

Plain NumPy (no ROS import anywhere in this package's math). Angles are radians, arrays
float64, ``...`` any leading batch shape. Invalid input raises RotationError (a ValueError).
"""

from rot_tools.core.axis_angle import (
    axis_angle_to_matrix, matrix_to_axis_angle, matrix_to_rotvec, rotvec_to_matrix)
from rot_tools.core.covariance import (
    change_covariance_frame, euler_covariance_to_rotvec, rotvec_covariance_to_euler,
    transform_pose_covariance)
from rot_tools.core.decomposition import decompose, Decomposition
from rot_tools.core.errors import RotationError
from rot_tools.core.euler import (
    EULER_SEQUENCES, euler_to_matrix, GIMBAL_LOCK_TOL, matrix_to_euler)
from rot_tools.core.fitting import (
    align_vectors, mean_rotation, random_rotations, rotation_distance, UNIQUE_TOL)
from rot_tools.core.hand_eye import (
    hand_eye, HandEyeCalibration, screw_congruence, ScrewCongruence)
from rot_tools.core.imu import check_imu, ImuChecks, ImuReference
from rot_tools.core.rigid import (
    compose_transforms, frame_to_matrix, homogeneous_to_transform, invert_transform,
    transform_points, transform_to_homogeneous)
from rot_tools.core.rodrigues import matrix_to_rodrigues, rodrigues_to_matrix
from rot_tools.core.screw import (
    PURE_TRANSLATION_ANGLE, Screw, screw_exp, screw_from_transform, screw_interpolate,
    screw_log, transform_from_screw)
from rot_tools.core.so3 import (
    is_rotation, matrix_to_quaternion, nearest_rotation, quaternion_to_matrix, rot_x, rot_y,
    rot_z, ROTATION_TOL, skew, validate_rotation)
from rot_tools.core.trajectory import (
    align_rotations, ALIGNMENTS, angular_speeds, delta_pairs, error_statistics,
    estimate_time_offset, hand_eye_rotation, HandEye, interpolate_poses, nearest_stamps,
    rotation_errors, RotationErrors, TimeOffset)
from rot_tools.core.transform_tree import (
    TransformLookupError, TransformTree, TransformTreeError)

__all__ = [
    'ALIGNMENTS', 'Decomposition', 'EULER_SEQUENCES', 'GIMBAL_LOCK_TOL', 'HandEye',
    'HandEyeCalibration', 'ImuChecks', 'ImuReference', 'ScrewCongruence',
    'PURE_TRANSLATION_ANGLE', 'ROTATION_TOL', 'RotationError', 'RotationErrors', 'Screw',
    'TimeOffset', 'TransformLookupError', 'TransformTree', 'TransformTreeError', 'UNIQUE_TOL',
    'align_rotations', 'align_vectors', 'angular_speeds', 'axis_angle_to_matrix',
    'change_covariance_frame', 'check_imu', 'compose_transforms', 'decompose', 'delta_pairs',
    'error_statistics', 'estimate_time_offset', 'euler_covariance_to_rotvec',
    'euler_to_matrix', 'frame_to_matrix', 'hand_eye_rotation', 'homogeneous_to_transform',
    'hand_eye', 'interpolate_poses', 'invert_transform', 'is_rotation', 'matrix_to_axis_angle',
    'matrix_to_euler', 'matrix_to_quaternion', 'matrix_to_rodrigues', 'matrix_to_rotvec',
    'mean_rotation', 'nearest_rotation', 'nearest_stamps', 'quaternion_to_matrix',
    'random_rotations', 'rodrigues_to_matrix', 'rot_x', 'rot_y', 'rot_z', 'rotation_distance',
    'rotation_errors', 'rotvec_covariance_to_euler', 'rotvec_to_matrix', 'screw_congruence',
    'screw_exp', 'screw_from_transform',
    'screw_interpolate', 'screw_log', 'skew', 'transform_from_screw', 'transform_points',
    'transform_pose_covariance', 'transform_to_homogeneous', 'validate_rotation']
