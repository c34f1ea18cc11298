"""Coerce and check array inputs: float64, the expected trailing shape, finite values."""

import math
import numbers

import numpy as np

from rot_tools.errors import RotationError


def as_float_array(x, tail, name):
    """Return x as a float64 array whose shape ends in ``tail``, or raise RotationError."""
    try:
        arr = np.asarray(x, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise RotationError(f'{name} must be numeric: {exc}') from None
    if arr.shape[arr.ndim - len(tail):] != tail or arr.ndim < len(tail):
        want = '(..., ' + ', '.join(map(str, tail)) + ')' if tail else 'any shape'
        raise RotationError(f'{name} must have shape {want}, got {arr.shape}')
    return arr


def require_finite(arr, name):
    """Raise RotationError naming how many entries of arr are NaN/Inf and where the first is."""
    if arr.size <= 16 and all(map(math.isfinite, arr.ravel().tolist())):
        return arr  # one item: plain floats are ~3x quicker than np.isfinite here
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
    """Return ``value`` if it is a real number in [0, below), else raise RotationError.

    The message says '<name> must be a number ≥ 0', or with a bound '<name> must be in
    <interval>' (the interval as written for people, e.g. '[0, π/4) rad').
    """
    if (isinstance(value, numbers.Real) and not isinstance(value, (bool, np.bool_))
            and 0 <= value < below):
        return value
    bound = 'a number ≥ 0' if below == math.inf else f'in {interval}'
    raise RotationError(f'{name} must be {bound}, got {value!r}')


def refuse_overflow(fits, what):
    """Raise RotationError where the flag ``fits`` (bool or bool array) is false.

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
    """(big, small) as text with digits[0] and digits[1] significant digits (3 for a measured
    size, 6 = :g for a tolerance), more where fewer would not show big > small: not
    '|cos| = 1 > tol 1' for 1 > 0.99999999. Equal numbers (or NaN) keep the given digits."""
    for extra in range(15):
        shown, bound = f'{big:.{digits[0] + extra}g}', f'{small:.{digits[1] + extra}g}'
        if float(shown) > float(bound) or not big > small:
            return shown, bound
    return repr(float(big)), repr(float(small))
