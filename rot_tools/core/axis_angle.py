"""
Axis-angle: Rodrigues' formula and its robust inverse.

A rotation by θ about the unit axis l̂ (right-hand rule) is (Jia, Rotation in the Space,
eq. 7; Cayero, Relations between Rotation Matrix and Euler axis-angle parametrization,
eq. 18)::

    Rot_l̂(θ) = cos θ·I + (1 − cos θ)·l̂l̂ᵀ + sin θ·[l̂]×

The rotation vector is θ·l̂. The inverse returns θ ∈ [0, π] and a unit axis; (l̂, θ) and
(−l̂, 2π − θ) — equivalently (−l̂, −θ) — describe the same rotation (Jia §3.3).
"""

import math

import numpy as np
from numpy import False_, True_
from rot_tools.core._arrays import refuse_overflow
from rot_tools.core.engine import (apply, dot, FLAG, FLOATS, MATRIX, norm_in_range, plain_item,
                                   SCALAR, unit, VECTOR)
from rot_tools.core.errors import RotationError
from rot_tools.core.so3 import apply_to_rotations, plain_rotation, run_on_floats


def sin_versin(ops, angle):
    """
    (sin θ, 1 − cos θ) from t = tan(θ/2): 2t/(1 + t²) and t·sin θ.

    One tangent instead of a sine and a cosine (NumPy's tangent is vectorised, its sine and
    cosine of float64 are not: ~8× faster in a batch); t·sin θ keeps its relative precision
    near 0, where 1 − cos θ subtracted from 1 would cancel.
    """
    t = ops.tan(0.5 * angle)
    s = 2.0 * t / (1.0 + t * t)
    return s, s * t


def _rodrigues(ops, x, y, z, angle):
    """Entries of cos θ·I + (1 − cos θ)·l̂l̂ᵀ + sin θ·[l̂]× for a unit (x, y, z)."""
    return rodrigues_entries(x, y, z, *sin_versin(ops, angle))


def rodrigues_entries(x, y, z, s, v):
    """Entries of Rodrigues' matrix for a unit (x, y, z), given s = sin θ and v = 1 − cos θ."""
    c = 1.0 - v
    vx, vy, vz, sx, sy, sz = v * x, v * y, v * z, s * x, s * y, s * z
    vxy, vxz, vyz = vx * y, vx * z, vy * z
    return [[c + vx * x, vxy - sz, vxz + sy],
            [vxy + sz, c + vy * y, vyz - sx],
            [vxz - sy, vyz + sx, c + vz * z]]


def _axis_angle_kernel(ops, axis, angle):
    (x, y, z), n = unit(ops, axis)  # a zero axis is refused unless the angle is 0 too
    return _rodrigues(ops, x, y, z, angle), (n == 0) & (angle != 0)


def axis_angle_to_matrix(axis, angle):
    """
    Rodrigues (Jia, eq. 7): axis (..., 3), angle (...) → (..., 3, 3), broadcasting.

    The axis is normalised. A zero axis with a zero angle gives the identity; a zero axis with
    a non-zero angle raises RotationError.
    """
    v = plain_item(axis, (3,))
    if v is not None and isinstance(angle, float) and math.isfinite(angle):
        n2 = dot(v, v)
        if 1e-290 <= n2 <= 1e290:  # fast path: one plain item, |axis| not rescaled by unit
            n = math.sqrt(n2)
            return np.array(_rodrigues(FLOATS, v[0] / n, v[1] / n, v[2] / n, float(angle)))
    matrix, bad = apply(_axis_angle_kernel, [(axis, (3,), 'axis', True),
                                             (angle, (), 'angle', True)], [MATRIX, FLAG])
    if bad is not False_ and bad.any():  # (one item's flag is one of NumPy's two bools)
        first = float(np.broadcast_to(np.asarray(angle, dtype=float), bad.shape)[bad].flat[0])
        raise RotationError(f'axis is zero but the angle is {first:g} rad: a rotation needs '
                            'a direction (a zero axis is allowed only with angle 0)')
    return matrix


def _rotvec_kernel(ops, v):
    angle, turns = norm_in_range(ops, v)  # |v| beyond 1.8e308: refused, tan(inf) avoided
    safe = ops.where(angle > 0, angle, 1.0)  # any axis will do at angle 0
    return _rodrigues(ops, v[0] / safe, v[1] / safe, v[2] / safe, angle), turns


def rotvec_to_matrix(rotvec):
    """
    Rotation matrix of the rotation vector θ·l̂; (..., 3) → (..., 3, 3); zero → identity.

    RotationError where the angle |θ·l̂| itself overflows float64.
    """
    v = plain_item(rotvec, (3,))
    out = v and run_on_floats(_rotvec_kernel, v)
    if out and out[1]:  # fast path: one plain item, the kernel on floats
        return np.array(out[0])
    matrix, turns = apply(_rotvec_kernel, [(rotvec, (3,), 'rotation vector', True)],
                          [MATRIX, FLAG])
    if turns is not True_:
        refuse_overflow(turns, 'the angle |θ·l̂| of the rotation vector')
    return matrix


def skew_and_cos(m):
    """
    Return (w, cos θ) of the rotation m.

    (w, cos θ) of the rotation m: w = ½(r32 − r23, r13 − r31, r21 − r12) = sin θ·l̂ and
    cos θ = (tr R − 1)/2, so that θ = atan2(|w|, cos θ) ∈ [0, π] (accurate at every angle).
    """
    w = [0.5 * (m[2][1] - m[1][2]), 0.5 * (m[0][2] - m[2][0]), 0.5 * (m[1][0] - m[0][1])]
    return w, 0.5 * (m[0][0] + m[1][1] + m[2][2] - 1.0)


def axis_angle_kernel(ops, m):
    """Return (unit axis, angle ∈ [0, π]) of the rotation m; see matrix_to_axis_angle."""
    w, cos = skew_and_cos(m)
    skew_axis, sin = unit(ops, w)
    angle = ops.atan2(sin, cos)
    near_pi = cos < 0
    if not ops.rare(near_pi):  # (an item, or a chunk, with every angle ≤ π/2)
        return skew_axis, angle
    # Near π the skew part vanishes with sin θ: take the axis from the symmetric part
    # (R + Rᵀ)/2 − cos θ·I = (1 − cos θ)·l̂l̂ᵀ, its column with the largest diagonal entry
    # (computed for every item of the chunk; used where near_pi).
    d0, d1, d2 = m[0][0] - cos, m[1][1] - cos, m[2][2] - cos
    s01, s02, s12 = (
        0.5 * (m[0][1] + m[1][0]), 0.5 * (m[0][2] + m[2][0]), 0.5 * (m[1][2] + m[2][1]))
    first = (d0 >= d1) & (d0 >= d2)
    second = (d1 > d0) & (d1 >= d2)
    col = [ops.where(first, d0, ops.where(second, s01, s02)),
           ops.where(first, s01, ops.where(second, d1, s12)),
           ops.where(first, s02, ops.where(second, s12, d2))]
    sym_axis, _ = unit(ops, col)
    # Its sign from the skew part (free at exactly π, where w = 0).
    flip = sym_axis[0] * w[0] + sym_axis[1] * w[1] + sym_axis[2] * w[2] < 0
    sign = ops.where(flip, -1.0, 1.0)
    axis = [ops.where(near_pi, sign * a + 0.0, b) for a, b in zip(sym_axis, skew_axis)]
    return axis, angle


def matrix_to_axis_angle(R, *, check=True):
    """
    Axis and angle of R: returns (axis (..., 3) unit, angle (...) ∈ [0, π]).

    With w = ½(r32 − r23, r13 − r31, r21 − r12) = sin θ·l̂ (the negative half of Jia's
    eq. 11's l) and cos θ = (Tr R − 1)/2 (eq. 12): θ = atan2(|w|, cos θ), accurate to rounding
    at every angle (acos loses half the digits near 0 and π; eq. 13's square root too).
    The axis is w/|w| while cos θ ≥ 0. Near π the skew part vanishes with sin θ, so there the
    axis comes from the symmetric part (R + Rᵀ)/2 − cos θ·I = (1 − cos θ)·l̂l̂ᵀ: its column
    with the largest diagonal entry, normalised, with the sign of w (at exactly π the sign is
    free: the largest component is made positive). At θ = 0 the axis is (0, 0, 1).
    """
    m = plain_rotation(R, check)
    out = m and run_on_floats(axis_angle_kernel, m)
    if out:  # fast path: one plain rotation, the kernel on floats
        return np.array(out[0]), np.float64(out[1])
    return apply_to_rotations(axis_angle_kernel, R, check, [VECTOR, SCALAR])


def _rotvec_of_matrix_kernel(ops, m):
    axis, angle = axis_angle_kernel(ops, m)
    return ([a * angle for a in axis],)


def matrix_to_rotvec(R, *, check=True):
    """Rotation vector θ·l̂ of R, θ ∈ [0, π]; (..., 3, 3) → (..., 3)."""
    m = plain_rotation(R, check)
    out = m and run_on_floats(_rotvec_of_matrix_kernel, m)
    if out:  # fast path: one plain rotation, the kernel on floats
        return np.array(out[0])
    (rotvec,) = apply_to_rotations(_rotvec_of_matrix_kernel, R, check, [VECTOR])
    return rotvec
