"""Tip geometry: the indenter's shape and size, in SI units."""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..errors import GeometryError
from ..units import format_length

__all__ = ["Tip", "TIP_KINDS"]

#: Tip kinds palpbayes knows, see :mod:`palpbayes.contact`.
TIP_KINDS = ("flat", "paraboloid", "sphere", "cone", "power")


@dataclass(frozen=True)
class Tip:
    """A rigid axisymmetric indenter.

    Parameters
    ----------
    kind
        ``"flat"`` (cylindrical flat punch), ``"paraboloid"`` (Hertz), ``"sphere"`` (exact
        Sneddon sphere), ``"cone"`` or ``"power"`` (profile f(r) = c·r^n).
    radius
        [m] Punch radius (flat) or radius of curvature (paraboloid, sphere).
    half_angle
        [rad] Half-opening angle of a cone, axis to flank (profile f = r·cot(alpha)).
    c, n
        Power-law profile f(r) = c·r^n, ``c`` in [m^(1-n)], ``n`` > 0 dimensionless.

    Raises
    ------
    GeometryError
        If the kind is unknown or a parameter it needs is missing, non-finite or out of range.
    """

    kind: str
    radius: float | None = None
    half_angle: float | None = None
    c: float | None = None
    n: float | None = None

    def __post_init__(self) -> None:
        kind = str(self.kind).strip().lower()
        object.__setattr__(self, "kind", kind)
        if kind not in TIP_KINDS:
            raise GeometryError(
                f"unknown tip kind {self.kind!r}; use one of {', '.join(TIP_KINDS)}"
            )
        if kind in ("flat", "paraboloid", "sphere"):
            _positive(self.radius, f"tip '{kind}' radius [m]", "give --radius in metres, e.g. 0.01")
        elif kind == "cone":
            _positive(self.half_angle, "cone half-angle [rad]", "give --half-angle in degrees")
            if not self.half_angle < math.pi / 2:
                raise GeometryError(
                    f"cone half-angle {self.half_angle} rad is not below pi/2; "
                    "give the half-opening angle (axis to flank)"
                )
        elif kind == "power":
            _positive(self.c, "power-law profile coefficient c", "profile is f(r) = c*r^n")
            _positive(self.n, "power-law profile exponent n", "profile is f(r) = c*r^n")

    def describe(self) -> str:
        """Short human-readable description, e.g. ``'sphere R=10 mm'`` or ``'sphere R=20 nm'``."""
        if self.kind in ("flat", "paraboloid", "sphere"):
            label = "a" if self.kind == "flat" else "R"
            return f"{self.kind} {label}={format_length(self.radius, 6)}"
        if self.kind == "cone":
            return f"cone alpha={math.degrees(self.half_angle):g} deg"
        return f"power c={self.c:g} n={self.n:g}"

    def scaled(self, factor: float) -> Tip:
        """The same tip with its length scale multiplied by ``factor`` (radius tolerance).

        For a cone the shape has no length scale, and the tip is returned unchanged.
        For a power-law profile, scaling lengths by ``s`` maps c to c·s^(1-n).
        """
        if self.kind in ("flat", "paraboloid", "sphere"):
            return Tip(self.kind, radius=self.radius * factor)
        if self.kind == "power":
            return Tip("power", c=self.c * factor ** (1.0 - self.n), n=self.n)
        return self


def _positive(value: float | None, what: str, fix: str) -> None:
    if value is None:
        raise GeometryError(f"{what} is missing ({fix})")
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise GeometryError(f"{what} {value!r} is not a number ({fix})") from None
    if not math.isfinite(v) or v <= 0:
        raise GeometryError(f"{what} must be a positive finite number, got {value!r} ({fix})")
