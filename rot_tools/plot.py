"""A 3-D picture of a rigid motion with matplotlib: what ``rot-tools ... --plot FILE`` draws.

matplotlib is the optional ``plot`` extra (``pip install 'rot_tools[plot]'``); this module
imports it, so rot-tools imports this module only when --plot is given. It uses no pyplot
and no display: the Figure is drawn on an Agg canvas and saved by the file's extension
(PNG, SVG, or any other format matplotlib writes).

The geometry is rot_tools.drawing's :class:`~rot_tools.drawing.Picture`, the same that
rotation_node's ``~/markers`` shows in RViz. In one 3-D axes with equal scales on x, y and
z: the reference frame (dashed, at the origin), the moved frame (solid, at b, its axes the
columns of R; x red, y green, z blue), the screw axis through its point c (orange; for a pure
rotation the rotation axis), the path (magenta: the helix of the origin, the arc of an axis
tip for a pure rotation, the straight path for a pure translation) and a title with θ, d and
the pitch. Every drawn line has a gid (REFERENCE_GIDS, MOVED_GIDS, 'screw_axis', 'path'),
which SVG keeps as the element id.
"""

import math

import matplotlib
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
import numpy as np

from rot_tools import drawing

REFERENCE_GIDS = ('reference_x', 'reference_y', 'reference_z')
MOVED_GIDS = ('moved_x', 'moved_y', 'moved_z')
AXIS_COLORS = ('tab:red', 'tab:green', 'tab:blue')

_TITLES = {drawing.IDENTITY: 'identity: nothing moves', drawing.ROTATION: 'rotation',
           drawing.TRANSLATION: 'pure translation', drawing.SCREW: 'screw motion'}


def default_scale(b, point):
    """Frame axes 1 long, or a quarter of the motion's extent max(|b|, |c|) if larger."""
    return max(1.0, 0.25 * max(math.hypot(*b), math.hypot(*point)))  # hypot: no overflow


def _vector_text(v):
    return '(' + ', '.join(f'{x + 0.0:.3g}' for x in v) + ')'


def _draw_frame(ax, origin, axes, gids, style, names):
    """Three lines origin → origin + axes[:, k], named at their tips; return their ends."""
    for k, (gid, color, name) in enumerate(zip(gids, AXIS_COLORS, names)):
        tip = origin + axes[:, k]
        ax.plot(*np.transpose([origin, tip]), color=color, gid=gid, **style)
        ax.text(*tip, name, color=color)
    return [origin, *(origin + axes.T)]


def _set_equal_limits(ax, points):
    """Limits that hold every point in a cube: equal scales on x, y and z."""
    points = np.asarray(points)
    low, high = points.min(axis=0), points.max(axis=0)
    center, half = (low + high) / 2, 0.55 * (high - low).max()
    for setter, c in zip((ax.set_xlim, ax.set_ylim, ax.set_zlim), center):
        setter(c - half, c + half)
    ax.set_box_aspect((1, 1, 1))


def figure(R, b=None, degrees=False, scale=None):
    """The matplotlib Figure of p ↦ R·p + b (b = 0 when None); see the module docstring.

    R (3, 3) is validated (rot_tools.decompose); θ in the title is in degrees when
    ``degrees``; ``scale`` is the length of the frame axes (default: default_scale).
    """
    b = np.zeros(3) if b is None else np.asarray(b, dtype=np.float64)
    pic = drawing.picture(R, b, 1.0, degrees)
    if scale is None:
        scale = default_scale(b, pic.screw.point)
    if scale != 1.0:
        pic = drawing.picture(R, b, scale, degrees)
    fig = Figure(figsize=(6.4, 6.4), layout='constrained')
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(projection='3d')  # matplotlib.projections registers mplot3d
    drawn = _draw_frame(ax, np.zeros(3), scale * np.eye(3), REFERENCE_GIDS,
                        dict(linestyle='--', linewidth=1.2, alpha=0.7), ('x', 'y', 'z'))
    drawn += _draw_frame(ax, pic.origin, scale * pic.frame, MOVED_GIDS,
                         dict(linewidth=2.5), ("x'", "y'", "z'"))
    ax.plot([], [], [], color='gray', linestyle='--', label='reference frame')
    ax.plot([], [], [], color='gray', linewidth=2.5, label='moved frame (columns of R, at b)')
    if pic.axis is not None:
        c = pic.screw.point
        name = 'rotation axis' if pic.kind == drawing.ROTATION else 'screw axis'
        ax.plot(*pic.axis.T, color='tab:orange', linewidth=1.5, gid='screw_axis',
                label=f'{name} along {_vector_text(pic.screw.direction)} '
                f'through {_vector_text(c)}')
        ax.scatter(*c, color='tab:orange', s=12)
        drawn += list(pic.axis)
    if pic.path is not None:
        ax.plot(*pic.path.T, color='magenta', linewidth=2.0, gid='path',
                label=f'path of the {pic.traced}')
        drawn += list(pic.path)
    ax.set_xlabel('x')
    ax.set_ylabel('y')
    ax.set_zlabel('z')
    _set_equal_limits(ax, drawn)
    ax.legend(loc='upper left', fontsize='small')
    ax.set_title(f"{_TITLES[pic.kind]}\n{pic.label.replace('theta', 'θ')}")
    return fig


SVG_STYLE = {'svg.fonttype': 'none', 'svg.hashsalt': 'rot_tools'}
"""SVG text stays text (a third of the size of glyph paths) and ids do not vary by run."""


def save(R, b, path, degrees=False):
    """Write figure(R, b, degrees) to ``path``, in the format its extension names.

    The file carries no date, so the same motion gives the same bytes.
    """
    fig = figure(R, b, degrees)
    with matplotlib.rc_context(SVG_STYLE):
        fig.savefig(path, metadata={'Date': None} if str(path).lower().endswith('.svg')
                    else None)
