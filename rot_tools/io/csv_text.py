"""
Decimal text of many floats at once, with NumPy: the numbers of ``rot-tools bag --csv``.

Python's ``'%g' % x`` costs a few hundred nanoseconds a number, more than everything else
``rot-tools bag`` does for a message. Here the digits of a whole chunk of rows are made by
array arithmetic instead: each number x is rounded to ``precision`` significant digits and
``precision`` decimal places, as rot-tools rounds the numbers it prints, by scaling |x| by
10^k (k = precision − the digits of its integer part, at least 0), rounding to an integer
and cutting that integer into groups of four digits that a table turns into text. Trailing
zeros of the fraction are dropped, and the point with them when nothing is left (``1``,
``0``, ``-2.5``); −0 is written 0; NaN is written as an empty field. The scaled integers
stay below 10^15, where float64 and int64 hold every integer: :func:`numbers_fit` checks
the numbers' size and ``precision`` (at most MAX_PRECISION) for that, and says when a chunk
must go through Python's formatting instead.

:func:`rows` returns the bytes of CSV lines: topic, stamp (exact, from integer nanoseconds:
``-0.500000000`` for −0.5 s), frame id, then the numbers, comma-separated.
"""

import numpy as np

MAX_PRECISION = 12
"""Most digits written here: |x|·10^k is then exact enough that the last digit is the
correctly rounded one but in the rarest near-ties; more goes to Python's formatting."""

_DIGITS4 = np.frombuffer(b''.join(b'%04d' % i for i in range(10000)), np.uint32)
"""'0000' … '9999' as four bytes each, read as one uint32: the text of a 4-digit group."""
_TRAILING4 = np.array([4 - len(('%04d' % i).rstrip('0')) for i in range(10000)], np.intp)
"""Trailing zeros of each 4-digit group (4 for 0000)."""
_POW10 = 10.0 ** np.arange(23)
_POW10_INT = 10 ** np.arange(19, dtype=np.int64)


def numbers_fit(values, precision):
    """Tell whether every finite value's digits at ``precision`` fit the int64 arithmetic."""
    values = np.asarray(values, dtype=np.float64).ravel()
    big = np.fmax.reduce(np.abs(values)) if values.size else 0.0  # NaN ignored, ±inf not
    return precision <= MAX_PRECISION and not big >= 1e15


def _groups(v, count):
    """Return the 4-digit groups (int) of integers v (int64, < 1e4**count), highest first."""
    out = []
    for _ in range(count - 1):
        v, r = np.divmod(v, 10000)
        out.append(r)
    out.append(v)
    return out[::-1]


def _write_groups(buf, start, groups):
    """Write the text of 4-digit groups at byte ``start`` of every row of ``buf``."""
    for k, g in enumerate(groups):
        buf[:, start + 4 * k:start + 4 * k + 4] = _DIGITS4[g].view(np.uint8).reshape(-1, 4)


def _digit_count(v, most):
    """Decimal digits of the integer part of v (≥ 0; 0 below 1), at most ``most``."""
    count = np.zeros(len(v), np.intp)
    top = v.max() if len(v) else 0
    for j in range(most):
        if top < _POW10[j]:
            break
        count += v >= _POW10[j]
    return count


def _product_error(a, b, p):
    """
    Return a·b − p exactly, for p = fl(a·b) (Dekker's two-product with Veltkamp's split).

    Each factor is split into halves of 26 bits, x = xh + xl, whose products are exact.
    """
    def split(x):
        c = 134217729.0 * x  # 2^27 + 1
        high = c - (c - x)
        return high, x - high
    ah, al = split(a)
    bh, bl = split(b)
    return ((ah * bh - p) + ah * bl + al * bh) + al * bl


def _rint_of_product(a, scale):
    """
    Return the exact a·scale rounded to an integer, ties to even (as Decimal and '%f' round).

    fl(a·scale) is rounded once already; rounding being monotonic, only a product that
    lands on a tie n + ½ is ambiguous (0.05 · 10 = 0.5 exactly, while 0.05 is
    0.05000000000000000277…): there the rounding error's sign decides.
    """
    p = a * scale
    r = np.rint(p)
    tie = np.flatnonzero(np.abs(p - r) == 0.5)
    if tie.size:
        err = _product_error(a[tie], scale[tie], p[tie])
        below = np.floor(p[tie])
        r[tie] = np.where(err > 0, below + 1.0, np.where(err < 0, below, r[tie]))
    return r


def number_cells(x, precision):
    """
    (bytes (n, width) uint8, keep (n, width) bool) of the text of each value of x (n,).

    Each cell is sign, integer digits, '.', fraction digits; ``keep`` marks the bytes of the
    shortest text (no leading zeros, no trailing zeros, no '-' for 0, nothing for NaN).
    Requires numbers_fit(x, precision).
    """
    x = np.asarray(x, dtype=np.float64)
    n = len(x)
    nan = np.isnan(x)
    a = np.abs(x)
    a[nan] = 0.0
    most = 16
    k = precision - np.minimum(_digit_count(a, most), precision)  # decimals of each value
    scaled = _rint_of_product(a, _POW10[k]).astype(np.int64)  # < 10^precision·(1 + …)
    ip, frac = np.divmod(scaled, _POW10_INT[k])
    frac_groups = -(-precision // 4)
    frac *= _POW10_INT[4 * frac_groups - k]  # left-aligned in the groups
    int_digits = max(1, len('%d' % ip.max())) if n else 1
    int_groups = -(-int_digits // 4)
    iw, fw = 4 * int_groups, 4 * frac_groups
    width = 1 + iw + 1 + fw
    buf = np.empty((n, width), np.uint8)
    buf[:, 0] = ord('-')
    _write_groups(buf, 1, _groups(ip, int_groups))
    buf[:, 1 + iw] = ord('.')
    groups = _groups(frac, frac_groups)
    _write_groups(buf, 2 + iw, groups)
    keep = np.empty((n, width), bool)
    shown = np.maximum(1, _digit_count(ip, iw))
    keep[:, 1:1 + iw] = np.arange(iw) >= (iw - shown)[:, None]
    last = np.full(n, -1, np.intp)  # the last non-zero fraction digit
    for j, g in enumerate(groups):
        last = np.where(g != 0, 4 * j + 3 - _TRAILING4[g], last)
    keep[:, 2 + iw:] = np.arange(fw) <= last[:, None]
    keep[:, 1 + iw] = last >= 0
    keep[:, 0] = np.signbit(x) & (scaled > 0)
    keep[nan] = False
    return buf, keep


def _strings(table, index):
    """(bytes (m, width), keep) of the strings table[index[i]] of each row."""
    lengths = np.array([len(t) for t in table], np.intp)
    width = int(lengths.max()) if len(table) else 0
    padded = np.zeros((len(table), width), np.uint8)
    for i, t in enumerate(table):
        padded[i, :len(t)] = np.frombuffer(t, np.uint8)
    return padded[index], np.arange(width) < lengths[index][:, None]


NS_PER_S = 1_000_000_000


def stamp_text(ns):
    """Return the text of a stamp of ``ns`` (int) nanoseconds: '[-]s.nnnnnnnnn', exact."""
    sec, nsec = divmod(abs(ns), NS_PER_S)
    return '%s%d.%09d' % ('-' if ns < 0 else '', sec, nsec)


def _stamps(ns):
    """(bytes, keep) of stamps of ``ns`` (m,) int64 nanoseconds, as stamp_text writes them."""
    ns = np.asarray(ns, np.int64)
    sec, nanosec = np.divmod(np.abs(ns), NS_PER_S)
    n = len(sec)
    digits = len('%d' % sec.max()) if n else 1
    groups = max(1, -(-digits // 4))
    width = 1 + 4 * groups + 1 + 12
    buf = np.empty((n, width), np.uint8)
    buf[:, 0] = ord('-')
    _write_groups(buf, 1, _groups(sec, groups))
    buf[:, 1 + 4 * groups] = ord('.')
    _write_groups(buf, 2 + 4 * groups, _groups(nanosec, 3))
    keep = np.ones((n, width), bool)
    keep[:, 0] = ns < 0
    shown = np.maximum(1, _digit_count(sec, 4 * groups))
    keep[:, 1:1 + 4 * groups] = np.arange(4 * groups) >= (4 * groups - shown)[:, None]
    keep[:, 2 + 4 * groups:5 + 4 * groups] = False  # 12 digits made, 9 shown
    return buf, keep


def rows(topic, ns, frames, frame, values, precision):
    """
    CSV lines (bytes) ``topic,stamp,frame,v1,...,vk`` of m rows.

    topic: bytes (already CSV-quoted); ns (m,) int64 stamps in nanoseconds, written exactly
    (stamp_text); frames: list of bytes (quoted)
    indexed by frame (m,); values (m, k) float64 with numbers_fit(values, precision), NaN
    an empty field.
    """
    m, k = values.shape
    cells, keep = number_cells(values.reshape(-1), precision)
    width = cells.shape[1] + 1
    text = np.empty((m * k, width), np.uint8)
    text[:, :-1] = cells
    text[:, -1] = ord(',')
    mask = np.empty((m * k, width), bool)
    mask[:, :-1] = keep
    mask[:, -1] = True
    text = text.reshape(m, k * width)
    mask = mask.reshape(m, k * width)
    text[:, -1] = ord('\n')
    head = np.frombuffer(topic + b',', np.uint8)
    stamp, stamp_keep = _stamps(ns)
    name, name_keep = _strings(frames, frame)
    comma = np.full((m, 1), ord(','), np.uint8)
    parts = [np.broadcast_to(head, (m, len(head))), stamp, comma, name, comma, text]
    keeps = [np.ones((m, len(head)), bool), stamp_keep, np.ones((m, 1), bool), name_keep,
             np.ones((m, 1), bool), mask]
    return np.concatenate(parts, axis=1)[np.concatenate(keeps, axis=1)].tobytes()
