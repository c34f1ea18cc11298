"""
Chasles' screw decomposition of rigid motions, and its exponential coordinates.

Every rigid motion p ↦ R·p + b (Jia, Rotation in the Space, §5) is a turn θ about a line
(direction l̂ through c) and a slide d along it: b = (I − R)·c + d·l̂. The axis is found in
the plane ⊥ l̂, where I − R is invertible; the twist (θ·l̂, θ·v) is written with b, so it
is smooth at θ = 0. Each function states its formula.
"""

__all__ = ['PURE_TRANSLATION_ANGLE', 'Screw', 'screw_exp', 'screw_from_transform',
           'screw_interpolate', 'screw_log', 'transform_from_screw']

import math
from typing import Any, NamedTuple

import numpy as np
from rot_tools.core._arrays import finite_array, refuse_overflow
from rot_tools.core.axis_angle import axis_angle_kernel, rodrigues_entries, sin_versin
from rot_tools.core.engine import (apply, cross, dot, FLAG, in_range, InRange, linear_in_range,
                                   SCALAR, Spec, unit, VECTOR)
from rot_tools.core.errors import RotationError
from rot_tools.core.rigid import MOTION, Motion
from rot_tools.core.so3 import apply_to_rotations, checked_rotation

PURE_TRANSLATION_ANGLE = 1e-12
"""Rotation angle (rad) below which screw_from_transform reports a pure translation.

Dropping such a rotation changes R by less than 1e-12, inside the round-trip tolerance; above
it the screw axis is computed, however far away (|c| grows like |b|/θ).
"""


class Screw(NamedTuple):
    """
    Chasles decomposition of (R, b); each field has the input's batch shape (...).

    direction: unit l̂ (..., 3); point: the axis point closest to the origin, ⊥ l̂ (..., 3);
    moment: point × direction (..., 3); angle: θ ∈ [0, π]; translation: d along l̂ (signed);
    pitch: d/θ, inf for a pure translation, 0 for the identity.

    θ below PURE_TRANSLATION_ANGLE is a pure translation: direction b/|b|, point 0, angle 0,
    translation |b|. The identity has direction (0, 0, 1) and all else 0. At θ = π the
    direction's sign is the one matrix_to_axis_angle picks; the translation, moment and
    twist follow it.
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


def screw_of_axis_kernel(ops, axis, angle, b):
    """
    Return InRange(the Screw of (Rot_axis(angle), b), fits).

    axis and angle as axis_angle_kernel gives them; fits is false where the screw's point,
    moment, translation or pitch overflowed float64.
    """
    b_unit = unit(ops, b)
    b_norm = b_unit.norm
    translating = angle < PURE_TRANSLATION_ANGLE
    direction = [ops.where(translating, p, q) for p, q in zip(b_unit.direction, axis)]
    d = ops.where(translating, b_norm, dot(b, axis))
    b_perp = [bi - d * li for bi, li in zip(b, direction)]
    turning = ops.where(translating, 1.0, angle)  # no division by a zero angle below
    cot_half = ops.where(translating, 0.0, 1.0 / ops.tan(0.5 * turning))
    swing = cross(direction, b_perp)
    # ½·b⊥ + (½·cot(θ/2))·l̂ × b⊥: halved first, so that a point that fits float64 does not
    # overflow on the way (½(b⊥ + …) did for |b| near 1.8e308); halving is exact.
    half_cot = 0.5 * cot_half
    point = [ops.where(translating, 0.0, 0.5 * p + half_cot * q) for p, q in zip(b_perp, swing)]
    moment = cross(point, direction)
    slope = d / turning
    pitch = ops.where(translating, ops.where(b_norm > 0, math.inf, 0.0), slope)
    fits = in_range(ops, [*point, *moment, d, ops.where(translating, 0.0, slope)])
    return InRange(value=Screw(direction=direction, point=point, moment=moment,
                               angle=ops.where(translating, 0.0, angle), translation=d + 0.0,
                               pitch=pitch + 0.0), fits=fits)


def refuse_far_axis(fits, angle, b):
    """
    Raise RotationError where fits is false.

    RotationError where fits is false: the screw's point, moment or pitch (~|b|/θ)
    overflowed float64, or the translation |b| did.
    """
    if fits.ndim == 0 and fits or fits.all():
        return
    index = tuple(int(i) for i in np.argwhere(~fits)[0]) if fits.ndim else ()
    size = float(np.abs(np.broadcast_to(np.asarray(b, dtype=float), fits.shape + (3,))[index]
                        ).max())
    theta = float(angle[index])
    where = f', first at item {index}' if fits.ndim else ''
    if theta == 0:
        raise RotationError(f'the screw translation |b| overflows float64: max|b_i| = '
                            f'{size:.3g}{where}')
    raise RotationError(
        'the screw overflows float64: its axis point and pitch grow like |b|/θ, and here '
        f'max|b_i| = {size:.3g} at θ = {theta:.3g} rad{where}')


_SCREW = Screw(direction=VECTOR, point=VECTOR, moment=VECTOR, angle=SCALAR,
               translation=SCALAR, pitch=SCALAR)
TWIST = Spec((6,))


def _screw_kernel(ops, m, b):
    turn = axis_angle_kernel(ops, m)
    return screw_of_axis_kernel(ops, turn.axis, turn.angle, b)


def screw_from_transform(R, b, *, check=True):
    """
    Chasles decomposition of p ↦ R·p + b as a Screw: b = (I − R)·c + d·l̂.

    R (..., 3, 3), b (..., 3), broadcasting. θ and l̂ as matrix_to_axis_angle gives them;
    then d = b·l̂, b⊥ = b − d·l̂, c = ½(b⊥ + cot(θ/2)·l̂ × b⊥) (solved in the plane ⊥ l̂,
    where I − R is invertible), m = c × l̂, h = d/θ. Jia's moment −(Rᵀ + I)·b⊥ (§5, eqs.
    17–18) is −2 sin θ times this m.
    RotationError where c or h overflow float64 (|b|/θ beyond ~1e308).
    """
    screw = _apply_rigid(_screw_kernel, R, b, check, InRange(value=_SCREW, fits=FLAG))
    refuse_far_axis(screw.fits, screw.value.angle, b)
    return screw.value


def twist_kernel(ops, axis, angle, b):
    """
    InRange(exponential coordinates (θ·l̂, θ·v) of (Rot_axis(angle), b), fits).

    θ·v = −(θ/2)·l̂ × b + (θ/2)·cot(θ/2)·b⊥ + d·l̂ (= −θ·l̂ × c + d·l̂ of the Screw), with
    (θ/2)·cot(θ/2) → 1 at θ = 0: no threshold, no division by a small θ.
    """
    half = 0.5 * angle
    tangent = ops.tan(half)
    flat = tangent == 0  # θ = 0, or so small that θ/2 underflows
    k = ops.where(flat, 1.0, half / ops.where(flat, 1.0, tangent))

    def twist_of(b):
        d = dot(b, axis)
        swing = cross(axis, b)
        return [k * (bi - d * li) - half * si + d * li for bi, li, si in zip(b, axis, swing)]
    u = linear_in_range(ops, twist_of, b)
    return InRange(value=[angle * li for li in axis] + u.value, fits=u.fits)


def _log_kernel(ops, m, b):
    turn = axis_angle_kernel(ops, m)
    return twist_kernel(ops, turn.axis, turn.angle, b)


def screw_log(R, b, *, check=True):
    """
    Exponential coordinates (θ·l̂, θ·v), v = −l̂ × c + h·l̂, of p ↦ R·p + b; (..., 6).

    θ·v = −(θ/2)·l̂ × b + (θ/2)·cot(θ/2)·b⊥ + d·l̂; θ·l̂ is the rotation vector for every θ
    (no pure-translation threshold: the identity rotation gives (0, b)). Inverse of
    screw_exp.
    """
    twist = _apply_rigid(_log_kernel, R, b, check, InRange(value=TWIST, fits=FLAG))
    refuse_overflow(twist.fits, 'θ·v of screw_log (|θ·v| ≤ π/2·|b|)')
    return twist.value


class _Exp(NamedTuple):
    motion: Motion
    turns: Any  # |ω| fits float64
    fits: Any  # b fits float64


def _exp_kernel(ops, twist):
    axis = unit(ops, twist[:3])
    turns = in_range(ops, [axis.norm])  # |ω| may overflow: then refused, sin(inf) avoided
    theta = ops.where(turns, axis.norm, 0.0)
    lhat, u = axis.direction, twist[3:]
    d = dot(lhat, u)
    trig = sin_versin(ops, theta)
    # sin θ/θ and (1 − cos θ)/θ; below 1e-8 rad their series 1 − θ²/6 and θ/2 − θ³/24 are
    # 1 and θ/2 to double precision (and 1 − cos θ would underflow for denormal θ).
    small = theta < 1e-8
    safe = ops.where(small, 1.0, theta)
    sinc = ops.where(small, 1.0, trig.sin / safe)
    versinc = ops.where(small, 0.5 * theta, trig.versin / safe)
    swing = cross(lhat, u)
    b = [sinc * (ui - d * li) + versinc * si + d * li for ui, li, si in zip(u, lhat, swing)]
    return _Exp(motion=Motion(R=rodrigues_entries(*lhat, trig), b=b), turns=turns,
                fits=in_range(ops, b))


def screw_exp(twist):
    """
    Rigid motion Motion(R, b) = exp of the twist (ω, u) = (θ·l̂, θ·v); (..., 6) → (R, b).

    R = Rot_l̂(θ) (Rodrigues) and b = (I − R)·c + d·l̂ with c = l̂ × u/θ, d = l̂·u, i.e.
    b = (sin θ/θ)·u⊥ + ((1 − cos θ)/θ)·l̂ × u + (l̂·u)·l̂, which is smooth at θ = 0 (b = u).
    RotationError where |ω| or b overflow float64.
    """
    out = apply(_exp_kernel, [(twist, (6,), 'twist', True)],
                _Exp(motion=MOTION, turns=FLAG, fits=FLAG))
    refuse_overflow(out.turns, 'the rotation angle |ω| of the twist')
    refuse_overflow(out.fits, 'b of screw_exp')
    return out.motion


class _ScrewMotion(NamedTuple):
    motion: Motion
    no_direction: Any  # a zero direction: refused
    fits: Any  # b fits float64


def _transform_of_screw_kernel(ops, direction, point, angle, translation):
    axis = unit(ops, direction)
    lhat = axis.direction
    trig = sin_versin(ops, angle)
    along = dot(point, lhat)
    swing = cross(lhat, point)
    b = [trig.versin * (ci - along * li) - trig.sin * si + translation * li
         for ci, li, si in zip(point, lhat, swing)]
    return _ScrewMotion(motion=Motion(R=rodrigues_entries(*lhat, trig), b=b),
                        no_direction=axis.norm == 0, fits=in_range(ops, b))


def transform_from_screw(direction, point, angle, translation):
    """
    Rigid motion Motion(R, b) of a screw: R = Rot_l̂(θ), b = (I − R)·point + d·l̂.

    direction (..., 3) is normalised (zero raises RotationError); point (..., 3) may be any
    point of the axis; angle, translation (...); broadcasting. Inverse of
    screw_from_transform. (I − R)·c = (1 − cos θ)·c⊥ − sin θ·l̂ × c with c⊥ = c − (c·l̂)·l̂,
    so tiny angles with far-away axes keep their digits.
    """
    out = apply(_transform_of_screw_kernel, [
        (direction, (3,), 'direction', True), (point, (3,), 'point', True),
        (angle, (), 'angle', True), (translation, (), 'translation', True)],
        _ScrewMotion(motion=MOTION, no_direction=FLAG, fits=FLAG))
    if out.no_direction.any():
        raise RotationError('screw direction must be non-zero, got |direction| = 0')
    refuse_overflow(out.fits, 'b = (I − R)·point + d·l̂ of transform_from_screw')
    return out.motion


def _require_broadcast(*shapes):
    """Refuse batch shapes of screw_interpolate's inputs that do not broadcast together."""
    if len(set(shapes)) == 1:  # the usual case, one item or equal batches: no test to pay
        return
    try:
        np.broadcast_shapes(*shapes)
    except ValueError:
        raise RotationError(
            'screw_interpolate: the batch shapes of R0, b0, R1, b1 and s do not broadcast '
            f"together: {', '.join(map(str, shapes))}") from None


def screw_interpolate(R0, b0, R1, b1, s, *, check=True):
    """
    Return the constant-screw motion from T0 = (R0, b0) to T1 = (R1, b1) at fractions s (...).

    T(s) = T0 · exp(s · log(T0⁻¹ T1)): every point moves along one helix about the relative
    screw axis; T(0) = T0 and T(1) = T1, and s outside [0, 1] continues the same motion.
    Returns Motion(R(s) (..., 3, 3), b(s) (..., 3)); RotationError where a step overflows
    float64.
    """
    R0, R1 = checked_rotation(R0, check), checked_rotation(R1, check)
    b0, b1 = finite_array(b0, (3,), 'translation b0'), finite_array(b1, (3,), 'translation b1')
    s = finite_array(s, (), 'fraction s')
    _require_broadcast(R0.shape[:-2], b0.shape[:-1], R1.shape[:-2], b1.shape[:-1], s.shape)
    R0t = np.swapaxes(R0, -1, -2)
    rel_R = R0t @ R1
    with np.errstate(over='ignore', invalid='ignore'):
        rel_b = np.einsum('...ij,...j->...i', R0t, b1 - b0)
        refuse_overflow(np.isfinite(rel_b).all(-1), 'R0ᵀ·(b1 − b0) of screw_interpolate')
        step = s[..., None] * screw_log(rel_R, rel_b, check=False)
        refuse_overflow(np.isfinite(step).all(-1), 's·log(T0⁻¹·T1) of screw_interpolate')
        step = screw_exp(step)
        b = np.einsum('...ij,...j->...i', R0, step.b) + b0
        refuse_overflow(np.isfinite(b).all(-1), 'b(s) of screw_interpolate')
    return Motion(R=R0 @ step.R, b=b)
