"""
Axis-angle: Rodrigues' formula and its robust inverse, the rotation and Rodrigues vectors.

Rot_l̂(θ) = cos θ·I + (1 − cos θ)·l̂l̂ᵀ + sin θ·[l̂]× (Jia, Rotation in the Space, eq. 7;
Cayero, Relations between Rotation Matrix and Euler axis-angle parametrization, eq. 18); the
rotation vector is θ·l̂. The inverse returns θ ∈ [0, π] and a unit axis. The Rodrigues
(Gibbs) vector is g = tan(θ/2)·l̂, infinite at θ = π.
"""

__all__ = ['axis_angle_to_matrix', 'matrix_to_axis_angle', 'matrix_to_rodrigues',
           'matrix_to_rotvec', 'rodrigues_to_matrix', 'rotvec_to_matrix']

import math
from typing import Any, NamedTuple

import numpy as np
from numpy import False_, True_
from rot_tools.core._arrays import finite_array, refuse_overflow
from rot_tools.core.engine import apply, FLAG, FLOATS, in_range, InRange, MATRIX, SCALAR
from rot_tools.core.engine import unit, VECTOR
from rot_tools.core.errors import RotationError
from rot_tools.core.so3 import apply_to_rotations, matrix_to_quaternion, quaternion_to_matrix


class AxisAngle(NamedTuple):
    """What matrix_to_axis_angle gives: a unit axis and an angle ∈ [0, π] (radians)."""

    axis: np.ndarray
    angle: Any


_AXIS_ANGLE = AxisAngle(axis=VECTOR, angle=SCALAR)


class SinVersin(NamedTuple):
    """sin θ and the versine 1 − cos θ of an angle θ."""

    sin: Any
    versin: Any


def sin_versin(ops, angle):
    """
    Return the SinVersin of θ from t = tan(θ/2): 2t/(1 + t²) and t·sin θ.

    One tangent instead of a sine and a cosine (NumPy's tangent is vectorised, its sine and
    cosine of float64 are not: see bench/README.md); t·sin θ keeps its relative precision
    near 0, where 1 − cos θ subtracted from 1 would cancel.
    """
    t = ops.tan(0.5 * angle)
    s = 2.0 * t / (1.0 + t * t)
    return SinVersin(sin=s, versin=s * t)


def _rodrigues(ops, x, y, z, angle):
    """Entries of cos θ·I + (1 − cos θ)·l̂l̂ᵀ + sin θ·[l̂]× for a unit (x, y, z)."""
    return rodrigues_entries(x, y, z, sin_versin(ops, angle))


def rodrigues_entries(x, y, z, trig):
    """Entries of Rodrigues' matrix for a unit (x, y, z), given the SinVersin of θ."""
    s, v = trig.sin, trig.versin
    c = 1.0 - v
    vx, vy, vz, sx, sy, sz = v * x, v * y, v * z, s * x, s * y, s * z
    vxy, vxz, vyz = vx * y, vx * z, vy * z
    return [[c + vx * x, vxy - sz, vxz + sy],
            [vxy + sz, c + vy * y, vyz - sx],
            [vxz - sy, vyz + sx, c + vz * z]]


class _AxisAngleMatrix(NamedTuple):
    matrix: Any
    no_axis: Any  # a zero axis with a non-zero angle: refused


_AXIS_ANGLE_MATRIX = _AxisAngleMatrix(matrix=MATRIX, no_axis=FLAG)


def _axis_angle_kernel(ops, axis, angle):
    axis = unit(ops, axis)  # a zero axis is refused unless the angle is 0 too
    return _AxisAngleMatrix(matrix=_rodrigues(ops, *axis.direction, angle),
                            no_axis=(axis.norm == 0) & (angle != 0))


def axis_angle_to_matrix(axis, angle):
    """
    Rodrigues (Jia, eq. 7): axis (..., 3), angle (...) → (..., 3, 3), broadcasting.

    The axis is normalised. A zero axis with a zero angle gives the identity; a zero axis with
    a non-zero angle raises RotationError.
    """
    matrix = _plain_rodrigues(axis, angle)
    if matrix is not None:
        return matrix
    out = apply(_axis_angle_kernel, [(axis, (3,), 'axis', True), (angle, (), 'angle', True)],
                _AXIS_ANGLE_MATRIX)
    bad = out.no_axis
    if bad is not False_ and bad.any():  # (one item's flag is one of NumPy's two bools)
        first = float(np.broadcast_to(np.asarray(angle, dtype=float), bad.shape)[bad].flat[0])
        raise RotationError(f'axis is zero but the angle is {first:g} rad: a rotation needs '
                            'a direction (a zero axis is allowed only with angle 0)')
    return out.matrix


_MATRIX_IN_RANGE = InRange(value=MATRIX, fits=FLAG)


def _rotvec_kernel(ops, v):
    axis = unit(ops, v)  # v = θ·l̂; the zero vector gives l̂ = (0, 0, 1) and θ = 0
    fits = in_range(ops, [axis.norm])  # |v| beyond 1.8e308: refused, tan(inf) avoided
    return InRange(value=_rodrigues(ops, *axis.direction, ops.where(fits, axis.norm, 0.0)),
                   fits=fits)


def _plain_rodrigues(v, angle=None):
    """
    Return Rodrigues' matrix of one plain item, or None: the one fast path of the package.

    For rotvec_to_matrix (angle None: θ = |v|) and axis_angle_to_matrix.

    apply's own cost around these two kernels misses their one-item goal (bench/README.md):
    for one float64 (3,) array v with |v|² in [1e-290, 1e290] (where unit takes no rare
    path) and a finite float angle, the kernels' own steps on floats, unit's v/|v| and
    _rodrigues, give the same bits. None for anything else, which apply takes.
    test/test_backend.py holds it to the batch formula.
    """
    if type(v) is not np.ndarray or v.shape != (3,) or v.dtype != np.float64:
        return None
    x, y, z = v.tolist()
    n2 = x * x + y * y + z * z
    if not 1e-290 <= n2 <= 1e290:  # (False for NaN and inf too)
        return None
    n = math.sqrt(n2)
    if angle is None:
        angle = n
    elif not isinstance(angle, float) or not math.isfinite(angle):
        return None
    return np.array(_rodrigues(FLOATS, x / n + 0.0, y / n + 0.0, z / n, angle))


def rotvec_to_matrix(rotvec):
    """
    Rotation matrix of the rotation vector θ·l̂; (..., 3) → (..., 3, 3); zero → identity.

    The matrix of the axis rotvec/|rotvec| and the angle |rotvec| (as axis_angle_to_matrix
    gives it). RotationError where the angle |θ·l̂| itself overflows float64.
    """
    matrix = _plain_rodrigues(rotvec)
    if matrix is not None:
        return matrix
    out = apply(_rotvec_kernel, [(rotvec, (3,), 'rotation vector', True)], _MATRIX_IN_RANGE)
    if out.fits is not True_:
        refuse_overflow(out.fits, 'the angle |θ·l̂| of the rotation vector')
    return out.value


class SkewCos(NamedTuple):
    """A rotation's skew part w = sin θ·l̂ and cos θ."""

    skew: list
    cos: Any


def skew_and_cos(m):
    """
    Return the SkewCos of the rotation m.

    w = ½(r32 − r23, r13 − r31, r21 − r12) = sin θ·l̂ and cos θ = (tr R − 1)/2, so that
    θ = atan2(|w|, cos θ) ∈ [0, π] (accurate at every angle).
    """
    return SkewCos(
        skew=[0.5 * (m[2][1] - m[1][2]), 0.5 * (m[0][2] - m[2][0]), 0.5 * (m[1][0] - m[0][1])],
        cos=0.5 * (m[0][0] + m[1][1] + m[2][2] - 1.0))


def axis_angle_kernel(ops, m):
    """Return the AxisAngle (unit axis, angle ∈ [0, π]) of m; see matrix_to_axis_angle."""
    parts = skew_and_cos(m)
    w, cos = parts.skew, parts.cos
    skew_axis = unit(ops, w)  # its norm is sin θ
    angle = ops.atan2(skew_axis.norm, cos)
    near_pi = cos < 0
    if not ops.rare(near_pi):  # (an item, or a chunk, with every angle ≤ π/2)
        return AxisAngle(axis=skew_axis.direction, angle=angle)
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
    sym_axis = unit(ops, col).direction
    # Its sign from the skew part (free at exactly π, where w = 0).
    flip = sym_axis[0] * w[0] + sym_axis[1] * w[1] + sym_axis[2] * w[2] < 0
    sign = ops.where(flip, -1.0, 1.0)
    axis = [ops.where(near_pi, sign * a + 0.0, b)
            for a, b in zip(sym_axis, skew_axis.direction)]
    return AxisAngle(axis=axis, angle=angle)


def matrix_to_axis_angle(R, *, check=True):
    """
    Axis and angle of R: returns AxisAngle(axis (..., 3) unit, angle (...) ∈ [0, π]).

    With w = ½(r32 − r23, r13 − r31, r21 − r12) = sin θ·l̂ (the negative half of Jia's
    eq. 11's l) and cos θ = (Tr R − 1)/2 (eq. 12): θ = atan2(|w|, cos θ), accurate to rounding
    at every angle (acos loses half the digits near 0 and π; eq. 13's square root too).
    The axis is w/|w| while cos θ ≥ 0. Near π the skew part vanishes with sin θ, so there the
    axis comes from the symmetric part (R + Rᵀ)/2 − cos θ·I = (1 − cos θ)·l̂l̂ᵀ: its column
    with the largest diagonal entry, normalised, with the sign of w (at exactly π the sign is
    free: the largest component is made positive). At θ = 0 the axis is (0, 0, 1).
    """
    return apply_to_rotations(axis_angle_kernel, R, check, _AXIS_ANGLE)


def rotvec_of(turn):
    """Return the rotation vector angle·axis of an AxisAngle's entries."""
    return [a * turn.angle for a in turn.axis]


def _rotvec_of_matrix_kernel(ops, m):
    return rotvec_of(axis_angle_kernel(ops, m))


def matrix_to_rotvec(R, *, check=True):
    """Rotation vector θ·l̂ of R, θ ∈ [0, π]; (..., 3, 3) → (..., 3)."""
    return apply_to_rotations(_rotvec_of_matrix_kernel, R, check, VECTOR)


# The Rodrigues (Gibbs) vector g = tan(θ/2)·l̂. With the unit quaternion
# q = (sin(θ/2)·l̂, cos(θ/2)) in the ROS order (x, y, z, w), g = (x, y, z)/w, the same for q
# and −q; back, q = (g, 1)/√(1 + g·g). Composition and the Cayley transform
# R = (I + [g]×)(I − [g]×)⁻¹ make it the rotation's Cayley parameters. |g| grows without
# bound as θ → π; at θ = π (w = 0) g is infinite, and a hair from π it may overflow float64:
# a RotationError.

INFINITE_AT_PI = 'the Rodrigues vector tan(θ/2)·l̂ is infinite at θ = π (quaternion w = 0)'
"""Why a rotation by θ = π has no Rodrigues vector."""


def _no_rodrigues(w):
    """
    Return why the quaternion with real part w has no Rodrigues vector in float64.

    w = 0: θ = π. A w so small that (x, y, z)/w overflows: θ within 2·asin|w| ≈ 2|w| of π.
    """
    if w == 0.0:
        return INFINITE_AT_PI
    return (f'the Rodrigues vector tan(θ/2)·l̂ overflows float64 (beyond ±1.8e308): θ is '
            f'{2.0 * abs(w):.3g} rad from π (quaternion w = {w:.3g})')


def quaternion_to_rodrigues(q):
    """
    Return g = (x, y, z)/w of unit quaternions q (..., 4) as (x, y, z, w); (..., 3).

    RotationError where w = 0, a rotation by θ = π whose g is infinite, or where g overflows.
    """
    q = np.asarray(q, dtype=np.float64)
    w = q[..., 3]
    with np.errstate(divide='ignore', over='ignore', invalid='ignore'):
        g = q[..., :3] / w[..., None]
    at_pi = (w == 0.0) | np.isinf(g).any(axis=-1)
    if at_pi.any():
        first = tuple(int(i) for i in np.argwhere(at_pi)[0])
        raise RotationError(_no_rodrigues(w[first]) + (f' (item {first})' if w.ndim else ''))
    return g


def rodrigues_of_one(x, y, z, w):
    """
    Return quaternion_to_rodrigues of one quaternion, in plain floats: (x/w, y/w, z/w).

    The per-message path of rotation_node (no NumPy value made); RotationError at w = 0 or
    where g overflows.
    """
    if w == 0.0:
        raise RotationError(INFINITE_AT_PI)
    g = x / w, y / w, z / w
    if any(math.isinf(c) for c in g):
        raise RotationError(_no_rodrigues(w))
    return g


def matrix_to_rodrigues(R, *, check=True):
    """
    Return the Rodrigues vector g = tan(θ/2)·l̂ of rotations R (..., 3, 3); (..., 3).

    g = (x, y, z)/w of matrix_to_quaternion(R). R is validated unless check=False.
    RotationError at θ = π, where g is infinite.
    """
    return quaternion_to_rodrigues(matrix_to_quaternion(R, check=check))


def rodrigues_to_matrix(g):
    """
    Return the rotation matrix (..., 3, 3) of Rodrigues vectors g = tan(θ/2)·l̂ (..., 3).

    R = quaternion_to_matrix((g, 1)), the quaternion scaled by 1/max(1, |g_i|) first so that
    g·g cannot overflow. RotationError for NaN/Inf in g (θ = π has no finite g).
    """
    g = finite_array(g, (3,), 'Rodrigues vector g')
    scale = np.maximum(1.0, np.abs(g).max(axis=-1, keepdims=True))
    return quaternion_to_matrix(np.concatenate([g / scale, 1.0 / scale], axis=-1))
