"""Fit a relaxation modulus to one recorded cycle: :func:`fit_rheology` and its result.

``fit_rheology(trace, rheology="power-law")`` prepares the block means of the chosen segments
(:mod:`~palpbayes.rheology.cycle`), integrates the collapsed posterior on its grid
(:mod:`~palpbayes.rheology.posterior`), draws from it and checks the fit:

* a posterior-predictive check of the residuals binned in *time* (contact bins from the
  surface to the end of the record; :func:`palpbayes.checks.posterior_predictive_check`,
  Gelman, Meng & Stern 1996), the same test as the elastic fit's;
* a viscous drag on the probe, b·(−dz/dt), fitted with the retract by default (its out-of-
  contact force then shows it; :mod:`~palpbayes.rheology.posterior`), and when it is not
  fitted, a gap between the approach's and the retract's out-of-contact force flagged;
* a baseline that tilts with the height, F1·(z − z_ref), with ``baseline="linear"`` (as the
  elastic fit's ``--baseline linear``), and when it is not fitted, a slope of the
  out-of-contact residuals against the height flagged;
* adhesion: the retract's force dipping below the fitted baseline where the model's contact
  has ended (the tip pulled by the sample before it lets go), which no relaxation law has,
  flagged;
* flags, never silent: alpha at a bound of its prior; tau outside the recorded time scales
  (step to duration) or faster than one step; a surface at its prior bound; other basins of
  the surface × theta density; a contact that shrinks during the hold (Lee–Radok overstates
  the relaxation there; Ting's rule is applied on the retract only); a poor importance
  sample.

Moduli are reduced moduli E* [Pa] as everywhere in palpbayes; give ``nu`` to have Young's
moduli E = E*(1 − nu²) in the table too.
"""

from __future__ import annotations

import time as _time
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from ..checks import posterior_predictive_check
from ..checks.core import CheckResult
from ..contact import Tip, check_nu, youngs_modulus
from ..contact.viscoelastic import PowerLawKernel, PronyKernel, ramp_apparent_modulus
from ..errors import InputError
from ..groundtruth import DEFAULT_STRAIN_WINDOW
from ..intervals import LEVEL, central_band
from ..trace import IndentationTrace
from ..units import format_force
from .compression import PAPER_COMPRESSION_SPEED, compression_moduli
from .cycle import DEFAULT_SEGMENTS, MAX_POINTS, CycleData, prepare_cycle
from .design import lee_radok_columns
from .offcontact import N_SE, adhesion_dip, baseline_tilt, drag_gap
from .posterior import ALPHA_MAX, PHI_BOUNDS, RHEOLOGIES, GridPosterior, grid_posterior
from .ting import RETRACT, RetractDesign, with_retract

__all__ = ["RheologyFit", "fit_rheology", "curve_draws", "PARAMETERS", "SHRINK_FLAG", "MIN_ESS",
           "THIN_FLAG", "DRAG_N_SE", "BASELINES"]

#: Parameters of each rheology in table order: (name, unit, is a modulus).
PARAMETERS = {
    "power-law": (("E0", "Pa", True), ("alpha", "-", False)),
    "sls": (("E_inf", "Pa", True), ("E1", "Pa", True), ("tau", "s", False)),
}
_COMMON = (("z_surf", "m", False), ("offset", "N", False), ("sigma", "N", False),
           ("phi", "-", False))
#: Rows of the optional baseline terms: a viscous drag and a tilted baseline.
_EXTRA = (("drag", "N·s/m", False), ("tilt", "N/m", False))
#: Baseline models: a constant offset, or a line in the height (``tilt``).
BASELINES = ("constant", "linear")
#: Largest relative loss of depth during the hold before the shrinking contact is flagged.
SHRINK_FLAG = 0.02
#: Depth / specimen thickness above which the half-space assumption is flagged.
THIN_FLAG = 0.05
#: Smallest effective importance sample before the draws are flagged.
MIN_ESS = 400
#: Standard errors by which the approach's and the retract's out-of-contact force must differ
#: to be flagged (viscous drag, drift).
DRAG_N_SE = N_SE
#: Draws used for the force band and the posterior-predictive check.
_BAND_DRAWS = 100


@dataclass
class RheologyFit:
    """A viscoelastic fit of one cycle.

    Attributes
    ----------
    rheology
        ``"power-law"`` (E*(t) = E0*·(t/t0)^(−alpha)) or ``"sls"``
        (E*(t) = E_inf* + E1*·exp(−t/tau)).
    data
        The block means that were fitted.
    grid
        The collapsed posterior on its grid.
    draws
        Joint posterior draws (moduli E* [Pa], alpha or tau [s], z_surf [m], offset [N], sigma
        [N] of a block mean, phi; drag [N·s/m] and tilt [N/m] with those terms).
    ppc
        Posterior-predictive check (residuals binned in time).
    flags
        One line each; empty when nothing is flagged.
    offcontact
        The flags of the force out of contact (drag gap, tilt, adhesion:
        :mod:`~palpbayes.rheology.offcontact`), which fail the model check.
    nu
        Poisson's ratio if given (adds Young's moduli to the table).
    seconds
        Wall time of the fit [s].
    """

    rheology: str
    data: CycleData
    grid: GridPosterior
    draws: dict[str, np.ndarray]
    ppc: CheckResult
    flags: list[str] = field(default_factory=list)
    offcontact: list[str] = field(default_factory=list)
    nu: float | None = None
    seconds: float = 0.0

    @property
    def t0(self) -> float:
        return self.grid.t0

    @property
    def phi_at_bound(self) -> bool:
        """The noise correlation piles up at its prior's upper bound (> 5 % of the draws
        within 0.02 of it): the residuals drift, a misfit the noise model soaks up."""
        return bool(np.mean(self.draws["phi"] > PHI_BOUNDS[1] - 0.02) > 0.05)

    @property
    def model_ok(self) -> bool:
        """The posterior-predictive check passes, phi is not at its bound and the force out of
        contact shows no drag gap, tilt or adhesion that the model leaves out."""
        return bool(self.ppc.passed) and not self.phi_at_bound and not self.offcontact

    def table(self, level: float = LEVEL) -> pd.DataFrame:
        """One row per parameter: ``parameter``, ``unit``, ``median``, ``lo``, ``hi`` (the
        central ``level`` interval) and, for moduli with ``nu`` given, ``E`` rows too."""
        rows = []
        extra = tuple(e for e in _EXTRA if e[0] in self.draws)
        for name, unit, modulus in PARAMETERS[self.rheology] + _COMMON + extra:
            lo, med, hi = central_band(self.draws[name], level)
            rows.append({"parameter": name + ("*" if modulus else ""), "unit": unit,
                         "median": med, "lo": lo, "hi": hi})
            if modulus and self.nu is not None:
                rows.append({"parameter": name, "unit": unit,
                             **{k: youngs_modulus(v, self.nu) for k, v in
                                (("median", med), ("lo", lo), ("hi", hi))}})
        out = pd.DataFrame(rows)
        out.attrs.update(level=level, rheology=self.rheology, t0_s=self.t0, nu=self.nu)
        return out

    def relaxation(self, times, level: float = LEVEL) -> pd.DataFrame:
        """E*(t) [Pa] at ``times`` [s] > 0: median and central ``level`` band of the draws."""
        t = np.atleast_1d(np.asarray(times, dtype=float))
        if np.any(~np.isfinite(t)) or np.any(t <= 0):
            raise InputError("relaxation times must be positive numbers of seconds")
        E = self._moduli_at(t)
        lo, med, hi = central_band(E, level, axis=0)
        return pd.DataFrame({"time_s": t, "E_star_pa": med, "E_star_lo_pa": lo,
                             "E_star_hi_pa": hi})

    def _moduli_at(self, t: np.ndarray) -> np.ndarray:
        d = self.draws
        if self.rheology == "power-law":
            return d["E0"][:, None] * (t[None, :] / self.t0) ** (-d["alpha"][:, None])
        return d["E_inf"][:, None] + d["E1"][:, None] * np.exp(-t[None, :] / d["tau"][:, None])

    def kernels(self, n: int | None = None) -> list[PowerLawKernel | PronyKernel]:
        """The relaxation kernels of the first ``n`` draws (all by default)."""
        d, k = self.draws, len(self.draws["z_surf"]) if n is None else n
        if self.rheology == "power-law":
            return [PowerLawKernel(d["E0"][i], d["alpha"][i], self.t0) for i in range(k)]
        return [PronyKernel(d["E_inf"][i], (d["E1"][i],), (d["tau"][i],)) for i in range(k)]

    def apparent_modulus(self, speed: float, depth: float, level: float = LEVEL
                         ) -> tuple[float, float, float]:
        """E* [Pa] an elastic fit would read on a constant-speed ramp to ``depth`` [m] at
        ``speed`` [m/s] with this tip (:func:`~palpbayes.contact.viscoelastic.
        ramp_apparent_modulus`): median and central ``level`` interval over the draws."""
        if not (np.isfinite(speed) and speed > 0 and np.isfinite(depth) and depth > 0):
            raise InputError("speed [m/s] and depth [m] must be positive")
        n = min(len(self.draws["z_surf"]), 1000)
        vals = np.array([float(ramp_apparent_modulus(k, speed, depth, self.data.m))
                         for k in self.kernels(n)])
        return _median_interval(vals, level)

    def force_curves(self, n: int = _BAND_DRAWS, contact_only: bool = False) -> np.ndarray:
        """[N] Model force at the block means for ``n`` draws (n, points), offset, drag and
        tilt included (``contact_only``: the contact force alone): the draws
        :func:`curve_draws` picks."""
        return _force_curves(self.data, self.rheology, self.draws, self.t0, n, contact_only)

    def compression_modulus(self, height: float, speed: float = PAPER_COMPRESSION_SPEED,
                            strain_window=DEFAULT_STRAIN_WINDOW, level: float = LEVEL,
                            n: int = 400, toe: float = 0.0) -> tuple[float, float, float]:
        """Young's modulus [Pa] a compression test of this material would report: a specimen
        of ``height`` [m] at cross-head ``speed`` [m/s] (default the paper's 50 mm/min), read
        by the ground truth's rule over ``strain_window``
        (:func:`~palpbayes.rheology.compression.compression_moduli`); median and central
        ``level`` interval over ``n`` draws; ``toe`` [m] the test's slack (its strain
        history then starts with the toe).  Needs ``nu`` (the fit's)."""
        if self.nu is None:
            raise InputError("the compression modulus is a Young's modulus: fit with nu= "
                             "(--nu) to convert E* = E/(1 - nu^2)")
        vals = compression_moduli(self.kernels(min(n, len(self.draws["z_surf"]))), self.nu,
                                  speed, height, strain_window, toe)
        return _median_interval(vals, level)

    def summary_line(self) -> str:
        tab = self.table()
        parts = []
        for _, r in tab.iterrows():
            if r["parameter"] in ("offset", "phi", "sigma"):
                continue
            parts.append(f"{r['parameter']} {r['median']:.4g} [{r['lo']:.4g}, {r['hi']:.4g}] "
                         f"{r['unit']}")
        return "; ".join(parts)


def _median_interval(x: np.ndarray, level: float) -> tuple[float, float, float]:
    """Median and central ``level`` interval of draws ``x`` (:func:`~palpbayes.intervals.
    central_band`)."""
    lo, med, hi = central_band(x, level)
    return float(med), float(lo), float(hi)


def curve_draws(n_total: int, n: int) -> np.ndarray:
    """Indices of the draws (of ``n_total``) behind ``n`` force curves, evenly spread."""
    return np.linspace(0, n_total - 1, min(n, n_total)).round().astype(int)


def _force_curves(data: CycleData, rheology: str, draws: dict, t0: float, n: int,
                  contact_only: bool = False) -> np.ndarray:
    idx = curve_draws(len(draws["z_surf"]), n)
    k = idx.size
    win = data.windows()
    ret = data.segment == RETRACT
    design = (RetractDesign(data.edges, data.z_edges, data.sample_time[ret], data.m, t0)
              if rheology == "power-law" and ret.any() else None)
    out = np.empty((k, data.n_points))
    for r, i in enumerate(idx):
        z = draws["z_surf"][i:i + 1]
        if rheology == "power-law":
            alpha = float(draws["alpha"][i])
            f = draws["E0"][i] * with_retract(data, lee_radok_columns(
                win, z, data.z_edges, data.m, "power-law", alpha, t0), z, alpha, t0, design)[0]
        else:
            f = (draws["E_inf"][i] * lee_radok_columns(win, z, data.z_edges, data.m, None)[0]
                 + draws["E1"][i] * lee_radok_columns(win, z, data.z_edges, data.m,
                                                      "exponential", float(draws["tau"][i]))[0])
        out[r] = data.C * f
        if contact_only:
            continue
        out[r] += draws["offset"][i]
        if "drag" in draws:
            out[r] += draws["drag"][i] * data.speed
        if "tilt" in draws:
            out[r] += draws["tilt"][i] * (data.z - data.z_ref)
    return out


def _offcontact_flags(fit: RheologyFit, residual: np.ndarray, contact: np.ndarray
                      ) -> list[str]:
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
                       "reads as contact force (fit it: baseline='linear', --baseline linear)")
    dip = adhesion_dip(data, residual, contact, zs) if "retract" in data.segments else None
    if dip is not None and dip[0] < -N_SE * dip[1]:
        depth, se, t = dip
        out.append(f"after the model's contact ends the retract's force dips "
                   f"{format_force(-depth)} below the fitted baseline ({-depth / se:.1f} se, "
                   f"at {t:.3g} s): adhesion, the sample holding the tip before it lets go, "
                   "which Ting's rule does not model; it biases the fit of the retract (fit "
                   "--segments approach,hold, or cut the retract at the pull-off)")
    return out


def _flags(fit: RheologyFit) -> list[str]:
    d, data, grid = fit.draws, fit.data, fit.grid
    out = list(fit.offcontact)
    if fit.rheology == "power-law":
        a = d["alpha"]
        if np.mean(a < 0.01) > 0.05:
            out.append(f"alpha piles up at 0, the lower bound of its prior (P(alpha < 0.01) = "
                       f"{np.mean(a < 0.01):.2f}): no relaxation resolved; the elastic model "
                       "may do")
        if np.mean(a > ALPHA_MAX - 0.01) > 0.05:
            out.append(f"alpha piles up at {ALPHA_MAX}, the upper bound of its prior: the "
                       "material flows almost like a liquid, or the segments are wrong")
    else:
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


def fit_rheology(trace: IndentationTrace, rheology: str = "power-law", *,
                 tip: Tip | None = None, segments=DEFAULT_SEGMENTS, t0: float = 1.0,
                 nu: float | None = None, drag: bool | None = None,
                 baseline: str = "constant", n_draws: int = 4000,
                 max_points: int = MAX_POINTS,
                 rng: np.random.Generator | int | None = 0) -> RheologyFit:
    """Posterior of a relaxation modulus, the surface, offset and noise from one cycle.

    Parameters
    ----------
    trace
        The recording (SI; z up, pressing positive), with its segments or segments from the
        motion.
    rheology
        ``"power-law"``: E*(t) = E0*·(t/t0)^(−alpha) (Lee & Radok 1960); ``"sls"``: the
        standard linear solid E*(t) = E_inf* + E1*·exp(−t/tau).
    tip
        Indenter (default ``trace.tip``), a power law F = C·E*·d^m.
    segments
        Fitted segments (default approach and hold).  The retract (Ting's rule,
        :mod:`~palpbayes.rheology.ting`) is fitted with the power law only: the standard
        linear solid's t1 depends on E1*/E_inf*, which the collapsed grid cannot integrate.
    t0
        [s] Reference time of the power law (E0* is the modulus at t0).
    nu
        Poisson's ratio, only to add Young's moduli to the table.
    drag
        Fit a viscous drag on the probe, F = b·(−dz/dt) [N·s/m] (:mod:`~palpbayes.rheology.
        posterior`); None (default): when the retract is fitted, whose out-of-contact force
        tells the drag from the offset.
    baseline
        ``"constant"`` (an offset F0) or ``"linear"``: F0 + F1·(z − z_ref), z_ref the mean
        height of the baseline samples (a tilted or drifting baseline; F1 [N/m] is ``tilt``).
    n_draws
        Posterior draws kept.
    max_points
        Most block means fitted (:mod:`~palpbayes.rheology.cycle`).
    rng
        Seed or Generator of the draws and the check.

    Returns
    -------
    RheologyFit
    """
    start = _time.perf_counter()
    if rheology not in RHEOLOGIES:
        raise InputError(f"unknown rheology {rheology!r}; use one of "
                         f"{', '.join(RHEOLOGIES)} (or the elastic fit)")
    if nu is not None:
        nu = check_nu(nu)
    if baseline not in BASELINES:
        raise InputError(f"baseline {baseline!r}: use one of {', '.join(BASELINES)}")
    if not (isinstance(n_draws, int | np.integer) and n_draws >= 100):
        raise InputError(f"n_draws = {n_draws!r} must be a whole number >= 100")
    gen = np.random.default_rng(rng)
    data = prepare_cycle(trace, tip, segments=segments, max_points=max_points)
    if rheology == "sls" and "retract" in data.segments:
        raise InputError("the retract is fitted with the power law only (Ting's t1 depends "
                         "on E1*/E_inf* under the SLS, which the collapsed grid cannot "
                         "integrate); fit the SLS with --segments approach,hold")
    if drag is None:
        drag = "retract" in data.segments
    grid = grid_posterior(data, rheology, t0=t0, drag=bool(drag), tilt=baseline == "linear")
    draws = grid.draws(gen, int(n_draws))
    curves = _force_curves(data, rheology, draws, t0, _BAND_DRAWS)
    sub = curve_draws(n_draws, _BAND_DRAWS)
    base = draws["offset"][sub, None] + sum(
        draws[k][sub, None] * col for k, col in (("drag", data.speed),
                                                  ("tilt", data.z - data.z_ref)) if k in draws)
    t_contact = float(np.median(_contact_times(data, draws["z_surf"][sub])))
    # residuals binned in time: -time as the "height", the contact time as the "surface"
    ppc = posterior_predictive_check(-data.time, data.force, curves, draws["sigma"][sub],
                                     phi=draws["phi"][sub], rng=gen, z_surf=-t_contact,
                                     n_bins=12)
    fit = RheologyFit(rheology, data, grid, draws, ppc, nu=nu)
    fit.offcontact = _offcontact_flags(fit, data.force - np.median(curves, axis=0),
                                       np.median(curves - base, axis=0))
    fit.flags = _flags(fit)
    fit.seconds = _time.perf_counter() - start
    return fit


def _contact_times(data: CycleData, z_surf: np.ndarray) -> np.ndarray:
    """[s] First block time in contact for each surface height."""
    inside = data.z[None, :] < np.asarray(z_surf)[:, None]
    first = np.argmax(inside, axis=1)
    return data.time[first]
