"""
Every representation of one rigid motion (R, b), from the kernels of each.

:func:`decompose` gives arrays (one item or a batch) for the report, the drawing and people;
:func:`decompose_values` gives the numbers rotation_node publishes for one input, as plain
Python floats. Both run the same kernels (axis-angle, Euler, screw, twist, quaternion), so
at θ = π every representation of one input uses the same axis sign.
"""

from typing import NamedTuple

import numpy as np
from rot_tools.core.axis_angle import axis_angle_kernel
from rot_tools.core.engine import apply, FLAG, plain_item, SCALAR, VECTOR
from rot_tools.core.euler import angles_kernel, GIMBAL_LOCK_TOL, parse_sequence
from rot_tools.core.euler import RPY_SEQUENCE
from rot_tools.core.screw import refuse_far_axis, Screw, screw_of_axis_kernel, twist_kernel
from rot_tools.core.so3 import apply_to_rotations, quaternion_of_matrix_kernel, run_on_floats


class Decomposition(NamedTuple):
    """
    Every representation of one rigid motion p ↦ R·p + b, from one pass over R and b.

    axis, angle: as matrix_to_axis_angle; euler, degenerate: as matrix_to_euler for the
    sequence asked; screw: as screw_from_transform; twist: as screw_log. At θ = π all of them
    use the same axis sign.
    """

    axis: np.ndarray
    angle: np.ndarray
    euler: np.ndarray
    degenerate: np.ndarray
    screw: Screw
    twist: np.ndarray


def _motion_kernel(ops, m, b):
    """
    Compute every representation but the Euler angles.

    Every representation but the Euler angles (those depend on the sequence: angles_kernel,
    run beside this one).
    """
    axis, angle = axis_angle_kernel(ops, m)
    screw, screw_fits = screw_of_axis_kernel(ops, axis, angle, b)
    twist, twist_fits = twist_kernel(ops, axis, angle, b)
    return (axis, angle, *screw, twist, screw_fits & twist_fits)


_MOTION_OUTPUTS = [VECTOR, SCALAR, VECTOR, VECTOR, VECTOR, SCALAR, SCALAR, SCALAR,
                   ((6,), np.float64), FLAG]
_ANGLES_OUTPUTS = [VECTOR, FLAG]


def decompose(R, b, seq='ZYX', *, check=True):
    """
    Decomposition of (R (..., 3, 3), b (..., 3)) with Euler angles of ``seq`` (radians).

    One kernel run computes every representation but the Euler angles, and one more the
    angles, so the rot-tools report and each output of rotation_node come from the same
    numbers. RotationError where the screw overflows float64 (as screw_from_transform).
    """
    spec = parse_sequence(seq)
    axis, angle, *screw, twist, fits = apply_to_rotations(
        _motion_kernel, R, check, _MOTION_OUTPUTS, [(b, (3,), 'translation b', True)])
    refuse_far_axis(fits, angle, b)
    euler, lock = apply_to_rotations(angles_kernel, R, False, _ANGLES_OUTPUTS,
                                     params=(spec, GIMBAL_LOCK_TOL))
    return Decomposition(axis, angle, euler, lock, Screw(*screw), twist)


class Values(NamedTuple):
    """
    The numbers rotation_node publishes for one input, as plain Python floats.

    matrix: R row-major (9); rotvec: θ·l̂ (3); euler: the Euler angles of the sequence asked,
    rad (3); twist: screw_log (6); quaternion: (x, y, z, w), as matrix_to_quaternion gives
    it (4); rpy: roll, pitch, yaw (REP 103: about the fixed x, y, z axes, the extrinsic
    sequence 'xyz'), rad (3), whatever sequence was asked. For a batch, arrays with those
    last dimensions.
    """

    matrix: list
    rotvec: tuple
    euler: tuple
    twist: tuple
    quaternion: tuple
    rpy: tuple


_RPY = parse_sequence(RPY_SEQUENCE)


def _values_kernel(ops, m, b, spec):
    """Values' numbers but the matrix, the angle, and whether screw and twist fit float64."""
    values, axis, angle, twist_fits = _values_without_screw(ops, m, b, spec)
    _, screw_fits = screw_of_axis_kernel(ops, axis, angle, b)
    return (*values, angle, screw_fits & twist_fits)


def _values_without_screw(ops, m, b, spec):
    """(rotvec, euler, twist, q, rpy), axis, angle and the twist's in-range flag."""
    axis, angle = axis_angle_kernel(ops, m)
    twist, fits = twist_kernel(ops, axis, angle, b)
    (q,) = quaternion_of_matrix_kernel(ops, m)
    euler, _ = angles_kernel(ops, m, spec, GIMBAL_LOCK_TOL)
    rpy, _ = angles_kernel(ops, m, _RPY, GIMBAL_LOCK_TOL)
    rotvec = [axis[0] * angle, axis[1] * angle, axis[2] * angle]
    return (rotvec, euler, twist, q, rpy), axis, angle, fits


_FLOATS3 = ((3,), float)
_VALUES = [_FLOATS3, _FLOATS3, ((6,), float), ((4,), float), _FLOATS3, SCALAR, FLAG]

ORDINARY_B = 1e100
"""Below this max|b_i| the screw of any finite (R, b) fits float64: its point and pitch are
at most ~|b|/θ with θ ≥ PURE_TRANSLATION_ANGLE = 1e-12 (below it: a pure translation)."""


def decompose_values(R, b, seq='ZYX'):
    """
    Return the Values of one rigid motion (R (3, 3), b (3,)), from one kernel pass.

    R row-major (as given), rotation vector, Euler angles of ``seq`` (rad), twist,
    quaternion, and roll, pitch, yaw (rad: the Euler angles of 'xyz'). The same kernels
    as decompose and matrix_to_quaternion (so the same numbers, the same axis sign at
    θ = π), without building an array for each: rotation_node calls it for every message.
    R is not validated (check=False: the node builds R itself); RotationError where the
    screw overflows float64, as decompose.
    """
    spec = parse_sequence(seq)
    m, v = plain_item(R, (3, 3)), plain_item(b, (3,))
    if m is not None and v is not None and -ORDINARY_B <= min(v) and max(v) <= ORDINARY_B:
        # fast path, one plain item whose screw cannot overflow: the same kernels on FLOATS
        # without apply around them, and without the screw computed for its flag alone
        out = run_on_floats(_values_without_screw, m, v, spec)
        if out and out[3]:
            rotvec, euler, twist, q, rpy = out[0]
            return Values(m[0] + m[1] + m[2], tuple(rotvec), tuple(euler), tuple(twist),
                          tuple(q), tuple(rpy))
    rotvec, euler, twist, q, rpy, angle, fits = apply(
        _values_kernel, [(R, (3, 3), 'R', False), (b, (3,), 'translation b', True)], _VALUES,
        (spec,))
    refuse_far_axis(fits, angle, b)
    R = np.asarray(R, dtype=np.float64)
    matrix = R.ravel().tolist() if R.ndim == 2 else R.reshape(R.shape[:-2] + (9,))
    return Values(matrix, rotvec, euler, twist, q, rpy)
