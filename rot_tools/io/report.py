"""
Every representation of one rigid transform (R, b) as plain data, and its YAML / JSON text.

The data takes one path: (R, b) → :func:`transform_report` → :func:`to_yaml` or
:func:`to_json`. The ``rot-tools`` command line and the node's ``~/describe`` service print
the same report, so the key names below are part of the contract; they never depend on
options. Radians unless a key or ``unit`` says otherwise; lengths in the unit of b.

``transform_report(R, b=None, seq='ZYX', degrees=False, all_sequences=False, point=None)``
returns a dict of plain Python data (float, bool, str, list, dict; no NumPy types), keys in
this order::

    matrix:            [[r11, r12, r13], [r21, r22, r23], [r31, r32, r33]]   (list of rows)
    axis_angle:
      axis:            unit l̂ (at angle 0 it is [0, 0, 1])
      angle:           θ ∈ [0, π], rad
      angle_deg:       θ in degrees
      rotation_vector: θ·l̂, rad
      second_solution: the same rotation the other way round (Jia, Rotation in the Space,
                       §3.3: about −l̂ through −θ), as
                       {axis: −l̂, angle: 2π − θ, angle_deg: 360 − θ°}
    euler:
      sequence:        e.g. ZYX (upper case intrinsic, lower case extrinsic)
      unit:            rad | deg (``degrees``)
      angles:          [θ1, θ2, θ3]
      degenerate:      true at gimbal lock (then θ3 = 0 and θ1 carries the free angle)
      all_sequences:   only with ``all_sequences=True``: for each of the 24 sequences,
                       in rot_tools.EULER_SEQUENCES order, {angles: [...], degenerate: ...}
    rpy:               roll, pitch, yaw (REP 103): the rotations about the fixed x, y, z axes,
                       i.e. the Euler angles of the extrinsic sequence xyz, whatever ``seq``
                       is (at gimbal lock, pitch ±90°, yaw = 0 and roll carries the free angle)
      roll:            about x
      pitch:           about y (an angle, not the screw pitch below)
      yaw:             about z
      unit:            rad | deg, as euler.unit
    quaternion:        {x, y, z, w}: the unit quaternion of R in the ROS message order
                       (geometry_msgs/Quaternion), canonical sign (w > 0; at w = 0 the first
                       non-zero of x, y, z positive), from rot_tools.matrix_to_quaternion
    translation:       b = [x, y, z] (only when b is given)
    homogeneous:       only when b is given: the 4×4 matrix [[R, b], [0, 0, 0, 1]] of
                       p ↦ R·p + b, list of rows (rot_tools.transform_to_homogeneous)
    screw:             only when b is given (Chasles: rotation θ about the line through
                       ``point`` along ``direction``, then ``translation`` along it)
      direction:       unit l̂
      point:           the axis point closest to the origin (⊥ l̂)
      moment:          point × direction (Plücker)
      angle:           θ ∈ [0, π], rad
      angle_deg:       θ in degrees
      translation:     d, signed, along l̂
      pitch:           the screw pitch d/θ (length per rad; not rpy's pitch); inf for a pure
                       translation, 0 for the identity
    point:             only when ``point`` p (3,) is given (b = 0 when b is not)
      p:               the point as given, in the reference frame
      image:           R·p + b, where the motion takes it (rot_tools.transform_points)
      in_moved_frame:  Rᵀ·(p − b), its coordinates in the moved frame (Jia §4: q' = Rᵀq;
                       transform_points of invert_transform)

``degrees`` only switches the Euler angles (``euler.unit``); axis-angle and screw angles
always come in both ``angle`` (rad) and ``angle_deg``.

Text forms. Numbers are rounded to ``precision`` significant digits *and* decimal places
(default 12), so rounding noise such as 6.1e-17 prints as 0.0; −0.0 prints as 0.0;
``precision=None`` keeps full float precision.

- :func:`to_yaml`: a small deterministic emitter (no PyYAML needed), readable by any YAML
  1.1/1.2 parser. Mappings in block style, lists of scalars as flow lists
  ``[0.0, 0.0, 1.0]``, a matrix as a block list of flow rows; a mapping nested two or more
  levels deep whose values are all scalars or flat lists is written in flow style
  (``{axis: [...], angle: ...}``). Floats always carry a dot (``1.0e-05``), infinities
  and NaN are ``.inf``, ``-.inf``, ``.nan``; strings are quoted when YAML would read them
  as something else.
- :func:`to_json`: the same structure; JSON has no infinity, so ``inf``, ``-inf`` and
  ``nan`` are written as the strings ``"inf"``, ``"-inf"``, ``"nan"`` (Python's
  ``float()`` reads them back).
"""

import json
import math
import re

import numpy as np
from rot_tools.core.decomposition import decompose, RPY_SEQUENCE
from rot_tools.core.errors import RotationError
from rot_tools.core.euler import EULER_SEQUENCES, matrix_to_euler
from rot_tools.core.rigid import invert_transform, transform_points, transform_to_homogeneous
from rot_tools.core.so3 import matrix_to_quaternion

DEFAULT_PRECISION = 12
"""Significant digits and decimal places of printed numbers."""


def _floats(a):
    """Return a NumPy array (or scalar) as nested lists of Python floats."""
    return np.asarray(a, dtype=np.float64).tolist()


def _deg(rad):
    return float(np.degrees(rad))


def _euler(angles, degenerate, degrees):
    angles = np.degrees(angles) if degrees else angles
    return {'angles': _floats(angles), 'degenerate': bool(degenerate)}


def _rpy(R, degrees):
    angles, _ = matrix_to_euler(R, RPY_SEQUENCE, check=False)  # (validated by decompose)
    roll, pitch, yaw = _floats(np.degrees(angles) if degrees else angles)
    return {'roll': roll, 'pitch': pitch, 'yaw': yaw, 'unit': 'deg' if degrees else 'rad'}


_RPY_NAMES = {'rpy', 'rollpitchyaw'}
_YPR_NAMES = {'ypr', 'yawpitchroll'}


def sequence_hint(name):
    """
    Return a hint for a sequence name that means roll, pitch, yaw ('RPY', 'YPR'), or ''.

    No Euler sequence is spelt with the letters R, P, Y; people who type them mean
    REP 103's roll, pitch, yaw. For the messages that refuse such a name (rot-tools,
    rotation_node's euler_sequence, rotation_client), after a semicolon.
    """
    key = ''.join(c for c in str(name).lower() if c.isalpha())
    if key in _RPY_NAMES:
        return ('; roll, pitch, yaw (about the fixed x, y, z axes) are the extrinsic sequence '
                "'xyz': every report prints them as rpy, and rotation_node publishes them on "
                '~/rpy')
    if key in _YPR_NAMES:
        return ("; yaw, pitch, roll (about the moving z, y', x'' axes) are the intrinsic "
                "sequence 'ZYX'; every report prints them as rpy (roll, pitch, yaw), and "
                'rotation_node publishes them on ~/rpy')
    return ''


def transform_report(R, b=None, seq='ZYX', degrees=False, all_sequences=False, point=None):
    """
    Every representation of the rotation R (3, 3), and of (R, b) when b (3,) is given.

    R is validated as rot_tools.validate_rotation does (tol 1e-9); project a matrix typed
    with few digits with rot_tools.nearest_rotation first. ``point`` (3,) adds where the
    motion takes it and its coordinates in the moved frame. Returns the dict described in
    the module docstring. RotationError for a bad R, b, point, or sequence.
    """
    R = np.asarray(R, dtype=np.float64)
    if R.shape != (3, 3):
        raise RotationError(f'transform_report takes one rotation (3, 3), got {R.shape}')
    if b is not None and np.shape(b) != (3,):
        raise RotationError(f'translation b must have shape (3,), got {np.shape(b)}')
    if point is not None and np.shape(point) != (3,):
        raise RotationError(f'point p must have shape (3,), got {np.shape(point)}')
    motion = (R, np.zeros(3) if b is None else b)
    d = decompose(*motion, seq)
    angle = float(d.angle)
    euler = {'sequence': seq, 'unit': 'deg' if degrees else 'rad',
             **_euler(d.euler, d.degenerate, degrees)}
    if all_sequences:
        euler['all_sequences'] = {
            name: _euler(*matrix_to_euler(R, name, check=False), degrees)
            for name in EULER_SEQUENCES}
    report = {
        'matrix': _floats(R),
        'axis_angle': {
            'axis': _floats(d.axis),
            'angle': angle,
            'angle_deg': _deg(angle),
            'rotation_vector': _floats(d.axis * angle),
            'second_solution': {
                'axis': _floats(-d.axis),
                'angle': 2.0 * math.pi - angle,
                'angle_deg': 360.0 - _deg(angle),
            },
        },
        'euler': euler,
        'rpy': _rpy(R, degrees),
        # R was validated by decompose above.
        'quaternion': dict(zip('xyzw', _floats(matrix_to_quaternion(R, check=False)))),
    }
    if b is not None:
        screw = d.screw
        report['translation'] = _floats(b)
        report['homogeneous'] = _floats(transform_to_homogeneous(*motion, check=False))
        report['screw'] = {
            'direction': _floats(screw.direction),
            'point': _floats(screw.point),
            'moment': _floats(screw.moment),
            'angle': float(screw.angle),
            'angle_deg': _deg(screw.angle),
            'translation': float(screw.translation),
            'pitch': float(screw.pitch),
        }
    if point is not None:
        report['point'] = {
            'p': _floats(point),
            'image': _floats(transform_points(*motion, point, check=False)),
            'in_moved_frame': _floats(transform_points(
                *invert_transform(*motion, check=False), point, check=False)),
        }
    return report


# ---------------------------------------------------------------------------------------
# Numbers


def round_number(x, precision=DEFAULT_PRECISION):
    """Round x to ``precision`` significant digits and decimal places; −0.0 → 0.0."""
    x = float(x)
    if precision is None or not math.isfinite(x):
        return x + 0.0
    x = round(x, precision)
    if x != 0.0:
        x = float(f'{x:.{precision}g}')
    return x + 0.0  # −0.0 + 0.0 == +0.0


def _float_text(x):
    """Return repr(x) with a dot in the mantissa (YAML 1.1 reads 1e-05 as text)."""
    s = repr(x)
    if 'e' in s and '.' not in s:
        s = s.replace('e', '.0e')
    return s


# ---------------------------------------------------------------------------------------
# YAML

_PLAIN = re.compile(r'[A-Za-z_/][A-Za-z0-9_./ -]*\Z')
# Words YAML parsers read as booleans or null. A bare y or n stays a string for PyYAML
# (which ros2cli uses) and is how `ros2 topic echo` writes a quaternion's y, so a report's
# quaternion block pastes into `ros2 topic pub`.
_YAML_WORDS = frozenset('yes no true false on off null ~'.split())

# Characters of a string written escaped (YAML double-quoted scalar, JSON string): what
# YAML does not allow printed (C0 and C1 controls, DEL, lone surrogates, U+FFFE, U+FFFF),
# line and paragraph separators (YAML folds them) and the byte order mark. Everything else,
# emoji and accents included, is written as itself: json.dumps's ASCII escapes write a
# character beyond U+FFFF as a surrogate pair, which YAML reads as two lone surrogates.
_ESCAPED = re.compile('[^\x20-\x7e\xa0-\ud7ff\ue000-\ufefe\uff00-\ufffd'
                      '\U00010000-\U0010ffff]|[\u2028\u2029]')
_YAML_ESCAPED = re.compile(_ESCAPED.pattern + '|["\\\\]')
_SHORT_ESCAPES = {'"': '\\"', '\\': '\\\\', '\t': '\\t', '\n': '\\n', '\r': '\\r'}


def _escape(match):
    c = match.group()
    if c in _SHORT_ESCAPES:
        return _SHORT_ESCAPES[c]
    code = ord(c)
    return f'\\x{code:02x}' if code < 0x100 else (
        f'\\u{code:04x}' if code < 0x10000 else f'\\U{code:08x}')


def _yaml_string(text):
    """``text`` as a YAML double-quoted scalar: printable characters as themselves."""
    return '"' + _YAML_ESCAPED.sub(_escape, text) + '"'


def _json_string(text):
    r"""Return ``text`` as a JSON string: printable characters as is, the rest \uXXXX."""
    return _ESCAPED.sub(lambda m: f'\\u{ord(m.group()):04x}',
                        json.dumps(text, ensure_ascii=False))


def _yaml_scalar(x, precision):
    if x is None:
        return 'null'
    if isinstance(x, (bool, np.bool_)):
        return 'true' if x else 'false'
    if isinstance(x, (int, np.integer)):
        return str(int(x))
    if isinstance(x, (float, np.floating)):
        x = round_number(x, precision)
        if math.isnan(x):
            return '.nan'
        if math.isinf(x):
            return '.inf' if x > 0 else '-.inf'
        return _float_text(x)
    if isinstance(x, str):
        if _PLAIN.match(x) and not x.endswith(' ') and x.lower() not in _YAML_WORDS:
            return x
        return _yaml_string(x)
    raise TypeError(f'to_yaml: cannot write {type(x).__name__} {x!r}')


def _is_scalar(x):
    return not isinstance(x, (dict, list, tuple))


def _is_flat(x):
    return isinstance(x, (list, tuple)) and all(_is_scalar(v) for v in x)


def _yaml_flow(x, precision):
    if isinstance(x, dict):
        return '{' + ', '.join(
            f'{_yaml_scalar(k, precision)}: {_yaml_flow(v, precision)}'
            for k, v in x.items()) + '}'
    if isinstance(x, (list, tuple)):
        return '[' + ', '.join(_yaml_flow(v, precision) for v in x) + ']'
    return _yaml_scalar(x, precision)


def _yaml_value(x, indent, depth, precision):
    """(inline text, following block lines) of x as the value of a key or list item."""
    if _is_scalar(x) or _is_flat(x) or not x:
        return _yaml_flow(x, precision), []
    if isinstance(x, dict) and depth >= 3 and all(
            _is_scalar(v) or _is_flat(v) for v in x.values()):
        return _yaml_flow(x, precision), []
    return None, _yaml_block(x, indent, depth, precision)


def _yaml_block(x, indent, depth, precision):
    pad = '  ' * indent
    lines = []
    if isinstance(x, dict):
        for k, v in x.items():
            inline, block = _yaml_value(v, indent + 1, depth + 1, precision)
            key = _yaml_scalar(k, precision)
            lines.append(f'{pad}{key}: {inline}' if inline is not None else f'{pad}{key}:')
            lines.extend(block)
    else:
        for v in x:
            inline, block = _yaml_value(v, indent + 1, depth + 1, precision)
            if inline is not None:
                lines.append(f'{pad}- {inline}')
            else:  # the nested block starts on the dash line
                lines.append(f'{pad}- {block[0].lstrip()}')
                lines.extend(block[1:])
    return lines


def to_yaml(data, precision=DEFAULT_PRECISION):
    """Return a YAML document (ending in a newline) of a dict of plain data; deterministic."""
    if not isinstance(data, dict):
        raise TypeError('to_yaml takes a dict')
    if not data:
        return '{}\n'
    return '\n'.join(_yaml_block(data, 0, 0, precision)) + '\n'


# ---------------------------------------------------------------------------------------
# JSON


def _json_scalar(x, precision):
    if isinstance(x, (float, np.floating)):
        x = round_number(x, precision)
        if not math.isfinite(x):
            return json.dumps(str(x))  # "inf", "-inf", "nan"
        return _float_text(x)
    if isinstance(x, (bool, np.bool_)):
        return 'true' if x else 'false'
    if isinstance(x, (int, np.integer)):
        return str(int(x))
    if x is None:
        return 'null'
    if isinstance(x, str):
        return _json_string(x)
    raise TypeError(f'to_json: cannot write {type(x).__name__} {x!r}')


def _json(x, indent, precision):
    if _is_scalar(x):
        return _json_scalar(x, precision)
    if _is_flat(x) or not x:
        inner = ', '.join(_json_scalar(v, precision) for v in x)
        return '[' + inner + ']' if isinstance(x, (list, tuple)) else '{}'
    pad = '  ' * (indent + 1)
    if isinstance(x, dict):
        items = [f'{pad}{_json_string(str(k))}: {_json(v, indent + 1, precision)}'
                 for k, v in x.items()]
        return '{\n' + ',\n'.join(items) + '\n' + '  ' * indent + '}'
    items = [f'{pad}{_json(v, indent + 1, precision)}' for v in x]
    return '[\n' + ',\n'.join(items) + '\n' + '  ' * indent + ']'


def to_json(data, precision=DEFAULT_PRECISION):
    """Return a JSON document (ending in a newline); lists of numbers on one line."""
    return _json(data, 0, precision) + '\n'
