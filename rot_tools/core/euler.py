"""
Euler angles in all twelve axis sequences, intrinsic and extrinsic, with gimbal lock.

A sequence is three axes, no axis twice in a row (Jia, Rotation in the Space, §1). Upper case
is intrinsic, about the body's moving axes ('ZYX': R = Rot_z(θ1)·Rot_y(θ2)·Rot_x(θ3)); lower
case extrinsic, about the fixed axes, the product reversed ('zyx': R = Rot_x(θ3)·Rot_y(θ2)·
Rot_z(θ1)), as scipy names them. R maps body coordinates to world coordinates.
"""

__all__ = ['EULER_SEQUENCES', 'euler_to_matrix', 'GIMBAL_LOCK_TOL', 'matrix_to_euler']

import math
from typing import Any, NamedTuple

import numpy as np
from rot_tools.core._arrays import require_tolerance
from rot_tools.core.engine import apply, FLAG, MATRIX, VECTOR
from rot_tools.core.errors import RotationError
from rot_tools.core.so3 import apply_to_rotations

_AXES = 'XYZ'
EULER_SEQUENCES = tuple(
    a + b + c for a in _AXES for b in _AXES for c in _AXES if a != b and b != c)
EULER_SEQUENCES = EULER_SEQUENCES + tuple(s.lower() for s in EULER_SEQUENCES)
"""The 24 accepted names: 12 intrinsic (upper case) and 12 extrinsic (lower case)."""

GIMBAL_LOCK_TOL = 1e-6
"""Default distance (rad) of θ2 from its singular value below which a result is degenerate."""

RPY_SEQUENCE = 'xyz'
"""Roll, pitch, yaw (REP 103): rotations about the fixed x, y, z axes, in that order."""


class EulerAngles(NamedTuple):
    """
    What matrix_to_euler gives: angles (θ1, θ2, θ3) in radians, and degenerate.

    degenerate: true at gimbal lock (θ3 is then 0 and θ1 carries the free angle).
    """

    angles: np.ndarray
    degenerate: Any


_EULER_ANGLES = EulerAngles(angles=VECTOR, degenerate=FLAG)


class SequenceAxes(NamedTuple):
    """
    An Euler sequence as the kernels take it (parse_sequence).

    (i, j, k) are the axis indices of the equivalent *intrinsic* sequence Rot_i Rot_j Rot_?,
    with k the axis that is neither i nor j; sigma = +1 when (i, j, k) is a cyclic
    permutation of (0, 1, 2), else −1; proper is true for i-j-i sequences; extrinsic for a
    lower-case name (solved as the reversed intrinsic sequence).
    """

    i: int
    j: int
    k: int
    sigma: float
    proper: bool
    extrinsic: bool


def _parse(seq):
    axes = ['XYZ'.index(a) for a in seq.upper()]
    extrinsic = seq.islower()
    if extrinsic:
        axes.reverse()
    i, j, last = axes
    return SequenceAxes(i=i, j=j, k=3 - i - j, sigma=1.0 if j == (i + 1) % 3 else -1.0,
                        proper=last == i, extrinsic=extrinsic)


_PARSED = {seq: _parse(seq) for seq in EULER_SEQUENCES}


def parse_sequence(seq):
    """Return the SequenceAxes of an Euler sequence name; RotationError for another name."""
    try:
        return _PARSED[seq]
    except (KeyError, TypeError):
        raise RotationError(
            f'unknown Euler sequence {seq!r}: use one of {", ".join(EULER_SEQUENCES[:12])} '
            '(intrinsic) or the same in lower case (extrinsic)') from None


def _matrix_kernel(ops, a, spec):
    """Entries of Rot_i(θ1)·Rot_j(θ2)·Rot_m(θ3), m = i (proper) or k (Tait–Bryan)."""
    t1, t2, t3 = (a[2], a[1], a[0]) if spec.extrinsic else a  # (the reversed sequence)
    return _matrix_of_trig(
        ops.cos(t1), ops.sin(t1), ops.cos(t2), ops.sin(t2), ops.cos(t3), ops.sin(t3), spec)


def _matrix_of_trig(c1, s1, c2, s2, c3, s3, spec):
    """
    Entries of Rot_i(θ1)·Rot_j(θ2)·Rot_m(θ3) from the cosines and sines of the angles.

    Derived by applying the three elementary rotations to the unit vectors; Jia, eq. 1
    is the case (i, j, k) = (z, y, x), sigma = −1.
    """
    i, j, k, sig, proper = spec.i, spec.j, spec.k, spec.sigma, spec.proper
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
    return apply(_matrix_kernel, [(angles, (3,), 'Euler angles', True)], MATRIX,
                 (parse_sequence(seq),))


_HALF_PI, _TWO_PI = math.pi / 2, 2 * math.pi


def _wrap(angle):
    """Map −π to +π (and −0 to +0) so that outer angles lie in (−π, π]: −π + 2π is exact."""
    return angle + (angle == -math.pi) * _TWO_PI


def angles_kernel(ops, m, spec, lock_tol):
    """Return the EulerAngles of m; see matrix_to_euler for the method."""
    i, j, k, sig = spec.i, spec.j, spec.k, spec.sigma
    mi, mj, mk = m[i], m[j], m[k]
    if spec.proper:  # R[i,i] = cos θ2, (R[j,i], −σR[k,i]) = sin θ2·(sin θ1, cos θ1)
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
    if spec.extrinsic:
        # Solved as the reversed intrinsic sequence: its first angle is the extrinsic θ3,
        # the one to zero at lock; its last then comes from the peel with θ1 = 0.
        t1, t3 = t3, t1
    if ops.rare(lock):  # (an item, or a batch chunk, without lock skips the extra atan2)
        if spec.extrinsic:
            free = ops.atan2(sign3 * mj[other], mj[j])
        else:
            # At lock R·e_j = Rot_i(θ1)·e_j = cos θ1·e_j + σ sin θ1·e_k carries the free angle.
            free = ops.atan2(sig * mk[j], mj[j])
        t1, t3 = ops.where(lock, free, t1), ops.where(lock, 0.0, t3)
    return EulerAngles(angles=[_wrap(t1), t2 + 0.0, _wrap(t3)], degenerate=lock)


def matrix_to_euler(R, seq='ZYX', *, check=True, lock_tol=GIMBAL_LOCK_TOL):
    """
    Euler angles of R: returns EulerAngles(angles (..., 3), degenerate (...) bool).

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
    spec = parse_sequence(seq)
    lock_tol = require_tolerance(lock_tol, 'lock_tol', math.pi / 4, '[0, π/4) rad')
    return apply_to_rotations(angles_kernel, R, check, _EULER_ANGLES, params=(spec, lock_tol))
