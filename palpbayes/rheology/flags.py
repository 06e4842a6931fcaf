"""What a viscoelastic fit cannot explain or resolve, said in words: the flags of a
:class:`~palpbayes.rheology.fit.RheologyFit`.

Two lists, each one line per finding:

* :func:`offcontact_flags` -- what the force out of contact shows and the model leaves out
  (:mod:`~palpbayes.rheology.offcontact`): a gap between the approach and the retract when
  the drag is not fitted, a baseline that tilts with the height when it is constant, adhesion
  at pull-off (its hint names ``adhesion="cut"``; after that cut, what is left is checked).
  These fail the model check (``RheologyFit.model_ok``);
* :func:`fit_flags` -- a force that reads as if it were in another unit
  (:func:`force_scale_flags`, :mod:`palpbayes.forcescale`), those, and what the posterior
  shows: alpha piling up at a bound of its prior, tau faster than one step or slower than
  the record, phi at its bound (a drift the noise soaks up), a surface at its prior bound, a
  grid that did not settle, other basins, a contact that shrinks during the hold
  (:data:`SHRINK_FLAG`), a specimen thinner than 1/:data:`THIN_FLAG` of the depth, a poor
  importance sample (:data:`MIN_ESS`), an emcee chain that did not converge, and the failed
  posterior-predictive check.
"""

from __future__ import annotations

from typing import Any, Protocol

import numpy as np

from ..checks.core import CheckResult
from ..contact import youngs_factor
from ..forcescale import force_scale_flag
from ..sensor_noise import pp_from_sigma
from ..units import format_force
from .cycle import CycleData
from .offcontact import N_SE, adhesion_dip, baseline_tilt, drag_gap
from .posterior import ALPHA_MAX, PHI_BOUNDS, GridPosterior

__all__ = ["offcontact_flags", "fit_flags", "force_scale_flags", "SHRINK_FLAG", "THIN_FLAG",
           "MIN_ESS", "DRAG_N_SE", "TILT_HINT", "ADHESION_HINT"]


class FitView(Protocol):
    """What the flags read of a fit: the attributes of
    :class:`~palpbayes.rheology.fit.RheologyFit`, which imports this module (so the class is
    not imported here, and this Protocol has a name of its own)."""

    rheology: str
    data: CycleData
    grid: GridPosterior
    draws: dict[str, np.ndarray]
    ppc: CheckResult
    offcontact: list[str]
    sampler: Any

    @property
    def phi_at_bound(self) -> bool: ...

#: The tilt flag's hint; :func:`palpbayes.rheology.fit.fit_rheology` tries it before it is
#: given and replaces it by what the fit with a linear baseline gave.
TILT_HINT = "fit it: baseline='linear', --baseline linear"
#: The adhesion flag's hint: leave the retract out, or cut the pull-off out of it
#: (:mod:`~palpbayes.rheology.adhesion`).
ADHESION_HINT = ("fit --segments approach,hold, or cut the pull-off out of the retract: "
                 "adhesion='cut', --adhesion cut")
#: Largest relative loss of depth during the hold before the shrinking contact is flagged.
SHRINK_FLAG = 0.02
#: Depth / specimen thickness above which the half-space assumption is flagged.
THIN_FLAG = 0.05
#: Smallest effective importance sample before the draws are flagged.
MIN_ESS = 400
#: Standard errors by which the approach's and the retract's out-of-contact force must differ
#: to be flagged (viscous drag, drift).
DRAG_N_SE = N_SE


def offcontact_flags(fit: FitView, residual: np.ndarray) -> list[str]:
    """Flags of the force out of contact (:mod:`~palpbayes.rheology.offcontact`)."""
    data, grid, out = fit.data, fit.grid, []
    zs = float(np.median(fit.draws["z_surf"]))
    gap = drag_gap(data, zs) if "retract" in data.segments and not grid.drag else None
    if gap is not None and abs(gap[0]) > DRAG_N_SE * gap[1]:
        g, _, v = gap
        out.append(f"out of contact the approach's force lies {format_force(g)} "
                   f"{'above' if g > 0 else 'below'} the retract's: viscous drag on the "
                   f"probe (b = {g / (2 * v):.3g} N·s/m at {v * 1e6:.3g} µm/s) or a drifting "
                   "sensor; the fit reads that gap as relaxation (fit the drag: drag=True, "
                   "--drag on)")
    tilt = None if grid.tilt else baseline_tilt(data, residual, zs)
    if tilt is not None:
        f1, se, span = tilt
        if abs(f1) > N_SE * se and abs(f1) * span > data.sigma_center:
            out.append(f"out of contact the residuals tilt with the height: F1 = {f1:.3g} N/m "
                       f"({f1 / se:.1f} se; {format_force(f1 * span)} over "
                       f"{span * 1e6:.3g} µm above the surface): a tilted or drifting "
                       "baseline (an AFM's virtual deflection, a sensor drifting) that the fit "
                       f"reads as contact force ({TILT_HINT})")
    d = fit.draws
    trend = sum((float(np.median(d[k])) * col for k, col in (
        ("drag", data.speed), ("tilt", data.z - data.z_ref)) if k in d), np.zeros(data.n_points))
    dip = adhesion_dip(data, zs, trend) if "retract" in data.segments else None
    if dip is not None and dip[0] < -N_SE * dip[1]:
        depth, se, t = dip
        cut = getattr(fit, "adhesion_cut", None)
        hint = (ADHESION_HINT if cut is None else
                f"it is left after the adhesion cut of {cut.t_start:.4g}-{cut.t_end:.4g} s: a "
                "pull-off longer than the cut or a baseline that is not a line in the height; "
                "fit --segments approach,hold")
        out.append(f"where the tip lets go, the retract's force dips "
                   f"{format_force(-depth)} below its own baseline ({-depth / se:.1f} se, "
                   f"at {t:.3g} s): adhesion, the sample holding the tip before it lets go, "
                   f"which Ting's rule does not model; it biases the fit of the retract ({hint})")
    return out


def force_scale_flags(fit: FitView) -> list[str]:
    """The ``force scale`` flag of a fit whose force reads as if it were in another unit
    (:func:`palpbayes.forcescale.force_scale_doubt`: the tip's size, the noise of the samples
    before contact and the first modulus, E0 or E_inf, at its median), or none."""
    data, d = fit.data, fit.draws
    name = next(k for k in ("E0", "E_inf", "E") if k in d)
    nu = getattr(fit, "nu", None)
    modulus = float(np.median(d[name])) * youngs_factor(nu or 0.0)
    noise = pp_from_sigma(data.sigma_center * np.sqrt(data.block))
    depth = float(np.median(d["z_surf"]) - data.z.min())
    flag = force_scale_flag(data.trace.tip, depth, modulus, noise)
    return [] if flag is None else [flag]


def fit_flags(fit: FitView) -> list[str]:
    """Every flag of ``fit`` (module docstring): a doubted force unit first, then its
    :attr:`offcontact` ones."""
    d, data, grid = fit.draws, fit.data, fit.grid
    out = force_scale_flags(fit) + list(fit.offcontact)
    if fit.rheology == "power-law":
        a = d["alpha"]
        if np.mean(a < 0.01) > 0.05:
            out.append(f"alpha piles up at 0, the lower bound of its prior (P(alpha < 0.01) = "
                       f"{np.mean(a < 0.01):.2f}): no relaxation resolved; the elastic model "
                       "may do")
        if np.mean(a > ALPHA_MAX - 0.01) > 0.05:
            out.append(f"alpha piles up at {ALPHA_MAX}, the upper bound of its prior: the "
                       "material flows almost like a liquid, or the segments are wrong")
    elif fit.rheology == "sls":
        tau = d["tau"]
        lo, hi = np.percentile(tau, [5.0, 95.0])
        if lo < data.dt_min:
            out.append(f"tau reaches {lo:.3g} s, below one step of the fitted record "
                       f"({data.dt_min:.3g} s): a relaxation faster than the sampling is not "
                       "resolved (fit fewer blocks: max_points, or sample faster)")
        if hi > data.span:
            out.append(f"tau reaches {hi:.3g} s, beyond the recorded {data.span:.3g} s: the "
                       "slow relaxation is not resolved (hold longer)")
    if fit.phi_at_bound:
        out.append(f"the noise correlation phi piles up at {PHI_BOUNDS[1]}, the upper bound of "
                   "its prior: the residuals drift slowly, which is model misfit rather than "
                   "sensor noise")
    zlo, zhi = np.percentile(d["z_surf"], [5.0, 95.0])
    if zlo <= grid.z.min() <= data.z_lo or zhi >= grid.z.max() >= data.z_hi:
        out.append("the surface posterior reaches a bound of its prior (the deepest or the first "
                   "height): the contact point is not resolved")
    if fit.sampler is not None and not fit.sampler.converged:
        out.append("the emcee chain did not converge (" + "; ".join(fit.sampler.problems())
                   + "): its intervals are rough")
    if not grid.converged:
        out.append("the posterior grid did not settle in its iterations: the intervals may be "
                   "too narrow or too wide (report this record)")
    for z, th, drop in grid.other_basins:
        out.append(f"another basin of the posterior at z_surf = {z:.6g} m, "
                   f"{grid.theta_name} = {th:.3g}, {drop:.1f} below the best in log density")
    ess = float(d["ess"])
    if ess < MIN_ESS:
        out.append(f"the moduli's priors leave an effective sample of {ess:.0f} draws: the "
                   "intervals are rough")
    hold = data.segment == 1
    if hold.any():
        dep = np.median(d["z_surf"]) - data.z
        peak = float(dep[~hold].max()) if (~hold).any() else float(dep.max())
        loss = (peak - float(dep[hold].min())) / peak if peak > 0 else 0.0
        if loss > SHRINK_FLAG:
            out.append(f"the contact shrinks by {100 * loss:.1f} % of the depth during the hold "
                       "(the tip backs out as the force relaxes): Lee–Radok overstates the "
                       "relaxation there (Ting's rule is applied on the retract only)")
    thickness = data.trace.thickness
    if thickness is not None:
        depth = float(np.median(d["z_surf"]) - data.z.min())
        if depth > THIN_FLAG * thickness:
            out.append(f"the specimen is {1e3 * thickness:.3g} mm thick and the tip goes "
                       f"{1e3 * depth:.3g} mm deep ({100 * depth / thickness:.0f} %): the "
                       "viscoelastic fit takes a half-space, so the rigid base under a thin "
                       "layer reads as a stiffer material (not modelled here yet)")
    if not fit.ppc.passed:
        out.append(fit.ppc.flag)
    return out
