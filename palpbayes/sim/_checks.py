"""Argument checks shared by the simulator's modules (private).

Each helper turns a user value into a float or raises :class:`~palpbayes.errors.InputError`
with a message that names the quantity and its unit.
"""

from __future__ import annotations

import math

from ..errors import InputError


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
