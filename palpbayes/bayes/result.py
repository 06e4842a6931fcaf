"""The result of a Bayesian fit: draws, diagnostics, budget, tables and netCDF persistence.

:meth:`BayesResult.to_netcdf` writes the draws and, in the posterior attribute
:data:`STATE_ATTR`, everything else of the result as JSON (warnings, model checks with their
details, diagnostics, the budget table, the model with its exact tip);
:meth:`BayesResult.from_idata` rebuilds the result from them, equal in every field but the
fitted data and the least-squares fit, which the caller supplies
(:func:`palpbayes.campaign.results.load_fit`).

A fresh fit keeps its draws as numpy arrays (:class:`~palpbayes.bayes.posterior_data.
PosteriorData`) and writes its file with h5netcdf; its arviz ``InferenceData``
(:attr:`BayesResult.idata`) is made on first use, so that a fit imports neither arviz (nor
with it matplotlib) nor dask (issue 59).
"""

# Long module: one job, the Bayesian fit's result; BayesResult's tables and its netCDF round trip
#   are its interface.

from __future__ import annotations

import dataclasses
import json
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from ..checks import CheckResult, checks_summary
from ..contact import Tip
from ..errors import InputError
from ..fitdata import FitData, ModelSpec
from ..flagcodes import flag_columns
from ..intervals import LEVEL, central, central_band, hull
from ..io.atomic import write_netcdf_atomic
from ..refit import ALTERNATIVE_COLUMNS, layer_alternatives
from ..twin import Specimen
from ..twin.hyper_shape import LawModel
from .budget import Budget
from .diagnostics import Diagnostics, hdi
from .instron import instron_columns
from .lawfit import law_columns_of
from .layer_fit import concrete_draws
from .modelform import ModelForm
from .posterior_data import PosteriorData

if TYPE_CHECKING:  # arviz only for the annotation: a fit does not import it
    from arviz import InferenceData

__all__ = ["BayesResult", "LEVEL", "STATE_ATTR", "saved_state", "saved_model",
           "saved_fitted_model"]

#: Posterior attribute of a saved fit holding, as JSON, what its draws do not.
STATE_ATTR = "palpbayes_result"


@dataclass
class BayesResult:
    """Posterior of one trace.

    Attributes
    ----------
    groups
        The draws and the rest of the InferenceData's groups: a
        :class:`~palpbayes.bayes.posterior_data.PosteriorData` (numpy arrays) for a fresh
        fit, the arviz ``InferenceData`` for a fit read back from its file
        (:meth:`from_idata`); either reads as ``groups.posterior[name]``,
        ``groups.posterior.attrs``.  Posterior: ``E_star``, ``E`` (at the model's nu),
        ``E_total`` (with the budget), ``z_surf``, ``sigma``, ``F0`` [, ``phi`` | ``nu_t``].
        The arviz ``InferenceData`` itself is :attr:`idata`.
    diagnostics
        Convergence figures.
    budget
        Uncertainty budget (draws and variance table).
    data
        The fitted data.
    noise
        Noise model name.
    trace_id
        Identifier.
    lsq
        The paper's least-squares result on the same data.
    warnings
        Flags raised during the fit (prior-dominated, bimodal surface, a prior bound, a failed
        model check).
    baseline
        ``"constant"`` or ``"linear"`` baseline model.
    z_ref
        [m] Reference height of the linear baseline F0 + F1·(z − z_ref).
    checks
        Model-adequacy checks (:mod:`palpbayes.checks`), empty if not run.
    notes
        What the fit says but is no failure (the layer's base or thickness not identified,
        a thin-layer regime): reported in ``flags`` as ``info: ...``.
    fitted_model
        The concrete model at the posterior's centre (the more probable base, the median
        thickness), which the checks and the budget used; ``data.model`` when it is concrete.
    layer
        The layer's ``summary.csv`` columns (:func:`palpbayes.bayes.layer_fit.layer_columns`).
    model_form
        The alternatives of a fit with a material misfit and their envelope, E's full
        interval (:mod:`palpbayes.bayes.modelform`); None without material misfit.
    law
        The material law's ``summary.csv`` columns (:func:`palpbayes.bayes.lawfit.
        law_columns`: ``law``, ``law_params``, ``E_instron_law_pa`` ...); empty: linear.
    """

    groups: PosteriorData | InferenceData
    diagnostics: Diagnostics
    budget: Budget
    data: FitData
    noise: str
    trace_id: str
    lsq: object = None
    warnings: list[str] = field(default_factory=list)
    baseline: str = "constant"
    z_ref: float = 0.0
    checks: list = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    fitted_model: ModelSpec | None = None
    layer: dict = field(default_factory=dict)
    model_form: ModelForm | None = None
    law: dict = field(default_factory=dict)
    _idata: object = field(default=None, init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if self.fitted_model is None:
            self.fitted_model = self.data.model

    @property
    def idata(self) -> InferenceData:
        """The arviz ``InferenceData`` of the fit (posterior: ``E_star``, ``E``, ``E_total``,
        ``z_surf``, ``sigma``, ``F0`` ...; ``sample_stats``, ``observed_data``,
        ``constant_data``): for a fresh fit made from :attr:`groups` on first access (this
        imports arviz), then kept."""
        if not isinstance(self.groups, PosteriorData):
            return self.groups
        if self._idata is None:
            self._idata = self.groups.to_inference_data()
        return self._idata

    def __repr__(self) -> str:
        """A line of what the fit says (its arrays are in :attr:`idata` and :meth:`summary`):
        E, the full 90 % interval, converged, the model checks, the points, the engine."""
        from ..units import format_pressure

        lo, hi = self.intervals()["full"]
        ok = checks_summary(self.checks)["model_ok"]
        state = ["converged" if self.converged else "NOT converged"]
        if isinstance(ok, bool | np.bool_):
            state.append("model ok" if ok else "model check failed")
        state.append(f"{self.data.n_points} points")
        engine = self.groups.posterior.attrs.get("engine", "emcee")
        return (f"BayesResult({self.trace_id!r}: E {format_pressure(np.median(self.draws('E')))}"
                f" [{format_pressure(lo)}, {format_pressure(hi)}] (90 %), {', '.join(state)}; "
                f"{self.data.model.tip.describe()}, nu {self.data.model.nu:g}, {self.noise} "
                f"noise, {engine})")

    # ----------------------------------------------------------------- access
    def draws(self, name: str) -> np.ndarray:
        """All draws of a posterior variable, flattened over walkers."""
        return np.asarray(self.groups.posterior[name]).ravel()

    @property
    def converged(self) -> bool:
        return self.diagnostics.converged and not self.warnings

    def summary(self) -> pd.DataFrame:
        """Per-parameter table: mean, sd, median, central 90 % interval of the draws
        (``q05``, ``q95``), 90 % HDI, R-hat, ESS, and ``lo``/``hi``, the interval the fit
        reports: the central one, except for ``E_total`` (E with the budget), where it is the
        full interval (:meth:`intervals`: the budget's, widened to hold the statistical one,
        or after a material misfit the model form's envelope) — the summary row's ``E_lo_pa``
        and ``E_hi_pa``, so that a notebook and the command line quote one interval."""
        names = [n for n in ("E_total", "E", "E_star", "z_surf", "sigma", "F0", "F1", "phi",
                             "nu_t", "thickness", "bonded")
                 if n in self.groups.posterior]
        rows = []
        for n in names:
            x = self.draws(n)
            x = x[np.isfinite(x)]  # no layer (h = inf) has no thickness and no base
            if x.size < 2:
                continue
            lo, hi = central(x)
            reported = self.intervals()["full"] if n == "E_total" else (lo, hi)
            hdi_lo, hdi_hi = hdi(x, LEVEL)
            rows.append({
                "parameter": n, "unit": _UNITS[n], "mean": float(x.mean()),
                "sd": float(x.std(ddof=1)), "median": float(np.median(x)),
                "q05": lo, "q95": hi, "lo": float(reported[0]), "hi": float(reported[1]),
                "hdi90_lo": hdi_lo, "hdi90_hi": hdi_hi,
                "rhat": self.diagnostics.rhat.get(_SAMPLED.get(n, n), np.nan),
                "ess_bulk": self.diagnostics.ess_bulk.get(_SAMPLED.get(n, n), np.nan),
                "ess_tail": self.diagnostics.ess_tail.get(_SAMPLED.get(n, n), np.nan),
                # E and E_total are monotone in E_star: rank diagnostics are E_star's
            })
        return pd.DataFrame(rows).set_index("parameter")

    def intervals(self) -> dict[str, tuple[float, float]]:
        """[Pa] The three nested 90 % intervals of E the row reports (:meth:`summary_row`):
        ``stat`` the central interval of the statistical draws ``E`` (at the stated inputs),
        ``budget`` that of the ``E_total`` draws (the budget's inputs sampled) widened where
        needed to hold ``stat``, ``full`` the budget's or after a material misfit the model
        form's envelope (:mod:`palpbayes.bayes.modelform`), widened to hold ``budget``."""
        stat = central(self.draws("E"))
        budget = hull(central(self.draws("E_total")), stat)
        form = self.model_form
        full = budget if form is None else hull((form.lo_pa, form.hi_pa), budget)
        return {"stat": stat, "budget": budget, "full": full}

    def summary_row(self) -> dict:
        """One row of ``summary.csv`` (docs/design.md §7).

        ``E_pa`` is the estimate at the inputs the user stated (nu, tip, no compliance): the
        median of the statistical posterior ``E``, the same number as ``E_stat_pa``.  The
        budget widens the interval around it and does not move it: ``E_budget_lo/hi_pa`` is
        the central 90 % interval of the ``E_total`` draws (the budget's inputs sampled),
        widened where needed to hold the statistical one; ``E_lo_pa``/``E_hi_pa`` the full
        interval (the budget's, or with a material misfit the envelope of the model-form
        alternatives', :mod:`palpbayes.bayes.modelform`), which holds both.  A one-sided
        budget (nu ± 0.05 at nu 0.5, compliance that only stiffens) shifts the ``E_total``
        draws: their median is not the headline.
        """
        E = self.draws("E_total")
        Es = self.draws("E")
        z = self.draws("z_surf")
        iv = self.intervals()
        (slo, shi), (blo, bhi), (lo, hi) = iv["stat"], iv["budget"], iv["full"]
        form = self.model_form
        d = self.diagnostics
        E_med = float(np.median(Es))
        z_med = float(np.median(z))
        best = self.fitted_model
        sampled = {k: self.draws(k) for k in ("thickness", "bonded")
                   if k in self.groups.posterior}
        if sampled:  # the E of the fitted model's own draws (its base, layer or none)
            sel = concrete_draws(best, E.size, sampled.get("thickness"), sampled.get("bonded"))
            if sel.any():
                E_med = float(np.median(Es[sel]))
        checks = checks_summary(self.checks)
        bonded_draws = (self.draws("E_instron_bonded")
                        if "E_instron_bonded" in self.groups.posterior else None)
        instron = instron_columns(E, bonded_draws,
                                  str(self.groups.posterior.attrs.get("platens", "unknown")),
                                  (lo / blo, hi / bhi), float(np.median(Es) / np.median(E)))
        return {
            "trace_id": self.trace_id,
            "method": "bayes",
            "tip": self.data.model.tip.kind,
            "n_points": self.data.n_points,
            "E_pa": float(np.median(Es)),
            "E_sd_pa": float(E.std(ddof=1)),
            "E_lo_pa": lo,
            "E_hi_pa": hi,
            "Estar_pa": float(np.median(self.draws("E_star"))),
            "z_surf_m": float(np.median(z)),
            "z_surf_sd_m": float(z.std(ddof=1)),
            "sigma_n": float(np.median(self.draws("sigma"))),
            "converged": bool(self.converged),
            "rhat_max": d.rhat_max,
            "ess_min": d.ess_min,
            "nu": self.data.model.nu,
            "E_stat_pa": float(np.median(Es)),
            "E_stat_sd_pa": float(Es.std(ddof=1)),
            "E_stat_lo_pa": slo,
            "E_stat_hi_pa": shi,
            "E_budget_lo_pa": blo,
            "E_budget_hi_pa": bhi,
            **({"modelform_share_pct": 0.0, "modelform_models": ""} if form is None
               else form.columns()),
            "noise_model": self.noise,
            "tau_max": float(max(d.tau.values())),
            "acceptance": d.acceptance,
            "n_steps": d.n_steps,
            "baseline_model": self.baseline,
            "F0_n": float(np.median(self.draws("F0"))),
            **flag_columns("; ".join(self.warnings + d.problems() + checks["flags"]
                                     + [f"info: {n}" for n in self.notes])),
            "model_ok": checks["model_ok"],
            "m_free": checks["m_free"],
            "misfit_effect": checks["misfit_effect"],
            "misfit_checks": checks["misfit_checks"],
            "engine": self.groups.posterior.attrs.get("engine", "emcee"),
            "model_fitted": best.describe_layer(),
            **self.layer,
            **self._alternatives(Es, E_med, z_med, best),
            **instron,
            **law_columns_of(self.law, (lo / blo, hi / bhi)),
        }

    def _alternatives(self, E: np.ndarray, E_med: float, z_med: float, best: ModelSpec
                      ) -> dict:
        """E_halfspace/bonded/free_pa: the refits of :func:`palpbayes.refit.
        layer_alternatives`, and where the base was sampled the median of each base's draws."""
        if best.law is not None:  # the law's E0 read with linear models: not comparable
            return dict.fromkeys(ALTERNATIVE_COLUMNS, float("nan"))
        out = layer_alternatives(E_med, z_med, self.data.z, best, self.data.model)
        if "bonded" in self.groups.posterior:
            b = self.draws("bonded")
            for base, v in (("bonded", 1.0), ("free", 0.0)):
                if (b == v).sum() >= 20:
                    out[f"E_{base}_pa"] = float(np.median(E[b == v]))
        return out

    # ----------------------------------------------------------------- predictive
    def predictive(self, z: np.ndarray | None = None, n_draws: int = 200, noise: bool = False,
                   level: float = LEVEL, seed: int = 0) -> pd.DataFrame:
        """Posterior-predictive force curve on ``z`` [m] (default: the fitted samples).

        Returns a DataFrame with ``z_m, depth_m`` (from the median surface), ``median_n``,
        ``lo_n``, ``hi_n`` (central ``level`` band of the mean curve, or of new observations
        when ``noise`` is True).
        """
        z = self.data.z if z is None else np.asarray(z, dtype=float)
        rng = np.random.default_rng(seed)
        post = self.groups.posterior
        idx, curves = self.mean_curves(z, n_draws, rng)
        flat = {n: np.asarray(post[n]).ravel() for n in ("z_surf", "sigma")}
        if noise:
            curves = curves + rng.normal(0, 1, curves.shape) * flat["sigma"][idx][:, None]
        lo, med, hi = central_band(curves, level)
        zs = float(np.median(flat["z_surf"]))
        return pd.DataFrame({"z_m": z, "depth_m": zs - z, "median_n": med, "lo_n": lo,
                             "hi_n": hi})

    def mean_curves(self, z: np.ndarray | None = None, n_draws: int = 200,
                    rng: np.random.Generator | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Mean force curves [N] at ``z`` [m] for ``n_draws`` random posterior draws.

        Returns the flat draw indices (n_draws,) and the curves (n_draws, len(z)).
        """
        z = self.data.z if z is None else np.asarray(z, dtype=float)
        rng = rng or np.random.default_rng(0)
        post = self.groups.posterior
        names = [n for n in ("E_star", "z_surf", "F0", "F1", "thickness", "bonded")
                 if n in post]
        flat = {n: np.asarray(post[n]).ravel() for n in names}
        size = flat["E_star"].size
        idx = np.sort(rng.choice(size, size=min(n_draws, size), replace=False))
        layer = {k: flat[k][idx] if k in flat else None for k in ("thickness", "bonded")}
        depth = flat["z_surf"][idx, None] - z
        s = (self.fitted_model.shape_of_draws(depth, **layer)
             if any(v is not None for v in layer.values()) else self.fitted_model.shape(depth))
        curves = flat["E_star"][idx, None] * s + flat["F0"][idx, None]
        if "F1" in flat:
            curves = curves + flat["F1"][idx, None] * (z - self.z_ref)
        return idx, curves

    def median_theta(self) -> dict[str, float]:
        """Posterior medians of the mean-curve parameters (E_star, z_surf, F0, F1, sigma[, phi])."""
        post = self.groups.posterior
        return {n: float(np.median(np.asarray(post[n]))) for n in
                ("E_star", "z_surf", "F0", "F1", "sigma", "phi") if n in post}

    # ----------------------------------------------------------------- persistence
    def to_netcdf(self, path: str | os.PathLike) -> Path:
        """Write the InferenceData (h5netcdf engine, arviz's layout) atomically; arviz can
        open it (``az.from_netcdf``).

        The rest of the result goes into the posterior attribute :data:`STATE_ATTR` (also set
        on :attr:`groups` and, once made, :attr:`idata`), so that :meth:`from_idata` can
        rebuild it.  A fresh fit whose :attr:`idata` nobody asked for is written from its
        numpy arrays (:meth:`PosteriorData.to_netcdf
        <palpbayes.bayes.posterior_data.PosteriorData.to_netcdf>`: no arviz, xarray or dask
        import); otherwise the InferenceData is, as it may have been changed.
        """
        state = json.dumps(self._state(), default=_to_json, allow_nan=True)
        self.groups.posterior.attrs[STATE_ATTR] = state
        if isinstance(self.groups, PosteriorData) and self._idata is None:
            return self.groups.to_netcdf(path)
        self.idata.posterior.attrs[STATE_ATTR] = state
        return write_netcdf_atomic(self.idata, path)

    def _state(self) -> dict:
        """Everything but the draws, the fitted points and the least-squares fit."""
        model = self.data.model
        return {
            "trace_id": self.trace_id, "noise": self.noise, "baseline": self.baseline,
            "z_ref": self.z_ref, "warnings": list(self.warnings),
            "checks": [dataclasses.asdict(c) for c in self.checks],
            "diagnostics": dataclasses.asdict(self.diagnostics),
            "budget_table": None if self.budget is None else self.budget.table.to_dict("list"),
            "model": _model_state(model),
            "fitted_model": _model_state(self.fitted_model),
            "notes": list(self.notes),
            "layer": dict(self.layer),
            "model_form": None if self.model_form is None else self.model_form.to_state(),
            "law": dict(self.law),
        }

    @classmethod
    def from_idata(cls, idata, data: FitData, lsq: object = None) -> BayesResult:
        """The result that :meth:`to_netcdf` saved, from its InferenceData (read back with its
        attributes) and the fitted data and least-squares fit of the trace.

        Raises
        ------
        InputError
            The posterior has no :data:`STATE_ATTR` (not written by :meth:`to_netcdf`).
        """
        state = saved_state(idata)
        table = state["budget_table"]
        budget = None if table is None else Budget(
            E=np.asarray(idata.posterior["E_total"]), table=pd.DataFrame(table))
        fitted = state.get("fitted_model")
        return cls(groups=idata, diagnostics=Diagnostics(**state["diagnostics"]), budget=budget,
                   data=data, noise=state["noise"], trace_id=state["trace_id"], lsq=lsq,
                   warnings=list(state["warnings"]), baseline=state["baseline"],
                   z_ref=state["z_ref"], checks=[CheckResult(**c) for c in state["checks"]],
                   notes=list(state.get("notes", [])),
                   fitted_model=None if fitted is None else _model_from_state(fitted),
                   layer=dict(state.get("layer", {})),
                   model_form=None if state.get("model_form") is None
                   else ModelForm.from_state(state["model_form"]),
                   law=dict(state.get("law", {})))


def saved_state(idata) -> dict:
    """The JSON state that :meth:`BayesResult.to_netcdf` stored in a posterior, decoded.

    Raises
    ------
    InputError
        The posterior has no such state (written otherwise, or by an older palpbayes).
    """
    raw = dict(idata.posterior.attrs).get(STATE_ATTR)
    if raw is None:
        raise InputError("the posterior does not hold the fit's flags, checks, diagnostics and "
                         "budget (written by an older palpbayes?); refit the trace "
                         "('palpbayes fit --force')")
    return json.loads(str(raw), object_hook=_from_json)


def saved_model(idata) -> ModelSpec:
    """The contact model of a saved fit, exactly as fitted (tip, nu and the layer: thickness,
    bonding, thickness range)."""
    return _model_from_state(saved_state(idata)["model"])


def saved_fitted_model(idata) -> ModelSpec:
    """The concrete model at a saved fit's posterior centre (what its checks and budget used;
    the fitted model itself for fits written before layers were sampled)."""
    state = saved_state(idata)
    return _model_from_state(state.get("fitted_model") or state["model"])


def _model_state(model: ModelSpec) -> dict:
    return {"tip": dataclasses.asdict(model.tip), "nu": model.nu, "thickness": model.thickness,
            "bonding": model.bonding,
            "thickness_range": None if model.thickness_range is None
            else list(model.thickness_range), "p_bonded": model.p_bonded,
            "specimen": None if model.specimen is None
            else dataclasses.asdict(model.specimen),
            "law": None if model.law is None else dataclasses.asdict(model.law)}


def _model_from_state(m: dict) -> ModelSpec:
    """A :class:`ModelSpec` from :func:`_model_state` (or the older ``bonded`` flag)."""
    bonding = m.get("bonding") or ("bonded" if m.get("bonded", True) else "free")
    rng = m.get("thickness_range")
    block = m.get("specimen")
    law = m.get("law")
    if law is not None:  # JSON lists back to the model's tuples
        law = LawModel(**{**law, "nodes": tuple((n, tuple(g)) for n, g in law["nodes"]),
                          "point": None if law["point"] is None
                          else tuple((n, v) for n, v in law["point"])})
    return ModelSpec(Tip(**m["tip"]), nu=m["nu"], thickness=m["thickness"], bonding=bonding,
                     thickness_range=None if rng is None else tuple(rng),
                     p_bonded=m.get("p_bonded", 0.5),
                     specimen=None if block is None else Specimen(**block), law=law)


def _to_json(obj):
    """numpy values for :func:`json.dumps`; arrays keep their dtype and shape."""
    if isinstance(obj, np.ndarray):
        return {"__ndarray__": obj.tolist(), "dtype": obj.dtype.str, "shape": list(obj.shape)}
    if isinstance(obj, np.generic):
        return obj.item()
    raise TypeError(f"{type(obj).__name__} is not JSON serialisable")


def _from_json(obj: dict):
    if "__ndarray__" in obj:
        return np.array(obj["__ndarray__"], dtype=obj["dtype"]).reshape(obj["shape"])
    return obj


_UNITS = {"E_total": "Pa", "E_instron_bonded": "Pa", "E": "Pa", "E_star": "Pa", "z_surf": "m",
          "sigma": "N", "F0": "N", "F1": "N/m", "phi": "-", "nu_t": "-", "thickness": "m",
          "bonded": "-"}
_SAMPLED = {"E_total": "E_star", "E": "E_star", "E_instron_bonded": "E_star"}
