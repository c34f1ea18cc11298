"""
A rotation typed on the command line: counted, checked at ``--tol``, then made exact.

A matrix or a frame within ``--tol`` of a rotation becomes the nearest rotation, a quaternion
(x, y, z, w, or w, x, y, z with ``--wxyz``) within it of unit length is normalised; the math
then checks at 1e-9. Angles are radians unless ``--deg``. Refusals are one error line.
"""

import numpy as np
from rot_tools import frame_to_matrix, nearest_rotation, quaternion_to_matrix, validate_rotation
from rot_tools.cli.options import error, MATRIX_TOL
from rot_tools.core.errors import RotationError
from rot_tools.io.boundary import QUATERNION_TOLERANCE
from rot_tools.io.report import angle_hint


def count(values, n, what):
    """Return the n typed numbers as an array; an error line names ``what`` otherwise."""
    if len(values) != n:
        error(f'{what}: expected {n} numbers, got {len(values)}')
    return np.array(values)


def _tol(args, default):
    return default if args.tol is None else args.tol


def angles(args, values, size=None):
    """
    Return angles in radians; a hint when radians typed without --deg look like degrees.

    ``size`` is the angle the hint is about (default the largest |value|; a rotation
    vector's is its norm).
    """
    if args.deg:
        return np.radians(values)
    values = np.asarray(values, dtype=np.float64)
    hint = angle_hint(values if size is None else [size])
    if hint:
        args.hints.append(hint)
    return values


def matrix(args, values, what):
    """Validate a typed 3x3 matrix at --tol, then project it onto the nearest rotation."""
    R = count(values, 9, what).reshape(3, 3)
    try:
        validate_rotation(R, tol=_tol(args, MATRIX_TOL))
    except RotationError as exc:
        hint = ' (the tolerance is --tol)' if _det_sign(R) > 0 else ''
        error(f'{what}: {exc}{hint}')
    return nearest_rotation(R)


def _det_sign(R):
    """Sign of det R for any finite R: scaled first, so entries of 1e308 do not overflow."""
    scale = float(np.abs(R).max()) if np.isfinite(R).all() else 0.0
    if not scale > 0:
        return 0.0
    with np.errstate(all='ignore'):  # a singular R: LU divides by a zero pivot
        return float(np.sign(np.linalg.det(R / scale)))


def frame(args, values, what):
    """R = (û v̂ ŵ) of typed axes U V W, |cos| between axes ≤ --tol, then made exact."""
    u, v, w = count(values, 9, what).reshape(3, 3)
    try:
        R = frame_to_matrix(u, v, w, tol=_tol(args, MATRIX_TOL))
    except RotationError as exc:
        hint = ' (the tolerance is --tol)' if 'not orthogonal' in str(exc) else ''
        error(f'{what}: {exc}{hint}')
    return nearest_rotation(R)


def quaternion(args, values, what):
    """R of a typed quaternion: x y z w (w x y z with --wxyz), ||q| − 1| ≤ --tol."""
    q = count(values, 4, what)
    if args.wxyz:
        q = np.roll(q, -1)  # (w, x, y, z) → (x, y, z, w)
    try:
        return quaternion_to_matrix(q, tol=_tol(args, QUATERNION_TOLERANCE))  # normalises q
    except RotationError as exc:
        hint = ' (the tolerance is --tol)' if 'unit length' in str(exc) else ''
        error(f'{what}: {exc}{hint}')


def read(args, rotation, what):
    """
    Return rotation(args): (R, b, input sequence) of the typed input, or one error line.

    ``what`` starts the error line of a rotation the math refuses (a zero axis with an
    angle, a point whose image overflows).
    """
    args.hints = []
    if args.wxyz and not reads_quaternion(args):
        error('--wxyz: there is no quaternion to read (it applies to quaternion and screw '
              '--quaternion)')
    try:
        return rotation(args)
    except ValueError as exc:  # RotationError is a ValueError
        error(f'{what}: {exc}')


def reads_quaternion(args):
    """Return whether the typed input has a quaternion (quaternion, screw --quaternion)."""
    kind = getattr(args, 'input', args.command)  # covariance's input
    return kind == 'quaternion' or getattr(args, 'quaternion', None) is not None
