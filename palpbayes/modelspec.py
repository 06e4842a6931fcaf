"""The contact model of a fit (:class:`ModelSpec`): tip, Poisson ratio and the specimen's
layer (thickness and base, each known or to be inferred) or the specimen as tested (a block of
known footprint and height: :mod:`palpbayes.twin`), and the material law (linear, the paper's,
or a hyperelastic law at finite strain: :mod:`palpbayes.twin.hyper_shape`), with its shape
function F/E* = s(d) (:mod:`palpbayes.contact`).  :class:`palpbayes.fitdata.FitData` carries
one.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from .contact import DEFAULT_NU, Tip, check_nu, exponent, shape, youngs_modulus
from .errors import FitError, InputError
from .twin import Specimen, twin_shape
from .twin.hyper_shape import LawModel, law_shape
from .units import format_length

__all__ = ["ModelSpec", "BONDINGS"]

#: Base conditions of a layer that a fit can assume: bonded, free (frictionless) or unknown
#: (both, weighted by the data: a two-component mixture).
BONDINGS = ("bonded", "free", "unknown")
#: How finely an unknown thickness may be integrated (:attr:`ModelSpec.thickness_grid`).
THICKNESS_GRIDS = ("fine", "coarse")


@dataclass(frozen=True)
class ModelSpec:
    """Contact model: tip, Poisson ratio and the specimen's layer (finite thickness).

    A specimen of known thickness is a layer on a rigid base (:mod:`palpbayes.contact.layer`);
    without a thickness it is a half-space, the paper's model.  What is not known about the
    layer is a parameter of the Bayesian model: the base condition (``bonding="unknown"``: the
    bonded and the frictionless base as two components weighted by the data) and, with
    ``thickness_range``, the thickness itself (log-uniform prior).  A model with nothing
    unknown is *concrete*: it has one shape function (:meth:`shape`); :meth:`variant` gives
    the concrete model of each component.

    Parameters
    ----------
    tip
        The indenter.
    nu
        Poisson ratio [-] used to turn E* into E (and in the bonded layer solution).
    thickness
        [m] Layer thickness h when known; None for a half-space (or, with
        ``thickness_range``, an unknown thickness).
    bonding
        ``"bonded"``, ``"free"`` (frictionless base) or ``"unknown"`` (default: a block lying
        on a plate is neither).  Irrelevant for a half-space.
    thickness_range
        [m] (lo, hi) of the log-uniform prior of an unknown thickness; None when the thickness
        is known or absent.
    p_bonded
        Prior probability of the bonded base when ``bonding`` is unknown.
    specimen
        The block as tested (:class:`~palpbayes.twin.Specimen`: footprint and height); None:
        a layer of infinite width (or a half-space).  With a specimen the shape function is
        its finite-element twin's (:func:`palpbayes.twin.twin_shape`), and ``thickness`` is
        its height.
    law
        A hyperelastic law (:class:`~palpbayes.twin.hyper_shape.LawModel`) on the same
        geometry (the specimen, a wide cylinder of the known thickness, or a half-space
        proxy); None: linear elasticity, the paper's model.  Its free shape parameters make
        the model a mixture (not concrete); a foam's concrete variant takes its own nu.
    thickness_grid
        How finely an unknown thickness is integrated (:mod:`palpbayes.bayes.layers`):
        ``"fine"`` (the default, a fit's own layer) or ``"coarse"`` (the model form's layer
        alternative, whose interval counts only in an envelope: about 40 % fewer exact
        posteriors, full intervals of the 22 real curves within 0.2 %).
    """

    tip: Tip
    nu: float = DEFAULT_NU
    thickness: float | None = None
    bonding: str = "unknown"
    thickness_range: tuple[float, float] | None = None
    p_bonded: float = 0.5
    specimen: Specimen | None = None
    law: LawModel | None = None
    thickness_grid: str = "fine"

    def __post_init__(self) -> None:
        if self.thickness_grid not in THICKNESS_GRIDS:
            raise InputError(f"unknown thickness grid {self.thickness_grid!r}; use one of "
                             f"{', '.join(THICKNESS_GRIDS)}")
        object.__setattr__(self, "nu", check_nu(self.nu))
        if self.law is not None:
            if self.thickness_range is not None:
                raise InputError(f"a material law ({self.law.name}) needs the specimen's "
                                 "geometry: give --specimen or --thickness, or neither (a "
                                 "half-space), not --thickness unknown")
            own = self.law.foam_nu()
            if own is not None:  # a foam's concrete variant: its own Poisson ratio
                object.__setattr__(self, "nu", check_nu(own))
        if self.specimen is not None:
            if self.thickness_range is not None:
                raise InputError("a specimen's height is its thickness: give the specimen "
                                 "(--specimen) or an unknown thickness (--thickness unknown), "
                                 "not both")
            h = self.specimen.height
            if self.thickness is None:
                object.__setattr__(self, "thickness", h)
            elif not np.isclose(float(self.thickness), h, rtol=1e-9, atol=0.0):
                raise InputError(f"specimen thickness {self.thickness!r} m differs from the "
                                 f"specimen's height {h!r} m: give one of the two")
        if self.bonding not in BONDINGS:
            raise InputError(f"unknown bonding {self.bonding!r}; use one of "
                             f"{', '.join(BONDINGS)}")
        if self.thickness is not None:
            h = float(self.thickness)
            if not (np.isfinite(h) and h > 0):
                raise InputError(f"specimen thickness {self.thickness!r} m must be positive")
            object.__setattr__(self, "thickness", h)
        if self.thickness_range is not None:
            if self.thickness is not None:
                raise InputError("give either a known thickness or a thickness range (unknown "
                                 "thickness), not both")
            lo, hi = (float(v) for v in self.thickness_range)
            if not (np.isfinite(lo) and np.isfinite(hi) and 0 < lo < hi):
                raise InputError(f"thickness range {self.thickness_range!r} m must satisfy "
                                 "0 < lo < hi")
            object.__setattr__(self, "thickness_range", (lo, hi))
        if not 0.0 < self.p_bonded < 1.0:
            raise InputError(f"prior probability of a bonded base {self.p_bonded!r} must lie "
                             "strictly between 0 and 1")

    @property
    def has_layer(self) -> bool:
        """True when the specimen is modelled as a layer (thickness known or sampled)."""
        return self.thickness is not None or self.thickness_range is not None

    @property
    def thickness_unknown(self) -> bool:
        return self.thickness_range is not None

    @property
    def bases(self) -> tuple[str, ...]:
        """The base conditions the model allows: ``("bonded", "free")`` when unknown."""
        if not self.has_layer:
            return ("bonded",)
        return ("bonded", "free") if self.bonding == "unknown" else (self.bonding,)

    @property
    def base(self) -> str:
        """The base condition of a concrete layer model (``"bonded"`` for a half-space)."""
        self._require_concrete("a single base condition")
        return self.bases[0]

    @property
    def is_concrete(self) -> bool:
        """True when the model has one shape function (nothing about the layer unknown, every
        free shape parameter of its law given)."""
        law = self.law is None or self.law.is_concrete
        return law and (not self.has_layer
                        or (self.thickness is not None and self.bonding != "unknown"))

    def variant(self, *, thickness: float | None = None, base: str | None = None,
                law_point: dict | None = None) -> ModelSpec:
        """The concrete model with the given thickness [m], base and law shape parameters
        ``law_point`` (by name; defaults: the known thickness, the known base, the law's
        point)."""
        h = self.thickness if thickness is None else float(thickness)
        b = base if base is not None else (self.bonding if self.bonding != "unknown" else None)
        if self.has_layer and (h is None or b is None):
            raise InputError("a concrete variant of a layer model needs its thickness and base")
        spec = self.specimen
        if spec is not None and h != spec.height:
            spec = spec.with_height(h)
        law = self.law
        if law is not None and law_point is not None:
            law = law.at(law_point)
        return replace(self, thickness=h, thickness_range=None,
                       bonding=b if b is not None else self.bonding, specimen=spec, law=law)

    def half_space(self) -> ModelSpec:
        """The same tip and nu on a half-space, linear: the paper's model."""
        return replace(self, thickness=None, thickness_range=None, specimen=None, law=None)

    def with_nu(self, nu: float) -> ModelSpec:
        """The same model at Poisson ratio ``nu`` [-] (a foam's law whose nu is fixed: that
        nu too)."""
        law = self.law
        name = None if law is None else law.law.nu_parameter
        if name is not None and name in dict(law.nodes) and name not in law.free:
            law = replace(law, nodes=tuple((n, (float(nu),)) if n == name else (n, g)
                                           for n, g in law.nodes))
        return replace(self, nu=nu, law=law)

    def linear(self) -> ModelSpec:
        """The same model without its material law: linear elasticity on the same geometry
        (itself when it has no law)."""
        return self if self.law is None else replace(self, law=None)

    def layer_only(self) -> ModelSpec:
        """The same model with the specimen's footprint dropped: a layer of its height and
        infinite width (itself when there is no specimen)."""
        return self if self.specimen is None else replace(self, specimen=None)

    def _require_concrete(self, what: str) -> None:
        if not self.is_concrete:
            raise FitError(f"the model {self.describe()} has no {what}: its layer is partly "
                           "unknown (base or thickness); take a concrete variant "
                           "(ModelSpec.variant)")

    @property
    def exponent(self) -> float | None:
        """Exponent m of F = k·d^m on a half-space, None for the exact sphere, a layer or a
        material law."""
        return exponent(self.tip) if not self.has_layer and self.law is None else None

    def shape(self, depth: np.ndarray) -> np.ndarray:
        """F/E* [m²] at depth [m] (with the layer's bottom effect when it has one, the
        specimen twin's law when it has a specimen)."""
        self._require_concrete("single shape function")
        if self.law is not None:
            return self._law_shape(depth, self.bases[0])
        if self.thickness is None:
            return shape(depth, self.tip)
        if self.specimen is not None:
            return twin_shape(depth, self.tip, self.specimen, self.nu, self.bases[0])
        return shape(depth, self.tip, thickness_m=self.thickness, nu=self.nu,
                     base=self.bases[0])

    def shape_at(self, depth: np.ndarray, thickness=None, base: str | None = None
                 ) -> np.ndarray:
        """F/E* [m²] at ``depth`` for a thickness [m] (number or array broadcastable with
        ``depth``, e.g. one per draw) and a base; None: the model's own."""
        h = self.thickness if thickness is None else thickness
        if self.law is not None:
            if thickness is not None and not np.allclose(thickness, self.thickness or np.inf):
                raise FitError("a material law's twin has the model's own thickness; another "
                               "thickness needs its own (ModelSpec.variant)")
            return self._law_shape(depth, base if base is not None else self.base)
        if h is None:
            return shape(depth, self.tip)
        b = base if base is not None else self.base
        if self.specimen is not None:
            self._same_height(h)
            return twin_shape(depth, self.tip, self.specimen, self.nu, b)
        return shape(depth, self.tip, thickness_m=h, nu=self.nu, base=b)

    def _law_shape(self, depth, base: str) -> np.ndarray:
        """F/E* [m²] of the concrete law at ``depth`` [m] on ``base``."""
        if self.law.mode == "correction":
            from .twin.hyper_correction import neo_hookean_correction

            return self.linear().shape_at(depth, base=base if self.has_layer else None) * (
                neo_hookean_correction(depth, self.tip, self.nu))
        return law_shape(depth, self.tip, self.nu, self.law, self.thickness, self.specimen,
                         base)

    def _same_height(self, thickness) -> None:
        h = np.asarray(thickness, dtype=float)
        if not np.allclose(h, self.specimen.height, rtol=1e-9, atol=0.0):
            raise FitError("the specimen twin's thickness is the specimen's height; another "
                           "thickness needs its own twin (ModelSpec.variant)")

    def shape_of_draws(self, depth: np.ndarray, thickness=None, bonded=None) -> np.ndarray:
        """F/E* [m²] of posterior draws (rows of ``depth``, shape (D, N)), each with its own
        thickness [m] (``inf``: no layer) and base (``bonded`` 1.0 / 0.0; NaN where there is
        no layer); None: the model's own.  Evaluated where the depth is positive only (the
        shape is 0 out of contact)."""
        depth = np.asarray(depth, dtype=float)
        if thickness is None and bonded is None:
            return self.shape(depth)
        rows_n = depth.shape[0]
        h = np.broadcast_to(np.inf if self.thickness is None and thickness is None
                            else (self.thickness if thickness is None else thickness),
                            (rows_n,)).astype(float)
        if bonded is None:
            b = np.full(rows_n, self.bases[0])
        else:
            b = np.where(np.asarray(bonded, dtype=float) == 0.0, "free", "bonded")
        out = np.zeros(depth.shape)
        if self.specimen is not None:
            self._same_height(h)
        h = np.broadcast_to(h[:, None], depth.shape)
        for base in np.unique(b):
            cells = (depth > 0) & (b == base)[:, None]
            if self.law is not None:
                out[cells] = self._law_shape(depth[cells], str(base))
            elif self.specimen is not None:
                out[cells] = twin_shape(depth[cells], self.tip, self.specimen, self.nu,
                                        str(base))
            else:
                out[cells] = shape(depth[cells], self.tip, thickness_m=h[cells], nu=self.nu,
                                   base=str(base))
        return out

    def shape_derivative(self, depth: np.ndarray) -> np.ndarray:
        """d(F/E*)/dd [m] by central differences (step 1e-9 m, one-sided at d = 0)."""
        h = 1e-9
        d = np.asarray(depth, dtype=float)
        return (self.shape(d + h) - self.shape(np.maximum(d - h, 0.0))) / (
            d + h - np.maximum(d - h, 0.0)
        )

    def to_E(self, Estar):
        """Young's modulus E = E*·(1 − nu²) [Pa]."""
        return youngs_modulus(Estar, self.nu)

    def describe_layer(self) -> str:
        """The layer in words: ``half-space``, ``h=20 mm, base unknown``, ``50 × 50 × 20 mm
        block, free base``, ..."""
        if not self.has_layer:
            return "half-space"
        if self.specimen is not None:
            h = self.specimen.describe()
        elif self.thickness is not None:
            h = f"h={self.thickness * 1e3:g} mm"
        else:
            lo, hi = self.thickness_range
            h = f"h unknown in [{format_length(lo)}, {format_length(hi)}]"
        base = {"bonded": "bonded", "free": "free base", "unknown": "base unknown"}[self.bonding]
        return f"{h}, {base}"

    def describe(self) -> str:
        law = "" if self.law is None else f", {self.law.describe()}"
        return f"{self.tip.describe()}, nu={self.nu:g}, {self.describe_layer()}{law}"
