"""Uncertainty budget of E in the style of GUM Supplement 1 (JCGM 101:2008).

A single trace identifies E* (and z_surf, sigma, F0) but not the inputs that turn it into the
material's Young's modulus.  Each input gets a stated distribution and is propagated by Monte
Carlo, one independent input draw per posterior draw:

    E = E*·(1 − nu²) · f_R(eps_R) / g_F · f_C(C)

=================  =====================================  ===================================
input              default distribution                   effect
=================  =====================================  ===================================
Poisson ratio nu   Uniform(nu − 0.05, nu + 0.05) in        factor 1 − nu² (design.md §8: PE foam
                   [0, 0.5] (half_width=0 fixes it)        estimates 0.27-0.33); on a bonded
                                                          layer also the refit of its bottom
                                                          effect at nu (a free one has none)
thickness h        Uniform ±2 % of a known layer           refit of the model curve (a sampled
                   thickness (caliper, a block that is     thickness is in the posterior
                   not flat)                               already)
tip radius         Uniform ±1 % (machining tolerance)     E* ∝ 1/g(R): refit of the model curve
force gain         Normal(1, 1 %) (calibration)           E* ∝ 1/gain
compliance C       Uniform(0, 2e-6 m/N) robot + sensor    depth d − C·F: refit of the curve
=================  =====================================  ===================================

"Refit" means: the posterior-median model curve F̂ = E*·s(d) is refitted with the perturbed
model s', E*' = E*·Σ s·s' / Σ s'² (least squares with E* linear), tabulated on a grid of the
perturbation and interpolated. For the twin of a specimen (:mod:`palpbayes.twin`) the Poisson
ratio's refit uses the twin at each node of nu, for either base (the block's free sides make
even a free one depend on nu); the tip-radius and thickness refits use the layer of the
specimen's height without its footprint (what the finite width adds to their sensitivity is of
second order, and a twin per perturbed tip or height would cost seconds each).  Under a
hyperelastic law (:mod:`palpbayes.twin.hyper_shape`) the Poisson ratio's refit is the law's
own twin at three nodes of nu (:func:`law_nu_nodes`: the finite-strain part of the curve
depends on nu at first order, e.g. a neo-Hookean sphere's 3 mm in a 20 mm block reads E
+6 % linear at nu 0.3 and −2 % at 0.45), for either base; the tip radius and thickness refits
are the linear model's on the same geometry (finite strain changes their sensitivity at
second order), the compliance's the law's own curve; a foam's nu, when sampled, is in the
posterior (``nu_draws``) and no input of the budget. Because the
factors multiply, their logarithms add and, the inputs being independent, the variance of ln E
is the sum of the variances of the logarithms of the factors: the *share* of each input is its
term over the total.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import pandas as pd

from ..contact import youngs_factor
from ..errors import InputError
from ..fitdata import FitData, ModelSpec
from ..refit import refit_factor

__all__ = ["BudgetSpec", "Budget", "propagate", "nu_nodes", "law_nu_nodes"]


@dataclass(frozen=True)
class BudgetSpec:
    """Distributions of the inputs a trace cannot identify (see module docstring).

    Parameters
    ----------
    nu_range
        (lo, hi) of a uniform Poisson ratio; None: model nu ± ``nu_half_width``.
    nu_half_width
        Half-width around the model's nu when ``nu_range`` is None (0 fixes nu).
    radius_tolerance
        Relative half-width of the uniform tip-radius error (0.01 = ±1 %).
    gain_sd
        Relative standard deviation of the force-sensor gain.
    compliance_max
        [m/N] Upper bound of the uniform series compliance.
    thickness_tolerance
        Relative half-width of the uniform error of a known layer thickness (0.02 = ±2 %).
    """

    nu_range: tuple[float, float] | None = None
    nu_half_width: float = 0.05
    radius_tolerance: float = 0.01
    gain_sd: float = 0.01
    compliance_max: float = 2e-6
    thickness_tolerance: float = 0.02

    def nu_bounds(self, nu: float) -> tuple[float, float]:
        lo, hi = self.nu_range if self.nu_range is not None else (
            nu - self.nu_half_width, nu + self.nu_half_width)
        lo, hi = max(lo, 0.0), min(hi, 0.5)  # truncated at the incompressible limit
        if not 0.0 <= lo <= hi <= 0.5:
            raise InputError(f"Poisson-ratio range ({lo}, {hi}) must lie within [0, 0.5]")
        return lo, hi

    @staticmethod
    def none() -> BudgetSpec:
        """A budget with every input fixed (statistical uncertainty only)."""
        return BudgetSpec(nu_half_width=0.0, radius_tolerance=0.0, gain_sd=0.0,
                          compliance_max=0.0, thickness_tolerance=0.0)


@dataclass
class Budget:
    """Propagated draws and the variance table.

    Attributes
    ----------
    E
        Draws of E with every input [Pa], same shape as the posterior draws of E*.
    table
        One row per input: ``input, distribution, rel_sd_pct, share_pct``.
    nu
        The Poisson ratio of each draw [-] (same shape as ``E``), None when not kept.
    """

    E: np.ndarray
    table: pd.DataFrame
    nu: np.ndarray | None = None


def _refit_factor(model: ModelSpec, depth: np.ndarray, alt_shape) -> float:
    return refit_factor(depth, model.shape, alt_shape)


#: Poisson ratios at which a bonded layer's refit is computed (then interpolated).
_NU_NODES = 5


def nu_nodes(spec: BudgetSpec, nu: float) -> np.ndarray:
    """The Poisson ratios [-] at which the budget refits a model whose shape depends on nu
    (a bonded layer, a specimen twin), and interpolates between: :data:`_NU_NODES` evenly over
    the budget's range, or ``[nu]`` when nu is fixed."""
    lo, hi = spec.nu_bounds(nu)
    return np.linspace(lo, hi, _NU_NODES) if hi > lo else np.array([float(nu)])


def law_nu_nodes(spec: BudgetSpec, nu: float) -> np.ndarray:
    """The Poisson ratios [-] at which the budget refits a model with a material law (each a
    finite-element curve): the range's ends and ``nu``; ``[nu]`` when nu is fixed."""
    lo, hi = spec.nu_bounds(nu)
    return np.unique([lo, float(nu), hi]) if hi > lo else np.array([float(nu)])


def propagate(estar: np.ndarray, data: FitData, z_surf: float, spec: BudgetSpec,
              rng: np.random.Generator, bonded: np.ndarray | None = None,
              sampled_thickness: bool = False, nu_draws: np.ndarray | None = None) -> Budget:
    """Propagate the budget over posterior draws ``estar`` [Pa] (any shape).

    Parameters
    ----------
    estar
        Posterior draws of E* [Pa].
    data
        The fitted data (depths of the fitted points).
    z_surf
        [m] Posterior median surface height (sets the depths of the model curve).
    spec
        Input distributions.
    rng
        Random generator for the input draws.
    bonded
        Per-draw base of a layer whose base was sampled (1.0 bonded, 0.0 free, NaN no layer):
        the nu refit of the bottom effect applies to the bonded draws only.  None: the base of
        ``data.model``.
    sampled_thickness
        The thickness was a parameter of the fit (its uncertainty is in ``estar``): no
        thickness input.
    nu_draws
        The Poisson ratio of each draw when it was a parameter of the fit (a foam's law):
        E = E*·(1 − nu²) per draw, no Poisson-ratio input.
    """
    model = data.model
    shape = estar.shape
    n = estar.size
    depth = np.clip(z_surf - data.z, 0.0, None)
    depth = depth[depth > 0]
    e_med = float(np.median(estar))

    lo, hi = spec.nu_bounds(model.nu)
    if nu_draws is not None:
        lo = hi = model.nu  # the posterior's: no input
    nu = (np.asarray(nu_draws, dtype=float).ravel() if nu_draws is not None
          else rng.uniform(lo, hi, n) if hi > lo else np.full(n, model.nu))
    log_nu = np.log(youngs_factor(nu))
    layered = model.has_layer and np.isfinite(model.thickness)
    law = model.law is not None
    twin = model.specimen is not None or law
    # the bases whose shape depends on nu: a bonded layer's; a twin's and a law's, both
    nu_bases = ("bonded", "free") if twin and model.has_layer else ("bonded",)
    draw_bases = (np.full(n, model.base) if bonded is None
                  else np.where(np.asarray(bonded, dtype=float).ravel() == 1.0, "bonded",
                                "free"))
    if (layered or law) and hi > lo and depth.size:
        grid = law_nu_nodes(spec, model.nu) if law else nu_nodes(spec, model.nu)
        for base in nu_bases:
            rows = draw_bases == base
            if not rows.any():
                continue
            base_model = model.variant(base=base) if model.has_layer else model
            fac = [_refit_factor(base_model, depth, base_model.with_nu(v).shape)
                   for v in grid]
            log_nu[rows] += np.log(np.interp(nu[rows], grid, fac))
    log_terms = {"E* (posterior)": np.log(estar.ravel()), "Poisson ratio": log_nu}
    rows = [("E* (posterior)", "posterior draws"),
            ("Poisson ratio", "posterior draws (the law's own)" if nu_draws is not None
             else f"Uniform({lo:.3g}, {hi:.3g})" if hi > lo else f"fixed {lo:.3g}")]

    tol = spec.radius_tolerance
    # the tip's and the height's refits: linear, without the footprint
    sized = model.linear().layer_only()
    if tol > 0 and model.tip.has_length_scale:
        grid = np.linspace(-tol, tol, 9)
        fac = [_refit_factor(sized, depth, replace(sized, tip=sized.tip.scaled(1 + e)).shape)
               for e in grid]
        eps = rng.uniform(-tol, tol, n)
        log_terms["tip radius"] = np.log(np.interp(eps, grid, fac))
        rows.append(("tip radius", f"Uniform(±{tol * 100:g} %)"))
    tol_h = spec.thickness_tolerance
    if tol_h > 0 and layered and not sampled_thickness and depth.size:
        grid = np.linspace(-tol_h, tol_h, 9)
        fac = [_refit_factor(sized, depth,
                             replace(sized, thickness=sized.thickness * (1 + e)).shape)
               for e in grid]
        eps = rng.uniform(-tol_h, tol_h, n)
        log_terms["thickness"] = np.log(np.interp(eps, grid, fac))
        rows.append(("thickness", f"Uniform(±{tol_h * 100:g} %)"))
    if spec.gain_sd > 0:
        gain = rng.normal(1.0, spec.gain_sd, n)
        log_terms["force gain"] = -np.log(gain)
        rows.append(("force gain", f"Normal(1, {spec.gain_sd * 100:g} %)"))
    if spec.compliance_max > 0:
        grid = np.linspace(0.0, spec.compliance_max, 9)
        f_hat = e_med * model.shape(depth)
        fac = []
        for c in grid:
            # the curve as measured with compliance c: the real depth is d − c·F
            real = np.clip(depth - c * f_hat, 0.0, None)
            s_true = model.shape(real)
            s_meas = model.shape(depth)
            fac.append(float(s_meas @ s_meas / (s_true @ s_meas)) if s_true @ s_meas > 0
                       else 1.0)
        C = rng.uniform(0.0, spec.compliance_max, n)
        log_terms["compliance"] = np.log(np.interp(C, grid, fac))
        rows.append(("compliance", f"Uniform(0, {spec.compliance_max:g} m/N)"))

    total = np.sum(list(log_terms.values()), axis=0)
    variances = {k: float(np.var(v)) for k, v in log_terms.items()}
    var_total = sum(variances.values())
    table = pd.DataFrame(
        [{"input": name, "distribution": dist,
          "rel_sd_pct": 100 * np.sqrt(variances[name]),
          "share_pct": 100 * variances[name] / var_total if var_total > 0 else np.nan}
         for name, dist in rows]
    )
    return Budget(E=np.exp(total).reshape(shape), table=table, nu=nu.reshape(shape))
