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

from typing import NamedTuple

import numpy as np

from rot_tools._arrays import finite_array, unit_vectors
from rot_tools.axis_angle import axis_angle_to_matrix, matrix_to_axis_angle
from rot_tools.errors import RotationError
from rot_tools.so3 import checked_rotation

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


def _dot(u, v):
    return np.einsum('...i,...i->...', u, v)


def _rigid(R, b, check):
    """Validate (R, b) and broadcast them to one batch shape."""
    R = checked_rotation(R, check)
    b = finite_array(b, (3,), 'translation b')
    shape = np.broadcast_shapes(R.shape[:-2], b.shape[:-1])
    return np.broadcast_to(R, shape + (3, 3)), np.broadcast_to(b, shape + (3,))


def screw_from_transform(R, b, *, check=True):
    """Chasles decomposition of p ↦ R·p + b as a Screw (formulas in the module docstring).

    R (..., 3, 3), b (..., 3), broadcasting. θ and l̂ from matrix_to_axis_angle; then
    d = b·l̂, b⊥ = b − d·l̂, c = ½(b⊥ + cot(θ/2)·l̂ × b⊥), m = c × l̂, h = d/θ.
    """
    R, b = _rigid(R, b, check)
    axis, angle = matrix_to_axis_angle(R, check=False)
    translating = angle < PURE_TRANSLATION_ANGLE
    b_dir, b_norm = unit_vectors(b)
    direction = np.where(translating[..., None], b_dir, axis)
    d = np.where(translating, b_norm, _dot(b, axis))
    b_perp = b - d[..., None] * direction
    with np.errstate(divide='ignore'):
        cot_half = np.where(translating, 0.0, 1.0 / np.tan(0.5 * angle))
    point = 0.5 * (b_perp + cot_half[..., None] * np.cross(direction, b_perp))
    point = np.where(translating[..., None], 0.0, point)
    angle = np.where(translating, 0.0, angle)
    with np.errstate(divide='ignore', invalid='ignore'):
        pitch = np.where(translating, np.where(b_norm > 0, np.inf, 0.0), d / angle)
    return Screw(direction, point, np.cross(point, direction), angle + 0.0, d + 0.0,
                 pitch + 0.0)


def screw_log(R, b, *, check=True):
    """Exponential coordinates (θ·l̂, θ·v), v = −l̂ × c + h·l̂, of p ↦ R·p + b; (..., 6).

    θ·v = −θ·l̂ × c + d·l̂; a pure translation gives (0, b). Inverse of screw_exp.
    """
    s = screw_from_transform(R, b, check=check)
    theta = s.angle[..., None]
    moving = -theta * np.cross(s.direction, s.point) + s.translation[..., None] * s.direction
    return np.concatenate([theta * s.direction, moving], axis=-1)


def screw_exp(twist):
    """Rigid motion (R, b) = exp of the twist (ω, u) = (θ·l̂, θ·v); (..., 6) → (R, b).

    R = Rot_l̂(θ) (Rodrigues) and b = (I − R)·c + d·l̂ with c = l̂ × u/θ, d = l̂·u, i.e.
    b = (sin θ/θ)·u⊥ + ((1 − cos θ)/θ)·l̂ × u + (l̂·u)·l̂, which is smooth at θ = 0 (b = u).
    """
    twist = finite_array(twist, (6,), 'twist')
    axis, theta = unit_vectors(twist[..., :3])
    u = twist[..., 3:]
    d = _dot(axis, u)
    u_perp = u - d[..., None] * axis
    sinc = np.sinc(theta / np.pi)                                   # sin θ / θ
    versinc = np.sin(0.5 * theta) * np.sinc(0.5 * theta / np.pi)   # (1 − cos θ) / θ
    b = sinc[..., None] * u_perp + versinc[..., None] * np.cross(axis, u) + d[..., None] * axis
    return axis_angle_to_matrix(axis, theta), b


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
    axis, norm = unit_vectors(direction)
    if not (norm > 0).all():
        raise RotationError('screw direction must be non-zero, got |direction| = 0')
    theta = angle[..., None]
    moving = -theta * np.cross(axis, point) + translation[..., None] * axis
    shape = np.broadcast_shapes(axis.shape, moving.shape)
    return screw_exp(np.concatenate([np.broadcast_to(theta * axis, shape), moving], axis=-1))


def screw_interpolate(R0, b0, R1, b1, s, *, check=True):
    """The constant-screw motion from T0 = (R0, b0) to T1 = (R1, b1) at fractions s (...).

    T(s) = T0 · exp(s · log(T0⁻¹ T1)): every point moves along one helix about the relative
    screw axis; T(0) = T0 and T(1) = T1. Returns (R(s) (..., 3, 3), b(s) (..., 3)).
    """
    R0, b0 = _rigid(R0, b0, check)
    R1, b1 = _rigid(R1, b1, check)
    R0t = np.swapaxes(R0, -1, -2)
    rel_R = R0t @ R1
    rel_b = np.einsum('...ij,...j->...i', R0t, b1 - b0)
    twist = screw_log(rel_R, rel_b, check=False)
    s = finite_array(s, (), 'fraction s')
    step_R, step_b = screw_exp(s[..., None] * twist)
    return R0 @ step_R, np.einsum('...ij,...j->...i', R0, step_b) + b0
