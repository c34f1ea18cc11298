"""Chasles' screw decomposition of rigid motions, and its exponential coordinates.

A rigid motion T(p) = R·p + b (seed 000 §5) is a rotation by θ about a line — the screw axis,
direction l̂ through the point c — followed by a translation d along that same line
(Chasles' theorem)::

    T(p) = R·(p − c) + c + d·l̂,      so  b = (I − R)·c + d·l̂

The axis is reported in Plücker coordinates (l̂, m) with the moment m = c × l̂, and the pitch
h = d/θ (metres per radian). Seed 000 §5 finds c from (I − R)⁻¹·b⊥, but I − R is singular
along l̂; c is instead solved in the plane ⊥ l̂, where the 2-D rotation by θ is invertible::

    c = ½·(b⊥ + cot(θ/2)·l̂ × b⊥),     b⊥ = b − (b·l̂)·l̂,   d = b·l̂

(seed 000's moment −(Rᵀ + I)·b⊥ of eqs. 17–18 is −2 sin θ times this m: its l is −2 sin θ·l̂).

Exponential coordinates (a twist, screw_log / screw_exp) are the 6-vector (θ·l̂, θ·v) with
v = −l̂ × c + h·l̂, so that T = exp(θ·[l̂, v]); a pure translation is (0, b).

Special cases: θ below PURE_TRANSLATION_ANGLE is a pure translation (direction b/|b|, point 0,
angle 0, translation |b|, pitch inf); the identity has direction (0, 0, 1) and all else 0.
At θ = π the direction's sign is the one matrix_to_axis_angle picks, and translation, moment
and twist follow it.
"""

import math
from typing import NamedTuple

import numpy as np

from rot_tools._arrays import finite_array
from rot_tools._backend import apply, cross, dot, unit
from rot_tools.axis_angle import _rodrigues, axis_angle_kernel
from rot_tools.errors import RotationError
from rot_tools.so3 import apply_to_rotations, checked_rotation

PURE_TRANSLATION_ANGLE = 1e-12
"""Rotation angle (rad) below which screw_from_transform reports a pure translation.

Dropping such a rotation changes R by less than 1e-12, inside the round-trip tolerance; above
it the screw axis is computed, however far away (|c| grows like |b|/θ).
"""


class Screw(NamedTuple):
    """Chasles decomposition of (R, b); each field has the input's batch shape (...).

    direction: unit l̂ (..., 3); point: the axis point closest to the origin, ⊥ l̂ (..., 3);
    moment: point × direction (..., 3); angle: θ ∈ [0, π]; translation: d along l̂ (signed);
    pitch: d/θ, inf for a pure translation, 0 for the identity.
    """

    direction: np.ndarray
    point: np.ndarray
    moment: np.ndarray
    angle: np.ndarray
    translation: np.ndarray
    pitch: np.ndarray


def _apply_rigid(kernel, R, b, check, outputs):
    """apply_to_rotations(kernel) to the motion p ↦ R·p + b, R validated unless not check."""
    return apply_to_rotations(kernel, R, check, outputs, [(b, (3,), 'translation b', True)])


def screw_kernel(ops, m, b):
    """The Screw of (m, b); see screw_from_transform."""
    return screw_of_axis_kernel(ops, *axis_angle_kernel(ops, m), b)


def screw_of_axis_kernel(ops, axis, angle, b):
    """The Screw of (Rot_axis(angle), b), axis and angle as axis_angle_kernel gives them."""
    b_dir, b_norm = unit(ops, b)
    translating = angle < PURE_TRANSLATION_ANGLE
    direction = [ops.where(translating, p, q) for p, q in zip(b_dir, axis)]
    d = ops.where(translating, b_norm, dot(b, axis))
    b_perp = [bi - d * li for bi, li in zip(b, direction)]
    turning = ops.where(translating, 1.0, angle)  # no division by a zero angle below
    cot_half = ops.where(translating, 0.0, 1.0 / ops.tan(0.5 * turning))
    swing = cross(direction, b_perp)
    point = [ops.where(translating, 0.0, 0.5 * (p + cot_half * q)) for p, q in zip(b_perp, swing)]
    pitch = ops.where(translating, ops.where(b_norm > 0, math.inf, 0.0), d / turning)
    return (direction, point, cross(point, direction), ops.where(translating, 0.0, angle),
            d + 0.0, pitch + 0.0)


_VEC, _SCALAR = ((3,), np.float64), ((), np.float64)


def screw_from_transform(R, b, *, check=True):
    """Chasles decomposition of p ↦ R·p + b as a Screw (formulas in the module docstring).

    R (..., 3, 3), b (..., 3), broadcasting. θ and l̂ as matrix_to_axis_angle gives them;
    then d = b·l̂, b⊥ = b − d·l̂, c = ½(b⊥ + cot(θ/2)·l̂ × b⊥), m = c × l̂, h = d/θ.
    """
    return Screw(*_apply_rigid(screw_kernel, R, b, check, [_VEC] * 3 + [_SCALAR] * 3))


def twist_kernel(ops, direction, point, moment, angle, translation, pitch):
    """Exponential coordinates (θ·l̂, θ·v) of a Screw: θ·v = −θ·l̂ × c + d·l̂ = θ·m + d·l̂."""
    return ([angle * li for li in direction]
            + [angle * mi + translation * li for mi, li in zip(moment, direction)])


def _log_kernel(ops, m, b):
    return (twist_kernel(ops, *screw_kernel(ops, m, b)),)


def screw_log(R, b, *, check=True):
    """Exponential coordinates (θ·l̂, θ·v), v = −l̂ × c + h·l̂, of p ↦ R·p + b; (..., 6).

    θ·v = −θ·l̂ × c + d·l̂; a pure translation gives (0, b). Inverse of screw_exp.
    """
    (twist,) = _apply_rigid(_log_kernel, R, b, check, [((6,), np.float64)])
    return twist


def _exp_kernel(ops, twist):
    axis, theta = unit(ops, twist[:3])
    u = twist[3:]
    d = dot(axis, u)
    half = 0.5 * theta
    sh = ops.sin(half)
    # sin θ/θ and (1 − cos θ)/θ; below 1e-8 rad their series 1 − θ²/6 and θ/2 − θ³/24 are
    # 1 and θ/2 to double precision (and sin(θ/2) would underflow for denormal θ).
    small = theta < 1e-8
    safe = ops.where(small, 1.0, theta)
    sinc = ops.where(small, 1.0, 2.0 * sh * ops.cos(half) / safe)
    versinc = ops.where(small, half, 2.0 * sh * sh / safe)
    swing = cross(axis, u)
    b = [sinc * (ui - d * li) + versinc * si + d * li for ui, li, si in zip(u, axis, swing)]
    return _rodrigues(ops, axis[0], axis[1], axis[2], theta), b


def screw_exp(twist):
    """Rigid motion (R, b) = exp of the twist (ω, u) = (θ·l̂, θ·v); (..., 6) → (R, b).

    R = Rot_l̂(θ) (Rodrigues) and b = (I − R)·c + d·l̂ with c = l̂ × u/θ, d = l̂·u, i.e.
    b = (sin θ/θ)·u⊥ + ((1 − cos θ)/θ)·l̂ × u + (l̂·u)·l̂, which is smooth at θ = 0 (b = u).
    """
    return apply(_exp_kernel, [(twist, (6,), 'twist', True)], [((3, 3), np.float64), _VEC])


def transform_from_screw(direction, point, angle, translation):
    """Rigid motion (R, b) of a screw: R = Rot_l̂(θ), b = (I − R)·point + d·l̂.

    direction (..., 3) is normalised (zero raises RotationError); point (..., 3) may be any
    point of the axis; angle, translation (...). Inverse of screw_from_transform; computed
    as screw_exp of the twist (θ·l̂, −θ·l̂ × point + d·l̂).
    """
    direction = finite_array(direction, (3,), 'direction')
    point = finite_array(point, (3,), 'point')
    angle = finite_array(angle, (), 'angle')
    translation = finite_array(translation, (), 'translation')
    if not np.any(direction, axis=-1).all():
        raise RotationError('screw direction must be non-zero, got |direction| = 0')
    axis = direction / np.abs(direction).max(axis=-1, keepdims=True)
    axis /= np.linalg.norm(axis, axis=-1, keepdims=True)
    theta = angle[..., None]
    moving = -theta * np.cross(axis, point) + translation[..., None] * axis
    shape = np.broadcast_shapes(axis.shape, moving.shape)
    return screw_exp(np.concatenate([np.broadcast_to(theta * axis, shape), moving], axis=-1))


def screw_interpolate(R0, b0, R1, b1, s, *, check=True):
    """The constant-screw motion from T0 = (R0, b0) to T1 = (R1, b1) at fractions s (...).

    T(s) = T0 · exp(s · log(T0⁻¹ T1)): every point moves along one helix about the relative
    screw axis; T(0) = T0 and T(1) = T1, and s outside [0, 1] continues the same motion.
    Returns (R(s) (..., 3, 3), b(s) (..., 3)).
    """
    R0, R1 = checked_rotation(R0, check), checked_rotation(R1, check)
    b0, b1 = finite_array(b0, (3,), 'translation b0'), finite_array(b1, (3,), 'translation b1')
    R0t = np.swapaxes(R0, -1, -2)
    rel_R = R0t @ R1
    rel_b = np.einsum('...ij,...j->...i', R0t, b1 - b0)
    twist = screw_log(rel_R, rel_b, check=False)
    s = finite_array(s, (), 'fraction s')
    step_R, step_b = screw_exp(s[..., None] * twist)
    return R0 @ step_R, np.einsum('...ij,...j->...i', R0, step_b) + b0
