"""What a failed check does to E: effect sizes and severity (see :mod:`palpbayes.checks`).

A 3,840-sample trace (and a 16,000-sample AFM curve even more) rejects any real curve on a
p-value: the tests see misfit far below what matters for the modulus.  So each check also
reports its **effect**, the relative change of E* [-] under the alternative it points to, and
a **severity**:

``exponent``
    E* that the free power law F = k·d^m + F0' (+ F1'·(z − z_ref),
    :func:`~palpbayes.checks.free_exponent_fit`) implies at the height z̄ of the fit's mean
    contact depth d̄: E*_alt = [k·d_free(z̄)^m + F0' + F1'·(z̄ − z_ref) − F0 − F1·(z̄ − z_ref)]
    / s(d̄), against E*, each fit with its own surface and baseline: the modulus the law needs
    to reproduce the free law's contact force at the curve's typical depth.
``depth_consistency``
    The window ratio E*_shallow / E*_all − 1 (the shallow half of the depth against all).
``rate``
    Its own (:mod:`.rate`): −(relaxation over the hold), or the retract's E* ratio − 1.
``residual_structure``, ``ppc``
    The larger in magnitude of the two effects above (the exponent's only when that check
    failed) (the curve's E* changes at least that
    much when the law is changed to follow the structure) and of the alternative the residual
    pattern names: a drifting baseline under a constant one, E* refitted with a linear
    baseline; a constant offset (the paper's model has none), E* refitted with one.

A failed check is **material** when |effect| exceeds both :data:`EFFECT_REL` and the half
width of E*'s statistical 90 % interval; otherwise it is **negligible**: the misfit is real
but moves E less than the noise does, or by less than 2 %, a repeatability that palpation of
one specimen does not beat (the paper's repeated palpations scatter by 2–9 %).  ``model_ok``
of a fit follows material misfit; the raw statistics stay in each check's details.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ..errors import FitError
from ..fitdata import ModelSpec
from ..intervals import Z_LEVEL
from .core import CheckResult, ShapeTable
from .depth import profile_law_fit

__all__ = ["EFFECT_REL", "SEVERITIES", "grade_checks", "free_exponent_effect", "material",
           "checks_summary"]

#: |effect on E| below which a failed check is negligible whatever the interval [-].
EFFECT_REL = 0.02

#: Severity of a check: "" (passed), "negligible" or "material".
SEVERITIES = ("", "negligible", "material")



def free_exponent_effect(check: CheckResult, z, model: ModelSpec, z_surf: float,
                         estar: float, f0: float = 0.0, f1: float = 0.0,
                         z_ref: float | None = None) -> float:
    """E*_alt/E* − 1 [-] of a free-exponent check at the mean contact depth (module
    docstring; ``f0`` [N], ``f1`` [N/m] the law fit's baseline, ``z_ref`` [m] its reference,
    default the highest z); NaN without contact or without the free fit's numbers."""
    d = details = check.details
    if not {"k", "m", "z_surf_free", "F0"} <= set(details) or not estar > 0:
        return float("nan")
    z = np.asarray(z, dtype=float)
    depth = z_surf - z[z < z_surf]
    if depth.size == 0:
        return float("nan")
    z_ref = float(z.max()) if z_ref is None else float(z_ref)
    d_mean = float(np.mean(depth))
    z_bar = z_surf - d_mean
    d_free = max(float(d["z_surf_free"]) - z_bar, 0.0)
    s = float(ShapeTable(model, 1.5 * float(depth.max())).shape(np.array([d_mean]))[0])
    if not s > 0:
        return float("nan")
    contact = (float(d["k"]) * d_free ** float(d["m"]) + float(d["F0"])
               + float(d.get("F1", 0.0)) * (z_bar - z_ref) - f0 - f1 * (z_bar - z_ref))
    return contact / s / estar - 1.0


def _baseline_effect(z, f, model: ModelSpec, z_surf: float, z_ref: float,
                     phi: float | None) -> float:
    """E* with a linear baseline over E* with a constant one, − 1 [-]."""
    z = np.asarray(z, dtype=float)
    dmax = z_surf - float(z.min())
    if not dmax > 0:
        return float("nan")
    table = ShapeTable(model, 1.5 * dmax)
    const = profile_law_fit(z, f, table, z_surf, 0.25 * dmax, "constant", z_ref, phi)
    line = profile_law_fit(z, f, table, z_surf, 0.25 * dmax, "linear", z_ref, phi)
    return line["estar"] / const["estar"] - 1.0 if const["estar"] > 0 else float("nan")


def _largest(*effects: tuple[str, float]) -> tuple[str, float]:
    finite = [(k, v) for k, v in effects if math.isfinite(v)]
    if not finite:
        return "", float("nan")
    return max(finite, key=lambda kv: abs(kv[1]))


# Many parameters: as run_checks: the point estimates that size each failed check's effect on E.
def grade_checks(checks: list[CheckResult], z, force, model: ModelSpec, *, z_surf: float,
                 estar: float, f0: float = 0.0, f1: float = 0.0,
                 stat_rel_halfwidth: float | None = None,
                 baseline: str = "constant", z_ref: float | None = None,
                 noise_lag1: float | None = None) -> list[CheckResult]:
    """The checks with their effect on E and severity filled in (module docstring).

    Parameters
    ----------
    checks
        Results of :func:`~palpbayes.checks.run_checks` (one fit).
    z, force
        [m], [N] The fitted samples.
    model
        The fitted contact model.
    z_surf, estar, f0, f1
        [m], [Pa], [N], [N/m] The fit's surface, E* and baseline.
    stat_rel_halfwidth
        Half width of E*'s statistical 90 % interval over E* [-]; default 1.645 se/E* of the
        depth check's full fit.
    baseline, z_ref, noise_lag1
        The fit's baseline model, its reference height [m] and the noise's lag-1
        autocorrelation.

    Returns
    -------
    list of CheckResult
        Same order; ``details`` gain ``effect`` [-], ``effect_source`` and ``severity``.
    """
    by = {c.name: c for c in checks}
    z = np.asarray(z, dtype=float)
    f = np.asarray(force, dtype=float)
    z_ref = float(z.max()) if z_ref is None else float(z_ref)
    effects: dict[str, tuple[str, float]] = {}
    if "exponent" in by:
        effects["exponent"] = ("free exponent at the mean depth", free_exponent_effect(
            by["exponent"], z, model, z_surf, estar, f0, f1, z_ref))
    if "depth_consistency" in by:
        effects["depth_consistency"] = ("shallow-half window",
                                        float(by["depth_consistency"].statistic) - 1.0)
    shape_effect = _largest(*(v for k, v in effects.items()
                              if k == "depth_consistency" or not by[k].passed))
    res = by.get("residual_structure")
    pattern = res.details.get("pattern", "") if res is not None else ""
    misfit_effect = shape_effect
    if pattern == "drift" and baseline == "constant":
        try:
            misfit_effect = _largest(shape_effect, (
                "linear baseline", _baseline_effect(z, f, model, z_surf, z_ref, noise_lag1)))
        except (ValueError, np.linalg.LinAlgError, FitError):
            pass
    dc = by.get("depth_consistency")
    if pattern == "offset" and dc is not None and estar > 0:  # e.g. the paper's model (no F0)
        misfit_effect = _largest(misfit_effect, (
            "force offset fitted", float(dc.details["estar_all"]) / estar - 1.0))
    for name in ("residual_structure", "ppc"):
        if name in by:
            effects[name] = misfit_effect
    if stat_rel_halfwidth is None:
        dc = by.get("depth_consistency")
        se = dc.details.get("estar_all_se", float("nan")) if dc is not None else float("nan")
        stat_rel_halfwidth = Z_LEVEL * se / estar if estar > 0 else float("nan")
    limit = max(EFFECT_REL, stat_rel_halfwidth if math.isfinite(stat_rel_halfwidth) else 0.0)
    out = []
    for c in checks:
        source, eff = effects.get(c.name, (c.details.get("effect_source", ""),
                                           c.details.get("effect", float("nan"))))
        if c.passed:
            severity = ""
        elif math.isfinite(eff) and abs(eff) <= limit:
            severity = "negligible"
        else:
            severity = "material"  # an effect that cannot be sized counts
        details = dict(c.details, effect=eff, effect_source=source, severity=severity,
                       effect_limit=limit)
        out.append(replace(c, details=details))
    return out


def material(check: CheckResult) -> bool:
    """True for a failed check whose effect on E is material (ungraded failures count)."""
    return (not check.passed) and check.details.get("severity", "material") != "negligible"


def _effect_text(c: CheckResult) -> str:
    eff = c.details.get("effect", float("nan"))
    if not math.isfinite(eff):
        return "effect on E not sized"
    return f"moves E by {100 * eff:+.1f} % ({c.details.get('effect_source', '')})"


def checks_summary(checks: list[CheckResult]) -> dict:
    """The summary columns of a fit's checks.

    Returns
    -------
    dict
        ``model_ok`` (no material misfit; NaN when no check ran), ``m_free``,
        ``misfit_effect`` (the largest |effect| [-] of a material check, signed; 0 when none,
        NaN when no check ran or a material check's effect could not be sized),
        ``misfit_checks`` (names of the material checks, ";"-joined),
        and ``flags``: a list of texts, the material checks' flags with their effect, the
        negligible ones as ``info:`` lines.
    """
    if not checks:
        return {"model_ok": float("nan"), "m_free": float("nan"),
                "misfit_effect": float("nan"), "misfit_checks": "", "flags": []}
    flags, worst, names = [], 0.0, []
    for c in checks:
        if c.passed:
            continue
        if material(c):
            names.append(c.name)
            eff = c.details.get("effect", float("nan"))
            if not math.isfinite(eff):
                worst = float("nan")  # a material misfit of unknown size
            elif math.isfinite(worst) and abs(eff) > abs(worst):
                worst = eff
            flags.append(f"{c.flag} [material: {_effect_text(c)}]")
        else:
            what = c.name + (f" ({c.details['pattern']} pattern)"
                             if c.details.get("pattern") else "")
            flags.append(f"info: {what} check fails statistically but is negligible: "
                         f"{_effect_text(c)}, within ±{100 * c.details['effect_limit']:.1f} %")
    m = next((c.statistic for c in checks if c.name == "exponent"), float("nan"))
    return {"model_ok": not names, "m_free": m, "misfit_effect": worst,
            "misfit_checks": ";".join(names), "flags": flags}
