"""
The reply of rotation_node's ~/screw_path (nav_msgs/srv/GetPlan).

The constant-screw (Chasles) motion from start to goal, poses at most ``tolerance`` apart,
bounded in steps and in bytes before anything is built.
"""

import math

import numpy as np
from rot_tools.core.screw import screw_from_transform, screw_interpolate
from rot_tools.io.boundary import pose_to_rt, RefusedInput
from rot_tools.ros.node import messages

FRAME_MISMATCH = 'frame_mismatch'
BAD_TOLERANCE = 'bad_tolerance'
PATH_TOO_LONG = 'path_too_long'
NOT_DECOMPOSABLE = 'not_decomposable'

DEFAULT_PATH_STEPS = 20
"""Steps of ~/screw_path when the request's tolerance is ≤ 0 (21 poses)."""

MAX_PATH_STEPS = 10_000
"""A tolerance that needs more steps than this is refused (the reply would be huge)."""

MAX_REPLY_BYTES = 16_000_000
"""Largest ~/screw_path reply (serialised bytes); beyond it the request is path_too_long."""

REPLY_BYTES_PER_POSE = 80
"""Serialised bytes of one PoseStamped of a reply, besides its frame_id: stamp 8, string
length 4 and terminating NUL 1, alignment of the pose at most 7, pose 7 × 8 = 56 (76; the
Path's header, sequence length and encapsulation fit in one more)."""


def screw_path(request, quaternion_tolerance):
    """
    Return the nav_msgs/Path of a GetPlan request: start, the screw motion, goal.

    Raises RefusedInput (frame_mismatch, bad_tolerance, path_too_long,
    not_decomposable, or the boundary's reasons for a bad pose).
    """
    start, goal = request.start, request.goal
    if start.header.frame_id != goal.header.frame_id:
        raise RefusedInput(
            FRAME_MISMATCH, f'start is in frame {start.header.frame_id!r}, goal in '
            f'{goal.header.frame_id!r}')
    R0, b0 = pose_to_rt(start.pose, quaternion_tolerance, 'start.pose')
    R1, b1 = pose_to_rt(goal.pose, quaternion_tolerance, 'goal.pose')
    with np.errstate(all='ignore'):
        if not np.isfinite(R0.T @ (b1 - b0)).all():
            raise RefusedInput(
                NOT_DECOMPOSABLE, 'start and goal are too far apart: goal.position '
                '− start.position overflows float64 (beyond ±1.8e308)')
        steps = path_steps(R0, b0, R1, b1, request.tolerance)
        check_reply_bytes(start.header.frame_id, steps + 1)
        Rs, bs = screw_interpolate(R0, b0, R1, b1, np.linspace(0.0, 1.0, steps + 1),
                                   check=False)
    if not (np.isfinite(Rs).all() and np.isfinite(bs).all()):
        raise RefusedInput(NOT_DECOMPOSABLE, 'values too large to interpolate')
    return messages.path_msg(start.header, start, goal, Rs, bs)


def path_steps(R0, b0, R1, b1, tolerance):
    """
    Return the number of equal steps keeping consecutive poses ``tolerance`` apart.

    The relative motion T0⁻¹T1 is a screw: angle θ about an axis at distance r from the
    origin of the start frame, translation d along it. Split into n equal steps, each
    turns θ/n, and the origin moves along a helix by a chord ≤ √((rθ)² + d²)/n.
    tolerance ≤ 0 means DEFAULT_PATH_STEPS; NaN, or one needing more than MAX_PATH_STEPS,
    raises RefusedInput.
    """
    if math.isnan(tolerance):
        raise RefusedInput(BAD_TOLERANCE, 'tolerance is NaN')
    if tolerance <= 0.0:
        return DEFAULT_PATH_STEPS
    screw = screw_from_transform(R0.T @ R1, R0.T @ (b1 - b0), check=False)
    theta = float(screw.angle)
    arc = math.hypot(float(np.linalg.norm(screw.point)) * theta, float(screw.translation))
    need = max(theta, arc) / tolerance
    if not need <= MAX_PATH_STEPS:
        raise RefusedInput(
            PATH_TOO_LONG, f'tolerance {tolerance:g} needs {need:.3g} steps, more than '
            f'{MAX_PATH_STEPS}')
    return max(1, math.ceil(need - 1e-9))  # 4 + rounding noise is 4 steps, not 5


def reply_bytes(frame_id, poses):
    """
    Return an upper bound of the serialised size of a GetPlan reply (CDR bytes).

    The path's header and each of its ``poses`` carries a copy of ``frame_id``:
    REPLY_BYTES_PER_POSE plus the frame_id's UTF-8 bytes each (the Path's own header
    and sequence length counted as one more pose).
    """
    size = len(frame_id.encode('utf-8', 'surrogatepass'))
    return (poses + 1) * (size + REPLY_BYTES_PER_POSE)


def check_reply_bytes(frame_id, poses):
    """
    Raise RefusedInput (path_too_long) if the reply would exceed MAX_REPLY_BYTES.

    Checked before anything is built: a frame_id of a hundred thousand bytes in each of
    10,001 poses is a reply of a gigabyte, and the node would hold it twice (messages and
    their serialisation).
    """
    size = reply_bytes(frame_id, poses)
    if size > MAX_REPLY_BYTES:
        frame_bytes = len(frame_id.encode('utf-8', 'surrogatepass'))
        raise RefusedInput(
            PATH_TOO_LONG, f'a reply of {poses} poses with a frame_id of {frame_bytes} '
            f'bytes would take {size / 1e6:.3g} MB, more than {MAX_REPLY_BYTES / 1e6:g} MB')
