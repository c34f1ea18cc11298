"""
Frames and rigid motions (Jia, Rotation in the Space, §4 and §5), one item or a batch.

A frame u-v-w is the rotation whose columns are its axes in the reference frame; a rigid
motion is p ↦ R·p + b, the 4×4 [[R, b], [0, 0, 0, 1]], composed by the matrix product.
Functions that take R validate it unless called with check=False (rot_tools.core.so3).
"""

__all__ = ['compose_transforms', 'frame_to_matrix', 'homogeneous_to_transform', 'invert_transform',
           'transform_points', 'transform_to_homogeneous']

from typing import Any, NamedTuple

import numpy as np
from rot_tools.core._arrays import apart, as_float_array, refuse_overflow, require_tolerance
from rot_tools.core.engine import (apply, cross, dot, FLAG, InRange, linear_in_range, MATRIX,
                                   SCALAR, Spec, unit, VECTOR)
from rot_tools.core.errors import RotationError
from rot_tools.core.so3 import (apply_to_named_rotations, apply_to_rotations, Defects,
                                defects_kernel, refuse_defects, ROTATION_TOL)

HOMOGENEOUS_ROW_TOL = 1e-9
"""Largest deviation of a homogeneous matrix's last row from (0, 0, 0, 1) that is accepted."""


class Motion(NamedTuple):
    """A rigid motion p ↦ R·p + b: R (..., 3, 3) and b (..., 3)."""

    R: np.ndarray
    b: np.ndarray


MOTION = Motion(R=MATRIX, b=VECTOR)
_HOMOGENEOUS = Spec((4, 4))


def _item(flags):
    """' (item i)' naming the first true entry of a batch of flags; '' for a single item."""
    if flags.ndim == 0:
        return ''
    return f' (item {tuple(int(i) for i in np.argwhere(flags)[0])})'


def _worst(size):
    """(index of the largest entry, ' (worst at item i)' or '' for a single item)."""
    worst = np.unravel_index(np.argmax(size), size.shape)
    return worst, f' (worst at item {tuple(map(int, worst))})' if size.ndim else ''


def _rotate(m, v):
    """R·v of a matrix and a 3-vector given as entry lists."""
    return [dot(row, v) for row in m]


class _Frame(NamedTuple):
    matrix: Any  # (û v̂ ŵ)
    norms: tuple  # |u|, |v|, |w|
    cosines: tuple  # û·v̂, û·ŵ, v̂·ŵ
    handedness: Any  # (û × v̂)·ŵ


_FRAME = _Frame(matrix=MATRIX, norms=(SCALAR,) * 3, cosines=(SCALAR,) * 3, handedness=SCALAR)


def _frame_kernel(ops, u, v, w):
    u, v, w = unit(ops, u), unit(ops, v), unit(ops, w)
    uh, vh, wh = u.direction, v.direction, w.direction
    return _Frame(matrix=[[uh[i], vh[i], wh[i]] for i in range(3)],
                  norms=(u.norm, v.norm, w.norm),
                  cosines=(dot(uh, vh), dot(uh, wh), dot(vh, wh)),
                  handedness=dot(cross(uh, vh), wh))


def frame_to_matrix(u, v, w, tol=ROTATION_TOL):
    """
    Return the rotation R = (û v̂ ŵ) of a frame whose axes u, v, w are written in x-y-z.

    u, v, w (..., 3), broadcasting → (..., 3, 3); each axis is normalised (Jia §4).
    RotationError names the defect: a zero axis; two axes whose unit vectors have
    |dot| > tol (which two, and the angle between them); a left-handed frame, (û × v̂)·ŵ < 0.
    With a tol above 1e-9 the result may miss validate_rotation's 1e-9: project it with
    nearest_rotation before handing it on.
    """
    tol = require_tolerance(tol, 'tol', 1.0, '[0, 1)')
    axes = [(x, (3,), f'frame axis {name}', True) for x, name in zip((u, v, w), 'uvw')]
    frame = apply(_frame_kernel, axes, _FRAME)
    for name, n in zip('uvw', frame.norms):
        zero = n == 0
        if zero.any():
            raise RotationError(f'frame axis {name} is zero (|{name}| = 0): an axis needs a '
                                f'direction{_item(zero)}')
    for pair, cos in zip(('u and v', 'u and w', 'v and w'), frame.cosines):
        size = np.abs(cos)
        if not (size <= tol).all():
            worst, where = _worst(size)
            shown, bound = apart(size[worst], tol)
            off = apart(90.0, np.degrees(np.arcsin(min(size[worst], 1.0))), (3, 3))[1]
            sign = '−' if cos[worst] > 0 else '+'
            raise RotationError(
                f'frame axes {pair} are not orthogonal: |cos| = {shown} > tol {bound}'
                f' (the angle between them is 90° {sign} {off}°){where}')
    left = frame.handedness < 0
    if left.any():
        raise RotationError('the frame (u, v, w) is left-handed: (û × v̂)·ŵ = '
                            f'{float(frame.handedness[left].flat[0]):.6g}, expected +1 (a '
                            f'reflection; reverse one axis){_item(left)}')
    return frame.matrix


def _points_kernel(ops, m, b, p):
    return linear_in_range(ops, lambda p, b: [x + y for x, y in zip(_rotate(m, p), b)], p, b)


def transform_points(R, b, p, *, check=True):
    """
    Return the image R·p + b of points p under the rigid motion (R, b) (Jia §5).

    R (..., 3, 3), b (..., 3), p (..., 3), broadcasting: one motion over many points, many
    motions over one point, or one each. Returns (..., 3).
    """
    image = apply_to_rotations(_points_kernel, R, check, InRange(value=VECTOR, fits=FLAG), [
        (b, (3,), 'translation b', True), (p, (3,), 'point p', True)])
    refuse_overflow(image.fits, 'R·p + b')
    return image.value


_MOTION_IN_RANGE = InRange(value=MOTION, fits=FLAG)


def _compose_kernel(ops, m1, m2, b1, b2):
    columns = [_rotate(m1, [m2[0][j], m2[1][j], m2[2][j]]) for j in range(3)]
    b = linear_in_range(ops, lambda b1, b2: [x + y for x, y in zip(_rotate(m1, b2), b1)],
                        b1, b2)
    return InRange(value=Motion(R=[[col[i] for col in columns] for i in range(3)], b=b.value),
                   fits=b.fits)


def compose_transforms(R1, b1, R2, b2, *, check=True):
    """
    T1∘T2, T2 applied first: (R1·R2, R1·b2 + b1) (Jia §5).

    R1, R2 (..., 3, 3), b1, b2 (..., 3), broadcasting → Motion(R (..., 3, 3), b (..., 3)).
    Equal to the product of the homogeneous matrices T1·T2.
    """
    out = apply_to_named_rotations(
        _compose_kernel, [(R1, 'R1'), (R2, 'R2')], check, _MOTION_IN_RANGE,
        [(b1, (3,), 'translation b1', True), (b2, (3,), 'translation b2', True)])
    refuse_overflow(out.fits, 'R1·b2 + b1')
    return out.value


def _invert_kernel(ops, m, b):
    mt = [[m[j][i] for j in range(3)] for i in range(3)]
    back = linear_in_range(ops, lambda b: [0.0 - x for x in _rotate(mt, b)], b)
    return InRange(value=Motion(R=mt, b=back.value), fits=back.fits)  # (0 − x: no −0.0)


def invert_transform(R, b, *, check=True):
    """
    T⁻¹ = Motion(Rᵀ, −Rᵀ·b) of p ↦ R·p + b; (..., 3, 3), (..., 3) → (..., 3, 3), (..., 3).

    transform_points(*invert_transform(R, b), p) = Rᵀ·(p − b) are the coordinates of p in
    the moved frame (Jia §4: q' = Rᵀ·q when b = 0).
    """
    out = apply_to_rotations(_invert_kernel, R, check, _MOTION_IN_RANGE,
                             [(b, (3,), 'translation b', True)])
    refuse_overflow(out.fits, '−Rᵀ·b')
    return out.value


def _homogeneous_kernel(ops, m, b):
    return [[*m[0], b[0]], [*m[1], b[1]], [*m[2], b[2]], [0.0, 0.0, 0.0, 1.0]]


def transform_to_homogeneous(R, b, *, check=True):
    """Return the 4×4 matrix [[R, b], [0, 0, 0, 1]] of p ↦ R·p + b; broadcasting → (..., 4, 4)."""
    return apply_to_rotations(_homogeneous_kernel, R, check, _HOMOGENEOUS,
                              [(b, (3,), 'translation b', True)])


class _Homogeneous(NamedTuple):
    motion: Motion
    last_row_off: Any  # max |last row − (0, 0, 0, 1)|
    defects: Defects  # of R


def _transform_of_homogeneous_kernel(ops, t):
    m = [t[0][:3], t[1][:3], t[2][:3]]
    off = ops.max_of(ops.abs(t[3][0]), ops.abs(t[3][1]), ops.abs(t[3][2]),
                     ops.abs(t[3][3] - 1.0))
    return _Homogeneous(motion=Motion(R=m, b=[t[0][3], t[1][3], t[2][3]]), last_row_off=off,
                        defects=defects_kernel(ops, m))


def homogeneous_to_transform(T, *, check=True):
    """
    Motion(R, b) of a homogeneous matrix T = [[R, b], [0, 0, 0, 1]]; (..., 4, 4) → (R, b).

    RotationError when the last row differs from (0, 0, 0, 1) by more than
    HOMOGENEOUS_ROW_TOL = 1e-9 (always), and when R is not a rotation (unless check=False).
    """
    out = apply(_transform_of_homogeneous_kernel, [(T, (4, 4), 'T', True)],
                _Homogeneous(motion=MOTION, last_row_off=SCALAR,
                             defects=Defects(orthogonality=SCALAR, det=SCALAR)))
    off = out.last_row_off
    if not (off <= HOMOGENEOUS_ROW_TOL).all():
        worst, where = _worst(off)
        row = as_float_array(T, (4, 4), 'T')[worst][3].tolist()
        raise RotationError(
            f'T is not a rigid motion: its last row is {row}, not [0, 0, 0, 1] '
            '(off by {} > {}){}'.format(*apart(off[worst], HOMOGENEOUS_ROW_TOL), where))
    if check:
        refuse_defects(out.defects, ROTATION_TOL, 'R (T[:3, :3])')
    return out.motion
