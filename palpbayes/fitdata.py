"""The data a fit sees: loading segment, contact onset, admissible surface range, fit window.

Shared by the least-squares baseline and the Bayesian model so both fit the same points.

Rules (docs/design.md §2):

* only the loading segment is used (approach + indentation, no hold/retract);
* the force is read against the pre-contact *baseline* (:mod:`palpbayes.baseline`): a sensor
  that was not tared, or whose baseline drifts, is normal input.  F_unc, when not given, is
  the baseline's noise read as a peak-to-peak spec (6·sd, :mod:`palpbayes.sensor_noise`);
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
from dataclasses import dataclass

import numpy as np

from .baseline import MIN_BASELINE_POINTS, Baseline, estimate_baseline
from .contact import Tip, get_law, youngs_factor
from .errors import FitError, InputError, NoContactError
from .modelspec import BONDINGS, ModelSpec
from .sensor_noise import PAPER_NOISE_PP
from .trace import IndentationTrace
from .units import format_force

__all__ = ["ModelSpec", "BONDINGS", "FitData", "prepare", "tared", "prepare_trace", "first_passage",
           "DEFAULT_F_UNC", "default_fit_fraction", "noise_from_baseline", "onset_reference"]

#: The paper's sensor uncertainty F_unc [N]: 48 mN peak-to-peak
#: (:data:`palpbayes.sensor_noise.PAPER_NOISE_PP`).
DEFAULT_F_UNC = PAPER_NOISE_PP


def default_fit_fraction(tip: Tip) -> float:
    """Fraction of the penetration skipped by default: the tip law's
    (``ContactLaw.default_fit_fraction``; the paper's 0.2 for the flat punch, 0 otherwise)."""
    return get_law(tip).default_fit_fraction


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
    cycle
        The whole recording (the tare subtracted) when it goes on past the loading (a hold,
        a retract: the rate check of :mod:`palpbayes.checks.rate`); None otherwise.
    max_depth
        [m] The window's depth limit below the contact onset (None: all samples).
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
    cycle: IndentationTrace | None = None
    max_depth: float | None = None

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

        Keeps the (walker × sample) work arrays of the Student-t likelihood and of a layer
        whose shape differs per walker below ~32 MB whatever the trace length (the sums over
        trial surfaces of the other fits form no such array: :mod:`palpbayes.shapekernel`).
        """
        step = max(1, max_elements // max(self.n_points, 1))
        return [slice(i, min(i + step, n_rows)) for i in range(0, n_rows, step)]

    def rough_modulus(self) -> float:
        """[Pa] E from the deepest point alone: the force above the baseline at the deepest
        fitted sample over the half-space law's shape at the depth below the contact onset,
        times 1 − nu² (NaN when either is not positive).  Within a factor of about 2 of the
        fit: enough to weigh a force's unit (:mod:`palpbayes.forcescale`), before any fit."""
        level = self.baseline.level - self.tare if self.baseline is not None else 0.0
        i = int(np.argmin(self.z))
        depth = self.z_contact - float(self.z[i])
        peak = float(self.force[i]) - level
        if not (depth > 0 and peak > 0):
            return float("nan")
        shape = float(self.model.half_space().shape(np.array([depth]))[0])
        return peak / shape * youngs_factor(self.model.nu) if shape > 0 else float("nan")

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
            "recording and the force's unit (--force-unit: a force in N read as mN is 1,000 "
            "times too small), or lower --f-unc/--noise-pp"
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
    return _window(loading, base, float(f_unc), model, fit_fraction, max_depth, tare, source,
                   trace if trace.n_points > loading.n_points else None)


def tared(data: FitData) -> FitData:
    """``data`` with the baseline level subtracted from the force: what :func:`prepare` gives
    with ``tare=True`` on the same trace and options, from the loading, baseline and F_unc
    already read (the trace is prepared once per fit; the contact onset is read again against
    the tared baseline).  ``data`` itself when it is tared already."""
    if data.tare != 0.0 or data.baseline is None:
        return data
    return _window(data.loading, data.baseline, data.f_unc, data.model, data.fit_fraction,
                   data.max_depth, True, data.loading.source or data.loading.trace_id,
                   data.cycle)


def _window(loading: IndentationTrace, base: Baseline, f_unc: float, model: ModelSpec,
            fit_fraction: float, max_depth: float | None, tare: bool, source: str,
            whole: IndentationTrace | None) -> FitData:
    """The contact onset and the fit window of a loading segment (:func:`prepare`); ``whole``
    is the untared recording when it goes on past the loading."""
    z, f = loading.z, loading.force
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
            f"{source}: only {n_contact} sample(s) in contact inside the fit window (below the "
            f"contact onset, where the force stays more than F_unc = {format_force(f_unc)} "
            "above its pre-contact level); the indentation is too shallow or the window too "
            "narrow (a shallow indentation's first samples in contact lie within F_unc: a "
            "lower --f-unc counts them; by default F_unc is 6 sd of the baseline noise)"
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
        cycle=None if whole is None else whole.replace(force=whole.force - offset),
        max_depth=max_depth,
    )
