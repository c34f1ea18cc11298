"""
Euler angles in all twelve axis sequences, intrinsic and extrinsic, with gimbal lock.

A sequence is three axis letters, e.g. ``'ZYX'``, with no letter repeated twice in a row:
six Tait–Bryan sequences (three different axes: XYZ XZY YXZ YZX ZXY ZYX) and six proper Euler
sequences (first axis = third: XYX XZX YXY YZY ZXZ ZYZ) — Jia, Rotation in the Space, §1,
counts them as 3·2·2.

Upper case is **intrinsic**: the rotations are about the body's moving axes, applied in the
order written, so (Jia, eq. 1 for Z-Y-X, yaw ϕ, pitch θ, roll ψ)::

    'ZYX':  R = Rot_z(θ1) · Rot_y(θ2) · Rot_x(θ3)

Lower case is **extrinsic**: the rotations are about the fixed world axes, the first written
applied first, so the matrix product is reversed::

    'zyx':  R = Rot_x(θ3) · Rot_y(θ2) · Rot_z(θ1)

This is scipy's naming. An extrinsic sequence equals the reversed intrinsic one with the angles
reversed ('zyx' (a, b, c) is 'XYZ' (c, b, a)). R maps body coordinates to world coordinates.

Ranges returned by matrix_to_euler: θ1, θ3 ∈ (−π, π]; θ2 ∈ [−π/2, π/2] for Tait–Bryan and
[0, π] for proper Euler sequences. Gimbal lock: when θ2 is within ``lock_tol`` of ±π/2
(Tait–Bryan) or of 0 or π (proper), the first and third axes line up and only θ1 ± θ3 is
defined; the result is flagged ``degenerate``, θ3 is set to 0 and θ1 carries the whole free
angle (for lower-case sequences too).
"""

import math
from math import atan2, pi, sqrt

import numpy as np
from numpy import empty, False_, True_
from rot_tools.core._arrays import require_tolerance
from rot_tools.core.engine import apply, FLAG, MATRIX, plain_item, VECTOR
from rot_tools.core.errors import RotationError
from rot_tools.core.so3 import apply_to_rotations, plain_rotation

_AXES = 'XYZ'
EULER_SEQUENCES = tuple(
    a + b + c for a in _AXES for b in _AXES for c in _AXES if a != b and b != c)
EULER_SEQUENCES = EULER_SEQUENCES + tuple(s.lower() for s in EULER_SEQUENCES)
"""The 24 accepted names: 12 intrinsic (upper case) and 12 extrinsic (lower case)."""

GIMBAL_LOCK_TOL = 1e-6
"""Default distance (rad) of θ2 from its singular value below which a result is degenerate."""

RPY_SEQUENCE = 'xyz'
"""Roll, pitch, yaw (REP 103): rotations about the fixed x, y, z axes, in that order."""


def _parse(seq):
    axes = ['XYZ'.index(a) for a in seq.upper()]
    extrinsic = seq.islower()
    if extrinsic:
        axes.reverse()
    i, j, last = axes
    sigma = 1.0 if j == (i + 1) % 3 else -1.0
    return i, j, 3 - i - j, sigma, last == i, extrinsic


_PARSED = {seq: _parse(seq) for seq in EULER_SEQUENCES}


def parse_sequence(seq):
    """
    Return (i, j, k, sigma, proper, extrinsic) for an Euler sequence name.

    (i, j, k) are the axis indices of the equivalent *intrinsic* sequence Rot_i Rot_j Rot_?,
    with k the axis that is neither i nor j; sigma = +1 when (i, j, k) is a cyclic
    permutation of (0, 1, 2), else −1; proper is true for i-j-i sequences.
    """
    try:
        return _PARSED[seq]
    except (KeyError, TypeError):
        raise RotationError(
            f'unknown Euler sequence {seq!r}: use one of {", ".join(EULER_SEQUENCES[:12])} '
            '(intrinsic) or the same in lower case (extrinsic)') from None


def _matrix_kernel(ops, a, spec):
    """Entries of Rot_i(θ1)·Rot_j(θ2)·Rot_m(θ3), m = i (proper) or k (Tait–Bryan)."""
    t1, t2, t3 = (a[2], a[1], a[0]) if spec[5] else a  # (extrinsic: the reversed sequence)
    return _matrix_of_trig(
        ops.cos(t1), ops.sin(t1), ops.cos(t2), ops.sin(t2), ops.cos(t3), ops.sin(t3), spec),


def _matrix_of_trig(c1, s1, c2, s2, c3, s3, spec):
    """
    Entries of Rot_i(θ1)·Rot_j(θ2)·Rot_m(θ3) from the cosines and sines of the angles.

    Derived by applying the three elementary rotations to the unit vectors; Jia, eq. 1
    is the case (i, j, k) = (z, y, x), sigma = −1.
    """
    i, j, k, sig, proper, _ = spec
    m = [[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]  # every entry is set below
    ri, rj, rk = m[i], m[j], m[k]
    if proper:
        ri[i], ri[j], ri[k] = c2, s2 * s3, sig * s2 * c3
        rj[i], rj[j], rj[k] = (
            s1 * s2, c1 * c3 - s1 * c2 * s3, -sig * (c1 * s3 + s1 * c2 * c3))
        rk[i], rk[j], rk[k] = (
            -sig * c1 * s2, sig * (c1 * c2 * s3 + s1 * c3), c1 * c2 * c3 - s1 * s3)
    else:
        ri[i], ri[j], ri[k] = c2 * c3, -sig * c2 * s3, sig * s2
        rj[i], rj[j], rj[k] = (
            sig * c1 * s3 + s1 * s2 * c3, c1 * c3 - sig * s1 * s2 * s3, -sig * s1 * c2)
        rk[i], rk[j], rk[k] = (
            s1 * s3 - sig * c1 * s2 * c3, c1 * s2 * s3 + sig * s1 * c3, c1 * c2)
    return m


def euler_to_matrix(angles, seq='ZYX'):
    """
    Rotation matrix of Euler angles (θ1, θ2, θ3) in radians; (..., 3) → (..., 3, 3).

    Intrinsic 'ABC': R = Rot_a(θ1)·Rot_b(θ2)·Rot_c(θ3); extrinsic 'abc': R = Rot_c(θ3)·Rot_b(θ2)·
    Rot_a(θ1). Any of the 24 names of EULER_SEQUENCES; another string raises RotationError.
    """
    spec = parse_sequence(seq)
    a = plain_item(angles, (3,))
    if a is not None:  # fast path, one plain item: _matrix_kernel with math's cos and sin
        t1, t2, t3 = (a[2], a[1], a[0]) if spec[5] else a  # (finite: they never raise)
        return np.array(_matrix_of_trig(
            math.cos(t1), math.sin(t1), math.cos(t2), math.sin(t2), math.cos(t3),
            math.sin(t3), spec))
    (matrix,) = apply(_matrix_kernel, [(angles, (3,), 'Euler angles', True)], [MATRIX], (spec,))
    return matrix


_HALF_PI, _TWO_PI, _MINUS_PI = math.pi / 2, 2 * math.pi, -math.pi


def _wrap(angle):
    """Map −π to +π (and −0 to +0) so that outer angles lie in (−π, π]: −π + 2π is exact."""
    return angle + (angle == -math.pi) * _TWO_PI


def angles_kernel(ops, m, spec, lock_tol):
    """Euler angles of m; see matrix_to_euler for the method."""
    i, j, k, sig, proper, extrinsic = spec
    mi, mj, mk = m[i], m[j], m[k]
    if proper:  # R[i,i] = cos θ2, (R[j,i], −σR[k,i]) = sin θ2·(sin θ1, cos θ1)
        y1, x1 = mj[i], -sig * mk[i]
        t2 = ops.atan2(ops.sqrt(y1 * y1 + x1 * x1), mi[i])
        lock = ops.minimum(t2, math.pi - t2) <= lock_tol
        sign3, other = -sig, k
    else:  # R[i,k] = σ sin θ2, (−σR[j,k], R[k,k]) = cos θ2·(sin θ1, cos θ1)
        y1, x1 = -sig * mj[k], mk[k]
        t2 = ops.atan2(sig * mi[k], ops.sqrt(y1 * y1 + x1 * x1))
        lock = _HALF_PI - ops.abs(t2) <= lock_tol
        sign3, other = sig, i
    t1 = ops.atan2(y1, x1)
    # Peel: row j of Rot_i(θ1)ᵀ·R = cos θ1·R[j] + σ sin θ1·R[k] is row j of Rot_m(θ3), m the
    # last axis, whose entries are cos θ3 at column j and sign3·sin θ3 at column `other`.
    # (x1, y1) is (cos θ1, sin θ1) times |sin θ2| or |cos θ2| ≥ 0: atan2 needs no division.
    s1 = sig * y1
    t3 = ops.atan2(sign3 * (x1 * mj[other] + s1 * mk[other]), x1 * mj[j] + s1 * mk[j])
    if extrinsic:
        # Solved as the reversed intrinsic sequence: its first angle is the extrinsic θ3,
        # the one to zero at lock; its last then comes from the peel with θ1 = 0.
        t1, t3 = t3, t1
    if ops.rare(lock):  # (an item, or a batch chunk, without lock skips the extra atan2)
        if extrinsic:
            free = ops.atan2(sign3 * mj[other], mj[j])
        else:
            # At lock R·e_j = Rot_i(θ1)·e_j = cos θ1·e_j + σ sin θ1·e_k carries the free angle.
            free = ops.atan2(sig * mk[j], mj[j])
        t1, t3 = ops.where(lock, free, t1), ops.where(lock, 0.0, t3)
    return [_wrap(t1), t2 + 0.0, _wrap(t3)], lock


def matrix_to_euler(R, seq='ZYX', *, check=True, lock_tol=GIMBAL_LOCK_TOL):
    """
    Euler angles of R: returns (angles (..., 3), degenerate (...) bool).

    θ2 from the entries that do not involve θ1, θ3 (Tait–Bryan: R[i,k] = σ sin θ2 with
    |(R[k,k], R[j,k])| = |cos θ2|; proper: R[i,i] = cos θ2, |(R[j,i], R[k,i])| = sin θ2),
    each as an atan2 so it is accurate at every angle. θ1 from the column that carries it.
    θ3 is then *peeled*: row j of Rot_i(θ1)ᵀ·R is row j of Rot_m(θ3), so θ3 absorbs any
    rounding of θ1 and euler_to_matrix reproduces R to rounding even a hair from gimbal lock
    (two separate atan2, as in textbooks, lose digits there). At lock (degenerate: θ2 within
    lock_tol of ±π/2 or of 0, π) θ3 = 0 and θ1 is the free angle. Lower-case sequences are
    solved as the reversed intrinsic sequence with its *first* angle zeroed, then read back.
    Ranges: θ1, θ3 ∈ (−π, π]; θ2 ∈ [−π/2, π/2] (Tait–Bryan) or [0, π] (proper).
    """
    try:
        spec = _PARSED[seq]  # (parse_sequence's table, read without a call)
    except (KeyError, TypeError):
        spec = parse_sequence(seq)  # (raises, naming the 24 sequences)
    if lock_tol is not GIMBAL_LOCK_TOL:  # (the default needs no check)
        lock_tol = require_tolerance(lock_tol, 'lock_tol', math.pi / 4, '[0, π/4) rad')
    m = plain_rotation(R, check)
    if m is None:
        return apply_to_rotations(angles_kernel, R, check, [VECTOR, FLAG],
                                  params=(spec, lock_tol))
    # Fast path, one plain rotation (finite: no float operation raises): angles_kernel written
    # with math, the same operations in the same order (so the same bits as on FLOATS), with
    # θ1 and θ3 computed only on the side of the lock that is kept, and the result filled
    # into an empty array by three stores (cheaper than np.array of a list).
    i, j, k, sig, proper, extrinsic = spec
    mi, mj, mk = m[i], m[j], m[k]
    if proper:
        y1, x1 = mj[i], -sig * mk[i]
        t2 = atan2(sqrt(y1 * y1 + x1 * x1), mi[i])
        lock = t2 <= lock_tol or pi - t2 <= lock_tol
        sign3, other = -sig, k
    else:
        y1, x1 = -sig * mj[k], mk[k]
        t2 = atan2(sig * mi[k], sqrt(y1 * y1 + x1 * x1))
        lock = _HALF_PI - abs(t2) <= lock_tol
        sign3, other = sig, i
    if lock:
        t1 = atan2(sign3 * mj[other], mj[j]) if extrinsic else atan2(sig * mk[j], mj[j])
        t3 = 0.0
    else:
        t1 = atan2(y1, x1)
        s1 = sig * y1
        t3 = atan2(sign3 * (x1 * mj[other] + s1 * mk[other]), x1 * mj[j] + s1 * mk[j])
        if extrinsic:
            t1, t3 = t3, t1
    angles = empty(3)
    angles[0] = pi if t1 == _MINUS_PI else t1 + 0.0  # (as _wrap)
    angles[1] = t2 + 0.0
    angles[2] = pi if t3 == _MINUS_PI else t3 + 0.0
    return angles, True_ if lock else False_
