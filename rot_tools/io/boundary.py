"""
The inbound boundary: a message's numbers → one rigid motion (R, b), or a refusal by reason.

rotation_node (one message at a time, its fields read by plain code) and ``rot-tools bag``
(columns of many messages) refuse the same inputs for the same reasons, so a count means the
same wherever it is printed: ``non_finite`` (NaN/±Inf in a used field), ``zero_quaternion``,
``non_unit_quaternion`` (|‖q‖ − 1| > the tolerance; within it q is normalised) and
``no_orientation`` (an Imu's orientation_covariance[0] = −1). The quaternion's rule is
:func:`quaternion_verdict`. No ROS is imported.
"""

import math
from typing import NamedTuple

import numpy as np
from rot_tools.core.euler import euler_to_matrix
from rot_tools.core.rigid import Motion
from rot_tools.core.so3 import quaternion_to_matrix

NON_FINITE = 'non_finite'
ZERO_QUATERNION = 'zero_quaternion'
NON_UNIT_QUATERNION = 'non_unit_quaternion'
NO_ORIENTATION = 'no_orientation'
REFUSAL_REASONS = (NON_FINITE, ZERO_QUATERNION, NON_UNIT_QUATERNION, NO_ORIENTATION)
"""Reasons this module refuses a message for; rotation_node adds its own."""

QUATERNION_TOLERANCE = 1e-3
"""Largest |‖q‖ − 1| of a quaternion accepted by default (rotation_node's quaternion_tolerance,
``rot-tools bag``, a typed or recorded quaternion); within it q is normalised."""

ACCEPTED = 0
"""Reason code of an accepted item; a refused one has ``REFUSAL_REASONS.index(r) + 1``."""
CODE = {reason: k + 1 for k, reason in enumerate(REFUSAL_REASONS)}
"""Reason → code (int8) of the batch checks."""


class RefusedInput(ValueError):
    """A message that is not a rigid transform; ``reason`` is a key of REFUSAL_REASONS."""

    def __init__(self, reason, message):
        super().__init__(message)
        self.reason = reason


# ---------------------------------------------------------------------------------------
# The rule


_SAFE_SQUARES = (1e-290, 1e290)
"""Where ‖q‖² = Σ q_i² lies in this range nothing overflowed or lost digits to underflow."""


class Verdict(NamedTuple):
    """Quaternions' reason codes (ACCEPTED or a refusal's) and their norms ‖q‖."""

    code: np.ndarray
    norm: np.ndarray


def quaternion_verdict(x, y, z, w, tolerance):
    """
    Return the Verdict of quaternions (x, y, z, w), arrays of components: the one rule.

    code: ACCEPTED, or the code of non_finite (a component NaN/±Inf), zero_quaternion
    (‖q‖ = 0) or non_unit_quaternion (|‖q‖ − 1| > tolerance). ‖q‖ = sqrt(Σ q_i²); where
    that sum is outside _SAFE_SQUARES (zero, NaN/Inf, overflow, underflow) it is m·‖q/m‖
    with m the largest |component|, which neither overflows nor underflows. The norm is
    meaningless where the code is non_finite.
    """
    with np.errstate(invalid='ignore', divide='ignore', over='ignore', under='ignore'):
        n2 = x * x + y * y + z * z + w * w
        norm = np.sqrt(n2)
        code = np.where(np.abs(norm - 1.0) > tolerance, CODE[NON_UNIT_QUATERNION], ACCEPTED)
        rare = ~((n2 >= _SAFE_SQUARES[0]) & (n2 <= _SAFE_SQUARES[1]))
        if rare.any():
            finite = np.isfinite(x) & np.isfinite(y) & np.isfinite(z) & np.isfinite(w)
            big = np.maximum(np.maximum(np.abs(x), np.abs(y)), np.maximum(np.abs(z), np.abs(w)))
            safe = np.where(finite & (big > 0), big, 1.0)
            sx, sy, sz, sw = x / safe, y / safe, z / safe, w / safe
            scaled = big * np.sqrt(sx * sx + sy * sy + sz * sz + sw * sw)
            slow = np.where(np.abs(scaled - 1.0) > tolerance, CODE[NON_UNIT_QUATERNION],
                            ACCEPTED)
            slow = np.where(big == 0, CODE[ZERO_QUATERNION], slow)
            slow = np.where(finite, slow, CODE[NON_FINITE])
            code = np.where(rare, slow, code)
            norm = np.where(rare, scaled, norm)
    return Verdict(code=code, norm=norm)


def refusal_text(code, name, components=None, norm=None, tolerance=None, fields='xyzw'):
    """
    Return the sentence of a refusal: what was wrong, and by how much.

    name: the field ('orientation', 'pose.pose.position', ...); components: its values
    (the first non-finite one is named); norm and tolerance for non_unit_quaternion.
    """
    reason = REFUSAL_REASONS[code - 1]
    if reason == NON_FINITE:
        for field, value in zip(fields, components):
            if not math.isfinite(value):
                return f'{name}.{field} is {float(value)}'
    if reason == ZERO_QUATERNION:
        return f'{name} is the zero quaternion'
    if reason == NON_UNIT_QUATERNION:
        return (f'{name} has norm {norm:.9g}, off 1 by {abs(norm - 1.0):.3g} > '
                f'quaternion_tolerance {tolerance:g}')
    if reason == NO_ORIENTATION:
        return 'orientation_covariance[0] is -1: the IMU gives no orientation estimate'
    raise ValueError(f'no refusal text for code {code}')  # pragma: no cover


def lacks_orientation(covariance0):
    """Tell where an Imu's orientation_covariance[0] says "no orientation" (== −1)."""
    return covariance0 == -1.0


# ---------------------------------------------------------------------------------------
# Per message: message -> (header, R, b)


def require_finite(name, values, members='xyz'):
    """Raise RefusedInput(NON_FINITE) naming the first member (name.member) NaN or ±Inf."""
    if not all(map(math.isfinite, values)):
        raise RefusedInput(NON_FINITE, refusal_text(CODE[NON_FINITE], name, values,
                                                    fields=members))


def quaternion_to_rotation(x, y, z, w, tolerance, name='orientation'):
    """
    Rotation matrix of a geometry_msgs/Quaternion's fields, refused unless near unit.

    Refused (RefusedInput) when a component is NaN/Inf, when q = 0, or when
    |‖q‖ − 1| > ``tolerance``; within the tolerance q is normalised (R is exactly orthogonal).
    ``name`` is the field's, for the refusal. The usual quaternion takes the rule's first
    branch in plain floats (the same operations); any other goes through the rule itself.
    """
    n2 = x * x + y * y + z * z + w * w
    if _SAFE_SQUARES[0] <= n2 <= _SAFE_SQUARES[1]:
        norm = math.sqrt(n2)
        code = CODE[NON_UNIT_QUATERNION] if abs(norm - 1.0) > tolerance else ACCEPTED
    else:
        verdict = quaternion_verdict(*np.array([[x], [y], [z], [w]], dtype=np.float64),
                                     tolerance)
        code, norm = int(verdict.code[0]), float(verdict.norm[0])
    if code:
        raise RefusedInput(REFUSAL_REASONS[code - 1],
                           refusal_text(code, name, (x, y, z, w), norm, tolerance))
    return quaternion_to_matrix((x / norm, y / norm, z / norm, w / norm))


def rigid_motion(position, orientation, tolerance, name='pose'):
    """
    Motion(R, b) of a position (x, y, z) and an orientation (x, y, z, w).

    b = the position, R from the quaternion; ``name``: the Pose's or Transform's field, whose
    members ``name.position``, ``name.orientation`` a refusal names (a Transform's are
    ``translation`` and ``rotation``: give ``name`` as (translation name, rotation name)).
    """
    p_name, q_name = ((f'{name}.position', f'{name}.orientation') if isinstance(name, str)
                      else name)
    require_finite(p_name, position)
    return Motion(R=quaternion_to_rotation(*orientation, tolerance, q_name),
                  b=np.array(position, dtype=np.float64))


def pose_to_rt(pose, tolerance, name='pose'):
    """Motion(R, b) of a geometry_msgs/Pose: R from the orientation, b = the position."""
    p, q = pose.position, pose.orientation
    return rigid_motion((p.x, p.y, p.z), (q.x, q.y, q.z, q.w), tolerance, name)


def transform_to_rt(transform, tolerance, name='transform'):
    """Motion(R, b) of a geometry_msgs/Transform: R from the rotation, b = the translation."""
    t, q = transform.translation, transform.rotation
    return rigid_motion((t.x, t.y, t.z), (q.x, q.y, q.z, q.w), tolerance,
                        (f'{name}.translation', f'{name}.rotation'))


def require_orientation(covariance0):
    """Raise RefusedInput(NO_ORIENTATION) when an Imu's orientation_covariance[0] is −1."""
    if lacks_orientation(covariance0):
        raise RefusedInput(NO_ORIENTATION, refusal_text(CODE[NO_ORIENTATION], 'orientation'))


def euler_to_rotation(angles, sequence, degrees, name='vector'):
    """Rotation matrix of Euler angles (θ1, θ2, θ3) of ``sequence``, in degrees if ``degrees``."""
    require_finite(name, angles)
    if degrees:
        angles = tuple(math.radians(a) for a in angles)
    return euler_to_matrix(angles, sequence)


# ---------------------------------------------------------------------------------------
# Batches: arrays of fields -> reason codes, then (R, b) of the accepted items


def check_batch(quaternions, tolerance, positions=None, covariance0=None):
    """
    Return the Verdict of N messages' fields: codes (N,) int8 and norms (N,).

    quaternions (N, 4) as (x, y, z, w); positions (N, 3) or None; covariance0 (N,) — an
    Imu's orientation_covariance[0] — or None. The code of each item is what the
    per-message converter would refuse it for (ACCEPTED when it would not): no_orientation
    first, then a non-finite position, then :func:`quaternion_verdict`.
    """
    q = np.asarray(quaternions, dtype=np.float64).reshape(-1, 4)
    verdict = quaternion_verdict(q[:, 0], q[:, 1], q[:, 2], q[:, 3], tolerance)
    code = np.asarray(verdict.code, dtype=np.int8)
    if positions is not None:
        bad = ~np.isfinite(np.asarray(positions, dtype=np.float64)).all(axis=1)
        code[bad] = CODE[NON_FINITE]
    if covariance0 is not None:
        code[lacks_orientation(np.asarray(covariance0, dtype=np.float64))] = CODE[NO_ORIENTATION]
    return Verdict(code=code, norm=verdict.norm)


def batch_refusal_text(fields, code, quaternion, norm, tolerance, position=None):
    """
    Return the sentence the per-message converter raises for one refused item.

    ``fields``: {role: path} of the message's fields (rot_tools.io.interface), for the names.
    """
    q_name, p_name = fields['orientation'], fields.get('position')
    if REFUSAL_REASONS[code - 1] == NON_FINITE and position is not None and not all(
            map(math.isfinite, position)):
        return refusal_text(code, p_name, position, fields='xyz')
    return refusal_text(code, q_name, quaternion, norm, tolerance)


def accepted_rotations(quaternions, norms, code):
    """Rotation matrices (M, 3, 3) of the accepted items (code 0), q normalised, as a batch."""
    ok = code == ACCEPTED
    q = np.asarray(quaternions, dtype=np.float64)[ok] / np.asarray(norms)[ok][:, None]
    return quaternion_to_matrix(q.reshape(-1, 4)).reshape(-1, 3, 3)
