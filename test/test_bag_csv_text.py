"""rot_tools.io.csv_text: the CSV's numbers made with NumPy, against exact decimal rounding."""

import csv
from decimal import Decimal
import io
import math

from hypothesis import given, settings, strategies as st
import numpy as np
import pytest

from rot_tools.cli.bag_output import _number_text
from rot_tools.io import csv_text


def exact(value, precision):
    """Return value rounded to precision significant digits and decimal places (exact)."""
    digits = len('%d' % abs(value)) if abs(value) >= 1 else 0
    return round(Decimal(value), max(0, precision - digits))


def texts(values, precision):
    cells, keep = csv_text.number_cells(np.asarray(values, float), precision)
    return [bytes(c[k]).decode() for c, k in zip(cells, keep)]


RNG = np.random.default_rng(12)
VALUES = np.concatenate([
    RNG.normal(size=4000) * 10.0 ** RNG.integers(-14, 14, 4000),
    [0.0, -0.0, 1.0, -1.0, 0.5, 9.9999999999995, 99999.999999999, 1e-13, -4e-13, 5e-13,
     123456789012.0, 999999999999.9, 1e14, 10.0, 9.999999, math.pi, -math.pi, 1e-300]])


@pytest.mark.parametrize('precision', [1, 3, 6, 9, 12])
def test_numbers_are_rounded_exactly(precision):
    for value, text in zip(VALUES, texts(VALUES, precision)):
        want = exact(value, precision)
        assert Decimal(text) == want, (value, text, want)
        # the shortest text: no trailing zeros, no '-0', a point only before digits
        assert not (('.' in text and text.endswith('0')) or text.endswith('.'))
        assert text != '-0' and not text.startswith('-0') or text.startswith('-0.')
        assert text == _number_text(value, precision)  # the fallback writes the same


@settings(max_examples=300, deadline=None)
@given(st.floats(-9.9e14, 9.9e14, allow_nan=False), st.integers(1, 12))
def test_any_number_is_rounded_exactly(value, precision):
    assert Decimal(texts([value], precision)[0]) == exact(value, precision)


@pytest.mark.parametrize('value, precision, text', [
    (0.05, 1, '0.1'), (-0.05, 1, '-0.1'),  # 0.05·10 rounds to the tie 0.5; 0.05 is above it
    (0.15, 1, '0.1'), (0.35, 1, '0.3'),  # …and these below it
    (0.25, 1, '0.2'), (0.375, 2, '0.38'),  # true ties (binary fractions): to even
    (5e-13, 12, '0'), (2.5e-12, 12, '0.000000000002')])  # 12 decimals: both below
def test_a_product_that_lands_on_a_tie_is_rounded_as_the_exact_value(value, precision, text):
    assert texts([value], precision) == [text] == [_number_text(value, precision)]


def test_nan_is_an_empty_field_and_zero_has_no_sign():
    assert texts([math.nan, -0.0, -1e-20, 0.0], 12) == ['', '0', '0', '0']


def test_numbers_fit():
    assert csv_text.numbers_fit(np.array([1e14, -3.0, math.nan]), 12)
    assert not csv_text.numbers_fit(np.array([1e15]), 12)
    assert not csv_text.numbers_fit(np.array([math.inf]), 12)
    assert not csv_text.numbers_fit(np.array([1.0]), 13)


def test_rows_are_csv():
    ns = np.array([1, 47_580_000_000, 1_700_000_000_000_000_123, 5_999_999_999,
                   -12345 * 10**9, -2 * 10**9, -5 * 10**8, -1, -(2**31) * 10**9])
    values = RNG.normal(size=(len(ns), 5))
    values[0, 2:] = math.nan
    frames = [b'base_link', b'"a,b"']
    frame = np.arange(len(ns)) % 3 % 2
    text = csv_text.rows(b'/imu', ns, frames, frame, values, 12)
    rows = list(csv.reader(io.StringIO(text.decode())))
    want = ['0.000000001', '47.580000000', '1700000000.000000123', '5.999999999',
            '-12345.000000000', '-2.000000000', '-0.500000000', '-0.000000001',
            '-2147483648.000000000']
    assert [r[1] for r in rows] == want == [csv_text.stamp_text(int(x)) for x in ns]
    assert [Decimal(r[1]) * 10**9 for r in rows] == [Decimal(int(x)) for x in ns]
    assert [r[2] for r in rows] == [['base_link', 'a,b'][f] for f in frame]
    assert all(r[0] == '/imu' and len(r) == 8 for r in rows)
    assert rows[0][5:] == ['', '', '']
    for r, v in zip(rows, values):
        for t, x in zip(r[3:], v):
            assert (t == '') if math.isnan(x) else Decimal(t) == exact(x, 12)
