"""Axis-angle: Rodrigues' formula and its robust inverse.

A rotation by θ about the unit axis l̂ (right-hand rule) is (seed 000 eq. 7, seed 001 eq. 18)::

    Rot_l̂(θ) = cos θ·I + (1 − cos θ)·l̂l̂ᵀ + sin θ·[l̂]×

The rotation vector is θ·l̂. The inverse returns θ ∈ [0, π] and a unit axis; (l̂, θ) and
(−l̂, 2π − θ) — equivalently (−l̂, −θ) — describe the same rotation (seed 000 §3.3).
"""

import numpy as np

from rot_tools._arrays import finite_array, unit_vectors
from rot_tools.errors import RotationError
from rot_tools.so3 import checked_rotation


def axis_angle_to_matrix(axis, angle):
    """Rodrigues (seed 000 eq. 7): axis (..., 3), angle (...) → (..., 3, 3), broadcasting.

    The axis is normalised. A zero axis with a zero angle gives the identity; a zero axis with
    a non-zero angle raises RotationError. 1 − cos θ is evaluated as 2 sin²(θ/2), which keeps
    its relative precision at small angles.
    """
    axis = finite_array(axis, (3,), 'axis')
    angle = finite_array(angle, (), 'angle')
    unit, norm = unit_vectors(axis)
    bad = (norm == 0) & (angle != 0)
    if np.any(bad):
        first = float(np.broadcast_to(angle, bad.shape)[bad].flat[0])
        raise RotationError(f'axis is zero but the angle is {first:g} rad: a rotation needs '
                            'a direction (a zero axis is allowed only with angle 0)')
    x, y, z = unit[..., 0], unit[..., 1], unit[..., 2]
    c, s = np.cos(angle), np.sin(angle)
    v = 2.0 * np.sin(0.5 * angle) ** 2
    shape = np.broadcast_shapes(unit.shape[:-1], angle.shape)
    out = np.empty(shape + (3, 3))
    out[..., 0, 0] = c + v * x * x
    out[..., 0, 1] = v * x * y - s * z
    out[..., 0, 2] = v * x * z + s * y
    out[..., 1, 0] = v * x * y + s * z
    out[..., 1, 1] = c + v * y * y
    out[..., 1, 2] = v * y * z - s * x
    out[..., 2, 0] = v * x * z - s * y
    out[..., 2, 1] = v * y * z + s * x
    out[..., 2, 2] = c + v * z * z
    return out


def rotvec_to_matrix(rotvec):
    """Rotation matrix of the rotation vector θ·l̂; (..., 3) → (..., 3, 3); zero → identity."""
    rotvec = finite_array(rotvec, (3,), 'rotation vector')
    return axis_angle_to_matrix(rotvec, np.sqrt(np.einsum('...i,...i->...', rotvec, rotvec)))


def matrix_to_axis_angle(R, *, check=True):
    """Axis and angle of R: returns (axis (..., 3) unit, angle (...) ∈ [0, π]).

    With w = ½(r32 − r23, r13 − r31, r21 − r12) = sin θ·l̂ (the negative half of seed 000
    eq. 11's l) and cos θ = (Tr R − 1)/2 (eq. 12): θ = atan2(|w|, cos θ), accurate to rounding
    at every angle (acos loses half the digits near 0 and π; eq. 13's square root too).
    The axis is w/|w| while cos θ ≥ 0. Near π the skew part vanishes with sin θ, so there the
    axis comes from the symmetric part (R + Rᵀ)/2 − cos θ·I = (1 − cos θ)·l̂l̂ᵀ: its column
    with the largest diagonal entry, normalised, with the sign of w (at exactly π the sign is
    free: the largest component is made positive). At θ = 0 the axis is (0, 0, 1).
    """
    R = checked_rotation(R, check)
    w = 0.5 * np.stack([R[..., 2, 1] - R[..., 1, 2],
                        R[..., 0, 2] - R[..., 2, 0],
                        R[..., 1, 0] - R[..., 0, 1]], axis=-1)
    cos = 0.5 * (np.trace(R, axis1=-2, axis2=-1) - 1.0)
    axis, sin = unit_vectors(w)
    angle = np.arctan2(sin, cos)
    near_pi = cos < 0
    if np.any(near_pi):
        axis[near_pi] = _axis_near_pi(R[near_pi], cos[near_pi], w[near_pi])
    return axis, angle


def _axis_near_pi(R, cos, w):
    """Unit axis from the symmetric part (1 − cos θ)·l̂l̂ᵀ, signed so that l̂·w ≥ 0; (n,3,3)."""
    sym = 0.5 * (R + np.swapaxes(R, -1, -2))
    diag = np.arange(3)
    sym[..., diag, diag] -= cos[..., None]
    best = np.argmax(sym[..., diag, diag], axis=-1)
    column = np.take_along_axis(sym, best[..., None, None], axis=-1)[..., 0]
    axis = column / np.linalg.norm(column, axis=-1, keepdims=True)
    flip = np.einsum('...i,...i->...', axis, w) < 0
    return np.where(flip[..., None], -axis, axis)


def matrix_to_rotvec(R, *, check=True):
    """Rotation vector θ·l̂ of R, θ ∈ [0, π]; (..., 3, 3) → (..., 3)."""
    axis, angle = matrix_to_axis_angle(R, check=check)
    return axis * angle[..., None]
