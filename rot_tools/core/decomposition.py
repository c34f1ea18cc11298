"""
Every representation of one rigid motion (R, b), from one kernel pass.

:func:`decompose` gives the axis-angle, the rotation vector, the Euler angles of a sequence,
roll-pitch-yaw, the quaternion, the screw and the twist of p ↦ R·p + b at once, for one item
or a batch: the rot-tools report and every output of rotation_node read its fields by name.
Every field comes from the kernel of its own public function (axis_angle_kernel,
angles_kernel, quaternion_of_matrix_kernel, screw_of_axis_kernel, twist_kernel), so each
equals what that function gives, and at θ = π all of them use the same axis sign.
:func:`decompose_one` gives the same numbers for one motion as Python numbers.
"""

__all__ = ['decompose', 'Decomposition']

from typing import NamedTuple

import numpy as np
from rot_tools.core.axis_angle import axis_angle_kernel, rotvec_of
from rot_tools.core.engine import apply_to_one, FLAG, InRange, SCALAR, VECTOR
from rot_tools.core.euler import angles_kernel, GIMBAL_LOCK_TOL, parse_sequence, RPY_SEQUENCE
from rot_tools.core.screw import refuse_far_axis, Screw, screw_of_axis_kernel, twist_kernel
from rot_tools.core.screw import TWIST
from rot_tools.core.so3 import apply_to_rotations, QUATERNION, quaternion_of_matrix_kernel


class Decomposition(NamedTuple):
    """
    Every representation of one rigid motion p ↦ R·p + b, from one pass over R and b.

    Each field has the input's batch shape (...) followed by its own; one item gives NumPy
    scalars and arrays. axis (..., 3), angle (...) ∈ [0, π]: as matrix_to_axis_angle;
    rotvec (..., 3) = angle·axis: as matrix_to_rotvec; euler (..., 3), degenerate (...):
    as matrix_to_euler for the sequence asked; rpy (..., 3): roll, pitch, yaw (REP 103, the
    Euler angles of RPY_SEQUENCE, whatever sequence was asked); quaternion (..., 4): (x, y,
    z, w) with the canonical sign of matrix_to_quaternion; screw: a Screw, as
    screw_from_transform; twist (..., 6): as screw_log. At θ = π all of them use the same
    axis sign.
    """

    axis: np.ndarray
    angle: np.ndarray
    rotvec: np.ndarray
    euler: np.ndarray
    degenerate: np.ndarray
    rpy: np.ndarray
    quaternion: np.ndarray
    screw: Screw
    twist: np.ndarray


_RPY = parse_sequence(RPY_SEQUENCE)
_DECOMPOSITION = InRange(value=Decomposition(
    axis=VECTOR, angle=SCALAR, rotvec=VECTOR, euler=VECTOR, degenerate=FLAG, rpy=VECTOR,
    quaternion=QUATERNION, screw=Screw(direction=VECTOR, point=VECTOR, moment=VECTOR,
                                       angle=SCALAR, translation=SCALAR, pitch=SCALAR),
    twist=TWIST), fits=FLAG)


def _decomposition_kernel(ops, m, b, spec):
    """InRange(the Decomposition, where its screw and its twist fit float64)."""
    axis_angle = axis_angle_kernel(ops, m)
    screw = screw_of_axis_kernel(ops, axis_angle.axis, axis_angle.angle, b)
    twist = twist_kernel(ops, axis_angle.axis, axis_angle.angle, b)
    euler = angles_kernel(ops, m, spec, GIMBAL_LOCK_TOL)
    return InRange(value=Decomposition(
        axis=axis_angle.axis, angle=axis_angle.angle, rotvec=rotvec_of(axis_angle),
        euler=euler.angles, degenerate=euler.degenerate,
        rpy=angles_kernel(ops, m, _RPY, GIMBAL_LOCK_TOL).angles,
        quaternion=quaternion_of_matrix_kernel(ops, m), screw=screw.value, twist=twist.value),
        fits=screw.fits & twist.fits)


def decompose(R, b, seq='ZYX', *, check=True):
    """
    Return the Decomposition of p ↦ R·p + b: R (..., 3, 3), b (..., 3), broadcasting.

    Euler angles of ``seq`` (radians). R is validated as validate_rotation does unless
    check=False. One kernel pass computes every field, so the rot-tools report and each
    output of rotation_node come from the same numbers. RotationError where the screw
    overflows float64 (as screw_from_transform).
    """
    out = apply_to_rotations(_decomposition_kernel, R, check, _DECOMPOSITION,
                             [(b, (3,), 'translation b', True)], (parse_sequence(seq),))
    refuse_far_axis(out.fits, out.value.angle, b)
    return out.value


def decompose_one(R, b, seq='ZYX'):
    """
    Return decompose(R, b, seq, check=False) of one motion, its fields as Python numbers.

    R (3, 3), b (3,). The same numbers, from the same kernel pass, as the kernels give them on
    one item (rot_tools.core.engine.apply_to_one): floats (degenerate a bool), lists for the
    vectors, no NumPy value made. For a caller that writes the numbers out one by one, as
    rotation_node writes its messages. R is not validated; RotationError where the screw
    overflows float64, as decompose.
    """
    out = apply_to_one(_decomposition_kernel, [(R, (3, 3), 'R', False),
                                               (b, (3,), 'translation b', True)],
                       _DECOMPOSITION, (parse_sequence(seq),))
    if not out.fits:
        refuse_far_axis(np.asarray(out.fits), np.asarray(out.value.angle), b)
    return out.value
