"""Contact laws for rigid axisymmetric tips on an elastic half-space (docs/design.md §1).

Every law is written as F = E*·s(d), with E* = E/(1-nu²) the effective modulus and s(d) the
*shape function* [m²] of the tip (0 for d <= 0).  Power laws have s(d) = g·d^m, so
F = k·d^m with k = E*·g; the exact sphere has no power form but stays linear in E*.  An optional
bottom-effect factor of a layer on a rigid base (:mod:`.layer`; the literature's closed forms
in :mod:`.thickness`) multiplies s(d).

Each tip kind is one module of this package (``flat``, ``paraboloid``, ``sphere``, ``cone``,
``power``) holding its formulas and its :class:`~.registry.ContactLaw`, registered by
``LAW = register(ContactLaw(...))``.  Importing this package imports every module in it, so a
new tip kind is one new file here: :func:`get_law` and :func:`registered_kinds` find it, and so
do :class:`Tip`, the fits, the checks, the manifest and the command line.  Helper modules
(:mod:`.registry`, :mod:`.parameters`, :mod:`.layer`, :mod:`.thickness`, :mod:`.mdr`)
register nothing.

    >>> from palpbayes.contact import Tip, force
    >>> round(float(force(1e-3, E=100e3, nu=0.3, tip=Tip("paraboloid", radius=0.01))), 4)
    0.4633
"""

from __future__ import annotations

import importlib
import math
import pkgutil
from collections.abc import Callable

import numpy as np

from ..errors import GeometryError
from ..units import format_length
from . import layer
from .parameters import TIP_PARAMETERS, TipParameter, half_angle_from_degrees
from .registry import (
    ContactLaw,
    Tip,
    get_law,
    register,
    registered_kinds,
    registered_laws,
    unregister,
)
from .soe import SOE_TOLERANCE
from .thickness import dimitriadis_factor, garcia_factor
from .viscoelastic import (
    HereditaryContact,
    PowerLawKernel,
    PronyKernel,
    constant_strain_rate_stress,
    hereditary_contact,
    hereditary_force,
    ramp_apparent_modulus,
    standard_linear_solid,
)

# every module of the package: the law modules register themselves on import
for _module in pkgutil.iter_modules(__path__):
    importlib.import_module(f"{__name__}.{_module.name}")
del _module

__all__ = [
    "touching",
    "Tip",
    "TIP_KINDS",
    "TIP_PARAMETERS",
    "TipParameter",
    "ContactLaw",
    "register",
    "unregister",
    "get_law",
    "registered_kinds",
    "registered_laws",
    "fixed_exponents",
    "default_fit_fraction_text",
    "DEFAULT_NU",
    "DEFAULT_NU_NOTE",
    "shape",
    "force",
    "exponent",
    "prefactor",
    "effective_modulus",
    "youngs_modulus",
    "youngs_factor",
    "k_from_modulus",
    "modulus_from_k",
    "check_nu",
    "check_tip_plausible",
    "MAX_TIP_RADIUS_M",
    "half_angle_from_degrees",
    "thickness_factor",
    "dimitriadis_factor",
    "garcia_factor",
    "PowerLawKernel",
    "PronyKernel",
    "standard_linear_solid",
    "HereditaryContact",
    "hereditary_contact",
    "hereditary_force",
    "ramp_apparent_modulus",
    "constant_strain_rate_stress",
    "SOE_TOLERANCE",
]


def __getattr__(name: str):
    """``TIP_KINDS``: the registered tip kinds now (:func:`registered_kinds`), in display
    order, so a law registered after import is in it."""
    if name == "TIP_KINDS":
        return registered_kinds()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def fixed_exponents() -> dict[str, float]:
    """Tip kind -> exponent m of every registered law whose m does not depend on the tip's
    size (flat 1, paraboloid 1.5, cone 2), for naming the tip a fitted m points to."""
    return {law.kind: law.fixed_exponent for law in registered_laws()
            if law.fixed_exponent is not None}


def default_fit_fraction_text() -> str:
    """The registered laws' default fit fractions in words, e.g. ``'0.2 flat, 0 others'``."""
    parts = [f"{law.default_fit_fraction:g} {law.kind}" for law in registered_laws()
             if law.default_fit_fraction > 0]
    return ", ".join(parts + ["0 others"]) if parts else "0 for every tip"


#: Poisson ratio used when none is given: a foam value.  Silicone, gels and tissue are nearly
#: incompressible (0.45–0.5); E = E*·(1 − nu²) is 17 % lower at 0.5 than at 0.3.
DEFAULT_NU = 0.3
#: What a user should know when :data:`DEFAULT_NU` was assumed (printed by the command line).
DEFAULT_NU_NOTE = ("Poisson ratio not given: nu = 0.3 assumed (a foam value; foams 0.1-0.3, "
                   "silicone, gels and tissue 0.45-0.5; E = E*(1 - nu^2) is 17 % lower at 0.5 "
                   "than at 0.3): give --nu, or a nu column in the manifest")


def check_nu(nu: float) -> float:
    """Validate a Poisson ratio: finite and 0 <= nu <= 0.5 (0.5: incompressible, the usual
    choice for silicone, gels and tissue); return it as float.  Corrections undefined at 0.5
    refuse it themselves."""
    try:
        v = float(nu)
    except (TypeError, ValueError):
        raise GeometryError(f"Poisson ratio {nu!r} is not a number") from None
    if not (math.isfinite(v) and 0.0 <= v <= 0.5):
        raise GeometryError(
            f"Poisson ratio nu = {nu!r} is outside [0, 0.5]; "
            "give a value such as 0.3 for foam or 0.49 for silicone"
        )
    return v


#: [m] Largest plausible tip radius for palpation; a larger radius was almost surely given in mm.
MAX_TIP_RADIUS_M = 0.1


def _mm_as_metres(value: float) -> str:
    """``value`` divided by 1000, written like 0.010 or 0.0117 (the value if it was in mm)."""
    v = value * 1e-3
    text = f"{v:.3f}"
    return text if abs(float(text) - v) <= 1e-12 else f"{v:.4g}"


def check_tip_plausible(tip: Tip) -> None:
    """Reject a tip whose size cannot be meant for palpation (a unit slip).

    A radius (flat, paraboloid, sphere: any tip with a ``radius``) above
    :data:`MAX_TIP_RADIUS_M` = 0.1 m is taken for a value in millimetres given as metres
    (``--radius 10`` for a 10 mm tip).

    Raises
    ------
    GeometryError
        Naming the radius and the value in metres it probably should be.
    """
    if tip.radius is not None and tip.radius > MAX_TIP_RADIUS_M:
        raise GeometryError(
            f"tip radius {format_length(tip.radius, 6)} is implausibly large for palpation (more "
            f"than {format_length(MAX_TIP_RADIUS_M)}); --radius is in metres (so is the "
            "manifest's radius_m): "
            f"did you mean {_mm_as_metres(tip.radius)}?"
        )


def youngs_factor(nu):
    """E/E* = 1 − nu² [-]: the one place the package writes the plane-strain factor (a
    number or an array of nu)."""
    return 1.0 - np.square(nu) if isinstance(nu, np.ndarray) else 1.0 - nu * nu


def effective_modulus(E, nu: float):
    """E* = E/(1-nu²) [Pa]."""
    return E / youngs_factor(nu)


def youngs_modulus(Estar, nu: float):
    """E = E*·(1-nu²) [Pa]."""
    return Estar * youngs_factor(nu)


def thickness_factor(
    depth: np.ndarray, tip: Tip, thickness_m, nu: float, base: str = "bonded"
) -> np.ndarray:
    """Bottom-effect factor F_layer/F_half-space for ``tip`` on a layer of thickness h [-].

    The exact linear-elastic solution of :mod:`palpbayes.contact.layer` (the layer's
    integral equation, Hayes et al. 1972; Dimitriadis et al. 2002), read at chi = a(d)/h with
    a(d) the tip's half-space contact radius (``ContactLaw.contact_radius``: the punch radius,
    sqrt(R·d), Sneddon's sphere radius, (2/pi)·d·tan(alpha), the MDR radius of c·r^n).
    The closed-form series of the literature are in :mod:`palpbayes.contact.thickness`.

    Parameters
    ----------
    depth
        [m] Indentation depth(s).
    tip
        The indenter.
    thickness_m
        [m] Layer thickness h, a number or an array broadcastable with ``depth`` (one per
        walker or draw); ``inf`` is the half-space (factor 1).
    nu
        Poisson ratio [-] (the bonded base depends on it; the frictionless one does not).
    base
        ``"bonded"`` (no slip at the base) or ``"free"`` (frictionless base).

    Raises
    ------
    GeometryError
        For a tip whose law has no layer solution, a non-positive thickness or an unknown base.
    """
    h = _checked_thickness(np.asarray(thickness_m, dtype=float), thickness_m)
    return _layer_factor(get_law(tip), depth, tip, h, nu, _checked_base(base))


def _checked_thickness(h: np.ndarray, given) -> np.ndarray:
    if not (h.size and np.all(h > 0)):  # inf: no layer (the half-space limit), factor 1
        raise GeometryError(f"specimen thickness {given!r} m must be positive")
    return h


def _checked_base(base: str) -> str:
    if base not in layer.BASES:
        raise GeometryError(f"unknown base condition {base!r}; use one of "
                            f"{', '.join(layer.BASES)}")
    return base


def _layer_factor(law: ContactLaw, depth, tip: Tip, h: np.ndarray, nu: float, base: str
                  ) -> np.ndarray:
    """:func:`thickness_factor` for a law already looked up (h and base checked)."""
    _require_layer_solution(law, tip)
    return _factor_at_radius(law, law.contact_radius(np.asarray(depth, dtype=float), tip),
                             tip, h, nu, base)


def _require_layer_solution(law: ContactLaw, tip: Tip) -> None:
    if law.contact_radius is None:
        have = [x.kind for x in registered_laws() if x.contact_radius is not None]
        raise GeometryError(
            f"no layer (finite-thickness) solution for tip '{tip.kind}' (only "
            f"{', '.join(have)} have one); fit it as a half-space: --half-space on the "
            "command line (thickness=None in the API)")


def _factor_at_radius(law: ContactLaw, a: np.ndarray, tip: Tip, h: np.ndarray, nu: float,
                      base: str) -> np.ndarray:
    """The layer factor at half-space contact radii ``a`` [m] (:func:`thickness_factor`)."""
    n = law.profile_exponent(tip)
    if math.isinf(n):  # flat punch: a is the punch radius at every depth
        return layer.flat_table(nu, base).factor(a / h)
    return layer.profile_factor(a / h, n, nu, base)


def shape(
    depth: np.ndarray,
    tip: Tip,
    *,
    thickness_m=None,
    nu: float | None = None,
    base: str = "bonded",
) -> np.ndarray:
    """Force per unit effective modulus F/E* [m²] (0 for non-positive depth).

    Parameters
    ----------
    depth
        [m] Indentation depth d = z_surf - z_tip, any shape.
    tip
        The indenter.
    thickness_m
        [m] Layer thickness for the bottom effect (:func:`thickness_factor`; a number or an
        array broadcastable with ``depth``); None for a half-space.
    nu
        Poisson ratio [-], needed only with ``thickness_m``.
    base
        ``"bonded"`` or ``"free"`` base of the layer (only with ``thickness_m``).
    """
    law = get_law(tip)
    if thickness_m is None:
        return law.shape(depth, tip)
    if nu is None:
        raise GeometryError("the finite-thickness correction needs the Poisson ratio nu")
    h = _checked_thickness(np.asarray(thickness_m, dtype=float), thickness_m)
    base = _checked_base(base)
    if law.shape_and_radius is None:
        return law.shape(depth, tip) * _layer_factor(law, depth, tip, h, nu, base)
    _require_layer_solution(law, tip)
    s, a = law.shape_and_radius(np.asarray(depth, dtype=float), tip)  # one solve for both
    return s * _factor_at_radius(law, a, tip, h, nu, base)


def touching(shape: Callable[[np.ndarray], np.ndarray], depth: np.ndarray) -> np.ndarray:
    """``shape(depth)`` [m²] evaluated only where ``depth`` [m] is positive: 0 elsewhere, as
    every contact law gives (a grid of surface nodes leaves half its depths or more out of
    contact)."""
    inside = depth > 0
    if inside.all():
        return shape(depth)
    out = np.zeros(depth.shape)
    if inside.any():
        out[inside] = shape(depth[inside])
    return out


def force(
    depth: np.ndarray,
    E,
    nu: float,
    tip: Tip,
    *,
    thickness_m: float | None = None,
    base: str = "bonded",
) -> np.ndarray:
    """Contact force F [N] of ``tip`` pressed ``depth`` [m] into a material (E [Pa], nu [-]).

    F = E/(1-nu²)·s(d); 0 for non-positive depth.  Vectorised over ``depth`` (and ``E`` by
    broadcasting).
    """
    nu = check_nu(nu)
    s = shape(depth, tip, thickness_m=thickness_m, nu=nu, base=base)
    return effective_modulus(E, nu) * s


def exponent(tip: Tip) -> float | None:
    """Exponent m of F = k·d^m, or None when the tip's law is no power law (exact sphere)."""
    return get_law(tip).exponent_of(tip)


def prefactor(tip: Tip) -> float | None:
    """Geometry factor g of s(d) = g·d^m [m^(2-m)], or None when the tip's law is no power
    law (exact sphere)."""
    return get_law(tip).prefactor_of(tip)


def _power_prefactor(tip: Tip) -> float:
    g = prefactor(tip)
    if g is None:
        law = get_law(tip)
        hint = ""
        if law.hertz_approximation is not None:
            hint = (f"; use tip '{law.hertz_approximation(tip).kind}' for the Hertz "
                    "approximation")
        raise GeometryError(f"tip '{tip.kind}' has no power-law form F = k*d^m{hint}")
    return g


def k_from_modulus(E, nu: float, tip: Tip):
    """Power-law prefactor k = E/(1-nu²)·g of F = k·d^m [N/m^m]."""
    return effective_modulus(E, check_nu(nu)) * _power_prefactor(tip)


def modulus_from_k(k, nu: float, tip: Tip):
    """Young's modulus E = k·(1-nu²)/g [Pa] from F = k·d^m.

    For the paraboloid this is the paper's E = k·3(1-nu²)/(4·sqrt(R)).
    """
    return youngs_modulus(k / _power_prefactor(tip), check_nu(nu))
