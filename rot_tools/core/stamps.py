"""
The stamps of a stream of poses: checked, put in order, their steps, and pairs Δ apart.

Stamps are seconds (float64) or, where exactness matters (bags), integer nanoseconds.
"""

import decimal
import math
import numbers
from typing import Any, NamedTuple

import numpy as np
from rot_tools.core._arrays import finite_array, require_tolerance
from rot_tools.core.errors import RotationError

MAX_POSES = 1 << 28
"""Poses a count may name at most (delta_pairs): the pairs of more would not fit in memory."""

MIN_PERIOD = 1e-9
"""The median step of a stream's stamps at least (s): a nanosecond, ROS stamps' resolution."""

MODE_SHARE = 0.1
"""Share of the steps each group holds at least, for steps to fall into two groups."""

MODE_SEPARATION = 0.05
"""Distance between the two groups of steps at least, as a share of the period."""

MODE_CLEARANCE = 4.0
"""Distance between the two groups of steps at least, in their own spreads."""


def plain(x):
    """
    Write a number as messages show it: a plain decimal, the shortest that reads back the same.

    1311868229.576, 1e-07, 3 — never np.float64(...) nor a 300-digit expansion.
    """
    if isinstance(x, (int, np.integer)) and not isinstance(x, (bool, np.bool_)):
        if abs(x) < 10 ** 16:
            return str(int(x))
        try:
            return repr(float(x))
        except OverflowError:  # beyond float64: its leading digits and exponent
            return f'{decimal.Decimal(int(x)):.3e}'
    return repr(float(x))


def checked_stamps(stamps, name, least):
    """Return stamps (N,) as float64, finite and strictly increasing, N ≥ least; else raise."""
    t = finite_array(stamps, (), name)
    if t.ndim != 1:
        raise RotationError(f'{name} must have shape (N,), got {t.shape}')
    if len(t) < least:
        raise RotationError(f'{name} has {len(t)} stamp(s): at least {least} needed')
    back = t[1:] <= t[:-1]  # compared, not subtracted: t_k+1 − t_k may overflow
    if back.any():
        k = int(np.argmax(back))
        raise RotationError(f'{name} must be strictly increasing: {name}[{k + 1}] = '
                            f'{plain(t[k + 1])} follows {name}[{k}] = {plain(t[k])}')
    with np.errstate(over='ignore'):
        span = t[-1] - t[0] if len(t) else 0.0
    if not math.isfinite(span):
        raise RotationError(f'{name} span {plain(t[0])} to {plain(t[-1])} s: their '
                            'differences overflow float64')
    return t


class StampSteps(NamedTuple):
    """
    The steps between a stream's stamps (stamp_steps).

    period: the median step (s); spread: the standard deviation of the steps within half a
    period of it (s: gaps left out; 0 within the stamps' rounding); rate: 1/period (Hz);
    arrival_time: the steps fall into two groups (stamps taken as messages arrive, in the
    bursts a driver reads them in, rather than by the sensor's clock); modes: the two groups'
    median steps (s), or None.
    """

    period: float
    spread: float
    rate: float
    arrival_time: bool
    modes: Any


def _spread(steps):
    """Return 1.4826 × the median absolute deviation of steps (s): a group's robust spread."""
    return 1.4826 * float(np.median(np.abs(steps - np.median(steps))))


def stamp_steps(stamps):
    """
    Return the StampSteps of stamps (N,) in increasing order (seconds), N ≥ 2.

    Two groups: of the steps within half a period of the median, sorted, split at their
    largest jump between the MODE_SHARE and 1 − MODE_SHARE quantiles; the groups' medians at
    least MODE_SEPARATION·period and MODE_CLEARANCE times the larger group's spread apart.
    RotationError for a median step under MIN_PERIOD.
    """
    t = np.asarray(stamps, dtype=np.float64)
    with np.errstate(over='ignore'):
        steps = np.diff(t)
    if len(steps) < 1 or not np.isfinite(steps).all():
        raise RotationError(f'stamps need 2 finite steps at least, got {len(steps)}' if
                            len(steps) < 1 else 'the steps between the stamps overflow float64')
    period = float(np.median(steps))
    if not period >= MIN_PERIOD:
        raise RotationError(f'the median step is {period:.3g} s: under '
                            f'{MIN_PERIOD:g} s, the resolution of ROS stamps')
    near = np.sort(steps[np.abs(steps - period) <= period / 2])
    least = int(math.ceil(MODE_SHARE * len(near)))
    modes, arrival = None, False
    if least >= 2 and len(near) - 2 * least >= 1:
        jumps = np.diff(near[least - 1:len(near) - least + 1])
        cut = least + int(np.argmax(jumps))
        low, high = near[:cut], near[cut:]
        gap = float(np.median(high) - np.median(low))
        if gap >= MODE_SEPARATION * period and gap >= MODE_CLEARANCE * max(
                _spread(low), _spread(high)):
            modes, arrival = (float(np.median(low)), float(np.median(high))), True
    spread = float(np.std(near))
    rounding = 4 * np.finfo(float).eps * max(abs(t[0]), abs(t[-1]))
    return StampSteps(period=period, spread=spread if spread > rounding else 0.0, rate=1 / period,
                      arrival_time=arrival, modes=modes)


class StampOrder(NamedTuple):
    """
    A stream's samples to keep, in time order (order_stamps).

    index (K,): into the stamps as given; dropped_duplicates: samples left out because an
    earlier one has the same stamp; reordered: samples stamped earlier than one before them.
    """

    index: np.ndarray
    dropped_duplicates: int
    reordered: int


def order_stamps(stamps):
    """
    Put the samples of a stream in time order, as files and bags give them.

    stamps (N,): finite numbers in any order (seconds as floats, or integer nanoseconds:
    integers are compared as they are). The samples are sorted by stamp, stably (equal stamps
    keep their order), and of each run of equal stamps the first is kept (as evo's matching
    takes the first of equal stamps). Returns StampOrder(index, dropped_duplicates,
    reordered); index is sorted and strictly increasing in stamp: t[index] satisfies the
    other functions of this module.
    """
    given = stamps if isinstance(stamps, np.ndarray) else np.asarray(stamps)
    if given.dtype.kind in 'iu' and given.ndim == 1:
        t = given
    else:
        t = finite_array(stamps, (), 'stamps')
        if t.ndim != 1:
            raise RotationError(f'stamps must have shape (N,), got {t.shape}')
    reordered = int(np.count_nonzero(t[1:] < np.maximum.accumulate(t)[:-1])) if len(t) else 0
    index = np.argsort(t, kind='stable')
    ordered = t[index]
    first = np.ones(len(t), bool)
    first[1:] = ordered[1:] != ordered[:-1]
    return StampOrder(index=index[first], dropped_duplicates=int(len(t) - first.sum()),
                      reordered=reordered)


def delta_pairs(count, delta=1, unit='f', stamps=None, *, overlapping=False):
    """
    Index pairs (i, j) for relative errors: by default consecutive and not overlapping (evo's RPE).

    unit 'f' (frames): i runs over 0, delta, 2·delta, … < count and j is the next one (evo's
    filter_pairs_by_index without all_pairs). unit 's' (seconds, given stamps (count,),
    strictly increasing): from i = 0, j is the first index with t_j − t_i ≥ delta (within
    rounding of the stamps: 4·ε·max|t|), then i = j. overlapping: every pose i starts a pair
    instead, with j = i + delta frames or the first t_j ≥ t_i + delta (the mounting's
    intervals). count: a whole number in [0, MAX_POSES]. Returns an int array (K, 2);
    RotationError when no pair fits, and for a delta in seconds within the rounding of the
    stamps (at Unix times, about a microsecond), which cannot tell a pose from the next.
    """
    count = _count(count)
    if unit == 'f':
        if not _whole(delta):
            raise RotationError(f'delta in frames must be an integer ≥ 1, got {_shown(delta)}')
        step = int(min(delta, count + 1))
        if overlapping:
            i = np.arange(max(count - step, 0))
            pairs = np.stack([i, i + step], axis=-1)
        else:
            ids = np.arange(0, count, step)
            pairs = np.stack([ids[:-1], ids[1:]], axis=-1)
    elif unit == 's':
        pairs = _pairs_in_seconds(count, delta, stamps, overlapping)
    else:
        raise RotationError(f"unit must be 'f' (frames) or 's' (seconds), got {unit!r}")
    if not len(pairs):
        raise RotationError(f'delta = {_shown(delta)} {"frames" if unit == "f" else "s"} '
                            f'leaves no pair among {count} poses')
    return pairs


def _pairs_in_seconds(count, delta, stamps, overlapping):
    if stamps is None:
        raise RotationError("delta in seconds (unit 's') needs the stamps")
    t = checked_stamps(stamps, 'stamps', 1)
    if len(t) != count:
        raise RotationError(f'stamps has {len(t)} entries for {count} poses')
    if isinstance(delta, int) and not isinstance(delta, bool) and delta > 10 ** 308:
        # beyond float64, and so beyond any span of stamps
        raise RotationError(f'delta = {plain(delta)} s leaves no pair among {count} poses')
    step = require_tolerance(delta, 'delta')
    if step == 0:
        raise RotationError('delta in seconds must be > 0, got 0')
    far = max(abs(t[0]), abs(t[-1]))
    slack = 4 * np.finfo(float).eps * far
    if step <= slack:  # t_i + delta − slack would find i itself, again and again
        raise RotationError(
            f'delta = {plain(step)} s is within the rounding of stamps near {plain(far)} s '
            f'({slack:.2g} s): give a larger delta, or one in frames')
    reach = step - slack
    if overlapping:
        i = np.arange(count)
        with np.errstate(over='ignore'):  # beyond float64: no stamp reaches it anyway
            j = np.searchsorted(t, t + reach, side='left')
        j = np.maximum(j, i + 1)  # t_i + reach may round to t_i; t_i+1 is then far enough
        keep = j < count
        return np.stack([i[keep], j[keep]], axis=-1)
    chain = [0]
    while True:
        with np.errstate(over='ignore'):
            j = int(np.searchsorted(t, t[chain[-1]] + reach, side='left'))
        j = max(j, chain[-1] + 1)
        if j >= count:
            break
        chain.append(j)
    ids = np.array(chain)
    return np.stack([ids[:-1], ids[1:]], axis=-1)


def _count(count):
    """Return count as an int in [0, MAX_POSES], or raise RotationError."""
    if isinstance(count, (bool, np.bool_)):
        whole = False
    elif isinstance(count, (int, np.integer)):  # exact: a Python int may exceed float64
        whole = count >= 0
    else:
        whole = (isinstance(count, (float, np.floating)) and math.isfinite(count)
                 and float(count).is_integer() and count >= 0)
    if not whole:
        raise RotationError(f'count must be a whole number ≥ 0, got {_shown(count)}')
    if count > MAX_POSES:
        raise RotationError(f'count must be at most {MAX_POSES} poses, got {plain(count)}')
    return int(count)


def _shown(value):
    """Write a value for a message: a number as plain() writes it, anything else by repr()."""
    if isinstance(value, (numbers.Real, np.floating, np.integer)) and not isinstance(
            value, (bool, np.bool_)):
        try:
            return plain(value)
        except (OverflowError, ValueError):
            pass
    return repr(value)


def _whole(delta):
    """Whether delta is a whole number ≥ 1 (an int, or a float such as 2.0)."""
    if isinstance(delta, (bool, np.bool_)):
        return False
    if isinstance(delta, (int, np.integer)):  # exact: a Python int may exceed float64
        return delta >= 1
    try:
        return float(delta).is_integer() and delta >= 1
    except (TypeError, ValueError, OverflowError):
        return False
