"""
Every representation of one rigid transform (R, b) as plain data, and its YAML / JSON text.

(R, b) → :func:`transform_report` → :func:`to_yaml` or :func:`to_json`: the ``rot-tools``
one-shot commands and rotation_node's ``~/describe`` print this one report, so its keys are
part of the contract. Numbers are rounded before they are written (:func:`round_number`); the
writers are PyYAML and ``json``.
"""

import json
import math
import re

import numpy as np
from rot_tools.core.axis_angle import quaternion_to_rodrigues
from rot_tools.core.decomposition import decompose
from rot_tools.core.errors import RotationError
from rot_tools.core.euler import EULER_SEQUENCES, matrix_to_euler, RPY_SEQUENCE
from rot_tools.core.rigid import invert_transform, transform_points, transform_to_homogeneous
import yaml

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


def _rpy(angles, degrees):
    roll, pitch, yaw = _floats(np.degrees(angles) if degrees else angles)
    return {'roll': roll, 'pitch': pitch, 'yaw': yaw, 'unit': 'deg' if degrees else 'rad'}


def _rodrigues(quaternion):
    """Return tan(θ/2)·l̂ of the quaternion, None at θ = π (w = 0), where it is infinite."""
    try:
        return _floats(quaternion_to_rodrigues(quaternion))
    except RotationError:
        return None


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
                f"'{RPY_SEQUENCE}': every report prints them as rpy, and rotation_node publishes "
                'them on ~/rpy')
    if key in _YPR_NAMES:
        return ("; yaw, pitch, roll (about the moving z, y', x'' axes) are the intrinsic "
                "sequence 'ZYX'; every report prints them as rpy (roll, pitch, yaw), and "
                'rotation_node publishes them on ~/rpy')
    return ''


def angle_hint(angles):
    """
    Return a hint when angles typed in radians look like degrees (some |angle| > 2π), or ''.

    For the commands that read angles in radians unless told ``--deg`` (rot-tools,
    rotation_client): 'an angle of 30 rad is more than 2π: if it is in degrees, add --deg'.
    """
    size = float(np.max(np.abs(np.asarray(angles, dtype=np.float64))))
    if not size > 2.0 * np.pi:
        return ''
    return f'an angle of {size:g} rad is more than 2π: if it is in degrees, add --deg'


def transform_report(R, b=None, seq='ZYX', degrees=False, all_sequences=False, point=None):
    """
    Every representation of the rotation R (3, 3), and of (R, b) when b (3,) is given.

    R is validated as rot_tools.validate_rotation does; ``point`` (3,) adds where the motion
    takes it. Returns a dict of plain Python data, keys in this order (radians unless a key
    or ``unit`` says otherwise; ``degrees`` switches the Euler angles and rpy only):

    - matrix: R, a list of rows;
    - axis_angle: axis l̂, angle θ ∈ [0, π], angle_deg, rotation_vector θ·l̂, and
      second_solution {axis −l̂, angle 2π − θ, angle_deg} (Jia, Rotation in the Space, §3.3);
    - rodrigues: the Rodrigues (Gibbs) vector tan(θ/2)·l̂; null at θ = π, where it is infinite;
    - euler: sequence, unit, angles, degenerate (gimbal lock: θ3 = 0), and with
      ``all_sequences`` the angles and flag of each of the 24 sequences;
    - rpy: roll, pitch, yaw (REP 103: the extrinsic xyz angles, whatever ``seq``), unit;
    - quaternion: {x, y, z, w}, the canonical sign of matrix_to_quaternion;
    - with b: translation, homogeneous (4×4), screw {direction, point (closest to the
      origin), moment, angle, angle_deg, translation d, pitch d/θ};
    - with ``point`` p: point {p, image R·p + b, in_moved_frame Rᵀ·(p − b)}.

    RotationError for a bad R, b, point, or sequence.
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
            'rotation_vector': _floats(d.rotvec),
            'second_solution': {
                'axis': _floats(-d.axis),
                'angle': 2.0 * math.pi - angle,
                'angle_deg': 360.0 - _deg(angle),
            },
        },
        'rodrigues': _rodrigues(d.quaternion),
        'euler': euler,
        'rpy': _rpy(d.rpy, degrees),
        'quaternion': dict(zip('xyzw', _floats(d.quaternion))),
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
# Numbers and text


def round_number(x, precision=DEFAULT_PRECISION):
    """Round x to ``precision`` significant digits and decimal places; −0.0 → 0.0."""
    x = float(x)
    if precision is None or not math.isfinite(x):
        return x + 0.0
    x = round(x, precision)
    if x != 0.0:
        x = float(f'{x:.{precision}g}')
    return x + 0.0  # −0.0 + 0.0 == +0.0


class Exact(float):
    """A number written with every digit its float64 holds, whatever the precision (a stamp)."""


class _OneLine(dict):
    """A mapping three or more levels deep of scalars and flat lists: one line in YAML."""


def _flat(x):
    """Tell whether x is a scalar or a list of scalars."""
    return not isinstance(x, dict) and not (
        isinstance(x, list) and any(isinstance(v, (dict, list)) for v in x))


def _rounded(x, precision, non_finite, depth=0):
    """
    Return a copy of plain data ``x`` with every float rounded (:func:`round_number`).

    An :class:`Exact` is not: it keeps every digit.

    ``non_finite`` maps ±inf and NaN (``float`` keeps them, ``str`` spells them for JSON).
    NumPy scalars become Python ones; any other type is a TypeError. A mapping ``depth``
    >= 3 levels deep whose values are flat becomes a :class:`_OneLine` (JSON sees a dict).
    """
    if isinstance(x, dict):
        copy = {k: _rounded(v, precision, non_finite, depth + 1) for k, v in x.items()}
        return _OneLine(copy) if depth >= 3 and all(map(_flat, copy.values())) else copy
    if isinstance(x, (list, tuple)):
        return [_rounded(v, precision, non_finite, depth + 1) for v in x]
    if isinstance(x, (bool, np.bool_)):
        return bool(x)
    if isinstance(x, (int, np.integer)):
        return int(x)
    if isinstance(x, Exact):
        return float(x) if math.isfinite(x) else non_finite(float(x))
    if isinstance(x, (float, np.floating)):
        x = round_number(x, precision)
        return x if math.isfinite(x) else non_finite(x)
    if x is None or isinstance(x, str):
        return x
    raise TypeError(f'cannot write {type(x).__name__} {x!r}')


class _ReportDumper(yaml.SafeDumper):
    """PyYAML's safe dumper: flat lists and deep small mappings in flow style, text quoted."""


def _represent_list(dumper, data):
    return dumper.represent_sequence('tag:yaml.org,2002:seq', data, flow_style=_flat(data))


def _represent_one_line(dumper, data):
    return dumper.represent_mapping('tag:yaml.org,2002:map', data, flow_style=True)


def _represent_str(dumper, text):
    """
    Represent non-ASCII text, and text with a backslash, as a double-quoted string.

    Escapes of its characters (an ASCII terminal's) then read back as them, and every
    backslash of the document is in a double-quoted string (see ``_ASTRAL_ESCAPE``).
    """
    style = '"' if not text.isascii() or '\\' in text else None
    return dumper.represent_scalar('tag:yaml.org,2002:str', text, style=style)


_ReportDumper.add_representer(list, _represent_list)
_ReportDumper.add_representer(_OneLine, _represent_one_line)
_ReportDumper.add_representer(str, _represent_str)


# PyYAML escapes a character beyond U+FFFF in a double-quoted string (an emoji becomes
# \U0001F600) although YAML prints it: such an escape, not preceded by an escaped backslash,
# is written back as the character (only double-quoted strings hold backslashes).
_ASTRAL_ESCAPE = r'(?<!\\)((?:\\\\)*)\\U([0-9A-F]{8})'


def to_yaml(data, precision=DEFAULT_PRECISION):
    """Return a YAML document (ending in a newline) of a dict of plain data; deterministic."""
    if not isinstance(data, dict):
        raise TypeError('to_yaml takes a dict')
    text = yaml.dump(_rounded(data, precision, float), Dumper=_ReportDumper,
                     default_flow_style=False, sort_keys=False, allow_unicode=True,
                     width=math.inf)
    return re.sub(_ASTRAL_ESCAPE, lambda m: m.group(1) + chr(int(m.group(2), 16)), text)


# What json.dumps(ensure_ascii=False) leaves raw but is not printable, or not UTF-8 at all:
# DEL and the C1 controls, lone surrogates, line and paragraph separators, the byte order
# mark, U+FFFE and U+FFFF. They only occur inside strings, where \uXXXX reads back the same.
_UNPRINTABLE = '[\x7f-\x9f\ud800-\udfff\u2028\u2029\ufeff\ufffe\uffff]'


def to_json(data, precision=DEFAULT_PRECISION):
    """Return a JSON document (ending in a newline), indented by two; non-finite as strings."""
    text = json.dumps(_rounded(data, precision, str), indent=2, ensure_ascii=False,
                      allow_nan=False)
    return re.sub(_UNPRINTABLE, lambda m: f'\\u{ord(m.group()):04x}', text) + '\n'
