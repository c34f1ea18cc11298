"""
The geometry of a picture of one rigid motion, for every renderer (plain NumPy).

``rot-tools --plot`` (rot_tools.cli.plot, matplotlib) and rotation_node's ``~/markers``
(rot_tools.ros.node.messages, RViz) draw the same :class:`Picture`, computed here once. The motion
p ↦ R·p + b has the Chasles screw (l̂, c, θ, d) and the twist ξ = screw_log(R, b); a picture
of it holds, in the reference frame:

- the moved frame: its axes are the columns of R (Jia, Rotation in the Space, §4), drawn
  from b with length ``scale``;
- the screw axis: the line through c along l̂, as a segment from c + t_lo·l̂ to c + t_hi·l̂
  (pointing along +l̂: θ turns right-handed about it) that covers the projections onto the
  axis of the origin, the path and the moved frame, plus ``scale`` beyond each end;
- the path: the constant-screw motion T(s) = exp(s·ξ), s ∈ [0, 1], applied to a point p0,
  p(s) = R(s)·p0 + b(s) — a helix about the axis of radius dist(p0, axis) that turns s·θ and
  rises s·d (Jia §5, Chasles). p0 is the frame origin, whose path ends at b;
- a label: θ (in degrees or radians), d and the screw pitch h = d/θ, placed LABEL_OFFSET·scale off
  the middle of the path, across its chord (towards +z, or +x when the chord is within 60° of
  z) — beside the motion, however far away its axis is (|c| grows like |b|/θ as θ → 0).

Special cases. A pure rotation (b = 0) leaves the origin where it is, so the path is the arc
of the tip of a reference axis, p0 = scale·e_k, k the axis farthest from the rotation axis
(smallest |l̂_k|, x first on ties; about z it is the x tip), ending at the tip of the moved
axis k. A pure translation (θ = 0) has no axis to draw (its pitch is inf): the path is the
straight segment from 0 to b. The identity has nothing to draw.

The path is sampled with a step of at most MAX_STEP_ANGLE of turn and at most SAGITTA·scale
between a chord and the helix (a chord of a turn Δ at radius r is r(1 − cos(Δ/2)) ≈ r·Δ²/8
off the curve), and at most MAX_SEGMENTS segments; a straight path is one segment.

A motion whose picture overflows float64 (an axis 1e300 away) raises RotationError.
"""

import math
from typing import NamedTuple, Optional

import numpy as np
from rot_tools.core.errors import RotationError
from rot_tools.core.screw import Screw, screw_from_transform

MAX_STEP_ANGLE = math.radians(3.0)
"""Largest turn (rad) between two consecutive points of a path."""

SAGITTA = 2e-3
"""Largest distance between a chord of the path and the helix, as a fraction of ``scale``."""

MAX_SEGMENTS = 720
"""Most segments in a path, whatever the radius."""

LABEL_OFFSET = 0.3
"""The label sits this many ``scale`` off the middle of the path."""

IDENTITY, ROTATION, TRANSLATION, SCREW = 'identity', 'rotation', 'translation', 'screw'
"""Picture.kind: nothing to draw; b = 0; θ = 0; a general screw motion."""


class Picture(NamedTuple):
    """
    What to draw of one rigid motion p ↦ R·p + b; see the module docstring.

    kind: IDENTITY, ROTATION, TRANSLATION or SCREW. origin: b (3,), where the moved frame
    is drawn; frame: R (3, 3), the moved axes x, y, z are its columns; scale: the length of
    a frame axis. axis: (2, 3) start and end of the screw axis segment, None for a pure
    translation or the identity. path: (n, 3) points from p0 to R·p0 + b, None for the
    identity; traced: what the path carries ('origin', 'x-axis tip', ...), '' for the
    identity. label: the text (ASCII, lines separated by newlines), label_at: where it goes
    (3,). screw: the Screw of (R, b).
    """

    kind: str
    origin: np.ndarray
    frame: np.ndarray
    scale: float
    axis: Optional[np.ndarray]
    path: Optional[np.ndarray]
    traced: str
    label: str
    label_at: np.ndarray
    screw: Screw


def _number(x):
    """Write x to 4 significant digits, 'inf' for infinity, never '-0'."""
    return f'{x + 0.0:.4g}'


def label_text(screw, degrees=False):
    """
    Return the label of a Screw: 'theta = 90 deg, d = 0.5, screw pitch = 0.3183 /rad'.

    ASCII. "screw pitch", not "pitch": next to the angles of an IMU, a bare pitch reads as
    the Euler (roll, pitch, yaw) one.
    """
    theta = math.degrees(screw.angle) if degrees else float(screw.angle)
    unit = 'deg' if degrees else 'rad'
    return (f'theta = {_number(theta)} {unit}, d = {_number(screw.translation)}, '
            f'screw pitch = {_number(screw.pitch)}'
            + ('' if math.isinf(screw.pitch) else ' /rad'))


def path_segments(angle, radius, scale):
    """
    Segments that keep each step ≤ MAX_STEP_ANGLE and each chord ≤ SAGITTA·scale off.

    r·Δ²/8 ≤ SAGITTA·scale gives Δ ≤ √(8·SAGITTA·scale/r); one segment for a straight path
    (angle 0), at most MAX_SEGMENTS.
    """
    if angle == 0.0:
        return 1
    step = MAX_STEP_ANGLE
    if radius > 0.0:
        step = min(step, math.sqrt(8.0 * SAGITTA * scale / radius))
    if not angle < MAX_SEGMENTS * step:  # also for a step of 0 (an infinite radius)
        return MAX_SEGMENTS
    return max(1, math.ceil(angle / step))


class _Traced(NamedTuple):
    """The point p0 whose path is drawn, and its name."""

    name: str
    point: np.ndarray


def _traced_point(kind, direction, scale):
    """Return the _Traced origin, or for a pure rotation the axis tip farthest off its axis."""
    if kind != ROTATION:
        return _Traced(name='origin', point=np.zeros(3))
    k = int(np.argmin(np.abs(direction)))
    return _Traced(name=f"{'xyz'[k]}-axis tip", point=scale * np.eye(3)[k])


def label_point(path, scale):
    """
    Where the label goes: m + LABEL_OFFSET·scale·n̂, m the middle of the path.

    m is the path's middle point (of its middle chord for an even count of points); n̂ is the
    unit vector across the chord k = p_last − p_0 towards +z, ẑ − (ẑ·k̂)k̂ normalised, or towards
    +x when that is shorter than 1/2 (k within 60° of z). The chord of a path is never 0.
    """
    middle = (path[(len(path) - 1) // 2] + path[len(path) // 2]) / 2
    chord = (path[-1] - path[0]).tolist()
    if not all(map(math.isfinite, chord)):
        return middle + math.nan  # a path that overflowed: the picture is refused
    big = max(map(abs, chord))  # no overflow in the norm
    chord = [k / big for k in chord]
    length = math.hypot(*chord)
    chord = [k / length for k in chord]
    for up in _UPS:
        along = sum(u * k for u, k in zip(up, chord))
        side = [u - along * k for u, k in zip(up, chord)]
        length = math.hypot(*side)
        if length >= 0.5:
            break
    return middle + (LABEL_OFFSET * scale / length) * np.array(side)


_UPS = ((0.0, 0.0, 1.0), (1.0, 0.0, 0.0))
"""The directions label_point tries for its n̂, in order: +z, then +x."""


def screw_path(screw, p0, end, scale):
    """
    Points p(s) of the constant-screw motion from p0, s = 0, 1/n, ..., 1 ((n + 1, 3)).

    n = path_segments(θ, r, scale), r = |l̂ × u| the radius of the helix.
    The motion turns s·θ about the axis (c, l̂) and rises s·d along it (Jia §5, Chasles):
    p(s) = p0 + (I − Rot(s·θ))·u + s·d·l̂ with u = c − p0, where by Rodrigues
    (I − Rot(φ))·u = 2 sin²(φ/2)·u⊥ − sin φ·l̂ × u and u⊥ = u − (u·l̂)·l̂: no cancellation
    when the axis is far away (small θ). The ends are set to p0 and ``end`` = R·p0 + b exactly.
    """
    angle, translation = float(screw.angle), float(screw.translation)
    (x, y, z), (ux, uy, uz) = screw.direction.tolist(), (screw.point - p0).tolist()
    across = (y * uz - z * uy, z * ux - x * uz, x * uy - y * ux)  # l̂ × u
    along = x * ux + y * uy + z * uz
    n = path_segments(angle, math.hypot(*across), scale)
    s = np.arange(n + 1) / n
    # p(s) − p0 = [2 sin²(sθ/2), sin sθ, s]·[u⊥; −l̂ × u; d·l̂], one row of the left per point
    weights = np.empty((n + 1, 3))
    half = np.sin((0.5 * angle) * s)
    np.multiply(2.0 * half, half, out=weights[:, 0])
    np.sin(angle * s, out=weights[:, 1])
    weights[:, 2] = s
    path = weights @ np.array(((ux - along * x, uy - along * y, uz - along * z),
                               (-across[0], -across[1], -across[2]),
                               (translation * x, translation * y, translation * z)))
    path += p0
    path[0], path[-1] = p0, end
    return path


def picture(R, b, scale=1.0, degrees=False, decomposition=None):
    """
    Return the Picture of p ↦ R·p + b, R (3, 3) and b (3,); frame axes ``scale`` long.

    ``decomposition`` is rot_tools.decompose(R, b) when the caller has it already; the label
    gives θ in degrees when ``degrees``. R is validated (by screw_from_transform) when it is
    not given.
    """
    R = np.asarray(R, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    screw = (screw_from_transform(R, b) if decomposition is None
             else Screw(*(np.asarray(f, dtype=np.float64) for f in decomposition.screw)))
    angle, translation = float(screw.angle), float(screw.translation)
    direction, point = screw.direction, screw.point
    kind = (IDENTITY if angle == 0.0 and translation == 0.0 else TRANSLATION if angle == 0.0
            else ROTATION if not b.any() else SCREW)
    label = label_text(screw, degrees)
    if kind == IDENTITY:
        return Picture(kind=kind, origin=b, frame=R, scale=scale, axis=None, path=None,
                       traced='', label=label, label_at=b.copy(), screw=screw)
    traced = _traced_point(kind, direction, scale)
    p0 = traced.point
    with np.errstate(over='ignore', invalid='ignore'):  # checked below
        path = screw_path(screw, p0, R @ p0 + b, scale)
        label_at = label_point(path, scale)
        # Where the path, b and the moved frame's tips fall along the axis, t = (p − c)·l̂
        # (the origin is among them: the path starts there, or b = 0 for a pure rotation).
        drawn = np.concatenate((path, b[None], b + scale * R.T))
        t = drawn @ direction - float(point @ direction)
        lo, hi = float(t.min()) - scale, float(t.max()) + scale
        axis = None if kind == TRANSLATION else point + np.array(((lo,), (hi,))) * direction
    if not (np.isfinite(drawn).all() and np.isfinite(label_at).all()
            and (axis is None or np.isfinite(axis).all())):
        raise RotationError(
            f'the picture of this motion overflows float64 (scale {scale:.3g}, max|b_i| = '
            f'{np.abs(b).max():.3g}, screw axis point max|c_i| = {np.abs(point).max():.3g})')
    return Picture(kind=kind, origin=b, frame=R, scale=scale, axis=axis, path=path,
                   traced=traced.name, label=label, label_at=label_at, screw=screw)
