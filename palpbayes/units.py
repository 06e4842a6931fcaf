"""Forces, lengths and moduli written with an SI prefix for messages.

Messages must be readable for a 48 mN palpation sensor and for a 500 pN AFM cantilever alike,
so a value in SI base units is printed with the prefix that puts its mantissa in [1, 1000)::

    >>> format_force(4.8e-2)
    '48 mN'
    >>> format_force(-6.57e-10)
    '-657 pN'
    >>> format_length(5.147e-5)
    '51.5 µm'
    >>> format_pressure(111e3)
    '111 kPa'

The micro prefix is the MICRO SIGN ``"µ"`` (U+00B5), as everywhere else in palpbayes' messages
and figures; the readers (:mod:`palpbayes.io.units`) accept it, the Greek ``"μ"`` and ``"u"``.

Rounding is to ``digits`` significant digits, trailing zeros dropped like ``%g`` (so 0.048 N
is ``'48 mN'``, not ``'48.0 mN'``); a value that rounds up to 1000 takes the next prefix
(0.99996 N is ``'1 N'``).  Beyond the smallest or largest prefix the mantissa leaves [1, 1000)
(``'0.5 Pa'``, ``'2000 kN'``; exponent notation when it is below 0.001 or from 10⁶ on).  Zero
is ``'0 N'``, non-finite values ``'nan N'``, ``'inf N'``, ``'-inf N'``.

Use these helpers only in free-text messages (errors, warnings, command-line output); table
columns and figure axes keep their fixed units.
"""

from __future__ import annotations

import math
from decimal import Decimal
from numbers import Real

__all__ = ["MICRO", "FORCE_PREFIXES", "LENGTH_PREFIXES", "PRESSURE_PREFIXES", "format_si",
           "format_force", "format_length", "format_pressure", "format_pressure_interval",
           "interval_digits", "si_scale"]

#: The micro prefix used in messages: MICRO SIGN U+00B5.
MICRO = "\u00b5"

#: Prefixes (power of ten -> prefix) available for forces: pN ... kN.
FORCE_PREFIXES: dict[int, str] = {-12: "p", -9: "n", -6: MICRO, -3: "m", 0: "", 3: "k"}
#: Prefixes available for lengths: pm ... m (no km: a palpation spans millimetres).
LENGTH_PREFIXES: dict[int, str] = {-12: "p", -9: "n", -6: MICRO, -3: "m", 0: ""}
#: Prefixes available for pressures and moduli: Pa ... GPa.
PRESSURE_PREFIXES: dict[int, str] = {0: "", 3: "k", 6: "M", 9: "G"}


def _plain(m: Decimal, digits: int) -> str:
    """``m`` without trailing zeros and, inside [0.001, 10⁶), without an exponent."""
    if m != 0 and not Decimal("0.001") <= m < Decimal(1_000_000):
        return f"{float(m):.{digits}g}"
    text = format(m.normalize(), "f")
    return text


def format_si(x: float, unit: str, prefixes: dict[int, str], digits: int = 3) -> str:
    """Write ``x`` (in the base ``unit``) with the prefix that puts the mantissa in [1, 1000).

    Parameters
    ----------
    x
        The value in SI base units (N, m, Pa ...); any real number, including nan and ±inf.
    unit
        The base unit's symbol, e.g. ``"N"``.
    prefixes
        Powers of ten (multiples of 3) mapped to prefix symbols; must contain 0 (the base unit).
    digits
        Significant digits (at least 1); trailing zeros are dropped.

    Returns
    -------
    str
        Mantissa, one space, prefix and unit, e.g. ``'51.5 µm'``.

    Raises
    ------
    ValueError
        If ``digits`` is not a positive integer, ``prefixes`` lacks 0 or ``x`` is not a real
        number.
    """
    if isinstance(digits, bool) or not isinstance(digits, int) or digits < 1:
        raise ValueError(f"digits {digits!r} must be an integer >= 1")
    if 0 not in prefixes:
        raise ValueError("prefixes must contain 0 (the base unit)")
    if isinstance(x, bool) or not isinstance(x, Real):
        try:
            x = float(x)  # numpy scalars and 0-d arrays
        except (TypeError, ValueError):
            raise ValueError(f"{x!r} is not a real number") from None
    x = float(x)
    if math.isnan(x):
        return f"nan {unit}"
    if math.isinf(x):
        return f"{'-' if x < 0 else ''}inf {unit}"
    if x == 0:
        return f"0 {unit}"
    # Round in decimal first, so that 999.96 mN carries into 1.00e+00 N before a prefix is chosen.
    rounded = Decimal(f"{abs(x):.{digits - 1}e}")
    power = 3 * (rounded.adjusted() // 3)
    power = min(max(power, min(prefixes)), max(prefixes))
    while power not in prefixes:  # a gap in the table: the next smaller prefix available
        power -= 3
    sign = "-" if x < 0 else ""
    return f"{sign}{_plain(rounded.scaleb(-power), digits)} {prefixes[power]}{unit}"


def format_force(x_newton: float, digits: int = 3) -> str:
    """A force [N] with an SI prefix (pN, nN, µN, mN, N, kN), e.g. ``'48 mN'``.

    Parameters
    ----------
    x_newton
        The force in newtons.
    digits
        Significant digits (default 3).

    Returns
    -------
    str
        E.g. ``format_force(4.8e-2) == '48 mN'``, ``format_force(-6.57e-10) == '-657 pN'``.
    """
    return format_si(x_newton, "N", FORCE_PREFIXES, digits)


def format_length(x_metre: float, digits: int = 3) -> str:
    """A length [m] with an SI prefix (pm, nm, µm, mm, m), e.g. ``'51.5 µm'``.

    Parameters
    ----------
    x_metre
        The length in metres.
    digits
        Significant digits (default 3).

    Returns
    -------
    str
        E.g. ``format_length(5.147e-5) == '51.5 µm'``, ``format_length(0.01) == '10 mm'``.
    """
    return format_si(x_metre, "m", LENGTH_PREFIXES, digits)


def format_pressure(x_pa: float, digits: int = 3) -> str:
    """A pressure or modulus [Pa] with an SI prefix (Pa, kPa, MPa, GPa), e.g. ``'111 kPa'``.

    Parameters
    ----------
    x_pa
        The value in pascals.
    digits
        Significant digits (default 3).

    Returns
    -------
    str
        E.g. ``format_pressure(1.11e5) == '111 kPa'``, ``format_pressure(2.5e9) == '2.5 GPa'``.
    """
    return format_si(x_pa, "Pa", PRESSURE_PREFIXES, digits)


def interval_digits(lo: float, hi: float, digits: int = 3, most: int = 6) -> int:
    """Significant digits to print a value and its interval [lo, hi] with: ``digits``, or more
    where the interval is narrow, so that its width reads to about a tenth (34,810 to 34,990
    Pa: 4 digits, ``'34.81 kPa'`` and ``'34.99 kPa'``; with 3 both ends would read near 35 kPa
    and hide that 35 kPa lies outside).

    Parameters
    ----------
    lo, hi
        The interval's ends, in any one unit.
    digits
        The fewest significant digits (default 3).
    most
        The most (default 6).

    Returns
    -------
    int
        Between ``digits`` and ``most``; ``digits`` when an end is not finite or the width is 0.
    """
    lo, hi = float(lo), float(hi)
    width, top = abs(hi - lo), max(abs(lo), abs(hi))
    if not (math.isfinite(width) and width > 0):
        return digits
    need = math.floor(math.log10(top)) - math.floor(math.log10(width / 10))
    return min(max(digits, need + 1), max(digits, most))


def format_pressure_interval(x_pa: float, lo_pa: float, hi_pa: float, digits: int = 3) -> str:
    """A modulus [Pa] and its interval, ``'34.9 kPa [34.81 kPa, 34.99 kPa]'``: each with
    :func:`format_pressure` at the digits :func:`interval_digits` gives (``digits`` at least),
    so that a narrow interval's ends read apart.

    Parameters
    ----------
    x_pa, lo_pa, hi_pa
        The value and the interval's ends in pascals.
    digits
        The fewest significant digits (default 3).

    Returns
    -------
    str
        E.g. ``format_pressure_interval(34.9e3, 34.81e3, 34.99e3) ==
        '34.9 kPa [34.81 kPa, 34.99 kPa]'``.
    """
    d = interval_digits(lo_pa, hi_pa, digits)
    return (f"{format_pressure(x_pa, d)} [{format_pressure(lo_pa, d)}, "
            f"{format_pressure(hi_pa, d)}]")


def si_scale(largest: float, unit: str, prefixes: dict[int, str]) -> tuple[float, str]:
    """The factor and unit label an axis of values up to ``largest`` (in the base ``unit``)
    is drawn in: the prefix of :data:`FORCE_PREFIXES` etc. that puts ``largest`` in
    [1, 1000), e.g. ``si_scale(2e-9, "N", FORCE_PREFIXES) == (1e9, "nN")``; the base unit
    for 0 or a value that is not finite."""
    x = abs(float(largest))
    power = 0
    if math.isfinite(x) and x > 0:
        power = 3 * math.floor(math.log10(x) / 3)
        power = min(max(power, min(prefixes)), max(prefixes))
    return 10.0 ** -power, prefixes[power] + unit

