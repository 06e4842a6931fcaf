"""The contact-law registry: one :class:`ContactLaw` per tip kind, registered by its own module,
and the :class:`Tip` whose kind it looks up.

Each law module of :mod:`palpbayes.contact` (``flat.py``, ``sphere.py``, ...) ends with
``LAW = register(ContactLaw(...))``; :mod:`palpbayes.contact` imports every module of the
package, so a new tip kind is one new file.  Everything else in palpbayes asks the registry
(:func:`get_law`, :func:`registered_kinds`, :func:`registered_laws`) rather than naming kinds.

:class:`Tip` lives here because the two depend on each other: a tip is checked against its
kind's law (which parameters it needs), and a law's functions take a tip.

A law module imports from :mod:`.registry`, :mod:`.parameters` and helper modules
(:mod:`.thickness`, :mod:`.mdr`), never from the package :mod:`palpbayes.contact` itself (it is
still being imported when the law registers).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..errors import GeometryError
from .parameters import TIP_PARAMETERS

__all__ = ["Tip", "ContactLaw", "register", "unregister", "get_law", "registered_kinds",
           "registered_laws", "scale_radius"]


@dataclass(frozen=True)
class ContactLaw:
    """A rigid axisymmetric tip's contact law on an elastic half-space, with what palpbayes
    needs to know about it.

    The force is F = E*·s(d) with s the *shape function* [m²] (0 for d <= 0).

    Attributes
    ----------
    kind
        Tip kind, lower case (``Tip(kind, ...)``, the manifest's ``tip`` column, ``--tip``).
    parameters
        :class:`Tip` fields the law needs, each a key of
        :data:`~palpbayes.contact.parameters.TIP_PARAMETERS`, e.g. ``("radius",)``.
    shape
        ``shape(depth, tip) -> F/E*`` [m²] on the half-space; vectorised over ``depth``.
    exponent
        m of s = g·d^m: a number when it does not depend on the tip's size (flat 1), a
        function of the tip when it does (power-law profile), None when the law is no power law
        (exact sphere).
    prefactor
        ``prefactor(tip) -> g`` [m^(2-m)] of s = g·d^m, or None (no power law).
    reference
        Full citation of the law.
    name
        The law's name in messages, e.g. ``"Hertz"`` ("outside the Hertz law's validity").
    label
        Short label of the tip in prose, e.g. ``"flat punch"``.
    summary
        One or two sentences for the report's methods page: the law with its formula.
    describe
        ``describe(tip) -> str``, e.g. ``'flat a=10 mm'`` (:meth:`Tip.describe`).
    order
        Display order in tables, figures and lists (smaller first; ties by kind).
    scaled
        ``scaled(tip, factor) -> Tip`` with every length multiplied by ``factor`` (the budget's
        tip-radius tolerance), or None when the tip has no length scale (cone).
    contact_radius
        ``contact_radius(depth, tip) -> a`` [m], the contact radius on the half-space at each
        depth (the punch's radius for a flat punch): the length the bottom effect of a layer of
        thickness h is read against (:mod:`.layer`), or None when the law has no layer
        solution.
    profile_exponent
        ``profile_exponent(tip) -> n`` of the tip's profile f(r) = c·r^n near the apex (2 for
        paraboloid and sphere, 1 for the cone, ``math.inf`` for the flat punch), selecting the
        layer solution (:mod:`.layer`); None together with ``contact_radius``.
    shape_and_radius
        Optional ``shape_and_radius(depth, tip) -> (s, a)``: both at once, for a law whose
        contact radius costs as much as its shape (the exact sphere solves for it).
    default_fit_fraction
        Fraction of the penetration not fitted by default (the paper: 0.2 for the flat punch).
    max_depth, max_depth_name
        ``max_depth(tip)`` [m], the deepest indentation inside the law's validity (Hertz:
        d <= R), and what that depth is (``"tip radius"``); None: no limit.
    hertz_approximation
        ``hertz_approximation(tip) -> Tip``: the power-law tip the paper fitted in its place
        (sphere -> paraboloid of the same radius), fitted beside it and reported as
        ``E_hertz_pa``; None for no such column.
    profile
        ``profile(r, tip) -> f`` [m]: the tip's surface height above its apex at radius
        ``r`` [m] (``inf`` where the tip has no surface: beyond a flat punch's or a sphere's
        radius), what a finite-element contact solves against (:mod:`palpbayes.twin`);
        None: the tip cannot be set on a specimen twin.
    """

    kind: str
    parameters: tuple[str, ...]
    shape: Callable[[np.ndarray, Tip], np.ndarray]
    exponent: float | Callable[[Tip], float] | None
    prefactor: Callable[[Tip], float] | None
    reference: str
    name: str
    label: str
    summary: str
    describe: Callable[[Tip], str]
    order: int = 100
    scaled: Callable[[Tip, float], Tip] | None = None
    contact_radius: Callable[[np.ndarray, Tip], np.ndarray] | None = None
    profile_exponent: Callable[[Tip], float] | None = None
    shape_and_radius: Callable[[np.ndarray, Tip], tuple[np.ndarray, np.ndarray]] | None = None
    default_fit_fraction: float = 0.0
    max_depth: Callable[[Tip], float] | None = None
    max_depth_name: str = ""
    hertz_approximation: Callable[[Tip], Tip] | None = None
    profile: Callable[[np.ndarray, Tip], np.ndarray] | None = None

    def __post_init__(self) -> None:
        if not (isinstance(self.kind, str) and self.kind == self.kind.strip().lower()
                and self.kind.isidentifier()):
            raise ValueError(f"contact-law kind {self.kind!r} must be a lower-case identifier")
        unknown = [p for p in self.parameters if p not in TIP_PARAMETERS]
        if unknown:
            raise ValueError(f"contact law {self.kind!r}: unknown tip parameter(s) {unknown}; "
                             f"known: {', '.join(TIP_PARAMETERS)}")
        if (self.exponent is None) != (self.prefactor is None):
            raise ValueError(f"contact law {self.kind!r}: give both exponent and prefactor "
                             "(a power law) or neither")
        if (self.contact_radius is None) != (self.profile_exponent is None):
            raise ValueError(f"contact law {self.kind!r}: give both contact_radius and "
                             "profile_exponent (a layer solution) or neither")
        if not 0.0 <= self.default_fit_fraction < 1.0:
            raise ValueError(f"contact law {self.kind!r}: default_fit_fraction must lie in "
                             "[0, 1)")

    @property
    def fixed_exponent(self) -> float | None:
        """The exponent m when it does not depend on the tip's size, else None."""
        return None if self.exponent is None or callable(self.exponent) else float(self.exponent)

    def exponent_of(self, tip: Tip) -> float | None:
        """Exponent m of F = k·d^m for ``tip``, or None when the law is no power law."""
        if self.exponent is None or not callable(self.exponent):
            return self.fixed_exponent
        return float(self.exponent(tip))

    def prefactor_of(self, tip: Tip) -> float | None:
        """Geometry factor g of s = g·d^m [m^(2-m)] for ``tip``, or None."""
        return None if self.prefactor is None else float(self.prefactor(tip))


_LAWS: dict[str, ContactLaw] = {}


def register(law: ContactLaw) -> ContactLaw:
    """Add ``law`` to the registry and return it (``LAW = register(ContactLaw(...))``).

    Raises
    ------
    ValueError
        If a law of the same kind is registered already.
    """
    if law.kind in _LAWS:
        raise ValueError(f"a contact law for tip kind {law.kind!r} is registered already "
                         f"({_LAWS[law.kind].reference})")
    _LAWS[law.kind] = law
    return law


def unregister(kind: str) -> ContactLaw:
    """Remove and return the law of ``kind`` (for tests that register a law of their own).

    Raises
    ------
    KeyError
        If no law of that kind is registered.
    """
    return _LAWS.pop(kind)


def registered_laws() -> tuple[ContactLaw, ...]:
    """Every registered law, in display order."""
    return tuple(sorted(_LAWS.values(), key=lambda law: (law.order, law.kind)))


def registered_kinds() -> tuple[str, ...]:
    """Every registered tip kind, in display order (flat, sphere, paraboloid, cone, power)."""
    return tuple(law.kind for law in registered_laws())


def get_law(kind_or_tip: str | Tip) -> ContactLaw:
    """The law of a tip kind, or of a :class:`Tip`.

    Raises
    ------
    GeometryError
        If the kind is not registered (naming the registered ones).
    """
    kind = getattr(kind_or_tip, "kind", kind_or_tip)
    try:
        return _LAWS[str(kind).strip().lower()]
    except KeyError:
        raise GeometryError(
            f"unknown tip kind {kind!r}; use one of {', '.join(registered_kinds())}"
        ) from None


@dataclass(frozen=True)
class Tip:
    """A rigid axisymmetric indenter.

    Parameters
    ----------
    kind
        A registered tip kind (:func:`registered_kinds`): ``"flat"``
        (cylindrical flat punch), ``"paraboloid"`` (Hertz), ``"sphere"`` (exact Sneddon
        sphere), ``"cone"``, ``"power"`` (profile f(r) = c·r^n), or one registered since.
    radius
        [m] Punch radius (flat) or radius of curvature (paraboloid, sphere).
    half_angle
        [rad] Half-opening angle of a cone, axis to flank (profile f = r·cot(alpha)).
    c, n
        Power-law profile f(r) = c·r^n, ``c`` in [m^(1-n)], ``n`` > 0 dimensionless.

    The fields are those of :data:`~palpbayes.contact.parameters.TIP_PARAMETERS`; the kind's law
    says which it needs (``ContactLaw.parameters``), the others are ignored.

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
        law = get_law(self.kind)
        object.__setattr__(self, "kind", law.kind)
        for name in law.parameters:
            TIP_PARAMETERS[name].check(getattr(self, name), law.kind)

    def describe(self) -> str:
        """Short human-readable description, e.g. ``'sphere R=10 mm'`` or ``'sphere R=20 nm'``."""
        return get_law(self).describe(self)

    @property
    def has_length_scale(self) -> bool:
        """False when the tip's shape has no length (a cone): :meth:`scaled` changes nothing."""
        return get_law(self).scaled is not None

    def scaled(self, factor: float) -> Tip:
        """The same tip with its length scale multiplied by ``factor`` (radius tolerance).

        A tip without length scale (a cone) is returned unchanged.  For a power-law profile,
        scaling lengths by ``s`` maps c to c·s^(1-n).
        """
        scaled = get_law(self).scaled
        return self if scaled is None else scaled(self, factor)


def scale_radius(tip: Tip, factor: float) -> Tip:
    """``tip`` with its radius multiplied by ``factor``: the ``scaled`` of every law whose only
    length is the radius (flat, sphere, paraboloid)."""
    return dataclasses.replace(tip, radius=tip.radius * factor)
