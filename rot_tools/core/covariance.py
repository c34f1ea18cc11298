"""
Covariance of a rotation's small error in every representation, to first order.

The error δ is a rotation vector in the parent frame (R_true = exp([δ]×)·R, as
PoseWithCovariance has it) or the body frame (R_true = R·exp([δ]×)); Euler angles take it
through their rate matrix E, Σ_δ = E·Σ_θ·Eᵀ, which is singular at gimbal lock (Jia,
Rotation in the Space, §1 and §3).
"""

__all__ = ['change_covariance_frame', 'euler_covariance_to_rotvec', 'rotvec_covariance_to_euler',
           'transform_pose_covariance']

from typing import NamedTuple

import numpy as np
from rot_tools.core._arrays import apart, as_float_array, finite_array, refuse_overflow
from rot_tools.core.errors import RotationError
from rot_tools.core.euler import GIMBAL_LOCK_TOL, matrix_to_euler, parse_sequence, RPY_SEQUENCE
from rot_tools.core.so3 import rot_x, rot_y, rot_z, skew, validate_rotation

COVARIANCE_TOL = 1e-9
"""A covariance C must be symmetric within COVARIANCE_TOL·max|C|, with no eigenvalue below
−COVARIANCE_TOL·max|C|."""

FRAMES = ('parent', 'body')
CONVENTIONS = ('ros', 'se3')
_ELEMENTARY = (rot_x, rot_y, rot_z)


def _choice(value, allowed, name):
    if not isinstance(value, str) or value not in allowed:
        raise RotationError(
            f'{name} must be {" or ".join(map(repr, allowed))}, got {value!r}')
    return value


def _item(index):
    """Name a batch item in a message ('' for one item)."""
    return f' (item {index})' if index else ''


class CovarianceDefects(NamedTuple):
    """How far a matrix is from a covariance, per item: C is one where both are ≤ bound."""

    asymmetry: np.ndarray
    negativity: np.ndarray
    bound: np.ndarray


def covariance_defects(C):
    """
    Return the CovarianceDefects per item of C (..., n, n), finite float64.

    asymmetry = max|C − Cᵀ|, negativity = −(lowest eigenvalue of (C + Cᵀ)/2), bound =
    COVARIANCE_TOL·max|C|: C is a covariance where both are ≤ bound. Both are computed on
    C / max|C| and scaled back, so that entries near float64's largest neither overflow in
    C + Cᵀ nor stop the eigenvalue solver from converging.
    """
    scale = np.abs(C).max(axis=(-2, -1), initial=0.0)
    unit = C / np.where(scale > 0, scale, 1.0)[..., None, None]
    asymmetry = np.abs(unit - np.swapaxes(unit, -1, -2)).max(axis=(-2, -1), initial=0.0)
    S = 0.5 * (unit + np.swapaxes(unit, -1, -2))
    lowest = np.linalg.eigvalsh(S)[..., 0] if S.size else np.zeros(S.shape[:-2])
    with np.errstate(over='ignore'):  # |C − Cᵀ| up to 2·max|C|: inf where that overflows
        return CovarianceDefects(asymmetry=asymmetry * scale, negativity=-lowest * scale,
                                 bound=COVARIANCE_TOL * scale)


def validate_covariance(cov, size=3, name='cov'):
    """
    Return the symmetric part of cov (..., size, size) as float64, or raise RotationError.

    C must be finite, symmetric within COVARIANCE_TOL·max|C| and have no eigenvalue below
    −COVARIANCE_TOL·max|C| (a matrix PSD only after rounding passes); the message says by
    how much, and for a batch names its worst item.
    """
    C = finite_array(cov, (size, size), name)
    defects = covariance_defects(C)
    asymmetry, negativity, bound = defects.asymmetry, defects.negativity, defects.bound
    at = _worst(asymmetry, bound)
    if at is not None:
        shown, tol = apart(asymmetry[at], bound[at])
        raise RotationError(f'{name} is not symmetric: max|C − Cᵀ| = {shown} > '
                            f'{COVARIANCE_TOL:g}·max|C| = {tol}{_item(at)}')
    at = _worst(negativity, bound)
    if at is not None:
        shown, tol = apart(negativity[at], bound[at])
        raise RotationError(f'{name} is not positive semi-definite: its lowest eigenvalue is '
                            f'-{shown}, below -{COVARIANCE_TOL:g}·max|C| = -{tol}{_item(at)}')
    Ct = np.swapaxes(C, -1, -2)
    return np.where(C == Ct, C, 0.5 * C + 0.5 * Ct)  # (0.5·5e-324 is 0: a subnormal C kept)


def _worst(excess, bound):
    """Index of the item most beyond its bound (by excess/bound), or None if none is."""
    bad = excess > bound
    if not bad.any():
        return None
    with np.errstate(divide='ignore'):  # bound underflows to 0 for subnormal C: ratio inf
        ratio = np.divide(excess, bound, out=np.full(bad.shape, -np.inf), where=bad)
    return tuple(int(i) for i in np.unravel_index(np.argmax(ratio), ratio.shape))


def _batch(*shapes):
    """Return the broadcast of the batch shapes, or raise a RotationError naming them."""
    try:
        return np.broadcast_shapes(*shapes)
    except ValueError:
        raise RotationError(
            f'batch shapes {" and ".join(map(str, shapes))} do not broadcast') from None


class _Rates(NamedTuple):
    """The Euler-rate matrix E (..., 3, 3), and the distance to gimbal lock (...) in rad."""

    E: np.ndarray
    distance: np.ndarray


def _rate_matrix(angles, spec, frame):
    """
    Return the _Rates of Euler angles θ.

    E's columns are the angular velocity per unit rate of θ1, θ2, θ3. With the sequence
    written R = Rot_a(φ1)·Rot_b(φ2)·Rot_c(φ3) (extrinsic: θ = (φ3, φ2, φ1)) they are, for
    φ1, φ2, φ3: in the parent frame e_a, Rot_a(φ1)·e_b, Rot_a(φ1)·Rot_b(φ2)·e_c; in the body
    frame Rᵀ times those. det E = ±cos φ2 (Tait–Bryan) or ±sin φ2 (proper). The distance is
    that of φ2 to the nearest ±π/2 (Tait–Bryan) or 0, π (proper).
    """
    i, j, k, proper = spec.i, spec.j, spec.k, spec.proper
    phi = angles[..., ::-1] if spec.extrinsic else angles
    last = i if proper else k
    turn1 = _ELEMENTARY[i](phi[..., 0])
    turn12 = turn1 @ _ELEMENTARY[j](phi[..., 1])
    first = np.broadcast_to(np.eye(3)[i], turn1.shape[:-1])
    E = np.stack([first, turn1[..., :, j], turn12[..., :, last]], axis=-1)
    if frame == 'body':
        R = turn12 @ _ELEMENTARY[last](phi[..., 2])
        E = np.swapaxes(R, -1, -2) @ E
    if spec.extrinsic:
        E = E[..., ::-1]
    return _Rates(E=E, distance=_lock_distance(phi[..., 1], proper))


def _lock_distance(phi2, proper):
    """Distance of the middle angle φ2 to ±π/2 (Tait–Bryan) or to 0, π (proper), rad."""
    c2, s2 = np.abs(np.cos(phi2)), np.abs(np.sin(phi2))
    return np.arctan2(s2, c2) if proper else np.arctan2(c2, s2)


def gimbal_lock_distance(angles, seq=RPY_SEQUENCE):
    """
    Distance (rad, in [0, π/2]) of Euler angles (..., 3) of ``seq`` from gimbal lock.

    That of the middle angle θ2 to ±π/2 (Tait–Bryan: pitch for roll, pitch, yaw) or to 0, π
    (proper Euler). Near it the covariance of the angles grows as 1/distance² (det E → 0),
    and a first-order covariance stops meaning much once the middle
    angle's own standard deviation is not small against the distance.
    """
    spec = parse_sequence(seq)
    angles = finite_array(angles, (3,), 'Euler angles')
    return _lock_distance(angles[..., 1], spec.proper)


def _inverse(E, lock):
    """E⁻¹ by its adjugate: rows c2 × c3, c3 × c1, c1 × c2 over det E = c1·(c2 × c3)."""
    c1, c2, c3 = E[..., :, 0], E[..., :, 1], E[..., :, 2]
    rows = np.stack([np.cross(c2, c3), np.cross(c3, c1), np.cross(c1, c2)], axis=-2)
    det = np.sum(c1 * rows[..., 0, :], axis=-1)
    return rows / np.where(lock, 1.0, det)[..., None, None]


def _sandwich(M, C, what, skip=False):
    """
    M·C·Mᵀ, made exactly symmetric, as s·(M·(C/s)·Mᵀ) with s = max|C| per item.

    The product is linear in C: computed at the scale of 1, neither entries near float64's
    largest overflow on the way (C·Mᵀ, then a sum of three, then out + outᵀ), nor subnormal
    ones vanish (0.5·5e-324 is 0, and ROS reads an all-zero covariance as unknown). A result
    beyond float64 is a RotationError naming ``what`` (items where ``skip`` is true, as gimbal
    lock's, are not checked).
    """
    scale = np.abs(C).max(axis=(-2, -1), initial=0.0)[..., None, None]
    scale = np.where(scale > 0, scale, 1.0)
    out = M @ (C / scale) @ np.swapaxes(M, -1, -2)
    with np.errstate(over='ignore'):  # refused below
        out = scale * (0.5 * (out + np.swapaxes(out, -1, -2)))
    refuse_overflow(np.isfinite(out).all(axis=(-2, -1)) | skip, what)
    return out


def _rotation_covariance(cov):
    """Validate cov as a 3×3 rotation covariance or a 6×6 pose covariance (x, y, z, rx, ry, rz)."""
    cov = as_float_array(cov, (), 'cov')
    return validate_covariance(cov, 6 if cov.shape[-2:] == (6, 6) else 3)


class ConvertedCovariance(NamedTuple):
    """A covariance converted between representations, NaN where degenerate (gimbal lock)."""

    cov: np.ndarray
    degenerate: np.ndarray


def _through(M, C, distance, seq, direction):
    """
    Return the ConvertedCovariance M·C·Mᵀ, NaN where the angles are at gimbal lock.

    One item at lock is refused, naming the sequence and the distance to the lock.
    """
    shape = _batch(M.shape[:-2], C.shape[:-2])
    lock = np.broadcast_to(distance <= GIMBAL_LOCK_TOL, shape)
    if lock.ndim == 0 and lock:
        where = '0 or π' if parse_sequence(seq).proper else '±π/2'
        raise RotationError(
            f'{direction}: the {seq!r} angles are {float(distance):.3g} rad from gimbal lock '
            f'(θ2 = {where}), within GIMBAL_LOCK_TOL = {GIMBAL_LOCK_TOL:g}: the covariance of '
            'the Euler angles does not exist there (E(θ) is singular)')
    if C.shape[-1] == 6:  # a pose covariance (x, y, z, rx, ry, rz): diag(I, M)
        J = np.zeros(M.shape[:-2] + (6, 6))
        J[..., :3, :3] = np.eye(3)
        J[..., 3:, 3:] = M
        M = J
    out = _sandwich(M, C, f'{direction}: the converted covariance', lock)
    return ConvertedCovariance(cov=np.where(lock[..., None, None], np.nan, out),
                               degenerate=lock.copy() if lock.ndim else np.bool_(lock))


def rotvec_covariance_to_euler(R, cov, seq=RPY_SEQUENCE, frame='parent'):
    """
    Covariance of R's Euler angles from that of its error δ: ConvertedCovariance(Σ_θ, degenerate).

    Σ_θ = E⁻¹·Σ_δ·E⁻ᵀ with E(θ) the Euler-rate matrix of ``seq`` in ``frame``: 'parent'
    (R_true = exp([δ]×)·R, ROS's rotations about the parent's fixed X, Y, Z) or 'body'
    (R_true = R·exp([δ]×)). R (..., 3, 3); cov (..., 3, 3) in rad², or a 6×6 pose
    covariance (x, y, z, rx, ry, rz) whose rotation block is converted and whose cross terms
    go through the same E⁻¹. Within GIMBAL_LOCK_TOL of gimbal lock one item is refused; in a
    batch those items are NaN with degenerate True.
    """
    spec, frame = parse_sequence(seq), _choice(frame, FRAMES, 'frame')
    R = validate_rotation(R)
    C = _rotation_covariance(cov)
    rates = _rate_matrix(matrix_to_euler(R, seq, check=False).angles, spec, frame)
    M = _inverse(rates.E, rates.distance <= GIMBAL_LOCK_TOL)
    return _through(M, C, rates.distance, seq, 'rotvec_covariance_to_euler')


def euler_covariance_to_rotvec(angles, cov, seq=RPY_SEQUENCE, frame='parent'):
    """
    Covariance of the error δ of a rotation from that of its Euler angles (Σ_δ, degenerate).

    Σ_δ = E·Σ_θ·Eᵀ, the inverse of rotvec_covariance_to_euler (same ``seq``, ``frame``, 6×6
    and gimbal-lock rules): angles (..., 3) in rad, cov (..., 3, 3) in rad² or (..., 6, 6).
    """
    spec, frame = parse_sequence(seq), _choice(frame, FRAMES, 'frame')
    angles = finite_array(angles, (3,), 'Euler angles')
    C = _rotation_covariance(cov)
    rates = _rate_matrix(angles, spec, frame)
    return _through(rates.E, C, rates.distance, seq, 'euler_covariance_to_rotvec')


def transform_pose_covariance(R, b, cov6, convention='ros'):
    """
    6×6 covariance of a pose carried by the rigid motion (R, b) into another frame.

    The 6-vector is (x, y, z, rx, ry, rz): position first, as in PoseWithCovariance.
    'ros' (tf2's doTransform): position error and rotation vector both in the parent frame,
    diag(R, R)·C·diag(R, R)ᵀ (b plays no part). 'se3': C is the covariance of exponential
    coordinates ξ = (v, ω) on the left, T_true = exp(ξ^)·T, as pytransform3d's uncertainty
    module reads it (which orders ω first); Ad·C·Adᵀ with Ad = [[R, [b]×·R], [0, R]].
    """
    convention = _choice(convention, CONVENTIONS, 'convention')
    R = validate_rotation(R)
    b = finite_array(b, (3,), 'b')
    C = validate_covariance(cov6, 6, 'cov6')
    shape = _batch(R.shape[:-2], b.shape[:-1], C.shape[:-2])
    Ad = np.zeros(shape + (6, 6))
    Ad[..., :3, :3] = R
    Ad[..., 3:, 3:] = R
    if convention == 'se3':
        Ad[..., :3, 3:] = skew(b) @ R
    return _sandwich(Ad, C, 'transform_pose_covariance: the transformed covariance')


def change_covariance_frame(cov, R):
    """R·C·Rᵀ: a 3×3 covariance (..., 3, 3) of a vector in one frame, in the frame turned by R."""
    C = validate_covariance(cov)
    R = validate_rotation(R)
    _batch(C.shape[:-2], R.shape[:-2])
    return _sandwich(R, C, 'change_covariance_frame: the turned covariance')
