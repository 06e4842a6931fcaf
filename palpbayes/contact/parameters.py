"""Tip parameters: each size parameter a tip can carry, with its unit, manifest column and
command-line option.

A contact law names the parameters its tip needs (``ContactLaw.parameters``); this table says
how each is given by a user (manifest column, ``palpbayes fit`` option, unit), converted to SI
and checked.  :class:`~palpbayes.contact.registry.Tip` has one field per entry of
:data:`TIP_PARAMETERS`; a law needing a parameter not listed here adds a field there and an
entry here.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

from ..errors import GeometryError

__all__ = ["TipParameter", "TIP_PARAMETERS", "half_angle_from_degrees"]


def half_angle_from_degrees(degrees) -> float:
    """A cone half-opening angle given in degrees, validated, as radians [rad].

    The command line (``--half-angle``) and the manifest (``half_angle_deg``) give the angle in
    degrees while :class:`~palpbayes.contact.registry.Tip` takes radians; validating here keeps
    the error in the user's unit.

    Raises
    ------
    GeometryError
        If the angle is not a number strictly between 0 and 90 degrees.
    """
    try:
        v = float(degrees)
    except (TypeError, ValueError):
        raise GeometryError(f"cone half-angle {degrees!r} deg is not a number "
                            "(give --half-angle / half_angle_deg in degrees, e.g. 70)") from None
    if not (math.isfinite(v) and 0.0 < v < 90.0):
        raise GeometryError(
            f"cone half-angle {degrees!r} deg must lie strictly between 0 and 90 deg (the "
            "half-opening angle, axis to flank, in degrees: --half-angle / half_angle_deg)"
        )
    return math.radians(v)


@dataclass(frozen=True)
class TipParameter:
    """One size parameter of a tip.

    Attributes
    ----------
    name
        Field of :class:`~palpbayes.contact.registry.Tip` (SI value).
    what
        Its name in error messages; ``{kind}`` is replaced by the tip kind.
    fix
        How to give it, appended to error messages.
    column
        Manifest column holding it (:mod:`palpbayes.io.manifest`).
    option
        ``palpbayes fit`` option giving it for a single trace.
    metavar
        The option's placeholder in ``--help`` (None: argparse's default).
    unit, example
        Unit of the column and option, and an example value, for messages.
    help
        The option's help text.
    from_user
        Column/option value -> SI value (validating it), e.g. degrees -> radians.
    to_user
        SI value -> column value (the inverse of ``from_user``).
    upper, upper_message
        Exclusive upper bound of the SI value, and the message (``{value}`` replaced) when it
        is not below it; None: no bound beyond positivity.
    """

    name: str
    what: str
    fix: str
    column: str
    option: str
    metavar: str | None
    unit: str
    example: str
    help: str
    from_user: Callable[[float], float] = float
    to_user: Callable[[float], float] = float
    upper: float | None = None
    upper_message: str = ""

    def check(self, value: float | None, kind: str) -> None:
        """Raise :class:`~palpbayes.errors.GeometryError` unless ``value`` is a positive finite
        number (below :attr:`upper` when set); the message names the parameter and the fix."""
        what = self.what.format(kind=kind)
        if value is None:
            raise GeometryError(f"{what} is missing ({self.fix})")
        try:
            v = float(value)
        except (TypeError, ValueError):
            raise GeometryError(f"{what} {value!r} is not a number ({self.fix})") from None
        if not math.isfinite(v) or v <= 0:
            raise GeometryError(
                f"{what} must be a positive finite number, got {value!r} ({self.fix})")
        if self.upper is not None and not v < self.upper:
            raise GeometryError(self.upper_message.format(value=value))


#: Every tip parameter, in the order of the manifest's columns and of ``palpbayes fit --help``.
TIP_PARAMETERS: dict[str, TipParameter] = {
    p.name: p for p in (
        TipParameter("radius", "tip '{kind}' radius [m]", "give --radius in metres, e.g. 0.01",
                     "radius_m", "--radius", "M", "metres", "0.01", "tip radius [m]"),
        TipParameter("half_angle", "cone half-angle [rad]", "give --half-angle in degrees",
                     "half_angle_deg", "--half-angle", "DEG", "degrees", "70",
                     "cone half-angle [deg]", from_user=half_angle_from_degrees,
                     to_user=math.degrees, upper=math.pi / 2,
                     upper_message="cone half-angle {value} rad is not below pi/2; give the "
                                   "half-opening angle (axis to flank)"),
        TipParameter("c", "power-law profile coefficient c", "profile is f(r) = c*r^n",
                     "profile_c", "--profile-c", None, "m^(1-n)", "50",
                     "power-law profile c of f = c*r^n"),
        TipParameter("n", "power-law profile exponent n", "profile is f(r) = c*r^n",
                     "profile_n", "--profile-n", None, "-", "2",
                     "power-law profile n of f = c*r^n"),
    )
}
