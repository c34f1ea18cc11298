"""
Rotation matrices: elementary rotations, the skew matrix, validity checks, quaternions.

Column vectors, active rotations, p' = R·p; a rotation is 3×3 orthogonal with det R = +1
(Jia, Rotation in the Space, Theorem 1); any leading batch shape. Quaternions are only for
the boundary, in the ROS order (x, y, z, w). check=False trusts R to be a rotation: the
formula is applied to the matrix as given, whatever it means.
"""

__all__ = ['is_rotation', 'matrix_to_quaternion', 'nearest_rotation', 'quaternion_to_matrix',
           'rot_x', 'rot_y', 'rot_z', 'ROTATION_TOL', 'skew', 'validate_rotation']

import math
from typing import Any, NamedTuple

import numpy as np
from numpy import False_
from rot_tools.core._arrays import apart, as_float_array, finite_array, require_tolerance
from rot_tools.core.engine import apply, FLAG, MATRIX, SCALAR, Spec
from rot_tools.core.errors import RotationError

ROTATION_TOL = 1e-9
"""Default tolerance of is_rotation / validate_rotation on max|RᵀR − I| and |det R − 1|."""


def _elementary(angle, i):
    """Rotation by ``angle`` about coordinate axis i: the (j, k) plane turns (i, j, k cyclic)."""
    a = finite_array(angle, (), 'angle')
    c, s = np.cos(a), np.sin(a)
    j, k = (i + 1) % 3, (i + 2) % 3
    out = np.zeros(a.shape + (3, 3))
    out[..., i, i] = 1.0
    out[..., j, j] = c
    out[..., k, k] = c
    out[..., k, j] = s
    out[..., j, k] = -s
    return out


def rot_x(a):
    """Rot_x(a) = [[1, 0, 0], [0, cos a, −sin a], [0, sin a, cos a]]; (...) → (..., 3, 3)."""
    return _elementary(a, 0)


def rot_y(a):
    """Rot_y(a) = [[cos a, 0, sin a], [0, 1, 0], [−sin a, 0, cos a]]; (...) → (..., 3, 3)."""
    return _elementary(a, 1)


def rot_z(a):
    """Rot_z(a) = [[cos a, −sin a, 0], [sin a, cos a, 0], [0, 0, 1]]; (...) → (..., 3, 3)."""
    return _elementary(a, 2)


def skew(v):
    """Return [v]× = [[0, −v3, v2], [v3, 0, −v1], [−v2, v1, 0]], so [v]× @ w == v × w."""
    v = finite_array(v, (3,), 'v')
    x, y, z = v[..., 0], v[..., 1], v[..., 2]
    out = np.zeros(v.shape[:-1] + (3, 3))
    out[..., 0, 1], out[..., 0, 2] = -z, y
    out[..., 1, 0], out[..., 1, 2] = z, -x
    out[..., 2, 0], out[..., 2, 1] = -y, x
    return out


class Defects(NamedTuple):
    """How far a matrix is from a rotation: orthogonality = max|RᵀR − I|, and det R."""

    orthogonality: Any
    det: Any


_DEFECTS = Defects(orthogonality=SCALAR, det=SCALAR)


def defects_kernel(ops, m):
    """
    Return the Defects of the entries m.

    orthogonality from the six distinct entries of the Gram matrix RᵀR, det as the triple
    product of the rows. NaN entries propagate to NaN (never ≤ tol).
    """
    (a, b, c), (d, e, f), (g, h, i) = m
    err = ops.max_of(
        ops.abs(a * a + d * d + g * g - 1.0), ops.abs(b * b + e * e + h * h - 1.0),
        ops.abs(c * c + f * f + i * i - 1.0), ops.abs(a * b + d * e + g * h),
        ops.abs(a * c + d * f + g * i), ops.abs(b * c + e * f + h * i))
    return Defects(orthogonality=err,
                   det=a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g))


QUATERNION = Spec((4,))


def _defects(R):
    """Per item: the Defects of R."""
    return apply(defects_kernel, [(R, (3, 3), 'R', False)], _DEFECTS)


def is_rotation(R, tol=ROTATION_TOL):
    """
    Tell where max|RᵀR − I| ≤ tol and |det R − 1| ≤ tol; False for non-finite items.

    R is (..., 3, 3); the result is a bool, or a bool array of shape (...). A shape that is
    not (..., 3, 3) raises RotationError.
    """
    tol = require_tolerance(tol, 'tol')
    R = as_float_array(R, (3, 3), 'R')
    finite = np.isfinite(R).all(axis=(-2, -1))
    with np.errstate(invalid='ignore', over='ignore'):
        defects = _defects(np.where(finite[..., None, None], R, 0.0))
    ok = finite & (defects.orthogonality <= tol) & (np.abs(defects.det - 1.0) <= tol)
    return ok if ok.ndim else bool(ok)


def validate_rotation(R, tol=ROTATION_TOL):
    """
    Return R as a float64 array, or raise RotationError naming the defect.

    Checked in order: shape (..., 3, 3), finite entries, orthogonality max|RᵀR − I| ≤ tol
    (the message gives the size), det R = +1 (det −1 is a reflection).
    """
    tol = require_tolerance(tol, 'tol')
    R = finite_array(R, (3, 3), 'R')
    refuse_defects(_defects(R), tol)
    return R


def refuse_defects(defects, tol, name='R'):
    """
    Raise RotationError for the worst item whose Defects are out of tol.

    name: how the message calls the matrix: 'R', 'R2', 'R (T[:3, :3])'.
    """
    err, det = defects.orthogonality, defects.det
    if err.ndim == 0 and err <= tol and abs(det - 1.0) <= tol:
        return  # one good item: no NumPy reductions
    where = '' if err.ndim == 0 else ' (worst at item {})'
    if not (err <= tol).all():
        worst = np.unravel_index(np.argmax(err), err.shape)
        shown, bound = apart(err[worst], tol)
        raise RotationError(f'{name} is not orthogonal: max|RᵀR − I| = {shown} > tol {bound}'
                            + where.format(tuple(map(int, worst))))
    dev = np.abs(det - 1.0)
    if not (dev <= tol).all():
        worst = np.unravel_index(np.argmax(dev), dev.shape)
        kind = 'a reflection' if det[worst] < 0 else 'not a rotation'
        raise RotationError(
            f'{name} is {kind}: det R = {float(det[worst]):.6g}, expected +1'
            + where.format(tuple(map(int, worst))))


class _Checked(NamedTuple):
    """A kernel's output, and the Defects of each of its rotations."""

    value: Any
    defects: tuple


def _checked(ops, *args):
    """
    Return the _Checked output of a kernel: its own, and the Defects of its first inputs.

    args: the kernel's entries, then (kernel, count, params), as apply_to_named_rotations
    passes them: the first ``count`` entries are the rotations.
    """
    *entries, kernel, count, params = args
    return _Checked(value=kernel(ops, *entries, *params),
                    defects=tuple(defects_kernel(ops, m) for m in entries[:count]))


def apply_to_rotations(kernel, R, check, outputs, extra=(), params=()):
    """
    apply(kernel, [R, *extra], outputs, params) with R (..., 3, 3), validated in the same pass.

    With check, R must pass validate_rotation (tol ROTATION_TOL): its Defects are computed
    beside the kernel's outputs, which are dropped if R is refused.
    """
    return apply_to_named_rotations(kernel, [(R, 'R')], check, outputs, extra, params)


def apply_to_named_rotations(kernel, rotations, check, outputs, extra=(), params=()):
    """
    apply_to_rotations for several rotations: rotations = [(R1, 'R1'), (R2, 'R2'), ...].

    The kernel takes their entries first, then those of extra, then params; with check each
    rotation is validated under its name.
    """
    inputs = [(R, (3, 3), name, check) for R, name in rotations]
    if not check:
        return apply(kernel, [*inputs, *extra], outputs, params)
    checked = apply(_checked, [*inputs, *extra],
                    _Checked(value=outputs, defects=(_DEFECTS,) * len(rotations)),
                    (kernel, len(rotations), params))
    for defects, (_, name) in zip(checked.defects, rotations):
        refuse_defects(defects, ROTATION_TOL, name)
    return checked.value


def checked_rotation(R, check):
    """validate_rotation(R) when check is true, else R as a float64 (..., 3, 3) array."""
    return validate_rotation(R) if check else as_float_array(R, (3, 3), 'R')


def nearest_rotation(R):
    """
    Return the rotation closest to R in the Frobenius norm: U·diag(1, 1, det UVᵀ)·Vᵀ from R = USVᵀ.

    For matrices typed with a few significant digits; a reflection (det R < 0) is refused,
    since its nearest rotation is not what anyone meant.
    """
    R = finite_array(R, (3, 3), 'R')
    scale = np.abs(R).max(axis=(-2, -1), keepdims=True)
    R = R / np.where(scale > 0, scale, 1.0)  # the polar factor is scale-free; det can't overflow
    if (np.linalg.det(R) <= 0).any():
        raise RotationError('R has det R ≤ 0 (a reflection or singular), not near a rotation')
    u, _, vt = np.linalg.svd(R)
    return u @ vt  # det U·det Vᵀ = sign(det R) = +1


def quaternion_to_matrix(q, *, tol=None):
    """
    Rotation matrix of q = (x, y, z, w) — the ROS message order; q is normalised first.

    With s = 2/|q|²: R = I − s·[[y²+z², −(xy−zw), −(xz+yw)], ...] (the unit-quaternion
    matrix scaled so that any non-zero q gives a rotation). (..., 4) → (..., 3, 3). The only
    quaternion function in rot_tools: for message boundaries. Zero or non-finite q raises
    RotationError (naming the item of a batch). tol: None accepts any non-zero q; a number
    ≥ 0 also refuses q with ||q| − 1| > tol (a quaternion typed or sent as unit that is not),
    saying |q| and by how much (the worst item of a batch).
    """
    out = apply(_quaternion_kernel, [(q, (4,), 'quaternion (x, y, z, w)', True)],
                _QUATERNION_MATRIX)
    zero = out.zero
    if zero is not False_ and zero.any():  # (one item's flag is one of NumPy's two bools)
        where = f' (item {tuple(int(i) for i in np.argwhere(zero)[0])})' if zero.ndim else ''
        raise RotationError(f'quaternion (x, y, z, w) must be non-zero, got |q| = 0{where}')
    if tol is not None:
        _refuse_non_unit(np.asarray(q, dtype=np.float64), tol)  # a valid q: apply took it
    return out.matrix


def _refuse_non_unit(q, tol):
    """Raise RotationError for the worst q (..., 4) with ||q| − 1| > tol."""
    tol = require_tolerance(tol, 'tol')
    big = np.abs(q).max(axis=-1)  # |q| = big·|q/big|: |q|² cannot overflow
    scaled = np.linalg.norm(q / np.where(big > 0, big, 1.0)[..., None], axis=-1)
    with np.errstate(over='ignore'):
        sizes = big * scaled
    offs = np.abs(sizes - 1.0)
    if (offs <= tol).all():
        return
    worst = np.unravel_index(np.argmax(offs), offs.shape)
    where = f' (worst at item {tuple(map(int, worst))})' if offs.ndim else ''
    size, off = float(sizes[worst]), float(offs[worst])
    if math.isinf(size):  # beyond float64: |q| (and its distance from 1) from logarithms
        power = math.log10(big[worst]) + math.log10(scaled[worst])
        exponent = math.floor(power)
        size_text = f'{10 ** (power - exponent):.9g}e+{exponent}'
        off_text = f'{10 ** (power - exponent):.3g}e+{exponent}'
        tol_text = f'{tol:g}'
    else:
        size_text, (off_text, tol_text) = f'{size:.9g}', apart(off, tol)
    raise RotationError(f'quaternion (x, y, z, w) is not of unit length: |q| = {size_text}, '
                        f'off 1 by {off_text} > tol {tol_text}{where}')


class _QuaternionMatrix(NamedTuple):
    matrix: Any
    zero: Any  # q = 0, which has no rotation


_QUATERNION_MATRIX = _QuaternionMatrix(matrix=MATRIX, zero=FLAG)


def _quaternion_kernel(ops, q):
    x, y, z, w = q
    n2 = x * x + y * y + z * z + w * w
    zero = False
    if ops.rare((n2 < 1e-290) | (n2 > 1e290)):  # |q|² underflowed or overflowed, or q = 0
        big = ops.max_of(ops.abs(x), ops.abs(y), ops.abs(z), ops.abs(w))
        zero = big == 0
        safe = ops.where(zero, 1.0, big)  # q/max|q_i|: |q|² in [1, 4]
        x, y, z, w = x / safe, y / safe, z / safe, w / safe
        n2 = ops.where(zero, 1.0, x * x + y * y + z * z + w * w)
    s = 2.0 / n2
    sx, sy, sz = s * x, s * y, s * z
    xx, yy, zz, xy, xz, yz = sx * x, sy * y, sz * z, sx * y, sx * z, sy * z
    xw, yw, zw = sx * w, sy * w, sz * w
    return _QuaternionMatrix(matrix=[[1.0 - (yy + zz), xy - zw, xz + yw],
                                     [xy + zw, 1.0 - (xx + zz), yz - xw],
                                     [xz - yw, yz + xw, 1.0 - (xx + yy)]], zero=zero)


def quaternion_of_matrix_kernel(ops, m):
    """Return the unit (x, y, z, w) of m, canonical sign; see matrix_to_quaternion."""
    (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = m
    # M = 4·q·qᵀ in the order (x, y, z, w): its diagonal and off-diagonal entries.
    dx, dy = 1.0 + r00 - r11 - r22, 1.0 - r00 + r11 - r22
    dz, dw = 1.0 - r00 - r11 + r22, 1.0 + r00 + r11 + r22
    xy, xz, yz = r01 + r10, r02 + r20, r12 + r21
    xw, yw, zw = r21 - r12, r02 - r20, r10 - r01
    # Row i of M divided by 2·sqrt(M_ii) is q·sign(q_i). Take the row with the largest
    # diagonal: M_ii = 4·q_i² ≥ 1 there (the four sum to 4), so nothing small is divided by.
    use_x = (dx >= dy) & (dx >= dz) & (dx >= dw)
    use_y = (dy > dx) & (dy >= dz) & (dy >= dw)
    use_z = (dz > dx) & (dz > dy) & (dz >= dw)
    x, y, z, w = ops.where(use_x, [dx, xy, xz, xw], ops.where(
        use_y, [xy, dy, yz, yw], ops.where(use_z, [xz, yz, dz, zw], [xw, yw, zw, dw])))
    n = ops.sqrt(x * x + y * y + z * z + w * w)  # = 4·|q_i| ≥ 2 for a rotation
    # Canonical sign: w > 0; at w = 0 the first non-zero of x, y, z positive.
    lead = ops.where(w != 0, w, ops.where(x != 0, x, ops.where(y != 0, y, z)))
    s = ops.where(lead < 0, -1.0, 1.0) / n
    return [x * s + 0.0, y * s + 0.0, z * s + 0.0, w * s + 0.0]


def matrix_to_quaternion(R, *, check=True):
    """
    Return the unit quaternion (x, y, z, w) — the ROS order — of R; (..., 3, 3) → (..., 4).

    Canonical sign: w > 0, and at w = 0 (half turns) the first non-zero of x, y, z is
    positive. From M = 4·q·qᵀ, whose entries are sums and differences of entries of R
    (M_ww = 1 + tr R, M_xw = r32 − r23, M_xy = r12 + r21, ...): the row of M with the
    largest diagonal entry (≥ 1), normalised, so no small number is divided by and the
    result is accurate to rounding at every angle, 0 and π included. The boundary twin of
    quaternion_to_matrix, for messages and for people; never used inside the math.
    """
    return apply_to_rotations(quaternion_of_matrix_kernel, R, check, QUATERNION)
