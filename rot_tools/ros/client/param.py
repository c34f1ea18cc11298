"""
rotation_client's parameter commands: ``set NAME VALUE``, ``param get NAME``, ``param list``.

``set`` reads VALUE as the type the node declares for NAME; ``param get`` and ``param list``
print what ``ros2 param get`` and ``ros2 param list`` print.
"""

import math
import re
import sys

from rcl_interfaces.msg import ParameterType, ParameterValue
from rclpy.parameter import parameter_value_to_python
from rot_tools.ros.client.arguments import quoted
import yaml

SMALLEST = 5e-324
"""The smallest positive double."""
LARGEST = sys.float_info.max

T = ParameterType
TYPE_NAMES = {T.PARAMETER_BOOL: 'boolean', T.PARAMETER_INTEGER: 'integer',
              T.PARAMETER_DOUBLE: 'double', T.PARAMETER_STRING: 'string',
              T.PARAMETER_BYTE_ARRAY: 'byte array', T.PARAMETER_BOOL_ARRAY: 'boolean array',
              T.PARAMETER_INTEGER_ARRAY: 'integer array',
              T.PARAMETER_DOUBLE_ARRAY: 'double array',
              T.PARAMETER_STRING_ARRAY: 'string array'}
"""Each type by its name, as ``ros2 param list --param-type`` names it."""

LABELS = {T.PARAMETER_BOOL: 'Boolean value is:', T.PARAMETER_INTEGER: 'Integer value is:',
          T.PARAMETER_DOUBLE: 'Double value is:', T.PARAMETER_STRING: 'String value is:',
          T.PARAMETER_BYTE_ARRAY: 'Byte values are:',
          T.PARAMETER_BOOL_ARRAY: 'Boolean values are:',
          T.PARAMETER_INTEGER_ARRAY: 'Integer values are:',
          T.PARAMETER_DOUBLE_ARRAY: 'Double values are:',
          T.PARAMETER_STRING_ARRAY: 'String values are:'}
"""What ``ros2 param get`` prints before a value of each type."""

FIELDS = {T.PARAMETER_BOOL: 'bool_value', T.PARAMETER_INTEGER: 'integer_value',
          T.PARAMETER_DOUBLE: 'double_value', T.PARAMETER_STRING: 'string_value',
          T.PARAMETER_BYTE_ARRAY: 'byte_array_value', T.PARAMETER_BOOL_ARRAY: 'bool_array_value',
          T.PARAMETER_INTEGER_ARRAY: 'integer_array_value',
          T.PARAMETER_DOUBLE_ARRAY: 'double_array_value',
          T.PARAMETER_STRING_ARRAY: 'string_array_value'}
"""The member of rcl_interfaces/ParameterValue that holds a value of each type."""

ELEMENTS = {T.PARAMETER_BYTE_ARRAY: T.PARAMETER_INTEGER,
            T.PARAMETER_BOOL_ARRAY: T.PARAMETER_BOOL,
            T.PARAMETER_INTEGER_ARRAY: T.PARAMETER_INTEGER,
            T.PARAMETER_DOUBLE_ARRAY: T.PARAMETER_DOUBLE,
            T.PARAMETER_STRING_ARRAY: T.PARAMETER_STRING}
"""The type of an array's elements."""

NOT_A = {T.PARAMETER_BOOL: 'true or false', T.PARAMETER_INTEGER: 'an integer',
         T.PARAMETER_DOUBLE: 'a number', T.PARAMETER_STRING: 'a string',
         T.PARAMETER_BYTE_ARRAY: 'a list of bytes (integers 0 to 255)',
         T.PARAMETER_BOOL_ARRAY: 'a list of true or false',
         T.PARAMETER_INTEGER_ARRAY: 'a list of integers',
         T.PARAMETER_DOUBLE_ARRAY: 'a list of numbers',
         T.PARAMETER_STRING_ARRAY: 'a list of strings'}
"""What a value of each type must be, in the line that refuses one that is not."""


class DoesNotFit(Exception):
    """A value typed for a parameter that is not of the parameter's type (args: why, or none)."""


def _yaml(text):
    try:
        return yaml.safe_load(text)
    except yaml.YAMLError:
        return text


def _element(kind, value):
    """Return ``value`` (read from YAML) as an element of type ``kind``; DoesNotFit if not."""
    number = isinstance(value, (int, float)) and not isinstance(value, bool)
    if kind == T.PARAMETER_BOOL and isinstance(value, bool):
        return value
    if kind == T.PARAMETER_INTEGER and number and isinstance(value, int):
        return value
    if kind == T.PARAMETER_DOUBLE and number:
        return float(value)
    if kind == T.PARAMETER_STRING and isinstance(value, str):
        return value
    raise DoesNotFit


def _double(text):
    """
    Read a double: what float() reads ('1e-2', ' 2 ', 'nan'), or YAML ('.inf').

    A number float64 rounds to 0 or to infinity is DoesNotFit, unless it was typed so.
    """
    try:
        value = float(text)
    except ValueError:
        return _element(T.PARAMETER_DOUBLE, _yaml(text))
    digits = re.split('[eE]', text)[0]
    if value == 0.0 and re.search('[1-9]', digits):
        raise DoesNotFit(f'is below the smallest double, {SMALLEST:.2g}: it would be sent as 0')
    if math.isinf(value) and 'inf' not in text.lower():
        raise DoesNotFit(f'is beyond the largest double, {LARGEST:.4g}: it would be sent as '
                         'infinity')
    return value


def typed_value(kind, text):
    """
    Return the rcl_interfaces/ParameterValue of ``text`` as a parameter of type ``kind``.

    DoesNotFit when the text is not a value of that type (see the module's docstring).
    """
    if kind == T.PARAMETER_STRING:
        value = text
    elif kind == T.PARAMETER_DOUBLE:
        value = _double(text)
    elif kind in (T.PARAMETER_BOOL, T.PARAMETER_INTEGER):
        value = _element(kind, _yaml(text))
    elif kind in ELEMENTS:
        items = _yaml(text)
        if not isinstance(items, list):
            raise DoesNotFit
        value = [_element(ELEMENTS[kind], item) for item in items]
        if kind == T.PARAMETER_BYTE_ARRAY:
            if not all(0 <= item <= 255 for item in value):
                raise DoesNotFit
            value = [bytes([item]) for item in value]
    else:
        raise DoesNotFit
    return ParameterValue(type=kind, **{FIELDS[kind]: value})


def refusal(name, target, kind, text, why=None):
    """
    Return the line for ``text`` that does not fit parameter ``name`` of type ``kind``.

    ``why``: what is wrong with it (DoesNotFit's), or None: it is not of that type.
    """
    return (f'parameter {name} of node {target} is a {TYPE_NAMES[kind]}: {quoted(text.strip())} '
            + (why or f'is not {NOT_A[kind]}'))


def python_value(value):
    """Return the Python value of a ParameterValue (a list for an array)."""
    python = parameter_value_to_python(value)
    return list(python) if value.type in ELEMENTS else python


def shown(value):
    """Return a value as set's line prints it: repr (a double not finite: nan, inf)."""
    python = python_value(value)
    if isinstance(python, float) and not math.isfinite(python):
        return str(python)
    return repr(python)


def get_line(value):
    """
    Return what ``ros2 param get`` prints of a ParameterValue: ``Double value is: 0.001``.

    Its label, a space and the value as Python prints it; an array as a list. None for a
    parameter that is not set.
    """
    if value.type not in LABELS:
        return None
    python = python_value(value)
    return f'{LABELS[value.type]} {python}'


def list_lines(names, types=None):
    """
    Return what ``ros2 param list NODE`` prints: the names sorted, each indented by 2 spaces.

    With ``types`` ({name: ParameterType}), each name followed by ``(type: double)``, as
    ``--param-type`` prints it.
    """
    if types is None:
        return [f'  {name}' for name in sorted(names)]
    return [f'  {name} (type: {TYPE_NAMES.get(types.get(name), "not set")})'
            for name in sorted(names)]
