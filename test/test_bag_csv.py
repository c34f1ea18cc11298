"""rot-tools bag --csv: numbers rounded as numbers, each written as its shortest text."""

import csv
from decimal import Decimal
import io
import math

from hypothesis import given, settings, strategies as st
import numpy as np
import pytest

from rot_tools.cli import bag_output


def decimals(value, precision):
    """Return the decimals kept of a value: precision significant digits, at most precision."""
    return precision - 1 - Decimal(value).adjusted() if abs(value) >= 1 else precision


def exact(value, precision):
    """Return value rounded to precision significant digits and decimal places (exact)."""
    return Decimal(value).quantize(Decimal(1).scaleb(-decimals(value, precision)))


def near_a_tie(value, precision):
    """
    Tell whether value scaled to its last kept digit is near a tie (an integer and a half).

    There numeric rounding may go either way: value·10ᵏ, below 10^precision, is itself
    rounded to float64 first (half a unit in the 53rd bit).
    """
    scaled = Decimal(value).scaleb(decimals(value, precision))
    band = max(Decimal('1e-9'), Decimal(4e-16) * 10 ** precision)
    return abs(abs(scaled) % 1 - Decimal('0.5')) < band


RNG = np.random.default_rng(12)
VALUES = np.concatenate([
    RNG.normal(size=4000) * 10.0 ** RNG.integers(-14, 20, 4000),
    [0.0, 1.0, -1.0, 0.5, 99999.999999999, 1e-13, -4e-13, 123456789012.0, 999999999999.9,
     1e14, 10.0, 9.999999, math.pi, -math.pi, 1e-300, 1e300, 5e-324]])


@pytest.mark.parametrize('precision', [1, 3, 6, 9, 12, 15])
def test_numbers_are_rounded_to_significant_digits_and_decimals(precision):
    got = bag_output.rounded(VALUES, precision)
    for value, rounded in zip(VALUES, got):
        if not near_a_tie(value, precision):
            assert Decimal(repr(float(rounded))) == exact(value, precision), (value, rounded)


@settings(max_examples=300, deadline=None)
@given(st.floats(-1e20, 1e20, allow_nan=False), st.integers(1, 15))
def test_any_number_is_rounded_as_its_decimal_value(value, precision):
    if not near_a_tie(value, precision):
        rounded = bag_output.rounded(np.array([value]), precision)[0]
        assert Decimal(repr(float(rounded))) == exact(value, precision)


def test_zero_has_no_sign_and_nan_and_infinity_stay():
    got = bag_output.rounded(np.array([-0.0, -1e-20, math.nan, -math.inf, math.inf]), 12)
    assert [repr(float(x)) for x in got] == ['0.0', '0.0', 'nan', '-inf', 'inf']


@pytest.mark.parametrize('ns, text', [
    (1, '0.000000001'), (47_580_000_000, '47.580000000'),
    (1_700_000_000_000_000_123, '1700000000.000000123'), (-5 * 10**8, '-0.500000000'),
    (-1, '-0.000000001'), (-(2**31) * 10**9, '-2147483648.000000000')])
def test_stamps_are_exact(ns, text):
    assert bag_output.stamp_text(ns) == text
    assert Decimal(text) * 10**9 == ns


class Rows:
    """A Topic's fields that write_csv reads."""

    def __init__(self, values, ns, frames, frame):
        n = len(ns)
        self.topic, self.seq, self.seq_angles = '/t', None, None
        self.R, self.ns, self.frame = np.zeros((n, 3, 3)), np.array(ns), np.array(frame)
        self.columns = type('Columns', (), {'frame_ids': frames})
        self.position, self.quaternion, self.rpy = values[:, :3], values[:, 3:7], values[:, 7:10]
        self.rotvec, self.angle = values[:, 10:13], values[:, 13]
        self.omega, self.rpy_std = values[:, 14:17], values[:, 17:20]


def test_rows_are_csv_of_the_shortest_texts():
    values = RNG.normal(size=(5, 20)) * 10.0 ** RNG.integers(-8, 8, (5, 20))
    values[0, 14:] = math.nan
    values[1, 0] = -0.0
    rows = Rows(values, [1, 2, -5 * 10**8, 10**9, 3], ['base_link', '"a,b"'], [0, 1, 0, 1, 1])
    out = io.StringIO()
    bag_output.write_csv(out, [rows], False, 17, bag='=run.bag')
    table = list(csv.reader(io.StringIO(out.getvalue())))
    assert table[0][:4] == ['bag', 'topic', 'stamp', 'frame_id'] and len(table) == 6
    assert [r[0] for r in table[1:]] == ["'=run.bag"] * 5
    assert [r[2] for r in table[1:]] == ['0.000000001', '0.000000002', '-0.500000000',
                                         '1.000000000', '0.000000003']
    assert [r[3] for r in table[1:]] == ['base_link', '"a,b"', 'base_link', '"a,b"', '"a,b"']
    assert table[1][18:] == [''] * 6 and table[2][4] == '0.0'
    for row, want in zip(table[1:], bag_output.rounded(values, 17)):
        cells = row[4:]
        for cell, x in zip(cells, want):
            assert cell == ('' if math.isnan(x) else repr(float(x)))
