"""
The inbound boundary: a message's fields → one rigid transform (R, b), or a refusal.

Every input — a message reaching rotation_node, or a message read from a recorded bag by
``rot-tools bag`` — passes the same checks, refused for the same reasons at the same
thresholds, so that a count of refusals means the same thing wherever it is printed. This
module holds those checks and imports no ROS: the checks take the fields' values (and the
few that take a message object duck-type it: anything with the field names of the ROS
message), and they also come as batches over NumPy arrays of fields.

Reasons (``RefusedInput.reason``, and the keys of the counts):

- ``non_finite``: NaN or ±Inf in a field that is used (position, translation, orientation);
- ``zero_quaternion``: an orientation of norm 0 (recorders write q = 0 for "unset");
- ``non_unit_quaternion``: |‖q‖ − 1| > the tolerance (rotation_node's
  ``quaternion_tolerance``, default 1e-3); within it q is normalised;
- ``no_orientation``: a sensor_msgs/Imu whose orientation_covariance[0] is −1 (its way of
  saying it has no orientation estimate).

One rule, two engines. :func:`quaternion_verdict` decides a quaternion's reason from its
four components; it is written once against an ``ops`` namespace and run on Python floats
for one message (:data:`SCALAR`: what rotation_node calls per message) and on NumPy arrays
for a batch (:data:`ARRAY`: ``rot-tools bag``). Both engines do the same IEEE operations in
the same order, so a quaternion at the edge of the tolerance gets the same verdict either
way. Checks run in one order, which fixes the reason of a message with several defects:
no orientation (Imu), then a non-finite position or translation, then the quaternion.

Per message, every converter has the form ``convert(values, settings, fields)`` →
``Motion(R, b)``: ``values`` are the numbers it needs, in the message's order (rotation_node
reads them at the input row's field paths, rot_tools.io.interface), ``settings`` is
rotation_node's Settings (they read ``quaternion_tolerance``, and the Euler one
``euler_sequence`` and ``degrees``), ``fields`` the input's {role: path} (the names a
refusal gives); it raises :class:`RefusedInput`. For a batch, :func:`check_batch` gives each
item's Verdict: its reason code (0 = accepted; ``REFUSAL_REASONS[code - 1]``
otherwise) and :func:`refusal_text` the sentence the per-message converter would raise.
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
# The rule, for one item (Python floats) and for a batch (NumPy arrays)


class _ScalarOps:
    isfinite = staticmethod(math.isfinite)
    sqrt = staticmethod(math.sqrt)
    abs = staticmethod(abs)  # noqa: A003
    maximum = staticmethod(max)
    any = staticmethod(bool)  # noqa: A003

    @staticmethod
    def where(cond, a, b):
        return a if cond else b

    @staticmethod
    def outside(x, low, high):
        return not low <= x <= high


class _ArrayOps:
    isfinite = staticmethod(np.isfinite)
    sqrt = staticmethod(np.sqrt)
    abs = staticmethod(np.abs)  # noqa: A003
    maximum = staticmethod(np.maximum)
    any = staticmethod(np.any)  # noqa: A003
    where = staticmethod(np.where)

    @staticmethod
    def outside(x, low, high):
        return ~((x >= low) & (x <= high))


SCALAR = _ScalarOps()
ARRAY = _ArrayOps()

_SAFE_SQUARES = (1e-290, 1e290)
"""Where ‖q‖² = Σ q_i² lies in this range nothing overflowed or lost digits to underflow."""


class Verdict(NamedTuple):
    """A quaternion's reason code (ACCEPTED or a refusal's) and its norm ‖q‖."""

    code: object
    norm: object


def quaternion_verdict(ops, x, y, z, w, tolerance):
    """
    Return the Verdict of the quaternion (x, y, z, w): the one rule of both engines.

    code: ACCEPTED, or the code of non_finite (a component NaN/±Inf), zero_quaternion
    (‖q‖ = 0) or non_unit_quaternion (|‖q‖ − 1| > tolerance). ‖q‖ = sqrt(Σ q_i²), and
    where that sum is outside _SAFE_SQUARES (zero, NaN/Inf, overflow, underflow; rare)
    m·|q/m| with m the largest |component|, which neither overflows nor underflows. The
    norm is meaningless where the code is non_finite.
    """
    n2 = x * x + y * y + z * z + w * w
    norm = ops.sqrt(n2)
    code = ops.where(ops.abs(norm - 1.0) > tolerance, CODE[NON_UNIT_QUATERNION], ACCEPTED)
    rare = ops.outside(n2, *_SAFE_SQUARES)
    if ops.any(rare):
        finite = ops.isfinite(x) & ops.isfinite(y) & ops.isfinite(z) & ops.isfinite(w)
        big = ops.maximum(ops.maximum(ops.abs(x), ops.abs(y)),
                          ops.maximum(ops.abs(z), ops.abs(w)))
        safe = ops.where(finite & (big > 0), big, 1.0)
        sx, sy, sz, sw = x / safe, y / safe, z / safe, w / safe
        scaled = big * ops.sqrt(sx * sx + sy * sy + sz * sz + sw * sw)
        slow = ops.where(ops.abs(scaled - 1.0) > tolerance, CODE[NON_UNIT_QUATERNION],
                         ACCEPTED)
        slow = ops.where(big == 0, CODE[ZERO_QUATERNION], slow)
        slow = ops.where(finite, slow, CODE[NON_FINITE])
        code = ops.where(rare, slow, code)
        norm = ops.where(rare, scaled, norm)
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


def _require_finite(prefix, fields, values):
    """
    Raise RefusedInput(NON_FINITE) naming the first field (prefix.field) that is NaN or ±Inf.

    (The names are built only for the refusal: this runs for every message.)
    """
    if not all(map(math.isfinite, values)):
        raise RefusedInput(NON_FINITE, refusal_text(CODE[NON_FINITE], prefix, values,
                                                    fields=fields))


def quaternion_to_rotation(x, y, z, w, tolerance, name='orientation'):
    """
    Rotation matrix of a geometry_msgs/Quaternion's fields, refused unless near unit.

    Refused (RefusedInput) when a component is NaN/Inf, when q = 0, or when
    |‖q‖ − 1| > ``tolerance``; within the tolerance q is normalised (R is exactly orthogonal).
    ``name`` is the field's, for the refusal.
    """
    verdict = quaternion_verdict(SCALAR, x, y, z, w, tolerance)
    code, norm = verdict.code, verdict.norm
    if code:
        raise RefusedInput(REFUSAL_REASONS[code - 1],
                           refusal_text(code, name, (x, y, z, w), norm, tolerance))
    return quaternion_to_matrix((x / norm, y / norm, z / norm, w / norm))


TRANSFORM_FIELDS = {'position': 'transform.translation', 'orientation': 'transform.rotation'}
"""The fields of a geometry_msgs/TransformStamped's rotation and translation, by role."""


def rigid_of_fields(values, tolerance, orientation, position):
    """
    Motion(R, b) of a Pose's or a Transform's fields (px, py, pz, qx, qy, qz, qw).

    b = the position, R from the quaternion; ``orientation`` and ``position`` are the
    fields' names, for the refusal.
    """
    px, py, pz, qx, qy, qz, qw = values
    _require_finite(position, 'xyz', (px, py, pz))
    return Motion(R=quaternion_to_rotation(qx, qy, qz, qw, tolerance, orientation),
                  b=np.array((px, py, pz)))


def pose_to_rt(pose, tolerance, name='pose'):
    """Motion(R, b) of a geometry_msgs/Pose: R from the orientation, b = the position."""
    p, q = pose.position, pose.orientation
    return rigid_of_fields((p.x, p.y, p.z, q.x, q.y, q.z, q.w), tolerance,
                           f'{name}.orientation', f'{name}.position')


def pose_fields_to_rt(values, settings, fields):
    """
    Motion(R, b) of a Pose's or a Transform's (position, orientation) values: b, R from q.

    ``fields``: {'position': path, 'orientation': path} of the message, for the refusal
    (e.g. an Odometry's pose.pose.position; its covariance and twist are not used).
    """
    return rigid_of_fields(values, settings.quaternion_tolerance, fields['orientation'],
                           fields['position'])


def imu_fields_to_rt(values, settings, fields):
    """
    Motion(R, 0) of a sensor_msgs/Imu's (orientation x, y, z, w, orientation_covariance[0]).

    sensor_msgs/Imu marks "no orientation estimate" with orientation_covariance[0] = -1:
    such a message is refused (NO_ORIENTATION). Angular velocity, linear acceleration and
    the covariances are not used. ``fields['orientation']`` names the quaternion.
    """
    x, y, z, w, covariance0 = values
    name = fields['orientation']
    if lacks_orientation(covariance0):
        raise RefusedInput(NO_ORIENTATION, refusal_text(CODE[NO_ORIENTATION], name))
    return Motion(R=quaternion_to_rotation(x, y, z, w, settings.quaternion_tolerance, name),
                  b=np.zeros(3))


def quaternion_fields_to_rt(values, settings, fields):
    """Motion(R, 0) of a quaternion's (x, y, z, w); ``fields['orientation']`` names it."""
    return Motion(R=quaternion_to_rotation(*values, settings.quaternion_tolerance,
                                           fields['orientation']), b=np.zeros(3))


def euler_fields_to_rt(values, settings, fields):
    """
    Motion(R, 0) of Euler angles (θ1, θ2, θ3); ``fields['angles']`` names their Vector3.

    The angles are of ``settings.euler_sequence``, in degrees when ``settings.degrees``,
    else radians.
    """
    _require_finite(fields['angles'], 'xyz', values)
    if settings.degrees:
        values = tuple(math.radians(a) for a in values)
    return Motion(R=euler_to_matrix(values, settings.euler_sequence), b=np.zeros(3))


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
    with np.errstate(invalid='ignore', divide='ignore', over='ignore'):
        verdict = quaternion_verdict(ARRAY, q[:, 0], q[:, 1], q[:, 2], q[:, 3], tolerance)
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
