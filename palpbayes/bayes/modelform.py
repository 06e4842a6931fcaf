"""Model-form uncertainty: E's interval over the models a misfitting curve leaves plausible.

E's interval has three parts.  The **statistical** one is the posterior of E* (noise, the
unknown surface).  The **budget** adds the inputs a trace cannot identify (:mod:`.budget`:
Poisson ratio, tip radius, gain, compliance, thickness).  Both assume that the contact law is
right.  When the model checks find a *material* misfit (:mod:`palpbayes.checks.effect`), it
is not, and the curve does not say which other model is: the **model form** part is then the
spread of E over alternatives that stand for the misfits the checks name, each refitted and
given the same budget:

=====================  ====================================================================
alternative            what it stands for
=====================  ====================================================================
shallow half           the law holds near the surface only (strain stiffening, a stiffer
                       base felt at depth): E* over the shallower half of the depth
                       (:func:`palpbayes.checks.depth_consistency_check`)
deep half              something near the surface that the law lacks (a gradual onset, a soft
                       skin, adhesion, a blunted apex): E* over the deeper half, with its own
                       surface and force offset
layer, thickness       a finite thickness that was not given (half-space models whose
unknown                apparent modulus rises with depth: :func:`points_to_stiffer_base`):
                       the exact engine with h log-uniform (:mod:`.layers`), kept only when
                       it converges and its own checks find no material misfit
neo-Hookean            finite strain (a linear fit of a trace pressed deep, whether or not a
                       check fails): the same data read with the compressible neo-Hookean
                       solid at the same nu and geometry, kept when the data allow it and it
                       moves E by more than the statistical interval
                       (:mod:`palpbayes.bayes.strainform`)
=====================  ====================================================================

The full interval is the **envelope** of the 90 % intervals of the fitted model and of its
plausible alternatives (the interval of a probability box: Ferson et al., *Constructing
probability boxes and Dempster–Shafer structures*, SAND2002-4015, 2003; for model form, Riley &
Grandhi, *Reliab. Eng. Syst. Saf.* 96 (2011) 1137), not a weighted average: the depth windows are
fits to different points, so no likelihood weighs them against each other, and every one of
these models is itself an approximation.  The two weighted alternatives the literature offers
were not taken: stacking (Yao, Vehtari, Simpson & Gelman, *Bayesian Anal.* 13 (2018) 917)
collapses onto one model with 10^4 autocorrelated samples unless the folds are blocked, and a
Kennedy–O'Hagan discrepancy with a vague prior confounds E and can leave it wrong and
overconfident (Brynjarsdóttir & O'Hagan, *Inverse Probl.* 30 (2014) 114007).  Chosen by what
calibrates (slow suite, ``tests/statistical/test_modelform_calibration.py``: unmodelled layers
of 20–30 mm, bonded and lying free, strain stiffening, a gradual onset, a blunted paraboloid
apex, with the budget's inputs drawn).  Without a material misfit the full interval is the
budget interval, unless the neo-Hookean reading is kept: a linear fit of a deep trace then
carries finite strain even when no check fails.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable
from dataclasses import asdict, dataclass, replace

import numpy as np

from ..checks import checks_summary, material
from ..errors import ConvergenceWarning, PalpbayesError
from ..fitdata import FitData
from ..intervals import LEVEL, central
from ..units import format_pressure
from .layers import default_thickness_range
from .noisemodels import exact_noise

__all__ = ["Alternative", "ModelForm", "window_alternatives", "layer_alternative",
           "points_to_stiffer_base", "model_form", "interval_parts", "SEPARATOR",
           "summarise"]

#: Name of the layer alternative.
LAYER = "layer, thickness unknown"

#: Separator of the alternatives in ``modelform_models`` (their notes may contain "; ").
SEPARATOR = " | "


@dataclass(frozen=True)
class Alternative:
    """One model of the model-form interval.

    Attributes
    ----------
    name
        ``"as fitted"``, ``"shallow half"``, ``"deep half"`` or ``"layer, thickness unknown"``.
    E_pa, lo_pa, hi_pa
        [Pa] Median and central 90 % interval of E under it, with the budget.
    plausible
        True when it enters the envelope.
    note
        Why it is left out (empty when plausible).
    """

    name: str
    E_pa: float
    lo_pa: float
    hi_pa: float
    plausible: bool = True
    note: str = ""

    def describe(self) -> str:
        """``"name E [lo, hi]"``, with ``" (left out: why)"`` when not plausible (only the
        reason when it has no numbers)."""
        if not all(math.isfinite(v) for v in (self.E_pa, self.lo_pa, self.hi_pa)):
            return f"{self.name} (left out: {self.note or 'no estimate'})"
        text = (f"{self.name} {format_pressure(self.E_pa)} "
                f"[{format_pressure(self.lo_pa)}, {format_pressure(self.hi_pa)}]")
        return text if self.plausible else f"{text} (left out: {self.note})"


@dataclass(frozen=True)
class ModelForm:
    """The model-form part of E's interval: the alternatives and their envelope.

    Attributes
    ----------
    alternatives
        The fitted model first, then each alternative (plausible or not).
    lo_pa, hi_pa
        [Pa] Envelope of the plausible models' 90 % intervals: E's full interval.
    """

    alternatives: tuple[Alternative, ...]
    lo_pa: float
    hi_pa: float

    def share(self) -> float:
        """Share of the full interval's width that the model form adds [-]:
        1 − (budget width)/(full width); 0 without alternatives."""
        fitted = self.alternatives[0]
        full = self.hi_pa - self.lo_pa
        return 0.0 if not full > 0 else max(0.0, 1.0 - (fitted.hi_pa - fitted.lo_pa) / full)

    def columns(self) -> dict:
        """``summary.csv`` columns: ``modelform_share_pct`` and ``modelform_models``."""
        return {"modelform_share_pct": 100.0 * self.share(),
                "modelform_models": SEPARATOR.join(a.describe()
                                                   for a in self.alternatives[1:])}

    def to_state(self) -> dict:
        """A JSON-able dict (:meth:`from_state` reads it back)."""
        return {"alternatives": [asdict(a) for a in self.alternatives],
                "lo_pa": self.lo_pa, "hi_pa": self.hi_pa}

    @classmethod
    def from_state(cls, state: dict) -> ModelForm:
        """The :class:`ModelForm` that :meth:`to_state` wrote."""
        return cls(tuple(Alternative(**a) for a in state["alternatives"]),
                   float(state["lo_pa"]), float(state["hi_pa"]))


def summarise(name: str, E: np.ndarray, level: float = LEVEL) -> Alternative:
    """The :class:`Alternative` ``name`` of draws ``E`` [Pa]: median and central interval."""
    lo, hi = central(E, level)
    return Alternative(name, float(np.median(E)), float(lo), float(hi))


def window_alternatives(E_total: np.ndarray, depth_details: dict, rng: np.random.Generator,
                        level: float = LEVEL) -> list[Alternative]:
    """The shallow- and deep-half alternatives from a depth-consistency check's details.

    Each is the fitted model's budget draws ``E_total`` [Pa] times the window's E*/E*_all,
    spread by the window's own relative standard error (a normal on the log scale; the
    covariance with the all-depth fit is ignored, which widens it).

    Parameters
    ----------
    E_total
        [Pa] The fitted model's draws of E with the budget.
    depth_details
        ``details`` of :func:`palpbayes.checks.depth_consistency_check` (``estar_all``,
        ``estar_shallow``, ``estar_deep`` [Pa] and their ``_se``).
    rng
        Generator of the windows' spread.
    level
        Central probability of each interval [-].

    Returns
    -------
    list of Alternative
        The windows in the details; one without a finite estimate (a deep-half fit at its
        search bound) is not plausible.
    """
    out = []
    all_ = depth_details.get("estar_all", float("nan"))
    z = rng.standard_normal(np.size(E_total))
    for name, key in (("shallow half", "estar_shallow"), ("deep half", "estar_deep")):
        if key not in depth_details:
            continue
        e, se = depth_details[key], depth_details.get(f"{key}_se", float("nan"))
        if not (math.isfinite(e) and e > 0 and math.isfinite(all_) and all_ > 0
                and math.isfinite(se)):
            out.append(Alternative(name, math.nan, math.nan, math.nan, False,
                                   "no fit: too few samples, or its surface at the search "
                                   "bound"))
            continue
        draws = np.ravel(E_total) * (e / all_) * np.exp(se / e * z)
        out.append(summarise(name, draws, level))
    return out


def layer_alternative(fit: Callable[..., object], data: FitData, z_surf: float, *,
                      noise: str = "gaussian", **options) -> Alternative:
    """The alternative 'a layer of unknown thickness' of a half-space fit.

    ``fit`` (:func:`palpbayes.bayes.fit.fit_bayes_data`) runs the exact engine on ``data``
    with h log-uniform over :func:`~palpbayes.bayes.layers.default_thickness_range` of the
    contact depth below ``z_surf`` [m] (Gaussian noise for a Student-t fit, which the exact
    engine lacks), with ``options`` (baseline, priors, budget, seed, ...), on the loading
    alone (no rate check: the layer is judged on what it is meant to explain).  Plausible
    when it converges, raises no flag, and its own checks ran and find no material misfit;
    otherwise the note names what did not hold (a flag by its headline, e.g. "thickness
    posterior at its lower prior bound (722 nm)").  A fit it refuses (or that fails
    numerically) is an implausible alternative with the reason.

    Parameters
    ----------
    fit
        The fitting function (:func:`palpbayes.bayes.fit.fit_bayes_data`, returning a
        :class:`~palpbayes.bayes.BayesResult`; passed in because this module is imported by
        the one that defines it).
    data
        The half-space fit's data.
    z_surf
        [m] Its posterior median surface height.
    noise
        Its noise model.
    **options
        Passed to ``fit``.

    Returns
    -------
    Alternative
    """
    try:
        model = replace(data.model, thickness_range=default_thickness_range(
            z_surf - float(np.min(data.z))), thickness_grid="coarse")
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ConvergenceWarning)
            res = fit(replace(data, model=model, cycle=None), engine="exact",
                      with_model_form=False, log_prob=False,
                      noise=exact_noise(noise), **options)
    except (PalpbayesError, ValueError, np.linalg.LinAlgError) as exc:
        return Alternative(LAYER, math.nan, math.nan, math.nan, False, f"not fitted: {exc}")
    E = np.ravel(res.draws("E_total"))
    checks = checks_summary(res.checks)
    # a flag (a posterior at a prior bound, ...) by its headline, the text before its first
    # ":"; "; " separates the reasons, so none holds one
    why = (["not converged (" + ", ".join(res.diagnostics.problems()) + ")"]
           if not res.diagnostics.converged else []) + [
        w.split(":")[0].replace("; ", ", ") for w in res.warnings] + (
        [] if checks["model_ok"] is True else
        [f"its own checks fail ({checks['misfit_checks']})" if res.checks
         else "its checks did not run"])
    alt = summarise(LAYER, E, LEVEL)
    return replace(alt, plausible=not why, note="; ".join(why))


def points_to_stiffer_base(checks: list) -> bool:
    """True when a check finds a material misfit and the curve's apparent modulus rises with
    depth (the depth check's shallow/all ratio below 1, or a free exponent above the law's,
    whether or not those checks fail on their own): what a layer on a stiffer base does, so
    the layer alternative is worth its fit.  Rate dependence alone does not count."""
    if not any(material(c) for c in checks if c.name != "rate"):
        return False
    for c in checks:
        d = c.details
        if c.name == "depth_consistency" and d.get("ratio", 1.0) < 1.0:
            return True
        if c.name == "exponent" and d.get("m", 0.0) > d.get("m_law", math.inf):
            return True
    return False


def model_form(E_total: np.ndarray, checks: list, rng: np.random.Generator,
               fit_layer: Callable[[], Alternative | None] | None = None,
               level: float = LEVEL,
               nonlinear: Callable[[], Alternative | None] | None = None) -> ModelForm | None:
    """The model-form interval of a fit whose checks found a material misfit, or whose
    neo-Hookean reading is kept (module docstring); None otherwise.

    Parameters
    ----------
    E_total
        [Pa] The fitted model's draws of E with the budget.
    checks
        Its graded model checks (:func:`palpbayes.checks.grade_checks`).
    rng
        Generator of the windows' spread.
    fit_layer
        Fits the layer with an unknown thickness and returns its :class:`Alternative` (with
        ``plausible`` set from its own checks and convergence), or None when it does not
        apply; called only when a material check points to a stiffer base
        (:func:`points_to_stiffer_base`); None: no layer alternative.
    level
        Central probability of each interval [-].
    nonlinear
        The neo-Hookean reading (:func:`nonlinear_alternative`), called for every fit; None:
        none.

    Returns
    -------
    ModelForm or None
        The alternatives and their envelope; when no interval is finite, the envelope is
        NaN.
    """
    strain = nonlinear() if nonlinear is not None else None
    fitted = summarise("as fitted", E_total, level)
    if not any(material(c) for c in checks if c.name != "rate"):
        # rate dependence: the remedy is the time-dependent fit, not a window
        if strain is None or not strain.plausible:
            return None
        return ModelForm((fitted, strain), min(fitted.lo_pa, strain.lo_pa),
                         max(fitted.hi_pa, strain.hi_pa))
    alts = [fitted]
    depth = next((c for c in checks if c.name == "depth_consistency"), None)
    if depth is not None:
        alts += window_alternatives(E_total, depth.details, rng, level)
    if fit_layer is not None and points_to_stiffer_base(checks):
        layer = fit_layer()
        if layer is not None:
            alts.append(layer)
    if strain is not None:
        alts.append(strain)
    keep = [a for a in alts if a.plausible and math.isfinite(a.lo_pa) and math.isfinite(a.hi_pa)]
    if not keep:
        return ModelForm(tuple(alts), math.nan, math.nan)
    return ModelForm(tuple(alts), min(a.lo_pa for a in keep), max(a.hi_pa for a in keep))


def interval_parts(E: float, stat: tuple[float, float], budget: tuple[float, float],
                   full: tuple[float, float]) -> str:
    """One line of the interval's three parts, each as −/+ % of ``E``.

    Parameters
    ----------
    E
        [Pa] The estimate.
    stat, budget, full
        [Pa] (lo, hi) of the statistical interval, with the budget, and with the model form.

    Returns
    -------
    str
        e.g. ``"statistical -0.2/+0.2 %, + budget -5.4/+5.2 %, + model form -31.0/+5.2 %"``;
        the model-form part left out when it adds nothing; empty when ``E`` is not finite.
    """
    def pct(lo, hi):
        return f"{100 * (lo / E - 1):+.1f}/{100 * (hi / E - 1):+.1f} %"

    if not (math.isfinite(E) and E > 0):
        return ""
    text = f"statistical {pct(*stat)}, + budget {pct(*budget)}"
    if full[0] < budget[0] or full[1] > budget[1]:
        text += f", + model form {pct(*full)}"
    return text
