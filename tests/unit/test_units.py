"""SI-prefixed forces, lengths and moduli for messages (palpbayes.units)."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from propbudget import examples

from palpbayes.units import (
    FORCE_PREFIXES,
    LENGTH_PREFIXES,
    MICRO,
    PRESSURE_PREFIXES,
    format_force,
    format_length,
    format_pressure,
    format_si,
)

_TEXT = re.compile(r"^(-?[0-9.]+(?:e[-+][0-9]+)?) ([pnµmkMG]?)(N|m|Pa)$")
_FACTOR = {"p": 1e-12, "n": 1e-9, "µ": 1e-6, "m": 1e-3, "": 1.0, "k": 1e3, "M": 1e6, "G": 1e9}


def _parse(text: str) -> tuple[float, str, str]:
    """(printed number, prefix, unit) of a formatted value."""
    match = _TEXT.match(text)
    assert match, text
    return float(match[1]), match[2], match[3]


@pytest.mark.parametrize("x, text", [
    (4.8e-2, "48 mN"),
    (-6.57e-10, "-657 pN"),
    (1.0, "1 N"),
    (12.5, "12.5 N"),
    (2.5e3, "2.5 kN"),
    (8e-3, "8 mN"),
    (5.79098e-11, "57.9 pN"),
    (3.2e-6, "3.2 µN"),
    (1.5e-9, "1.5 nN"),
    (0.99996, "1 N"),          # rounds up to 1000 mN -> the next prefix
    (999.4e-3, "999 mN"),
    (1e-3, "1 mN"),
    (5e6, "5000 kN"),          # beyond kN: the mantissa leaves [1, 1000)
    (5e-13, "0.5 pN"),
    (1e-20, "1e-08 pN"),       # far beyond pN: exponent notation
])
def test_format_force(x, text):
    assert format_force(x) == text


@pytest.mark.parametrize("x, text", [
    (5.147e-5, "51.5 µm"),
    (0.01, "10 mm"),
    (0.0117, "11.7 mm"),
    (0.5, "500 mm"),
    (2.0, "2 m"),
    (1500.0, "1500 m"),        # no km
    (2e-8, "20 nm"),
    (-3.21e-10, "-321 pm"),
    (7e-13, "0.7 pm"),
])
def test_format_length(x, text):
    assert format_length(x) == text


@pytest.mark.parametrize("x, text", [
    (111e3, "111 kPa"),
    (13e3, "13 kPa"),
    (1.9e6, "1.9 MPa"),
    (2.5e9, "2.5 GPa"),
    (70e9, "70 GPa"),
    (3e12, "3000 GPa"),
    (420.0, "420 Pa"),
    (0.5, "0.5 Pa"),           # no mPa
    (-97e3, "-97 kPa"),
])
def test_format_pressure(x, text):
    assert format_pressure(x) == text


@pytest.mark.parametrize("fmt, unit", [(format_force, "N"), (format_length, "m"),
                                       (format_pressure, "Pa")])
def test_zero_and_non_finite(fmt, unit):
    assert fmt(0.0) == f"0 {unit}"
    assert fmt(-0.0) == f"0 {unit}"
    assert fmt(0) == f"0 {unit}"
    assert fmt(float("nan")) == f"nan {unit}"
    assert fmt(float("inf")) == f"inf {unit}"
    assert fmt(float("-inf")) == f"-inf {unit}"


def test_digits():
    assert format_force(4.8e-2, digits=1) == "50 mN"
    assert format_force(0.04825, digits=2) == "48 mN"
    assert format_force(0.0482512, digits=6) == "48.2512 mN"
    assert format_length(1.23456e-4, digits=4) == "123.5 µm"
    assert format_pressure(1.234e5, digits=2) == "120 kPa"
    assert format_force(0.048) == format_force(0.048, digits=3)


@pytest.mark.parametrize("digits", [0, -1, 2.5, True, "3"])
def test_bad_digits(digits):
    with pytest.raises(ValueError, match="digits"):
        format_force(1e-3, digits=digits)


def test_accepts_numpy_and_int():
    assert format_force(np.float64(2e-3)) == "2 mN"
    assert format_force(np.float32(2e-3)) == "2 mN"
    assert format_length(np.array(3e-9)) == "3 nm"
    assert format_force(2) == "2 N"
    with pytest.raises(ValueError, match="not a real number"):
        format_force("1 mN")


def test_micro_sign_is_u00b5():
    assert MICRO == "\u00b5"
    assert format_force(1e-6) == "1 \u00b5N"
    assert format_length(1e-6) == "1 \u00b5m"
    assert "\u03bc" not in format_length(1e-6)  # not the Greek mu


def test_format_si_gaps_and_checks():
    # a table with a gap takes the next smaller prefix: 5e-5 m in mm
    assert format_si(5e-5, "m", {0: "", -3: "m"}) == "0.05 mm"
    with pytest.raises(ValueError, match="contain 0"):
        format_si(1.0, "N", {-3: "m"})


_FINITE = st.floats(min_value=-1e15, max_value=1e15, allow_nan=False, allow_infinity=False)


@pytest.mark.parametrize("fmt, prefixes", [(format_force, FORCE_PREFIXES),
                                           (format_length, LENGTH_PREFIXES),
                                           (format_pressure, PRESSURE_PREFIXES)])
@settings(max_examples=examples(300), deadline=None)
@given(x=_FINITE, digits=st.integers(min_value=1, max_value=8))
def test_round_trip(fmt, prefixes, x, digits):
    """The printed number times the prefix factor is x to within rounding to ``digits``."""
    text = fmt(x, digits)
    number, prefix, _ = _parse(text)
    factor = _FACTOR[prefix]
    assert prefix in prefixes.values()
    back = number * factor
    if x == 0:
        assert back == 0
        return
    assert math.copysign(1.0, back) == math.copysign(1.0, x)
    # rounding to d significant digits: relative error <= 0.5 * 10**(1 - d) (+ float slack)
    assert abs(back - x) <= 0.5 * 10.0 ** (1 - digits) * abs(x) * (1 + 1e-9) + 1e-300
    lo, hi = 10.0 ** min(prefixes), 10.0 ** max(prefixes)
    if lo <= abs(x) < 999.0 * hi:  # inside the prefix range: mantissa in [1, 1000)
        assert 1 <= abs(number) < 1000, text
    # %g-like: no trailing zeros after a decimal point
    assert not re.search(r"\.\d*0(?!\d)|\.(?!\d)", text.split(" ")[0].split("e")[0]), text


def test_a_narrow_interval_keeps_the_digits_that_tell_its_ends_apart():
    """Issue 58: the viscoelastic console's E0* [34,810, 34,990] Pa around a true 35,000 Pa
    would read [34.8 kPa, 35 kPa] at 3 digits, as if it held the truth."""
    from palpbayes.units import format_pressure_interval, interval_digits

    assert format_pressure_interval(34.9e3, 34.81e3, 34.99e3) == "34.9 kPa [34.81 kPa, 34.99 kPa]"
    assert format_pressure_interval(20.8e3, 15.1e3, 34.5e3) == "20.8 kPa [15.1 kPa, 34.5 kPa]"
    assert interval_digits(0.2494, 0.2507) == 4
    assert interval_digits(1.0, 1.0) == 3 and interval_digits(1.0, float("nan")) == 3
    assert interval_digits(1e6, 1e6 + 1e-6) == 6  # at most `most`
