"""The strain window of a ground-truth fit: its check, the sensitivity windows, the rule text.

A window ``(lo, hi)`` is a pair of fractions of the specimen height (0.05 = 5 %), in
toe-compensated strain unless ``toe_compensation`` is False (:mod:`palpbayes.compression.fit`).
:func:`sensitivity_windows` gives the three nearby windows of ``E_window_spread_pa`` and
:func:`describe_rule` the one-line rule written to the summary's ``rule`` column;
:func:`toe_compression` is the smooth toe the rule's compensation is exact for (the
simulator's, and the compression modulus of a fitted relaxation modulus).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from ..errors import InputError

__all__ = ["DEFAULT_STRAIN_WINDOW", "sensitivity_windows", "describe_rule", "toe_compression",
           "check_strain_window"]

#: Default fit window [-] in toe-compensated engineering strain (0-5 %).
DEFAULT_STRAIN_WINDOW: tuple[float, float] = (0.0, 0.05)


def check_strain_window(strain_window: Sequence[float]) -> tuple[float, float]:
    """``strain_window`` as (lo, hi) fractions of the height; :class:`InputError` unless
    0 <= lo < hi <= 1 (a window above 1 was probably given in percent)."""
    try:
        lo, hi = (float(v) for v in strain_window)
    except (TypeError, ValueError):
        raise InputError(f"strain_window must be two numbers (lo, hi), got {strain_window!r}") \
            from None
    if not (math.isfinite(lo) and math.isfinite(hi) and 0.0 <= lo < hi):
        raise InputError(f"strain_window must satisfy 0 <= lo < hi, got ({lo}, {hi})")
    if hi > 1.0:
        raise InputError(f"strain_window is a fraction of the height (0.05 = 5 %), got "
                         f"({lo}, {hi}); did you give percent?")
    return lo, hi


def sensitivity_windows(
    strain_window: Sequence[float] = DEFAULT_STRAIN_WINDOW,
) -> tuple[tuple[float, float], ...]:
    """The windows of the window-sensitivity figure ``E_window_spread_pa``.

    For a window [lo, hi] of width w: [lo, lo + 0.6·w] (shorter), [lo, hi] (the window) and
    [lo + 0.2·w, hi + 0.2·w] (shifted up); 0-3 %, 0-5 % and 1-6 % for the default 0-5 %.
    """
    lo, hi = check_strain_window(strain_window)
    w = hi - lo
    return ((lo, round(lo + 0.6 * w, 12)), (lo, hi),
            (round(lo + 0.2 * w, 12), round(hi + 0.2 * w, 12)))


def _pct_range(window: Sequence[float]) -> str:
    return f"{100 * window[0]:g}-{100 * window[1]:g} %"


def describe_rule(strain_window: Sequence[float] = DEFAULT_STRAIN_WINDOW,
                  toe_compensation: bool = True, skip_toe: bool = False) -> str:
    """One line naming the rule behind the ``E_*`` columns (written to the summary's ``rule``)."""
    window = check_strain_window(strain_window)
    if toe_compensation:
        origin = ("strain measured from the toe offset (zero-point construction of ASTM D638 "
                  "Annex A1)")
        if skip_toe:
            origin += ", points below twice the toe offset skipped"
    else:
        origin = "of measured strain (no toe compensation)"
    spread = ", ".join(_pct_range(w) for w in sensitivity_windows(window))
    return (f"E: least-squares slope of engineering stress on engineering strain over "
            f"{_pct_range(window)} {origin}; E_plain: the same window of measured strain, the "
            f"phantom dataset's 0-5 % convention (compare with its published table); E_sd per "
            f"test: prewhitened Newey-West HAC; window spread: range of E over {spread}")


def toe_compression(x: ArrayLike, toe: float) -> np.ndarray:
    """Effective compression [m] of a block with ``toe`` [m] of slack, smooth (C¹) toe.

    u(x) = x²/(4·toe) for 0 <= x < 2·toe, and x - toe beyond; u and du/dx are continuous at
    x = 2·toe, and the linear part extrapolates to zero at x = toe.  toe = 0 gives u = x.
    """
    x = np.clip(np.asarray(x, dtype=float), 0.0, None)
    if toe == 0:
        return x
    return np.where(x < 2.0 * toe, x * x / (4.0 * toe), x - toe)
