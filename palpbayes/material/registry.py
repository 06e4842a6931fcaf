"""The constitutive-law registry: one :class:`MaterialLaw` per hyperelastic law, registered by
its own module, as the contact laws are (:mod:`palpbayes.contact.registry`).

Every law is written the one way a finite-element code and a compression curve both need it:
the principal Kirchhoff stresses tau_i = lambda_i·dW/dlambda_i of its strain energy W at the
principal stretches (lambda_1, lambda_2, lambda_3), and their derivatives
dtau_i/d(ln lambda_j) (the material tangent in principal form: Simo & Taylor 1991, Comput.
Methods Appl. Mech. Eng. 85:273; Miehe 1994, Int. J. Numer. Methods Eng. 37:1981).  For an
isotropic solid that is all there is to a law.

Compressibility.  The solid of a law at a small-strain Poisson ratio nu is

    W = W~(lambda_1, lambda_2, lambda_3) + kappa/2·(ln J)²,       J = lambda_1·lambda_2·lambda_3,

with W~ the law's :attr:`MaterialLaw.tau` part and kappa = :meth:`MaterialLaw.bulk`:

* the laws written in the isochoric stretches lambda_bar_i = J^(-1/3)·lambda_i (Mooney–Rivlin,
  Yeoh, Ogden, exponential) take W~ = W(lambda_bar), whose stresses are the deviatoric
  projection of W's (:func:`isochoric`), and kappa the small-strain bulk modulus
  K = 2·mu0·(1 + nu)/(3·(1 − 2·nu));
* the neo-Hookean solid is the classic compressible one (docs/design.md §14; Ciarlet 1988,
  Bonet & Wood 2008): W = mu/2·(I1 − 3 − 2 ln J) + lambda/2·(ln J)², kappa the Lamé lambda;
* the foam (Ogden–Hill hyperfoam) carries its own compressibility (its nu is a parameter) and
  kappa = 0.

nu = 0.5 is the incompressible limit: a compression curve then eliminates the pressure
(:mod:`palpbayes.material.uniaxial`), a finite-element code needs a mixed u–p form.

Parameters.  A law's natural parameters (``mu``, ``C10``, ``mu_1`` ... in Pa, exponents
dimensionless) are a dict; a fit samples the small-strain modulus E0 with dimensionless
*shape* parameters instead (:attr:`MaterialLaw.shape`, :meth:`MaterialLaw.natural`), so that
E0 is a coordinate of every posterior.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numpy as np

from ..errors import InputError

__all__ = ["MaterialLaw", "ShapeParameter", "register", "material_law", "registered_laws",
           "law_names", "isochoric", "bulk_modulus", "lame_lambda", "LINEAR"]

#: The law of the paper's model: linear small-strain elasticity (no finite strain).
LINEAR = "linear"


@dataclass(frozen=True)
class ShapeParameter:
    """A dimensionless shape parameter of a law, as a fit samples it.

    Attributes
    ----------
    name
        Its name in tables (``"c2"``, ``"alpha"``).
    bounds
        The prior's support (uniform); the law's domain of stability inside it is checked
        by :meth:`MaterialLaw.check`.
    default
        A typical value: the start of a fit, the simulator's default.
    text
        What it is, in words, with its formula.
    """

    name: str
    bounds: tuple[float, float]
    default: float
    text: str


@dataclass(frozen=True)
class MaterialLaw:
    """An isotropic hyperelastic law, with what palpbayes needs to know about it.

    Attributes
    ----------
    name
        Registry name, lower case (``--law NAME``): ``"neo-hookean"``, ``"yeoh"`` ...
    title
        How prose names it: ``"neo-Hookean"``.
    parameters
        (name, unit) of the natural parameters, in order.
    energy
        The strain energy in words and symbols.
    reference
        The citation.
    tau
        ``tau(lam, p) -> (..., 3)`` principal Kirchhoff stresses [Pa] of W~ at the principal
        stretches ``lam`` (..., 3), natural parameters ``p``.
    dtau
        ``dtau(lam, p) -> (..., 3, 3)``: dtau_i/d(ln lambda_j) [Pa].
    mu0
        ``mu0(p) -> mu0`` [Pa], the small-strain shear modulus.
    shape
        The dimensionless shape parameters a fit samples beside E0.
    natural
        ``natural(E0, shape, nu) -> p``: the natural parameters of the solid whose small-strain
        modulus is E0 [Pa] at Poisson ratio nu with ``shape`` (a dict by name).
    kind
        ``"isochoric"`` (W~ = W(lambda_bar), bulk K), ``"lame"`` (the neo-Hookean solid,
        bulk Lamé lambda) or ``"foam"`` (its own compressibility, no bulk term).
    nu_parameter
        The natural parameter that is the foam's small-strain Poisson ratio (None: nu is the
        caller's).
    stable
        ``stable(p, lam) -> bool``: the parameters make a solid along the stretches ``lam``
        (..., 3): a positive small-strain shear modulus and the law's own limits (exponents
        away from 0, the foam's nu in [0, 0.5), Yeoh's dW/dI1 > 0 along the path).  A fit
        also asks for a compressive stress that rises with strain
        (:mod:`palpbayes.compression.finite`).
    order
        Display order.
    """

    name: str
    title: str
    parameters: tuple[tuple[str, str], ...]
    energy: str
    reference: str
    tau: Callable[[np.ndarray, Mapping[str, float]], np.ndarray]
    dtau: Callable[[np.ndarray, Mapping[str, float]], np.ndarray]
    mu0: Callable[[Mapping[str, float]], float]
    shape: tuple[ShapeParameter, ...]
    natural: Callable[[float, Mapping[str, float], float], dict[str, float]]
    kind: str = "isochoric"
    nu_parameter: str | None = None
    stable: Callable[[Mapping[str, float], np.ndarray], bool] = field(
        default=lambda p, lam: True)
    order: int = 100

    def nu0(self, p: Mapping[str, float], nu: float | None = None) -> float:
        """The small-strain Poisson ratio [-]: the foam's own, else ``nu`` (None: 0.5, the
        incompressible solid)."""
        if self.nu_parameter is not None:
            return float(p[self.nu_parameter])
        return 0.5 if nu is None else float(nu)

    def E0(self, p: Mapping[str, float], nu: float | None = None) -> float:
        """The small-strain Young's modulus E0 = 2·mu0·(1 + nu0) [Pa]."""
        return 2.0 * self.mu0(p) * (1.0 + self.nu0(p, nu))

    def bulk(self, p: Mapping[str, float], nu: float) -> float:
        """kappa [Pa] of the volumetric term kappa/2·(ln J)² at Poisson ratio ``nu``: the
        bulk modulus (``kind`` isochoric), the Lamé lambda (neo-Hookean), 0 (foam); inf at
        nu = 0.5."""
        if self.kind == "foam":
            return 0.0
        mu = self.mu0(p)
        return (bulk_modulus(mu, nu) if self.kind == "isochoric" else lame_lambda(mu, nu))

    def shape_defaults(self) -> dict[str, float]:
        """The shape parameters' typical values."""
        return {s.name: s.default for s in self.shape}

    def check(self, p: Mapping[str, float]) -> None:
        """Raise InputError naming the parameter when ``p`` misses one or is not finite."""
        for name, unit in self.parameters:
            v = p.get(name)
            if v is None or not np.isfinite(v):
                raise InputError(f"the {self.title} law needs a finite {name} [{unit}], got "
                                 f"{v!r}")

    def describe(self, p: Mapping[str, float]) -> str:
        """``'Yeoh C10=2.1 kPa, C20=-40 Pa, C30=3.2 Pa'``-like text of natural parameters."""
        parts = []
        for name, unit in self.parameters:
            v = float(p[name])
            parts.append(f"{name}={v:.4g}" + ("" if unit == "-" else f" {unit}"))
        return f"{self.title} " + ", ".join(parts)


_REGISTRY: dict[str, MaterialLaw] = {}


def register(law: MaterialLaw) -> MaterialLaw:
    """Add ``law`` to the registry (its name must be new) and return it."""
    if law.name in _REGISTRY:
        raise ValueError(f"material law {law.name!r} is registered twice")
    _REGISTRY[law.name] = law
    return law


def material_law(name: str | MaterialLaw) -> MaterialLaw:
    """The registered law called ``name`` (case and ``_``/``-`` insensitive).

    Raises
    ------
    InputError
        An unknown name, with the names there are.
    """
    if isinstance(name, MaterialLaw):
        return name
    key = str(name).strip().lower().replace("_", "-")
    if key not in _REGISTRY:
        raise InputError(f"unknown material law {name!r}: use one of "
                         f"{', '.join(law_names())}")
    return _REGISTRY[key]


def registered_laws() -> list[MaterialLaw]:
    """Every registered law in display order."""
    return sorted(_REGISTRY.values(), key=lambda law: (law.order, law.name))


def law_names() -> list[str]:
    """Names of the registered laws, in display order (with ``linear``, the small-strain law
    that is not registered here: it has no finite strain)."""
    return [LINEAR] + [law.name for law in registered_laws()]


def bulk_modulus(mu: float, nu: float) -> float:
    """K = 2·mu·(1 + nu)/(3·(1 − 2·nu)) [Pa]; inf at nu = 0.5."""
    return float("inf") if nu >= 0.5 else 2.0 * mu * (1.0 + nu) / (3.0 * (1.0 - 2.0 * nu))


def lame_lambda(mu: float, nu: float) -> float:
    """Lamé's lambda = 2·mu·nu/(1 − 2·nu) [Pa]; inf at nu = 0.5."""
    return float("inf") if nu >= 0.5 else 2.0 * mu * nu / (1.0 - 2.0 * nu)


#: The deviatoric projector on principal log-stretches, P = I − 1/3·11^T.
_P = np.eye(3) - 1.0 / 3.0


def isochoric(tau_bar: Callable, dtau_bar: Callable) -> tuple[Callable, Callable]:
    """(tau, dtau) of W~(lambda) = W(lambda_bar), lambda_bar = J^(-1/3)·lambda, from W's
    principal Kirchhoff stresses ``tau_bar(lam_bar, p)`` and tangent ``dtau_bar(lam_bar, p)``.

    With ln lambda_bar = P·ln lambda (P the deviatoric projector): tau = P·tau_bar and
    dtau/d ln lambda = P·(dtau_bar/d ln lambda_bar)·P, exactly.
    """
    def tau(lam, p):
        lam = np.asarray(lam, dtype=float)
        bar = lam * np.prod(lam, axis=-1, keepdims=True) ** (-1.0 / 3.0)
        return tau_bar(bar, p) @ _P

    def dtau(lam, p):
        lam = np.asarray(lam, dtype=float)
        bar = lam * np.prod(lam, axis=-1, keepdims=True) ** (-1.0 / 3.0)
        return _P @ dtau_bar(bar, p) @ _P

    return tau, dtau
