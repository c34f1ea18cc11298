"""Euler angles in all twelve axis sequences, intrinsic and extrinsic, with gimbal lock.

A sequence is three axis letters, e.g. ``'ZYX'``, with no letter repeated twice in a row:
six Tait–Bryan sequences (three different axes: XYZ XZY YXZ YZX ZXY ZYX) and six proper Euler
sequences (first axis = third: XYX XZX YXY YZY ZXZ ZYZ) — seed 000 §1 counts them as 3·2·2.

Upper case is **intrinsic**: the rotations are about the body's moving axes, applied in the
order written, so (seed 000 eq. 1 for Z-Y-X, yaw ϕ, pitch θ, roll ψ)::

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

import numpy as np

from rot_tools._arrays import finite_array
from rot_tools.errors import RotationError
from rot_tools.so3 import checked_rotation

_AXES = 'XYZ'
EULER_SEQUENCES = tuple(
    a + b + c for a in _AXES for b in _AXES for c in _AXES if a != b and b != c)
EULER_SEQUENCES = EULER_SEQUENCES + tuple(s.lower() for s in EULER_SEQUENCES)
"""The 24 accepted names: 12 intrinsic (upper case) and 12 extrinsic (lower case)."""

GIMBAL_LOCK_TOL = 1e-6
"""Default distance (rad) of θ2 from its singular value below which a result is degenerate."""


def parse_sequence(seq):
    """Return (i, j, k, sigma, proper, extrinsic) for an Euler sequence name.

    (i, j, k) are the axis indices of the equivalent *intrinsic* sequence Rot_i Rot_j Rot_?,
    with k the axis that is neither i nor j; sigma = +1 when (i, j, k) is a cyclic
    permutation of (0, 1, 2), else −1; proper is true for i-j-i sequences.
    """
    if not isinstance(seq, str) or seq not in EULER_SEQUENCES:
        raise RotationError(
            f'unknown Euler sequence {seq!r}: use one of {", ".join(EULER_SEQUENCES[:12])} '
            '(intrinsic) or the same in lower case (extrinsic)')
    extrinsic = seq.islower()
    axes = [_AXES.index(a) for a in seq.upper()]
    if extrinsic:
        axes.reverse()
    i, j, last = axes
    k = 3 - i - j
    sigma = 1.0 if j == (i + 1) % 3 else -1.0
    return i, j, k, sigma, last == i, extrinsic


def _intrinsic_entries(c1, s1, c2, s2, c3, s3, i, j, k, sig, proper):
    """Entries {(row, col): value} of Rot_i(θ1)·Rot_j(θ2)·Rot_m(θ3), m = i or k.

    Derived by applying the three elementary rotations to the unit vectors (seed 000 eq. 1 is
    the case i, j, k = z, y, x, sig = −1).
    """
    if proper:
        return {
            (i, i): c2, (i, j): s2 * s3, (i, k): sig * s2 * c3,
            (j, i): s1 * s2, (j, j): c1 * c3 - s1 * c2 * s3,
            (j, k): -sig * (c1 * s3 + s1 * c2 * c3),
            (k, i): -sig * c1 * s2, (k, j): sig * (c1 * c2 * s3 + s1 * c3),
            (k, k): c1 * c2 * c3 - s1 * s3,
        }
    return {
        (i, i): c2 * c3, (i, j): -sig * c2 * s3, (i, k): sig * s2,
        (j, i): sig * c1 * s3 + s1 * s2 * c3, (j, j): c1 * c3 - sig * s1 * s2 * s3,
        (j, k): -sig * s1 * c2,
        (k, i): s1 * s3 - sig * c1 * s2 * c3, (k, j): c1 * s2 * s3 + sig * s1 * c3,
        (k, k): c1 * c2,
    }


def euler_to_matrix(angles, seq='ZYX'):
    """Rotation matrix of Euler angles (θ1, θ2, θ3) in radians; (..., 3) → (..., 3, 3).

    Intrinsic 'ABC': R = Rot_a(θ1)·Rot_b(θ2)·Rot_c(θ3); extrinsic 'abc': R = Rot_c(θ3)·Rot_b(θ2)·
    Rot_a(θ1). Any of the 24 names of EULER_SEQUENCES; another string raises RotationError.
    """
    i, j, k, sig, proper, extrinsic = parse_sequence(seq)
    a = finite_array(angles, (3,), 'Euler angles')
    if extrinsic:
        a = a[..., ::-1]
    c, s = np.cos(a), np.sin(a)
    entries = _intrinsic_entries(
        c[..., 0], s[..., 0], c[..., 1], s[..., 1], c[..., 2], s[..., 2], i, j, k, sig, proper)
    out = np.empty(a.shape[:-1] + (3, 3))
    for (row, col), value in entries.items():
        out[..., row, col] = value
    return out


def _wrap(angle):
    """Map −π to +π (and −0 to +0) so that outer angles lie in (−π, π]."""
    return np.where(angle == -np.pi, np.pi, angle) + 0.0


def matrix_to_euler(R, seq='ZYX', *, check=True, lock_tol=GIMBAL_LOCK_TOL):
    """Euler angles of R: returns (angles (..., 3), degenerate (...) bool).

    θ2 from the entries that do not involve θ1, θ3 (Tait–Bryan: R[i,k] = σ sin θ2 with
    hypot(R[k,k], R[j,k]) = |cos θ2|; proper: R[i,i] = cos θ2, hypot(R[j,i], R[k,i]) = sin θ2),
    each as an atan2 so it is accurate at every angle. θ1 from the column/row that carries it.
    θ3 is then *peeled*: row j of Rot_i(θ1)ᵀ·R is row j of Rot_m(θ3), so θ3 absorbs any error
    of θ1 and euler_to_matrix reproduces R to rounding even a hair from gimbal lock (the two
    separate atan2 of the textbook lose digits there). At lock (degenerate) θ3 = 0 and θ1 is the
    free angle read from column j: R·e_j = Rot_i(θ1)·e_j. Lower-case sequences are solved as
    the reversed intrinsic sequence whose *first* angle is zeroed instead, then read back.
    Ranges: θ1, θ3 ∈ (−π, π]; θ2 ∈ [−π/2, π/2] (Tait–Bryan) or [0, π] (proper).
    """
    i, j, k, sig, proper, extrinsic = parse_sequence(seq)
    R = checked_rotation(R, check)
    m = [[R[..., r, c] for c in range(3)] for r in range(3)]
    if proper:
        t2 = np.arctan2(np.hypot(m[j][i], m[k][i]), m[i][i])
        t1 = np.arctan2(m[j][i], -sig * m[k][i])
        lock = np.minimum(t2, np.pi - t2) <= lock_tol
    else:
        t2 = np.arctan2(sig * m[i][k], np.hypot(m[k][k], m[j][k]))
        t1 = np.arctan2(-sig * m[j][k], m[k][k])
        lock = np.pi / 2 - np.abs(t2) <= lock_tol
    # Row j of Rot_i(θ1)ᵀ·R, i.e. c1·R[j] + σ s1·R[k], is row j of Rot_m(θ3), m the last axis.
    c1, s1 = np.cos(t1), np.sin(t1)
    row = [c1 * m[j][c] + sig * s1 * m[k][c] for c in range(3)]
    sign3 = -sig if proper else sig
    other = k if proper else i
    t3 = np.arctan2(sign3 * row[other], row[j])
    if extrinsic:
        # Intrinsic reversed: the first angle here is the extrinsic θ3, the one to zero.
        free_last = np.arctan2(sign3 * m[j][other], m[j][j])  # the peel with θ1 = 0
        t1, t3 = np.where(lock, 0.0, t1), np.where(lock, free_last, t3)
        t1, t3 = t3, t1
    else:
        t1 = np.where(lock, np.arctan2(sig * m[k][j], m[j][j]), t1)
        t3 = np.where(lock, 0.0, t3)
    angles = np.stack([_wrap(t1), t2 + 0.0, _wrap(t3)], axis=-1)
    return angles, lock
