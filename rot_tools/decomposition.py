"""Every representation of one rigid motion (R, b) from one pass of the kernels.

:func:`decompose` gives arrays (one item or a batch) for the report, the drawing and people;
:func:`decompose_values` gives the numbers rotation_node publishes for one input, as plain
Python floats. Both run the same kernels (axis-angle, Euler, screw, twist, quaternion), so
at θ = π every representation of one input uses the same axis sign.
"""

from functools import partial
from typing import NamedTuple

import numpy as np

from rot_tools._backend import apply
from rot_tools.axis_angle import axis_angle_kernel
from rot_tools.euler import angles_kernel, EULER_SEQUENCES, GIMBAL_LOCK_TOL, parse_sequence
from rot_tools.screw import refuse_far_axis, Screw, screw_of_axis_kernel, twist_kernel
from rot_tools.so3 import apply_to_rotations, quaternion_of_matrix_kernel


class Decomposition(NamedTuple):
    """Every representation of one rigid motion p ↦ R·p + b, from one pass over R and b.

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


def _decompose_kernel(ops, m, b, spec):
    axis, angle = axis_angle_kernel(ops, m)
    angles, lock = angles_kernel(ops, m, spec, GIMBAL_LOCK_TOL)
    screw, screw_fits = screw_of_axis_kernel(ops, axis, angle, b)
    twist, twist_fits = twist_kernel(ops, axis, angle, b)
    return (axis, angle, angles, lock, *screw, twist, screw_fits & twist_fits)


_VEC, _NUM = ((3,), np.float64), ((), np.float64)
_DECOMPOSE_KERNELS = {seq: partial(_decompose_kernel, spec=parse_sequence(seq))
                      for seq in EULER_SEQUENCES}


def decompose(R, b, seq='ZYX', *, check=True):
    """Decomposition of (R (..., 3, 3), b (..., 3)) with Euler angles of ``seq`` (radians).

    One kernel run computes every representation, so the rot-tools report and each output of
    rotation_node come from the same numbers. RotationError where the screw overflows
    float64 (as screw_from_transform).
    """
    parse_sequence(seq)  # raises the RotationError of an unknown sequence
    out = apply_to_rotations(_DECOMPOSE_KERNELS[seq], R, check, [
        _VEC, _NUM, _VEC, ((), np.bool_), _VEC, _VEC, _VEC, _NUM, _NUM, _NUM,
        ((6,), np.float64), ((), np.bool_)], [(b, (3,), 'translation b', True)])
    refuse_far_axis(out[11], out[1], b)
    return Decomposition(*out[:4], Screw(*out[4:10]), out[10])


class Values(NamedTuple):
    """The numbers rotation_node publishes for one input, as plain Python floats.

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


RPY_SEQUENCE = 'xyz'
"""Roll, pitch, yaw (REP 103): rotations about the fixed x, y, z axes, in that order."""

_RPY_SPEC = parse_sequence(RPY_SEQUENCE)


class _Unbranched:
    """An engine's ops whose ``any`` is always true: a kernel's optional branch always runs.

    The kernels skip work nobody needs with ``if ops.any(cond):`` (matrix_to_euler's gimbal
    lock), and the compiled one-item engine (rot_tools._trace) follows each such branch as a
    path of its own. The roll, pitch, yaw of the node's values kernel would double its paths
    (to 96 for 22 of the 24 sequences: the lock of 'xyz' is another test than theirs), more
    than rot_tools._trace compiles, and every message would run on Python floats, 7x slower.
    Run through this, the lock's extra atan2 is computed on every item and the
    ``ops.where`` that follows picks the result: one path, the same numbers.
    """

    def __init__(self, ops):
        self._ops = ops

    @staticmethod
    def any(cond):
        return True

    def __getattr__(self, name):
        return getattr(self._ops, name)


def _values_kernel(ops, m, b, spec):
    axis, angle, angles, _, *_, twist, fits = _decompose_kernel(ops, m, b, spec)
    (q,) = quaternion_of_matrix_kernel(ops, m)
    rpy, _ = angles_kernel(_Unbranched(ops), m, _RPY_SPEC, GIMBAL_LOCK_TOL)
    return [a * angle for a in axis], angles, twist, q, rpy, angle, fits


_FLOATS3 = ((3,), float)
_VALUES_OUTPUTS = [_FLOATS3, _FLOATS3, ((6,), float), ((4,), float), _FLOATS3, _NUM,
                   ((), np.bool_)]
_VALUES_KERNELS = {seq: partial(_values_kernel, spec=parse_sequence(seq))
                   for seq in EULER_SEQUENCES}


def decompose_values(R, b, seq='ZYX'):
    """Return the Values of one rigid motion (R (3, 3), b (3,)), from one kernel pass.

    R row-major (as given), rotation vector, Euler angles of ``seq`` (rad), twist,
    quaternion, and roll, pitch, yaw (rad). The same kernels
    as decompose and matrix_to_quaternion (so the same numbers, the same axis sign at
    θ = π), without building an array for each: rotation_node calls it for every message.
    R is not validated (check=False: the node builds R itself); RotationError where the
    screw overflows float64, as decompose.
    """
    parse_sequence(seq)  # raises the RotationError of an unknown sequence
    rotvec, euler, twist, q, rpy, angle, fits = apply(
        _VALUES_KERNELS[seq], [(R, (3, 3), 'R', False), (b, (3,), 'translation b', True)],
        _VALUES_OUTPUTS)
    refuse_far_axis(fits, angle, b)
    R = np.asarray(R, dtype=np.float64)
    matrix = R.ravel().tolist() if R.ndim == 2 else R.reshape(R.shape[:-2] + (9,))
    return Values(matrix, rotvec, euler, twist, q, rpy)
