"""
A 3-D picture of a rigid motion with matplotlib: what ``rot-tools ... --plot FILE`` draws.

matplotlib is the optional ``plot`` extra: rot-tools imports this module only when --plot
is given. No pyplot and no display: the Figure is drawn on an Agg canvas and saved in the
format of the file's extension. The geometry is rot_tools.io.drawing's Picture.
"""

import math
import os

import matplotlib
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
import numpy as np
from rot_tools.cli import output_file
from rot_tools.io import drawing

REFERENCE_GIDS = ('reference_x', 'reference_y', 'reference_z')
MOVED_GIDS = ('moved_x', 'moved_y', 'moved_z')
AXIS_COLORS = ('tab:red', 'tab:green', 'tab:blue')

_TITLES = {drawing.IDENTITY: 'identity: nothing moves', drawing.ROTATION: 'rotation',
           drawing.TRANSLATION: 'pure translation', drawing.SCREW: 'screw motion'}


AXIS_REACH = 3.0
"""An axis farther than this many half-widths of the view from its centre is not drawn."""


def _length(v):
    """|v| without overflow (math.hypot scales)."""
    return math.hypot(*v)


def default_scale(pic):
    """
    Frame axes 1 long, or a quarter of the motion's reach if larger.

    The reach is the farthest point of the path (of a Picture drawn at scale 1) from the
    origin, |b| at least; the screw axis, however far, does not count.
    """
    if pic.path is None:
        return 1.0
    return max(1.0, 0.25 * max(_length(p) for p in pic.path))


def _vector_text(v):
    return '(' + ', '.join(f'{x + 0.0:.3g}' for x in v) + ')'


def _draw_frame(ax, origin, axes, gids, style, names):
    """Three lines origin → origin + axes[:, k], named at their tips; return their ends."""
    for k, (gid, color, name) in enumerate(zip(gids, AXIS_COLORS, names)):
        tip = origin + axes[:, k]
        ax.plot(*np.transpose([origin, tip]), color=color, gid=gid, **style)
        ax.text(*tip, name, color=color)
    return [origin, *(origin + axes.T)]


def _cube(points):
    """(centre, half-width) of the cube that holds every point with a 10 % margin."""
    points = np.asarray(points)
    low, high = points.min(axis=0), points.max(axis=0)
    return (low + high) / 2, 0.55 * (high - low).max()


def _set_equal_limits(ax, center, half):
    """Return the cube centre ± half on x, y and z: equal scales."""
    for setter, c in zip((ax.set_xlim, ax.set_ylim, ax.set_zlim), center):
        setter(c - half, c + half)
    ax.set_box_aspect((1, 1, 1))


def _draw_axis(ax, pic, drawn):
    """
    Draw the screw axis of ``pic``; return the view's (centre, half-width).

    The view is _cube(drawn), grown to hold the axis segment when the axis is near: within
    AXIS_REACH·half of the centre m (distance |(m − c) × l̂|). Far: a dotted line from m to
    the cube's face toward f, the axis point nearest m (f = c + ((m − c)·l̂)·l̂), and the
    axis's distance |c| from the origin in the legend.
    """
    center, half = _cube(drawn)
    c, u = pic.screw.point, pic.screw.direction
    name = 'rotation axis' if pic.kind == drawing.ROTATION else 'screw axis'
    label = f'{name} along {_vector_text(u)} through {_vector_text(c)}'
    away = center - c
    if _length(np.cross(away, u)) <= AXIS_REACH * half:
        ax.plot(*pic.axis.T, color='tab:orange', linewidth=1.5, gid='screw_axis', label=label)
        ax.scatter(*c, color='tab:orange', s=12)
        return _cube([*drawn, *pic.axis])
    toward = c + (away @ u) * u - center
    toward /= np.abs(toward).max()  # reaches the cube's face at half·toward
    ax.plot(*np.transpose([center, center + half * toward]), color='tab:orange',
            linewidth=1.5, linestyle=':', gid='toward_axis',
            label=f'{label},\n{_length(c):.3g} from the origin: off the view, dotted toward it')
    return center, half


def figure(R, b=None, degrees=False, scale=None):
    """
    Return the matplotlib Figure of p ↦ R·p + b (b = 0 when None).

    One 3-D axes with equal scales: the reference frame (dashed), the moved frame (solid, at
    b; x red, y green, z blue), the screw axis (orange), the path (magenta) and a title with
    θ, d and the pitch; each line has a gid (REFERENCE_GIDS, MOVED_GIDS, 'screw_axis',
    'path', 'toward_axis'), kept as the SVG element id. The view is sized by the motion,
    never by the axis (about |b|/θ away for a small turn): an axis within AXIS_REACH
    half-widths of the view's centre is drawn whole, a farther one is pointed at by a dotted
    line, its distance in the legend.

    R (3, 3) is validated (rot_tools.decompose); θ in the title is in degrees when
    ``degrees``; ``scale`` is the length of the frame axes (default: default_scale).
    """
    b = np.zeros(3) if b is None else np.asarray(b, dtype=np.float64)
    pic = drawing.picture(R, b, 1.0, degrees)
    if scale is None:
        scale = default_scale(pic)
    if scale != 1.0:
        pic = drawing.picture(R, b, scale, degrees)
    fig = Figure(figsize=(6.4, 6.4), layout='constrained')
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(projection='3d')  # matplotlib.projections registers mplot3d
    drawn = _draw_frame(ax, np.zeros(3), scale * np.eye(3), REFERENCE_GIDS,
                        {'linestyle': '--', 'linewidth': 1.2, 'alpha': 0.7}, ('x', 'y', 'z'))
    drawn += _draw_frame(ax, pic.origin, scale * pic.frame, MOVED_GIDS,
                         {'linewidth': 2.5}, ("x'", "y'", "z'"))
    ax.plot([], [], [], color='gray', linestyle='--', label='reference frame')
    ax.plot([], [], [], color='gray', linewidth=2.5, label='moved frame (columns of R, at b)')
    drawn += [] if pic.path is None else list(pic.path)
    view = _cube(drawn) if pic.axis is None else _draw_axis(ax, pic, drawn)
    if pic.path is not None:
        ax.plot(*pic.path.T, color='magenta', linewidth=2.0, gid='path',
                label=f'path of the {pic.traced}')
    ax.set_xlabel('x')
    ax.set_ylabel('y')
    ax.set_zlabel('z')
    _set_equal_limits(ax, *view)
    ax.legend(loc='upper left', fontsize='small')
    ax.set_title(f"{_TITLES[pic.kind]}\n{pic.label.replace('theta', 'θ')}")
    return fig


SVG_STYLE = {'svg.fonttype': 'none', 'svg.hashsalt': 'rot_tools'}
"""SVG text stays text (smaller than glyph paths) and ids do not vary from run to run."""


def save(R, b, path, degrees=False):
    """
    Write figure(R, b, degrees) to ``path``, in the format its extension names.

    The file carries no date, so the same motion gives the same bytes; it is written whole or
    not at all (rot_tools.cli.output_file).
    """
    fig = figure(R, b, degrees)
    kind = os.path.splitext(str(path))[1][1:].lower() or 'png'
    with matplotlib.rc_context(SVG_STYLE), output_file.complete_or_nothing(path, 'wb') as out:
        fig.savefig(out, format=kind, metadata={'Date': None} if kind == 'svg' else None)
