"""
rot_tools: rotations and rigid motions without quaternions, for one item or a batch.

Plain NumPy (no ROS import anywhere in this package's math). Angles are radians, arrays
float64, ``...`` any leading batch shape. Invalid input raises RotationError (a ValueError).

The names below are imported from their modules on first use of one (PEP 562), so that
``import rot_tools.<module>`` stays light: the rotation_node console script must install its
signal handlers before NumPy and rclpy load (see rot_tools.ros.entry).
"""

_HOME = {
    'rot_tools.core.axis_angle': (
        'axis_angle_to_matrix', 'matrix_to_axis_angle', 'matrix_to_rotvec', 'rotvec_to_matrix'),
    'rot_tools.core.covariance': (
        'change_covariance_frame', 'euler_covariance_to_rotvec', 'rotvec_covariance_to_euler',
        'transform_pose_covariance'),
    'rot_tools.core.errors': ('RotationError',),
    'rot_tools.core.euler': (
        'EULER_SEQUENCES', 'GIMBAL_LOCK_TOL', 'euler_to_matrix', 'matrix_to_euler'),
    'rot_tools.core.fitting': (
        'align_vectors', 'mean_rotation', 'random_rotations', 'rotation_distance', 'UNIQUE_TOL'),
    'rot_tools.core.decomposition': ('Decomposition', 'decompose'),
    'rot_tools.core.rigid': (
        'compose_transforms', 'frame_to_matrix', 'homogeneous_to_transform', 'invert_transform',
        'transform_points', 'transform_to_homogeneous'),
    'rot_tools.core.screw': (
        'PURE_TRANSLATION_ANGLE', 'Screw', 'screw_exp', 'screw_from_transform',
        'screw_interpolate', 'screw_log', 'transform_from_screw'),
    'rot_tools.core.so3': (
        'ROTATION_TOL', 'is_rotation', 'matrix_to_quaternion', 'nearest_rotation',
        'quaternion_to_matrix', 'rot_x', 'rot_y', 'rot_z', 'skew', 'validate_rotation'),
    'rot_tools.core.transform_tree': (
        'TransformLookupError', 'TransformTree', 'TransformTreeError'),
    'rot_tools.core.trajectory': (
        'ALIGNMENTS', 'HandEye', 'RotationErrors', 'TimeOffset', 'align_rotations',
        'angular_speeds', 'delta_pairs', 'error_statistics', 'estimate_time_offset',
        'hand_eye_rotation', 'interpolate_poses', 'nearest_stamps', 'rotation_errors'),
}
_MODULE_OF = {name: module for module, names in _HOME.items() for name in names}

__all__ = sorted(_MODULE_OF)


def __getattr__(name):
    """Import every public name from its module on the first access of one."""
    if name not in _MODULE_OF:
        raise AttributeError(f'module {__name__!r} has no attribute {name!r}')
    import importlib  # (here: a module attribute would show in dir(rot_tools))
    for module, names in _HOME.items():
        loaded = importlib.import_module(module)
        globals().update((n, getattr(loaded, n)) for n in names)
    # The hook goes once everything is here: CPython does not cache attribute look-ups on a
    # module that has one (``rt.name`` would cost ~20 ns more on every call).
    globals().pop('__getattr__', None)  # (None: another thread's first access did it)
    return globals()[name]


def __dir__():
    return sorted(set(globals()) | set(__all__))
