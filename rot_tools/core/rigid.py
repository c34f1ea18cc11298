"""
Frames and rigid motions (Jia, Rotation in the Space, §4 and §5), one item or a batch.

**Frames** (Jia §4). A frame u-v-w turned from the reference frame x-y-z is the
rotation whose columns are its axes written in x-y-z::

    R = (û v̂ ŵ)

A point rigidly attached to the frame, with coordinates p in u-v-w, has coordinates R·p in
x-y-z; conversely a point q of x-y-z has coordinates q' = Rᵀ·q in u-v-w.

**Rigid motions** (Jia §5). T(p) = R·p + b, a rotation followed by a translation::

    T1∘T2 (T2 first)              = (R1·R2, R1·b2 + b1)
    a translation b, then R       = R then the translation R·b      (R(p + b) = R·p + R·b)
    T⁻¹                           = (Rᵀ, −Rᵀ·b)
    rotation about a line through q = (R, (I − R)·q)             (transform_from_screw)

so with b ≠ 0 a point p of x-y-z has coordinates Rᵀ·(p − b) in the moved frame:
transform_points(*invert_transform(R, b), p). In homogeneous coordinates T is the 4×4
matrix [[R, b], [0, 0, 0, 1]], and composition is the matrix product.

Functions that take R validate it (tol 1e-9) unless called with check=False, which trusts R
to be a rotation (a matrix that is not one gives a meaningless result, NaN or inf included:
see rot_tools.core.so3). Results that leave float64's range (translations near 1.8e308) raise
RotationError instead of returning inf.
"""

import numpy as np
from rot_tools.core._arrays import apart, as_float_array, refuse_overflow, require_tolerance
from rot_tools.core.engine import (apply, cross, dot, FLAG, linear_in_range, MATRIX, SCALAR,
                                   unit, VECTOR)
from rot_tools.core.errors import RotationError
from rot_tools.core.so3 import (
    apply_to_named_rotations, apply_to_rotations, defects_kernel, refuse_defects, ROTATION_TOL)

HOMOGENEOUS_ROW_TOL = 1e-9
"""Largest deviation of a homogeneous matrix's last row from (0, 0, 0, 1) that is accepted."""

_HOMOGENEOUS = ((4, 4), np.float64)


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


def _frame_kernel(ops, u, v, w):
    (uh, nu), (vh, nv), (wh, nw) = unit(ops, u), unit(ops, v), unit(ops, w)
    matrix = [[uh[i], vh[i], wh[i]] for i in range(3)]
    return (matrix, nu, nv, nw, dot(uh, vh), dot(uh, wh), dot(vh, wh),
            dot(cross(uh, vh), wh))


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
    matrix, *norms, uv, uw, vw, handed = apply(_frame_kernel, axes, [MATRIX] + [SCALAR] * 7)
    for name, n in zip('uvw', norms):
        zero = n == 0
        if zero.any():
            raise RotationError(f'frame axis {name} is zero (|{name}| = 0): an axis needs a '
                                f'direction{_item(zero)}')
    for pair, cos in (('u and v', uv), ('u and w', uw), ('v and w', vw)):
        size = np.abs(cos)
        if not (size <= tol).all():
            worst, where = _worst(size)
            shown, bound = apart(size[worst], tol)
            off = apart(90.0, np.degrees(np.arcsin(min(size[worst], 1.0))), (3, 3))[1]
            sign = '−' if cos[worst] > 0 else '+'
            raise RotationError(
                f'frame axes {pair} are not orthogonal: |cos| = {shown} > tol {bound}'
                f' (the angle between them is 90° {sign} {off}°){where}')
    left = handed < 0
    if left.any():
        raise RotationError('the frame (u, v, w) is left-handed: (û × v̂)·ŵ = '
                            f'{float(handed[left].flat[0]):.6g}, expected +1 (a reflection; '
                            f'reverse one axis){_item(left)}')
    return matrix


def _points_kernel(ops, m, b, p):
    return linear_in_range(ops, lambda p, b: [x + y for x, y in zip(_rotate(m, p), b)], p, b)


def transform_points(R, b, p, *, check=True):
    """
    Return the image R·p + b of points p under the rigid motion (R, b) (Jia §5).

    R (..., 3, 3), b (..., 3), p (..., 3), broadcasting: one motion over many points, many
    motions over one point, or one each. Returns (..., 3).
    """
    q, fits = apply_to_rotations(_points_kernel, R, check, [VECTOR, FLAG], [
        (b, (3,), 'translation b', True), (p, (3,), 'point p', True)])
    refuse_overflow(fits, 'R·p + b')
    return q


def _compose_kernel(ops, m1, m2, b1, b2):
    columns = [_rotate(m1, [m2[0][j], m2[1][j], m2[2][j]]) for j in range(3)]
    b, fits = linear_in_range(ops, lambda b1, b2: [x + y for x, y in zip(_rotate(m1, b2), b1)],
                              b1, b2)
    return [[col[i] for col in columns] for i in range(3)], b, fits


def compose_transforms(R1, b1, R2, b2, *, check=True):
    """
    T1∘T2, T2 applied first: (R1·R2, R1·b2 + b1) (Jia §5).

    R1, R2 (..., 3, 3), b1, b2 (..., 3), broadcasting → (R (..., 3, 3), b (..., 3)). Equal
    to the product of the homogeneous matrices T1·T2.
    """
    R, b, fits = apply_to_named_rotations(
        _compose_kernel, [(R1, 'R1'), (R2, 'R2')], check, [MATRIX, VECTOR, FLAG],
        [(b1, (3,), 'translation b1', True), (b2, (3,), 'translation b2', True)])
    refuse_overflow(fits, 'R1·b2 + b1')
    return R, b


def _invert_kernel(ops, m, b):
    mt = [[m[j][i] for j in range(3)] for i in range(3)]
    back, fits = linear_in_range(ops, lambda b: [0.0 - x for x in _rotate(mt, b)], b)
    return mt, back, fits  # (0 − x: no −0.0 for b = 0)


def invert_transform(R, b, *, check=True):
    """
    T⁻¹ = (Rᵀ, −Rᵀ·b) of p ↦ R·p + b; (..., 3, 3), (..., 3) → (Rᵀ, −Rᵀ·b).

    transform_points(*invert_transform(R, b), p) = Rᵀ·(p − b) are the coordinates of p in
    the moved frame (Jia §4: q' = Rᵀ·q when b = 0).
    """
    Rt, back, fits = apply_to_rotations(_invert_kernel, R, check, [MATRIX, VECTOR, FLAG],
                                        [(b, (3,), 'translation b', True)])
    refuse_overflow(fits, '−Rᵀ·b')
    return Rt, back


def _homogeneous_kernel(ops, m, b):
    return ([[*m[0], b[0]], [*m[1], b[1]], [*m[2], b[2]], [0.0, 0.0, 0.0, 1.0]],)


def transform_to_homogeneous(R, b, *, check=True):
    """Return the 4×4 matrix [[R, b], [0, 0, 0, 1]] of p ↦ R·p + b; broadcasting → (..., 4, 4)."""
    (T,) = apply_to_rotations(_homogeneous_kernel, R, check, [_HOMOGENEOUS],
                              [(b, (3,), 'translation b', True)])
    return T


def _transform_of_homogeneous_kernel(ops, t):
    m = [t[0][:3], t[1][:3], t[2][:3]]
    off = ops.max_of(ops.abs(t[3][0]), ops.abs(t[3][1]), ops.abs(t[3][2]),
                     ops.abs(t[3][3] - 1.0))
    return (m, [t[0][3], t[1][3], t[2][3]], off, *defects_kernel(ops, m))


def homogeneous_to_transform(T, *, check=True):
    """
    (R, b) of a homogeneous matrix T = [[R, b], [0, 0, 0, 1]]; (..., 4, 4) → (R, b).

    RotationError when the last row differs from (0, 0, 0, 1) by more than
    HOMOGENEOUS_ROW_TOL = 1e-9 (always), and when R is not a rotation (unless check=False).
    """
    R, b, off, err, det = apply(_transform_of_homogeneous_kernel, [(T, (4, 4), 'T', True)],
                                [MATRIX, VECTOR, SCALAR, SCALAR, SCALAR])
    if not (off <= HOMOGENEOUS_ROW_TOL).all():
        worst, where = _worst(off)
        row = as_float_array(T, (4, 4), 'T')[worst][3].tolist()
        raise RotationError(
            f'T is not a rigid motion: its last row is {row}, not [0, 0, 0, 1] '
            '(off by {} > {}){}'.format(*apart(off[worst], HOMOGENEOUS_ROW_TOL), where))
    if check:
        refuse_defects(err, det, ROTATION_TOL, 'R (T[:3, :3])')
    return R, b
