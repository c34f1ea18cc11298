"""
The Rodrigues (Gibbs) vector g = tan(θ/2)·l̂ of a rotation by θ about the unit axis l̂.

With the unit quaternion q = (sin(θ/2)·l̂, cos(θ/2)) in the ROS order (x, y, z, w),
g = (x, y, z)/w, the same for q and −q; back, q = (g, 1)/√(1 + g·g). Composition and the
Cayley transform R = (I + [g]×)(I − [g]×)⁻¹ make it the rotation's Cayley parameters. |g|
grows without bound as θ → π; at θ = π (w = 0) g is infinite, and a hair from π it may
overflow float64: a RotationError.
"""

import math

import numpy as np
from rot_tools.core._arrays import finite_array
from rot_tools.core.errors import RotationError
from rot_tools.core.so3 import matrix_to_quaternion, quaternion_to_matrix


AT_PI = 'the Rodrigues vector tan(θ/2)·l̂ is infinite at θ = π (quaternion w = 0)'
"""Why a rotation by θ = π has no Rodrigues vector."""


def _no_rodrigues(w):
    """
    Return why the quaternion with real part w has no Rodrigues vector in float64.

    w = 0: θ = π. A w so small that (x, y, z)/w overflows: θ within 2·asin|w| ≈ 2|w| of π.
    """
    if w == 0.0:
        return AT_PI
    return (f'the Rodrigues vector tan(θ/2)·l̂ overflows float64 (beyond ±1.8e308): θ is '
            f'{2.0 * abs(w):.3g} rad from π (quaternion w = {w:.3g})')


def quaternion_to_rodrigues(q):
    """
    Return g = (x, y, z)/w of unit quaternions q (..., 4) as (x, y, z, w); (..., 3).

    RotationError where w = 0, a rotation by θ = π whose g is infinite, or where g overflows.
    """
    q = np.asarray(q, dtype=np.float64)
    w = q[..., 3]
    with np.errstate(divide='ignore', over='ignore', invalid='ignore'):
        g = q[..., :3] / w[..., None]
    at_pi = (w == 0.0) | np.isinf(g).any(axis=-1)
    if at_pi.any():
        first = tuple(int(i) for i in np.argwhere(at_pi)[0])
        raise RotationError(_no_rodrigues(w[first]) + (f' (item {first})' if w.ndim else ''))
    return g


def rodrigues_of_one(x, y, z, w):
    """
    Return quaternion_to_rodrigues of one quaternion, in plain floats: (x/w, y/w, z/w).

    The per-message path of rotation_node (no NumPy value made); RotationError at w = 0 or
    where g overflows.
    """
    if w == 0.0:
        raise RotationError(AT_PI)
    g = x / w, y / w, z / w
    if any(math.isinf(c) for c in g):
        raise RotationError(_no_rodrigues(w))
    return g


def matrix_to_rodrigues(R, *, check=True):
    """
    Return the Rodrigues vector g = tan(θ/2)·l̂ of rotations R (..., 3, 3); (..., 3).

    g = (x, y, z)/w of matrix_to_quaternion(R). R is validated unless check=False.
    RotationError at θ = π, where g is infinite.
    """
    return quaternion_to_rodrigues(matrix_to_quaternion(R, check=check))


def rodrigues_to_matrix(g):
    """
    Return the rotation matrix (..., 3, 3) of Rodrigues vectors g = tan(θ/2)·l̂ (..., 3).

    R = quaternion_to_matrix((g, 1)), the quaternion scaled by 1/max(1, |g_i|) first so that
    g·g cannot overflow. RotationError for NaN/Inf in g (θ = π has no finite g).
    """
    g = finite_array(g, (3,), 'Rodrigues vector g')
    scale = np.maximum(1.0, np.abs(g).max(axis=-1, keepdims=True))
    return quaternion_to_matrix(np.concatenate([g / scale, 1.0 / scale], axis=-1))
