"""Coerce and check array inputs: float64, the expected trailing shape, finite values."""

import decimal
import math
import numbers

import numpy as np
from rot_tools.core.errors import RotationError


def as_float_array(x, tail, name):
    """
    Return x as a float64 array whose shape ends in ``tail``, or raise RotationError.

    Refused: what is not numeric, complex numbers (casting would drop the imaginary part),
    dates and durations (datetime64, timedelta64: casting would give their raw counts),
    numbers beyond float64's range (Python ints, Fractions, long doubles), a wrong shape.
    """
    if type(x) is not float and (type(x) is not np.ndarray or x.dtype.kind not in 'fiub'):
        x = _numeric_array(x, name)
    try:
        arr = np.asarray(x, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise RotationError(f'{name} must be numeric: {exc}') from None
    if arr.shape[arr.ndim - len(tail):] != tail or arr.ndim < len(tail):
        want = '(..., ' + ', '.join(map(str, tail)) + ')' if tail else 'any shape'
        raise RotationError(f'{name} must have shape {want}, got {arr.shape}')
    return arr


def _numeric_array(x, name):
    """
    Return x as an array of real numbers within float64's range (any dtype), or raise.

    For inputs that are not already a real NumPy array: nested lists of Python numbers,
    complex arrays, objects. NumPy's own cast would drop an imaginary part with only a
    ComplexWarning and raise OverflowError for a Python int beyond float64.
    """
    try:
        arr = np.asarray(x)
    except (TypeError, ValueError, OverflowError) as exc:
        raise RotationError(f'{name} must be numeric: {exc}') from None
    if arr.dtype.kind == 'c':
        return _refuse_complex(arr, name)
    if arr.dtype.kind in 'mM':  # NumPy would cast dates and durations to their raw counts
        raise RotationError(f'{name} must be numbers, got {arr.dtype} values: seconds are '
                            'needed, e.g. (t - t[0]) / np.timedelta64(1, "s")')
    if arr.dtype.kind == 'O':  # Python ints beyond int64, Fractions, complex in a list, ...
        flat = arr.ravel().tolist()
        for v in flat:
            if isinstance(v, (complex, np.complexfloating)):
                _refuse_complex(np.asarray(v), name)
        try:
            out = np.array(flat, dtype=np.float64).reshape(arr.shape)
        except OverflowError:
            big = next(v for v in flat if _overflows(v))
            raise RotationError(f'{name} must be numeric within float64 (±1.8e308), got '
                                f'{_short(big)}') from None
        except (TypeError, ValueError) as exc:
            raise RotationError(f'{name} must be numeric: {exc}') from None
        return out
    if arr.dtype.kind == 'f' and arr.dtype.itemsize > 8:  # long double: may not fit
        with np.errstate(over='ignore'):
            out = arr.astype(np.float64)
        beyond = np.isinf(out) & np.isfinite(arr)
        if beyond.any():
            raise RotationError(f'{name} must be numeric within float64 (±1.8e308), got '
                                f'{arr[beyond].flat[0]!r}')
        return out
    return arr


def _overflows(v):
    try:
        float(v)
    except OverflowError:
        return True
    except (TypeError, ValueError):
        pass
    return False


def _short(v):
    """Write a huge number short enough for a message: 1e+400 rather than 401 digits."""
    text = str(v)
    if len(text) <= 30:
        return text
    sign = '-' if text.startswith('-') else ''
    digits = len(text.lstrip('-').split('/')[0]) - 1
    return f'{sign}{text.lstrip("-")[0]}.{text.lstrip("-")[1:3]}e+{digits}'


def _refuse_complex(arr, name):
    imag = np.abs(arr.imag)
    first = arr.ravel()[int(np.argmax(imag.ravel() != 0))] if imag.any() else arr.ravel()[0]
    raise RotationError(f'{name} must be real, got complex numbers (e.g. {complex(first)}): '
                        'take the real part or the modulus yourself')


def require_finite(arr, name):
    """Raise RotationError naming how many entries of arr are NaN/Inf and where the first is."""
    if arr.size <= 16 and all(map(math.isfinite, arr.ravel().tolist())):
        return arr  # one item: plain floats are quicker than np.isfinite here
    finite = np.isfinite(arr)
    if not finite.all():
        bad = np.argwhere(~finite)
        first = tuple(int(i) for i in bad[0])
        raise RotationError(
            f'{name} must be finite: {len(bad)} non-finite value(s), '
            f'first {arr[first]} at index {first}')
    return arr


def finite_array(x, tail, name):
    """as_float_array followed by require_finite."""
    return require_finite(as_float_array(x, tail, name), name)


def require_tolerance(value, name, below=math.inf, interval=''):
    """
    Return ``value`` as a float if it is a real number in [0, below), else raise RotationError.

    Any real numeric type is taken (int, float, Fraction, Decimal, NumPy scalars, a 0-d
    array); complex numbers, bools, NaN and numbers beyond float64 are refused. The message
    says '<name> must be a number ≥ 0', or with a bound '<name> must be in <interval>' (the
    interval as written for people, e.g. '[0, π/4) rad').
    """
    number = None
    if isinstance(value, np.ndarray) and value.ndim == 0 and value.dtype.kind in 'iuf':
        value = value[()]
    if (isinstance(value, (numbers.Real, decimal.Decimal))
            and not isinstance(value, (bool, np.bool_))):
        try:
            number = float(value)
        except (OverflowError, ValueError):
            number = None
    if number is not None and 0 <= number < below:
        return number
    bound = 'a number ≥ 0' if below == math.inf else f'in {interval}'
    shown = _short(value) if isinstance(value, (int, numbers.Rational)) else repr(value)
    raise RotationError(f'{name} must be {bound}, got {shown}')


def refuse_overflow(fits, what):
    """
    Raise RotationError where the flag ``fits`` (bool or bool array) is false.

    what: the quantity that left float64's range, e.g. 'R·p + b'; the message adds the
    first offending item of a batch.
    """
    if fits.ndim == 0:
        if not fits:
            raise RotationError(f'{what} overflows float64 (beyond ±1.8e308)')
    elif not fits.all():
        first = tuple(int(i) for i in np.argwhere(~fits)[0])
        raise RotationError(f'{what} overflows float64 (beyond ±1.8e308), first at item {first}')


def apart(big, small, digits=(3, 6)):
    """
    Write (big, small) as text with digits[0] and digits[1] significant digits.

    3 for a measured size, 6 = :g for a tolerance; more where fewer would not show
    big > small: not '|cos| = 1 > tol 1' for 1 > 0.99999999. Equal numbers (or NaN) keep the
    given digits.
    """
    for extra in range(15):
        shown, bound = f'{big:.{digits[0] + extra}g}', f'{small:.{digits[1] + extra}g}'
        if float(shown) > float(bound) or not big > small:
            return shown, bound
    return repr(float(big)), repr(float(small))
