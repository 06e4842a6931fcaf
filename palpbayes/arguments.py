"""Argument checks shared by the package: a user's number, coefficient or seed.

Each helper turns a user value into a float (or an int, for a seed) or raises
:class:`~palpbayes.errors.InputError` with a message that names the quantity and its unit.
"""

from __future__ import annotations

import math
import numbers

from .errors import InputError

__all__ = ["finite", "positive", "nonneg", "ar1_phi", "check_seed", "check_thickness"]


def finite(value, what: str) -> float:
    """``value`` as a finite float."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise InputError(f"{what} {value!r} is not a number") from None
    if not math.isfinite(v):
        raise InputError(f"{what} must be finite, got {value!r}")
    return v


def positive(value, what: str) -> float:
    """``value`` as a finite float > 0."""
    v = finite(value, what)
    if v <= 0:
        raise InputError(f"{what} must be positive, got {value!r}")
    return v


def nonneg(value, what: str) -> float:
    """``value`` as a finite float >= 0."""
    v = finite(value, what)
    if v < 0:
        raise InputError(f"{what} must be non-negative, got {value!r}")
    return v


def ar1_phi(value) -> float:
    """An AR(1) coefficient phi in (-1, 1)."""
    v = finite(value, "AR(1) coefficient phi")
    if not -1.0 < v < 1.0:
        raise InputError(f"AR(1) coefficient phi = {value!r} must lie in (-1, 1)")
    return v


def check_seed(seed) -> int:
    """``seed`` as an int: a non-negative whole number (a Python or numpy integer, not a
    bool), the one rule of every ``seed=`` of the package."""
    if isinstance(seed, bool) or not isinstance(seed, numbers.Integral) or seed < 0:
        raise InputError(f"seed {seed!r} must be a non-negative whole number")
    return int(seed)


def check_thickness(value, what: str = "thickness") -> float | str | None:
    """A block's thickness as given [m]: None (none given), ``"unknown"`` (to be inferred) or
    a positive number of metres; ``what`` names it in the message (``"--thickness"`` for the
    command line)."""
    if value is None:
        return None
    if str(value).strip().lower() == "unknown":
        return "unknown"
    try:
        h = float(value)
    except (TypeError, ValueError):
        raise InputError(f"{what} {value!r} is neither a thickness in metres nor "
                         "'unknown'") from None
    if not (math.isfinite(h) and h > 0):
        raise InputError(f"{what} {value!r} must be a positive thickness in metres")
    return h
