"""The data a fit sees: loading segment, contact onset, admissible surface range, fit window.

Shared by the least-squares baseline and the Bayesian model so both fit the same points.

Rules (docs/design.md §2):

* only the loading segment is used (approach + indentation, no hold/retract);
* the force is read against the pre-contact *baseline* (:mod:`palpbayes.baseline`): a sensor
  that was not tared, or whose baseline drifts, is normal input.  F_unc, when not given, is
  the baseline's noise read as a peak-to-peak spec (6·sd, :mod:`palpbayes.noise`);
* the *contact onset* z_c is where the measured force last lies within ±F_unc of its
  reference before it stays above it (linear interpolation between the two samples), read
  along the samples where the tip reaches a new deepest point (:func:`first_passage`; all
  samples when z is monotone).  The reference is zero — the paper's constraint
  −F_unc <= F(z_surf) <= F_unc, exactly — when the sensor is tared to within F_unc, and the
  baseline level b otherwise (untared: |F(z_surf) − b| <= F_unc, the only form that has a
  solution).  It admits z_surf in [z_c, z_top], z_top the start of the approach: the
  least-squares baseline's search range.  The Bayesian model does not use it: its surface
  prior spans the whole loading range [z_min, z_top];
* ``tare=True`` subtracts the baseline level from the force (zeroing the sensor), so that the
  paper's model, which has no offset term, can be fitted to an untared recording;
* for a tip with ``fit_fraction`` f > 0 (the paper uses f = 0.2 for the flat punch) only samples
  with z <= z_c − f·(z_c − z_min) are fitted, a window fixed once from z_c so the objective is a
  smooth function of z_surf;  with f = 0 every loading sample (approach included) is fitted.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from .baseline import MIN_BASELINE_POINTS, Baseline, estimate_baseline
from .contact import Tip, check_nu, exponent, get_law, shape
from .errors import FitError, InputError, NoContactError
from .noise import PAPER_NOISE_PP
from .trace import IndentationTrace
from .units import format_force, format_length

__all__ = ["ModelSpec", "BONDINGS", "FitData", "prepare", "prepare_trace", "first_passage",
           "DEFAULT_F_UNC", "default_fit_fraction", "noise_from_baseline", "onset_reference"]

#: The paper's sensor uncertainty F_unc [N]: 48 mN peak-to-peak
#: (:data:`palpbayes.noise.PAPER_NOISE_PP`).
DEFAULT_F_UNC = PAPER_NOISE_PP


def default_fit_fraction(tip: Tip) -> float:
    """Fraction of the penetration skipped by default: the tip law's
    (``ContactLaw.default_fit_fraction``; the paper's 0.2 for the flat punch, 0 otherwise)."""
    return get_law(tip).default_fit_fraction


#: Base conditions of a layer that a fit can assume: bonded, free (frictionless) or unknown
#: (both, weighted by the data: a two-component mixture).
BONDINGS = ("bonded", "free", "unknown")


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
    """

    tip: Tip
    nu: float = 0.3
    thickness: float | None = None
    bonding: str = "unknown"
    thickness_range: tuple[float, float] | None = None
    p_bonded: float = 0.5

    def __post_init__(self) -> None:
        object.__setattr__(self, "nu", check_nu(self.nu))
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
        """True when the model has one shape function (nothing about the layer unknown)."""
        return not self.has_layer or (self.thickness is not None and self.bonding != "unknown")

    def variant(self, *, thickness: float | None = None, base: str | None = None) -> ModelSpec:
        """The concrete model with the given thickness [m] and base (defaults: the known
        thickness, the known base)."""
        h = self.thickness if thickness is None else float(thickness)
        b = base if base is not None else (self.bonding if self.bonding != "unknown" else None)
        if self.has_layer and (h is None or b is None):
            raise InputError("a concrete variant of a layer model needs its thickness and base")
        return replace(self, thickness=h, thickness_range=None,
                       bonding=b if b is not None else self.bonding)

    def half_space(self) -> ModelSpec:
        """The same tip and nu on a half-space (the paper's model)."""
        return replace(self, thickness=None, thickness_range=None)

    def _require_concrete(self, what: str) -> None:
        if not self.is_concrete:
            raise FitError(f"the model {self.describe()} has no {what}: its layer is partly "
                           "unknown (base or thickness); take a concrete variant "
                           "(ModelSpec.variant)")

    @property
    def exponent(self) -> float | None:
        """Exponent m of F = k·d^m on a half-space, None for the exact sphere or a layer."""
        return exponent(self.tip) if not self.has_layer else None

    def shape(self, depth: np.ndarray) -> np.ndarray:
        """F/E* [m²] at depth [m] (with the layer's bottom effect when it has one)."""
        self._require_concrete("single shape function")
        if self.thickness is None:
            return shape(depth, self.tip)
        return shape(depth, self.tip, thickness_m=self.thickness, nu=self.nu,
                     base=self.bases[0])

    def shape_at(self, depth: np.ndarray, thickness=None, base: str | None = None
                 ) -> np.ndarray:
        """F/E* [m²] at ``depth`` for a thickness [m] (number or array broadcastable with
        ``depth``, e.g. one per draw) and a base; None: the model's own."""
        h = self.thickness if thickness is None else thickness
        if h is None:
            return shape(depth, self.tip)
        b = base if base is not None else self.base
        return shape(depth, self.tip, thickness_m=h, nu=self.nu, base=b)

    def shape_of_draws(self, depth: np.ndarray, thickness=None, bonded=None) -> np.ndarray:
        """F/E* [m²] of posterior draws (rows of ``depth``, shape (D, N)), each with its own
        thickness [m] (``inf``: no layer) and base (``bonded`` 1.0 / 0.0; NaN where there is
        no layer); None: the model's own."""
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
        out = np.empty(depth.shape)
        for base in np.unique(b):
            rows = b == base
            out[rows] = shape(depth[rows], self.tip, thickness_m=h[rows, None], nu=self.nu,
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
        return Estar * (1.0 - self.nu**2)

    def describe_layer(self) -> str:
        """The layer in words: ``half-space``, ``h=20 mm, base unknown``, ..."""
        if not self.has_layer:
            return "half-space"
        if self.thickness is not None:
            h = f"h={self.thickness * 1e3:g} mm"
        else:
            lo, hi = self.thickness_range
            h = f"h unknown in [{format_length(lo)}, {format_length(hi)}]"
        base = {"bonded": "bonded", "free": "free base", "unknown": "base unknown"}[self.bonding]
        return f"{h}, {base}"

    def describe(self) -> str:
        return f"{self.tip.describe()}, nu={self.nu:g}, {self.describe_layer()}"


@dataclass(frozen=True)
class FitData:
    """Points to fit and the surface constraint.

    Attributes
    ----------
    z, force
        [m], [N] fitted samples (window applied).
    z_contact
        [m] Contact onset z_c: lower end of the admissible surface range.
    z_top
        [m] Highest loading sample: upper end of the admissible range.
    z_min
        [m] Deepest loading sample.
    f_unc
        [N] Sensor uncertainty used in the constraint.
    fit_fraction
        Fraction of the penetration skipped at the start of contact.
    loading
        The whole loading segment (for the constraint and plots).
    model
        The contact model.
    baseline
        Pre-contact baseline of the loading segment (before any tare).
    tare
        [N] Force subtracted from the measured force (the baseline level when tared, else 0).
    """

    z: np.ndarray
    force: np.ndarray
    z_contact: float
    z_top: float
    z_min: float
    f_unc: float
    fit_fraction: float
    loading: IndentationTrace
    model: ModelSpec
    baseline: Baseline | None = None
    tare: float = 0.0

    @property
    def z_prior(self) -> tuple[float, float]:
        """[m] Support of the Bayesian surface prior: the whole loading range [z_min, z_top]."""
        return self.z_min, self.z_top

    @property
    def n_points(self) -> int:
        return int(self.z.size)

    @property
    def shape(self) -> Callable[[np.ndarray], np.ndarray]:
        return self.model.shape

    def blocks(self, n_rows: int, max_elements: int = 1 << 22) -> list[slice]:
        """Slices over ``n_rows`` trial surfaces so that rows × n_points <= ``max_elements``.

        Keeps the (trial surface × sample) work arrays of least squares and of the likelihood
        table below ~32 MB whatever the trace length.
        """
        step = max(1, max_elements // max(self.n_points, 1))
        return [slice(i, min(i + step, n_rows)) for i in range(0, n_rows, step)]

    def measured_force_at(self, z_surf: float | np.ndarray) -> np.ndarray:
        """Measured force [N] when the tip first passed ``z_surf`` on the way down.

        First passage in time order: the force is interpolated over the samples where the tip
        reaches a new deepest point, so a noisy, locally non-monotone z (robot position noise)
        gives the force of the same approach that defines the contact onset, not a mixture of
        samples sorted by height.  For monotone z this is plain interpolation of F(z).
        """
        z, f = first_passage(self.loading.z, self.loading.force)
        return np.interp(z_surf, z[::-1], f[::-1]) - self.tare


def first_passage(z: np.ndarray, force: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The samples (in time order) where the tip reaches a new deepest point [m], [N].

    z is strictly decreasing along them; with monotone z these are all samples.  The contact
    onset and the force "where the tip passes z_surf" (the paper's constraint) are both read
    from this sequence, so they agree when robot position noise makes z locally non-monotone.
    """
    keep = np.flatnonzero(np.diff(np.minimum.accumulate(z), prepend=np.inf) < 0)
    return z[keep], force[keep]


def _contact_onset(z: np.ndarray, f: np.ndarray, f_unc: float, base: Baseline,
                   source: str) -> float:
    """Height [m] where F − baseline last lies within ±f_unc before staying above it."""
    reference = onset_reference(base, f_unc)
    excess = f - reference
    inside = np.abs(excess) <= f_unc
    if inside.all() or excess.max() <= f_unc:
        raise NoContactError(
            f"{source}: no contact: the force never leaves ±{format_force(f_unc)} around its "
            f"pre-contact level ({format_force(reference)}; largest rise "
            f"{format_force(excess.max())}), so the tip never reaches the surface; check the "
            "recording, or lower --f-unc/--noise-pp"
        )
    if not inside.any():
        raise InputError(
            f"{source}: the force is never within ±{format_force(f_unc)} of its pre-contact "
            f"level ({format_force(reference)}); give the sensor noise with --noise-pp"
        )
    last = int(np.flatnonzero(inside)[-1])
    if last == f.size - 1:
        raise NoContactError(
            f"{source}: the force is back within ±{format_force(f_unc)} of its pre-contact "
            "level at the deepest point; the tip does not stay in contact (is the force sign "
            "flipped? try --force-sign -1)"
        )
    # interpolate where |F − baseline| crosses f_unc between samples `last` and `last + 1`
    f0, f1 = excess[last], excess[last + 1]
    target = np.sign(f1) * f_unc
    w = 0.0 if f1 == f0 else float(np.clip((target - f0) / (f1 - f0), 0.0, 1.0))
    return float(z[last] + w * (z[last + 1] - z[last]))


def onset_reference(base: Baseline, f_unc: float) -> float:
    """[N] Force level the contact onset is read against: 0 on a sensor tared to within
    ``f_unc`` (the paper's constraint as written), the baseline level otherwise."""
    return float(base.level) if abs(base.level) > f_unc else 0.0


def noise_from_baseline(base: Baseline, source: str) -> float:
    """[N] The peak-to-peak noise spec read off the baseline (6·sd), or a clear error."""
    if base.n >= MIN_BASELINE_POINTS and base.sd == 0:
        raise InputError(
            f"{source}: the force before contact has no noise (a noise-free simulation?), so "
            "no noise spec can be read from it; give --noise-pp (or --f-unc) in N"
        )
    if not base.reliable:
        raise InputError(
            f"{source}: too few samples before contact ({base.n}) to estimate the sensor noise; "
            "give it with --noise-pp (the sensor's peak-to-peak noise in N), or record a "
            "longer approach"
        )
    return base.noise_pp


def prepare_trace(
    trace: IndentationTrace,
    model: ModelSpec | None = None,
    *,
    f_unc: float | None = None,
    fit_fraction: float | None = None,
    max_depth: float | None = None,
    tare: bool = False,
) -> FitData:
    """The fit data of ``trace`` under ``model`` (default ``ModelSpec(trace.tip)``): the common
    first step of :func:`~palpbayes.lsq.fit_lsq` and :func:`~palpbayes.bayes.fit_bayes`.

    Raises :class:`~palpbayes.errors.FitError` when ``model`` is None and the trace has no tip;
    the other arguments are those of :func:`prepare`.
    """
    if model is None:
        if trace.tip is None:
            raise FitError(f"{trace.trace_id}: no tip geometry given; pass a ModelSpec")
        model = ModelSpec(trace.tip)
    return prepare(trace, model, f_unc=f_unc, fit_fraction=fit_fraction, max_depth=max_depth,
                   tare=tare)


def prepare(
    trace: IndentationTrace,
    model: ModelSpec,
    *,
    f_unc: float | None = None,
    fit_fraction: float | None = None,
    max_depth: float | None = None,
    tare: bool = False,
) -> FitData:
    """Select the loading segment, the contact onset and the fit window of ``trace``.

    Parameters
    ----------
    trace
        The measurement (SI).
    model
        Contact model.
    f_unc
        [N] Sensor uncertainty of the constraint |F(z_surf)| <= F_unc (paper: 48 mN); None:
        the baseline's noise as a peak-to-peak spec (:func:`noise_from_baseline`).
    fit_fraction
        Fraction of the penetration (from the contact onset) left out; None for the paper's
        default (:func:`default_fit_fraction`).
    max_depth
        [m] Drop samples deeper than this below the contact onset (None: keep all).
    tare
        Subtract the baseline level from the force (zero the sensor) before fitting.

    Raises
    ------
    NoContactError
        If the force never rises above ``f_unc`` or the trace has too few contact samples.
    InputError
        If no surface height satisfies the constraint, or an option is out of range.
    """
    if f_unc is not None and not (np.isfinite(f_unc) and f_unc > 0):
        raise InputError(f"F_unc must be a positive force in newtons, got {f_unc!r}")
    if fit_fraction is None:
        fit_fraction = default_fit_fraction(model.tip)
    if not 0.0 <= fit_fraction < 1.0:
        raise InputError(f"fit fraction {fit_fraction!r} must lie in [0, 1)")
    source = trace.source or trace.trace_id
    loading = trace.loading_segment()
    z, f = loading.z, loading.force
    base = estimate_baseline(z, f)
    if f_unc is None:
        if np.ptp(f) == 0:
            raise NoContactError(f"{source}: no contact: the force never leaves its constant "
                                 f"value ({format_force(f[0])}) over the whole loading")
        f_unc = noise_from_baseline(base, source)
    z_c = _contact_onset(*first_passage(z, f - (base.level if tare else 0.0)), f_unc,
                         base.shifted(-base.level) if tare else base, source)
    z_min = float(z.min())
    keep = np.ones(z.size, dtype=bool)
    if fit_fraction > 0:
        keep &= z <= z_c - fit_fraction * (z_c - z_min)
    if max_depth is not None:
        keep &= z >= z_c - max_depth
    n_contact = int(np.count_nonzero(keep & (z < z_c)))
    if n_contact < 5:
        raise NoContactError(
            f"{source}: only {n_contact} sample(s) in contact inside the fit window; the "
            "indentation is too shallow or the window too narrow"
        )
    offset = base.level if tare else 0.0
    return FitData(
        z=np.ascontiguousarray(z[keep]),
        force=np.ascontiguousarray(f[keep] - offset),
        z_contact=z_c,
        z_top=float(z.max()),
        z_min=z_min,
        f_unc=float(f_unc),
        fit_fraction=float(fit_fraction),
        loading=loading,
        model=model,
        baseline=base,
        tare=float(offset),
    )
