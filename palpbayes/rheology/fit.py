"""Fit a relaxation modulus to one recorded cycle: :func:`fit_rheology` and its result.

``fit_rheology(trace, rheology="power-law")`` prepares the block means of the chosen segments
(:mod:`~palpbayes.rheology.cycle`), integrates the collapsed posterior on its grid
(:mod:`~palpbayes.rheology.posterior`), draws from it and checks the fit:

* a posterior-predictive check of the residuals binned in *time* (contact bins from the
  surface to the end of the record; :func:`palpbayes.checks.posterior_predictive_check`,
  Gelman, Meng & Stern 1996), the same test as the elastic fit's;
* a viscous drag on the probe, b·(−dz/dt), fitted with the retract by default (its out-of-
  contact force then shows it; :mod:`~palpbayes.rheology.posterior`), and a baseline that
  tilts with the height, F1·(z − z_ref), with ``baseline="linear"`` (as the elastic fit's
  ``--baseline linear``);
* flags, never silent (:mod:`~palpbayes.rheology.flags`): what the force out of contact
  shows and the model leaves out (a drag gap, a tilt, adhesion at pull-off:
  :mod:`~palpbayes.rheology.offcontact`; these fail the model check), alpha or tau at the
  edge of what the record resolves, a surface at its prior bound, other basins, a contact
  that shrinks during the hold, a thin specimen, a poor importance sample or an emcee chain
  that did not converge.

With ``adhesion="cut"`` the adhesive pull-off of the retract is found and removed before the
fit (:mod:`~palpbayes.rheology.adhesion`), and the checks run on what is left.

Moduli are reduced moduli E* [Pa] as everywhere in palpbayes; give ``nu`` to have Young's
moduli E = E*(1 − nu²) in the table too.
"""

# Long module: one job, a relaxation fit of one cycle; RheologyFit's accessors and fit_rheology
#   share the force-curve and baseline helpers.

from __future__ import annotations

import time as _time
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from ..arguments import check_seed
from ..checks import posterior_predictive_check
from ..checks.core import CheckResult
from ..compression import DEFAULT_STRAIN_WINDOW
from ..contact import Tip, check_nu, youngs_modulus
from ..contact.viscoelastic import PowerLawKernel, PronyKernel, ramp_apparent_modulus
from ..errors import InputError, PalpbayesError
from ..intervals import LEVEL, central_band
from ..trace import IndentationTrace
from ..units import format_pressure
from .adhesion import AdhesionCut, cut_adhesion
from .column_table import ColumnTable
from .compression import PAPER_COMPRESSION_SPEED, compression_moduli
from .cycle import DEFAULT_SEGMENTS, MAX_POINTS, CycleData, check_segments, prepare_cycle
from .design import lee_radok_columns
from .flags import TILT_HINT, fit_flags, offcontact_flags
from .posterior import PHI_BOUNDS, RHEOLOGIES, GridPosterior, grid_posterior
from .sampler import EmceeRheology, sample_emcee
from .ting import RETRACT, RetractDesign, with_retract

__all__ = ["RheologyFit", "fit_rheology", "curve_draws", "PARAMETERS", "BASELINES", "ENGINES",
           "ADHESION"]

#: Parameters of each rheology in table order: (name, unit, is a modulus).
PARAMETERS = {
    "power-law": (("E0", "Pa", True), ("alpha", "-", False)),
    "sls": (("E_inf", "Pa", True), ("E1", "Pa", True), ("tau", "s", False)),
    "elastic": (("E", "Pa", True),),
}
_COMMON = (("z_surf", "m", False), ("offset", "N", False), ("sigma", "N", False),
           ("phi", "-", False))
#: Rows of the optional baseline terms: a viscous drag and a tilted baseline.
_EXTRA = (("drag", "N·s/m", False), ("tilt", "N/m", False))
#: Baseline models: a constant offset, or a line in the height (``tilt``).
BASELINES = ("constant", "linear")
#: Posterior engines: the collapsed grid, or emcee started from it.
ENGINES = ("grid", "emcee")
#: What the fit does with an adhesive pull-off on the retract: fit the record as it is, or
#: cut the pull-off out first (:mod:`~palpbayes.rheology.adhesion`).
ADHESION = ("keep", "cut")
#: Draws used for the force band and the posterior-predictive check.
_BAND_DRAWS = 100


@dataclass
class RheologyFit:
    """A viscoelastic fit of one cycle.

    Attributes
    ----------
    rheology
        ``"power-law"`` (E*(t) = E0*·(t/t0)^(−alpha)), ``"sls"``
        (E*(t) = E_inf* + E1*·exp(−t/tau)) or ``"elastic"`` (E*(t) = E*).
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
    sampler
        The emcee run behind the draws (``engine="emcee"``; None for the grid engine).
    nu
        Poisson's ratio if given (adds Young's moduli to the table).
    seconds
        Wall time of the fit [s].
    nodes
        Grid draws only: the grid node behind every draw, ``{"_theta_node", "_z_node"}``
        (:meth:`~palpbayes.rheology.posterior.GridPosterior.draws`), where the force curves
        are taken; empty for emcee's draws.
    adhesion_cut
        The adhesive stretch cut from the retract before the fit (``adhesion="cut"``;
        :class:`~palpbayes.rheology.adhesion.AdhesionCut`), None when nothing was cut.
    """

    rheology: str
    data: CycleData
    grid: GridPosterior
    draws: dict[str, np.ndarray]
    ppc: CheckResult
    flags: list[str] = field(default_factory=list)
    offcontact: list[str] = field(default_factory=list)
    sampler: EmceeRheology | None = None
    nu: float | None = None
    seconds: float = 0.0
    nodes: dict[str, np.ndarray] = field(default_factory=dict, repr=False)
    adhesion_cut: AdhesionCut | None = None

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
        central ``level`` interval) and, for moduli with ``nu`` given, ``E`` rows too.
        ``attrs`` hold the level, rheology, t0 [s], nu and ``adhesion_cut_s``: the (first,
        last) time [s] cut from the retract as adhesion, None when nothing was cut."""
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
        cut = self.adhesion_cut
        out.attrs.update(level=level, rheology=self.rheology, t0_s=self.t0, nu=self.nu,
                         adhesion_cut_s=None if cut is None else (cut.t_start, cut.t_end))
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
        if self.rheology == "elastic":
            return np.broadcast_to(d["E"][:, None], (d["E"].size, t.size)).copy()
        if self.rheology == "power-law":
            return d["E0"][:, None] * (t[None, :] / self.t0) ** (-d["alpha"][:, None])
        return d["E_inf"][:, None] + d["E1"][:, None] * np.exp(-t[None, :] / d["tau"][:, None])

    def kernels(self, n: int | None = None) -> list[PowerLawKernel | PronyKernel]:
        """The relaxation kernels of the first ``n`` draws (all by default)."""
        d, k = self.draws, len(self.draws["z_surf"]) if n is None else n
        if self.rheology == "elastic":  # the constant kernel: a power law of alpha 0
            return [PowerLawKernel(d["E"][i], 0.0, self.t0) for i in range(k)]
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

    def force_curves(self, n: int = _BAND_DRAWS) -> np.ndarray:
        """[N] Model force at the block means for ``n`` draws (n, points), offset, drag and
        tilt included: the draws :func:`curve_draws` picks."""
        return _force_curves(self.data, self.rheology, self.draws, self.t0, n, self.nodes,
                             None if self.sampler is None else self.sampler.table)

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
        if self.adhesion_cut is not None:
            c = self.adhesion_cut
            parts.append(f"adhesion cut {c.t_start:.4g}-{c.t_end:.4g} s")
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
                  nodes: dict | None = None, table: ColumnTable | None = None) -> np.ndarray:
    """[N] Model force at the block means for the ``n`` draws :func:`curve_draws` picks.

    The columns cost one hereditary matrix per distinct theta, so the draws are grouped by
    theta: a grid draw's moduli are conditional on its node (:meth:`~palpbayes.rheology.
    posterior.GridPosterior.draws`), and its curve is taken at the node's (theta, z_surf)
    (``nodes``: ``_theta_node``, ``_z_node``) — at most one matrix per theta node; emcee's
    draws (and a fit read back from disk) use each draw's own values, from emcee's column
    ``table`` when given (:class:`~palpbayes.rheology.column_table.ColumnTable`: the columns
    the chain itself used, one interpolation for all the draws instead of a hereditary
    matrix per draw)."""
    idx = curve_draws(len(draws["z_surf"]), n)
    if table is not None and not nodes and rheology != "elastic":
        theta = draws["alpha" if rheology == "power-law" else "tau"][idx]
        X = table.columns(np.log(theta) if table.log_theta else theta, draws["z_surf"][idx])
        moduli = np.column_stack([draws[table.ev.names[i]][idx] for i in table.moduli])
        return _baseline_terms(data, draws, idx, np.einsum("wnk,wk->wn", X, moduli))
    win = data.windows()
    ret = data.segment == RETRACT
    design = (RetractDesign(data.edges, data.z_edges, data.sample_time[ret], data.m, t0)
              if rheology == "power-law" and ret.any() else None)
    nodes = nodes or {}
    z = np.asarray(nodes.get("_z_node", draws["z_surf"]))[idx]
    out = np.empty((idx.size, data.n_points))
    if rheology == "elastic":
        out[:] = draws["E"][idx, None] * lee_radok_columns(win, z, data.z_edges, data.m, None)
    else:
        name, kind = ("alpha", "power-law") if rheology == "power-law" else ("tau",
                                                                             "exponential")
        theta = np.asarray(nodes.get("_theta_node", draws[name]))[idx]
        modulus = draws["E0" if rheology == "power-law" else "E1"][idx]
        for value in np.unique(theta):
            rows = np.flatnonzero(theta == value)
            cols = lee_radok_columns(win, z[rows], data.z_edges, data.m, kind, float(value),
                                     t0)
            if design is not None:
                cols = with_retract(data, cols, z[rows], float(value), t0, design)
            out[rows] = modulus[rows, None] * cols
        if rheology == "sls":
            out += draws["E_inf"][idx, None] * lee_radok_columns(win, z, data.z_edges, data.m,
                                                                 None)
    out *= data.C
    return _baseline_terms(data, draws, idx, out)


def _baseline_terms(data: CycleData, draws: dict, idx: np.ndarray, out: np.ndarray
                    ) -> np.ndarray:
    """``out`` (n, points) [N], the contact force of the draws ``idx``, plus their offset,
    drag b·(−dz/dt) and tilt F1·(z − z_ref) (those in ``draws``), in place."""
    out += draws["offset"][idx, None]
    if "drag" in draws:
        out += draws["drag"][idx, None] * data.speed[None, :]
    if "tilt" in draws:
        out += draws["tilt"][idx, None] * (data.z - data.z_ref)[None, :]
    return out


# Many parameters: one cycle's viscoelastic model (law, segments, t0, drag, baseline, adhesion) and
# its engine; rheology_options gathers them for files and manifests.
def fit_rheology(trace: IndentationTrace, rheology: str = "power-law", *,
                 tip: Tip | None = None, segments=DEFAULT_SEGMENTS, t0: float = 1.0,
                 nu: float | None = None, drag: bool | None = None,
                 baseline: str = "constant", engine: str = "grid", n_draws: int = 4000,
                 max_points: int = MAX_POINTS, adhesion: str = "keep",
                 rng: np.random.Generator | int | None = 0,
                 seed: int | None = None) -> RheologyFit:
    """Posterior of a relaxation modulus, the surface, offset and noise from one cycle.

    Parameters
    ----------
    trace
        The recording (SI; z up, pressing positive), with its segments or segments from the
        motion.
    rheology
        ``"power-law"``: E*(t) = E0*·(t/t0)^(−alpha) (Lee & Radok 1960); ``"sls"``: the
        standard linear solid E*(t) = E_inf* + E1*·exp(−t/tau); ``"elastic"``: E*(t) = E*,
        the rate-independent law fitted to the same block means (the force then follows the
        depth, F = C·E*·d^m, on the retract as on the approach), to compare with the others
        (:func:`~palpbayes.rheology.choice.compare_rheology`).
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
    engine
        ``"grid"`` (or ``"exact"``, the elastic fit's name for its grid engine): the collapsed
        posterior on its grid (:mod:`~palpbayes.rheology.posterior`);
        ``"emcee"``: the same posterior sampled with every parameter explicit, started from
        the grid's draws (:func:`~palpbayes.rheology.sampler.sample_emcee`; a cross-check, a
        few times slower; a chain that does not converge is flagged).
    n_draws
        Posterior draws kept.
    max_points
        Most block means fitted (:mod:`~palpbayes.rheology.cycle`).
    adhesion
        ``"keep"`` (default): fit the record as it is (an adhesive pull-off on the retract is
        flagged); ``"cut"``: first remove the retract's adhesive stretch, from where its force
        comes down to its own baseline to where it has recovered
        (:func:`~palpbayes.rheology.adhesion.cut_adhesion`; ``RheologyFit.adhesion_cut``), and
        check what is left.  Needs the retract in ``segments``.
    rng
        Seed or Generator of the draws and the check.
    seed
        Same as ``rng`` (the name :func:`palpbayes.fit` uses); give one or the other.

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
    if engine == "exact":  # the elastic fit's name for the posterior on a grid
        engine = "grid"
    if engine not in ENGINES:
        raise InputError(f"engine {engine!r}: use one of {', '.join(ENGINES)} (or exact, "
                         "which is grid)")
    if seed is not None:
        if rng not in (0, None):
            raise InputError("give the seed once: seed= or rng=, not both")
        rng = check_seed(seed)
    if baseline not in BASELINES:
        raise InputError(f"baseline {baseline!r}: use one of {', '.join(BASELINES)}")
    if not (isinstance(n_draws, int | np.integer) and n_draws >= 100):
        raise InputError(f"n_draws = {n_draws!r} must be a whole number >= 100")
    if adhesion not in ADHESION:
        raise InputError(f"adhesion {adhesion!r}: use one of {', '.join(ADHESION)}")
    cut, uncut = None, trace
    if adhesion == "cut":
        trace, cut = _cut_pull_off(trace, segments)
    gen = np.random.default_rng(rng)
    data = prepare_cycle(trace, tip, segments=segments, max_points=max_points)
    if rheology == "sls" and "retract" in data.segments:
        raise InputError("the retract is fitted with the power law only (Ting's t1 depends "
                         "on E1*/E_inf* under the SLS, which the collapsed grid cannot "
                         "integrate); fit the SLS with --segments approach,hold")
    if drag is None:
        drag = "retract" in data.segments
    grid = grid_posterior(data, rheology, t0=t0, drag=bool(drag), tilt=baseline == "linear")
    sampler = None
    if engine == "emcee":
        sampler = sample_emcee(data, rheology, t0=t0, drag=grid.drag, tilt=grid.tilt,
                               n_draws=int(n_draws), rng=gen, grid=grid)
        draws = {**sampler.draws, "ess": np.array(np.inf)}  # no importance resampling
    else:
        draws = grid.draws(gen, int(n_draws))
    nodes = {k: draws.pop(k) for k in ("_theta_node", "_z_node") if k in draws}
    curves = _force_curves(data, rheology, draws, t0, _BAND_DRAWS, nodes,
                           None if sampler is None else sampler.table)
    sub = curve_draws(n_draws, _BAND_DRAWS)
    t_contact = float(np.median(_contact_times(data, draws["z_surf"][sub])))
    # residuals binned in time: -time as the "height", the contact time as the "surface"
    ppc = posterior_predictive_check(-data.time, data.force, curves, draws["sigma"][sub],
                                     phi=draws["phi"][sub], rng=gen, z_surf=-t_contact,
                                     n_bins=12)
    fit = RheologyFit(rheology, data, grid, draws, ppc, sampler=sampler, nu=nu, nodes=nodes,
                      adhesion_cut=cut)
    fit.offcontact = offcontact_flags(fit, data.force - np.median(curves, axis=0))
    if baseline == "constant" and any(TILT_HINT in f for f in fit.offcontact):
        tried = _tried_tilt(fit, uncut, rheology, tip=tip, segments=segments, t0=t0, nu=nu,
                            drag=drag, engine=engine, n_draws=n_draws, max_points=max_points,
                            adhesion=adhesion, rng=int(gen.integers(2**62)))
        fit.offcontact = [f.replace(TILT_HINT, tried) for f in fit.offcontact]
    fit.flags = fit_flags(fit)
    fit.seconds = _time.perf_counter() - start
    return fit


def _cut_pull_off(trace: IndentationTrace, segments) -> tuple[IndentationTrace,
                                                               AdhesionCut | None]:
    """``adhesion="cut"``: the trace without its retract's adhesive stretch, and the cut
    (:func:`~palpbayes.rheology.adhesion.cut_adhesion`); InputError when the fitted segments
    leave out the retract, where the cut is made."""
    names = check_segments(segments)
    if "retract" not in names:
        raise InputError(f"adhesion='cut' (--adhesion cut) cuts the pull-off out of the "
                         f"retract, which --segments {','.join(names)} does not fit: add the "
                         "retract (e.g. --segments approach,retract) or leave the adhesion at "
                         "keep")
    return cut_adhesion(trace)  # a cut trace keeps the segment codes it was cut by


def _tried_tilt(fit: RheologyFit, trace: IndentationTrace, rheology: str, **kw) -> str:
    """What the tilt flag's hint (:data:`~palpbayes.rheology.flags.TILT_HINT`) gives when it is
    tried: the same fit with a linear baseline.  The hint is kept, with the moduli it gives,
    when that fit's model check passes; otherwise the words say it was tried and why it does
    not help (a fit that fails, a model check that still fails) with the first modulus it
    reads, so that nobody follows a hint that makes the answer worse (issue 46: on the real
    stress-relaxation cell the SLS failed and the power law's E0* moved +52 %)."""
    name = PARAMETERS[rheology][0][0]
    try:
        alt = fit_rheology(trace, rheology, baseline="linear", **kw)
    except PalpbayesError as exc:
        return (f"--baseline linear was tried and its fit fails: "
                f"{str(exc).replace('; ', ', ')}")
    before = float(np.median(fit.draws[name]))
    after = float(np.median(alt.draws[name]))
    moved = f"{name}* {format_pressure(after)}, {after / before - 1:+.1%} against this fit"
    if alt.model_ok:
        return f"{TILT_HINT}: tried, its model check passes, {moved}"
    return f"--baseline linear was tried and does not help, its model check still fails, {moved}"


def _contact_times(data: CycleData, z_surf: np.ndarray) -> np.ndarray:
    """[s] First block time in contact for each surface height."""
    inside = data.z[None, :] < np.asarray(z_surf)[:, None]
    first = np.argmax(inside, axis=1)
    return data.time[first]
