"""Comparison tables: ground truth vs the paper's least squares vs the Bayesian model.

:func:`compare` reads a results folder written by :func:`palpbayes.campaign.fit_campaign`
and writes, atomically,

* ``comparison.csv`` — one row per material × tip × method (:data:`COMPARISON_COLUMNS`);
* ``pooled.csv`` — the hierarchical details of every Bayesian group
  (:meth:`palpbayes.pooling.PooledEstimate.row`);
* ``budget.csv`` — per material × tip, each input's share of the variance of log E of the
  pooled estimate (``material, tip, input, distribution, rel_sd_pct, share_pct``);
* ``stiffening.csv``, ``stiffening_parameters.csv``, ``stiffening_curves.csv`` — only when
  some material × tip has Bayesian fits at
  :data:`~palpbayes.campaign.stiffening_tables.STIFFENING_MIN_REST_TIMES` or more distinct
  positive rest times: the stiffening law fitted to them, its parameters and its E(t) band
  (:mod:`palpbayes.campaign.stiffening_tables`);
* ``indentation.csv`` — when the trace files can be read: each trace replayed through the
  online estimator, where a ±2 % rule stopped (:mod:`palpbayes.campaign.indentation`).

The report draws these tables; it fits nothing.

What the numbers are
--------------------
least squares (``lsq``), as the paper: ``E_pa`` ± ``E_sd_pa`` is the mean ± sd over the traces;
``E_lo_pa``/``E_hi_pa`` the 90 % t interval of the mean, mean ± t(0.95, n − 1)·sd/sqrt(n);
``E_new_*`` the 90 % t prediction interval of a new specimen, mean ± t·sd·sqrt(1 + 1/n).

Bayes (``bayes``), hierarchical pooling (:mod:`palpbayes.pooling`): ``E_pa``, ``E_sd_pa`` and the
90 % interval describe exp(mu)·f, the material's median modulus with the shared uncertainty
budget f; ``E_new_*`` the posterior predictive exp(mu + tau·z)·f of a new specimen.  The
pooling input of trace i is the *statistical* posterior of E (netCDF variable ``E``), never the
budgeted ``E_total``: the budget is shared by the traces of a group and applied once, to the
pooled draws.  ``tau_prior_sd`` is the scale of tau's half-normal prior.  ``E_new_sd_pa`` is
the sd of the predictive draws; with few traces it is dominated by tau's heavy right tail, so
the text table and ``gt_z_new`` use the 90 % interval instead.

Against the ground truth (Instron mean GT ± sd over specimens):

* ``rel_err_pct`` = 100·(GT − E)/GT (the paper's convention);
* ``gt_in_new_interval``: GT inside the 90 % interval *for a new specimen* (``E_new_lo_pa`` …
  ``E_new_hi_pa``) — the posterior predictive for Bayes and the t prediction interval for least
  squares, so both methods are judged by the same kind of interval: each Instron specimen and
  each palpated location is one draw from the material's population;
* ``gt_z_new`` = (E − GT)/sqrt(sd_new² + GT_sd²), one definition for both methods: sd_new
  (column ``E_new_sd_eq_pa``) = (``E_new_hi_pa`` − ``E_new_lo_pa``)/(2·1.645), the
  normal-equivalent sd of the same 90 % new-specimen interval that ``gt_in_new_interval``
  uses, i.e. the spread a user would quote for a new specimen with that method.  It is neither the
  sd over traces (which ignores that the mean of n traces is itself uncertain) nor the sd of
  the Bayesian predictive draws ``E_new_sd_pa`` (inflated by the heavy right tail of tau when
  a group has few traces).  With GT_sd = 0 and a symmetric interval, |z| > 1.645 exactly
  when GT is outside the interval.  The GT sd in the denominator is why a small z can sit
  next to ``gt_in_new_interval = False`` when the Instron specimens themselves scatter;
* ``gt_in_E_interval``: GT inside the row's own interval ``E_lo_pa`` … ``E_hi_pa`` (the
  material's median for Bayes, the mean of the traces for least squares): a narrower claim,
  which a material whose specimens differ from the palpated one can fail while
  ``gt_in_new_interval`` holds.

``paper_*`` are the paper's published robot (least-squares) estimates for White/Pink/Grey ×
flat/sphere/paraboloid (:data:`palpbayes.paper.PAPER_ROBOT_ESTIMATES`); ``paper_err_pct`` is
recomputed from the printed E and the paper's Instron means, because the printed sphere errors
do not follow from the printed values (see that constant's note).

Reference values are read by :mod:`palpbayes.campaign.reference`, the per-trace posteriors by
:mod:`palpbayes.pooling.inputs`; the text layout is :mod:`palpbayes.campaign.compare_text`.
"""

# Long module: one job, the comparison table; its row builders are private to compare().

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
from scipy import stats
from scipy.special import expit

from .. import outputs
from ..bayes.budget import BudgetSpec
from ..bayes.result import saved_fitted_model, saved_model
from ..contact import DEFAULT_NU, registered_kinds
from ..errors import DataFileError, FitError, InputError
from ..fitdata import ModelSpec
from ..flagcodes import flag_columns
from ..intervals import LEVEL
from ..io.atomic import write_csv_atomic
from ..io.manifest import tip_from_row
from ..io.tabular import parse_bool
from ..pooling.inputs import fitdata_from_posterior, posterior_attrs, read_posterior
from ..pooling.model import TAU_PRIOR_SD, log_normal_summary, pool_group
from ..refit import ALTERNATIVE_COLUMNS
from .compare_text import format_comparison
from .fitjob import trace_seed
from .indentation import indentation_study
from .instron import INSTRON_GROUP_COLUMNS, instron_group_columns, instron_gt_columns
from .reference import (
    gt_columns,
    load_groundtruth,
    new_specimen_sd,
    paper_columns,
    paper_estimates,
)
from .settings import read_settings
from .stiffening_tables import fit_stiffening_tables

__all__ = ["COMPARISON_COLUMNS", "POOLED_COLUMNS", "Comparison",
           "compare", "load_groundtruth", "paper_estimates"]

COMPARISON_COLUMNS = [
    "material", "tip", "method", "n_traces", "E_pa", "E_sd_pa", "E_lo_pa", "E_hi_pa",
    "E_new_pa", "E_new_lo_pa", "E_new_hi_pa", "gt_E_pa", "gt_sd_pa", "rel_err_pct",
    "gt_in_new_interval", "gt_in_E_interval", "gt_z_new", "residual_n2", "converged_all",
    "paper_E_pa", "paper_sd_pa", "paper_err_pct", "z_surf_err_mean_m",
    # extras
    "E_new_sd_pa", "tau", "gt_n", "n_failed", "notes", "flag_codes", "flag_level",
    "E_new_sd_eq_pa", "tau_prior_sd",
    # the layer: group means of the rows' E read as a half-space, a bonded and a free layer
    # (for lsq: what the layer would do to the paper's estimate), and for bayes the group's
    # posterior probability of a bonded base (every trace lies on the same plate)
    "E_halfspace_pa", "E_bonded_pa", "E_free_pa", "p_bonded",
    # bayes with the specimen's twin: what a compression test of a new specimen would read,
    # beside the Instron (palpbayes.campaign.instron)
    *INSTRON_GROUP_COLUMNS,
]
BUDGET_COLUMNS = ["material", "tip", "input", "distribution", "rel_sd_pct", "share_pct"]
#: Columns of ``pooled.csv`` (:meth:`palpbayes.pooling.PooledResult.row` plus the group's
#: representative trace); written as a header-only table when no group has Bayes rows.
POOLED_COLUMNS = (
    ["material", "tip", "n_traces"]
    + [f"{stem}{q}{unit}" for stem, unit in (("mu", ""), ("tau", ""), ("E_stat", "_pa"),
                                             ("E", "_pa"), ("E_mean", "_pa"), ("E_new", "_pa"),
                                             ("factor", ""))
       for q in ("", "_sd", "_lo", "_hi")]
    + ["m_spread", "s_max", "tau_prior_sd", "rhat_max", "ess_min", "tau_max", "n_steps",
       "n_draws", "converged", "notes", "flag_codes", "flag_level", "representative_trace",
       "budget_applied", "p_bonded",
       "base_ratio"]
)
#: The Bayesian row's moduli of ``comparison.csv``, copied from its group's ``pooled.csv``
#: row: one computation (:meth:`palpbayes.pooling.PooledEstimate.row`), equal in both files.
POOLED_SHARED = ("E_pa", "E_sd_pa", "E_lo_pa", "E_hi_pa", "E_new_pa", "E_new_sd_pa",
                 "E_new_lo_pa", "E_new_hi_pa")


@dataclass
class Comparison:
    """Tables of one results folder (see module docstring)."""

    comparison: pd.DataFrame
    pooled: pd.DataFrame
    budget: pd.DataFrame
    groundtruth: pd.DataFrame | None
    groundtruth_source: str | None
    results_dir: Path
    stiffening: pd.DataFrame | None = None
    indentation: pd.DataFrame | None = None

    def format(self) -> str:
        """The comparison in the paper's layout (:func:`format_comparison`)."""
        return format_comparison(self.comparison, self.groundtruth_source)


# ----------------------------------------------------------------------------- inputs


def _campaign_dir(res: Path, settings: dict) -> Path | None:
    rel, ab = settings.get("campaign_dir_relative"), settings.get("campaign_dir")
    for cand in ((res / rel) if rel else None, Path(ab) if ab else None):
        if cand is not None and cand.is_dir():
            return cand.resolve()
    return None


def _read_summary(res: Path) -> pd.DataFrame:
    path = res / outputs.SUMMARY
    if not path.is_file():
        raise DataFileError(res, f"no {outputs.SUMMARY} in this folder",
                            "give the --out folder of 'palpbayes fit' on a campaign manifest")
    df = pd.read_csv(path, dtype={"trace_id": str, "material": str, "tip": str,
                                  "method": str, "notes": str})
    missing = {"trace_id", "method", "tip", "material", "E_pa"} - set(df.columns)
    if missing:
        raise DataFileError(path, f"lacks column(s) {', '.join(sorted(missing))}")
    df["material"] = df["material"].fillna("")
    df["notes"] = df["notes"].fillna("") if "notes" in df.columns else ""
    return df


def _budget_spec(fields: dict) -> BudgetSpec:
    b = dict(fields.get("budget") or {})
    if b.get("nu_range") is not None:
        b["nu_range"] = tuple(b["nu_range"])
    try:
        return BudgetSpec(**b)
    except TypeError:
        return BudgetSpec()


def _order(values: pd.Series, preferred: list[str]) -> list[str]:
    seen = list(dict.fromkeys(values))
    return [v for v in preferred if v in seen] + [v for v in seen if v not in preferred]


# ----------------------------------------------------------------------------- groups


def _lsq_row(g: pd.DataFrame, level: float) -> dict:
    ok = g[np.isfinite(g["E_pa"])]
    E = ok["E_pa"].to_numpy(float)
    n = E.size
    row = {"n_traces": n, "n_failed": len(g) - n, "converged_all": n == len(g) and n > 0,
           "residual_n2": float(ok["rss_n2"].mean()) if "rss_n2" in ok and n else np.nan}
    if n == 0:
        return row
    mean = float(E.mean())
    sd = float(E.std(ddof=1)) if n > 1 else np.nan
    t = float(stats.t.ppf(0.5 + level / 2, n - 1)) if n > 1 else np.nan
    half, half_new = t * sd / np.sqrt(n), t * sd * np.sqrt(1 + 1 / n)
    row.update({"E_pa": mean, "E_sd_pa": sd, "E_lo_pa": mean - half, "E_hi_pa": mean + half,
                "E_new_pa": mean, "E_new_sd_pa": sd * np.sqrt(1 + 1 / n) if n > 1 else np.nan,
                "E_new_lo_pa": mean - half_new, "E_new_hi_pa": mean + half_new})
    return row


def _base_evidence(idata, p_prior: float) -> float:
    """ln Bayes factor bonded/free of one trace: the exact engine's, or (emcee) from the
    share of bonded draws, clipped to what the number of draws can tell."""
    bf = dict(idata.posterior.attrs).get("log_bf_bonded")
    if bf is not None and np.isfinite(float(bf)):
        return float(bf)
    b = np.asarray(idata.posterior["bonded"], dtype=float).ravel()
    b = b[~np.isnan(b)]
    if b.size == 0:
        return 0.0
    p = np.clip(b.mean(), 1.0 / (b.size + 1), b.size / (b.size + 1))
    return float(np.log(p / (1 - p)) - np.log(p_prior / (1 - p_prior)))


def _bayes_group(g: pd.DataFrame, res: Path, geometry: pd.DataFrame | None,
                 budget: BudgetSpec, seed: int, tau_prior_sd: float, settings, level: float,
                 settings_fields: dict | None = None
                 ) -> tuple[dict, dict | None, pd.DataFrame | None]:
    material, tip = g["material"].iloc[0], g["tip"].iloc[0]
    ids, ms, ss, meds, log_bf, ratios, models = [], [], [], [], [], [], []
    sampled_base = False
    for _, trow in g.iterrows():
        tid, E = trow["trace_id"], trow["E_pa"]
        path = outputs.posterior_path(res, tid)
        if not (np.isfinite(E) and path.is_file()):
            continue
        idata = read_posterior(path)
        draws = np.asarray(idata.posterior["E"]).ravel()
        estar = np.asarray(idata.posterior["E_star"]).ravel()
        try:
            model = saved_model(idata)
        except InputError:  # written without the fit's state: no layer to read
            model = None
        if model is not None and "bonded" in idata.posterior and model.bonding == "unknown":
            # every trace read as bonded: the base is shared by the group (pooling/model.py)
            sampled_base = True
            r = float(trow.get("E_free_pa", np.nan) / trow.get("E_bonded_pa", np.nan))
            r = r if np.isfinite(r) and r > 0 else 1.0
            free = np.asarray(idata.posterior["bonded"]).ravel() == 0.0
            draws = np.where(free, draws / r, draws)
            estar = np.where(free, estar / r, estar)
            ratios.append(r)
            log_bf.append(_base_evidence(idata, model.p_bonded))
        m, s = log_normal_summary(draws)
        ids.append(tid)
        ms.append(m)
        ss.append(s)
        models.append(model)
        meds.append((float(np.median(np.asarray(idata.posterior["z_surf"]))),
                     float(np.median(estar))))
    flags = []
    conv = g["converged"].map(parse_bool) if "converged" in g else pd.Series(False, index=g.index)
    row = {"n_traces": len(ids), "n_failed": len(g) - len(ids)}
    if not ids:
        row.update({"converged_all": False, **flag_columns("no Bayesian posterior to pool")})
        return row, None, None
    i_rep = int(np.argmin(np.abs(np.asarray(ms) - np.median(ms))))
    idata = read_posterior(outputs.posterior_path(res, ids[i_rep]))
    data = z_med = e_med = None
    spec = budget
    try:
        fitted = saved_fitted_model(idata)
    except InputError:  # no saved state: the geometry of traces.csv, as a half-space
        fitted = None
        if geometry is not None and ids[i_rep] in geometry.index:
            nu = float(posterior_attrs(idata).get("nu", DEFAULT_NU))
            fitted = ModelSpec(tip_from_row(geometry.loc[ids[i_rep]]), nu=nu)
    if fitted is None:
        spec = None
        flags.append("uncertainty budget not applied (no saved model and no traces.csv "
                     "geometry)")
    else:
        if sampled_base and fitted.has_layer:
            fitted = fitted.variant(base="bonded")  # the draws were read as bonded
        data = fitdata_from_posterior(idata, fitted)
        z_med, e_med = meds[i_rep]
    p_bonded = base_ratio = None
    if sampled_base:
        p0 = models[i_rep].p_bonded
        odds = np.log(p0 / (1 - p0)) + float(np.sum(log_bf))
        p_bonded = float(expit(odds))  # no overflow at decisive evidence
        base_ratio = float(np.median(ratios))
    pooled = pool_group(ms, ss, material=material, tip=tip, data=data, z_surf=z_med,
                        estar=e_med, budget=spec, tau_prior_sd=tau_prior_sd,
                        seed=trace_seed(seed, f"pool/{material}/{tip}"), settings=settings,
                        p_bonded=p_bonded, base_ratio=1.0 if base_ratio is None else base_ratio)
    if not pooled.posterior.converged:
        flags.append("pooled chain not converged: " + "; ".join(
            pooled.posterior.diagnostics.problems()))
    n_conv = int(conv[g["trace_id"].isin(ids)].sum())
    if n_conv < len(ids):
        flags.append(f"{len(ids) - n_conv} trace fit(s) not converged")
    # as a trace's row: the median at the stated inputs, the budget's interval around it;
    # pooled.csv's row is the one source of these numbers (comparison.csv copies them)
    prow = {**pooled.row(level), "representative_trace": ids[i_rep],
            "budget_applied": spec is not None}
    row.update({c: prow[c] for c in POOLED_SHARED})
    row.update({
        "tau": float(np.median(pooled.posterior.tau)),
        "tau_prior_sd": pooled.posterior.tau_prior_sd,
        "converged_all": bool(n_conv == len(g) and pooled.posterior.converged),
        **flag_columns("; ".join(flags)), "p_bonded": np.nan if p_bonded is None else p_bonded,
    })
    prow.update(p_bonded=row["p_bonded"],
                base_ratio=np.nan if base_ratio is None else base_ratio)
    row.update(instron_group_columns(pooled.E_new, pooled.nu, fitted, budget,
                                     str((settings_fields or {}).get("platens", "unknown"))))
    btab = pooled.budget.assign(material=material, tip=tip)[BUDGET_COLUMNS]
    return row, prow, btab


def _layer_means(g: pd.DataFrame) -> dict:
    """Group means of the rows' E read as a half-space, a bonded and a free layer."""
    out = {}
    for col in ALTERNATIVE_COLUMNS:
        x = pd.to_numeric(g[col], errors="coerce") if col in g else pd.Series(dtype=float)
        out[col] = float(x.mean()) if x.notna().any() else np.nan
    return out


# ----------------------------------------------------------------------------- main


def compare(
    results_dir: str | os.PathLike,
    *,
    groundtruth: str | os.PathLike | None = None,
    seed: int | None = None,
    tau_prior_sd: float = TAU_PRIOR_SD,
    pooling_settings=None,
    level: float = LEVEL,
    write: bool = True,
) -> Comparison:
    """Pool, compare with ground truth and the paper, and write the tables (module docstring).

    Parameters
    ----------
    results_dir
        Folder written by :func:`palpbayes.campaign.fit_campaign`.
    groundtruth
        Ground truth (see :func:`load_groundtruth`); None: the campaign's ``groundtruth/``.
    seed
        Seed of the pooling samplers (default: the fit's seed from ``settings.json``); each
        group's seed is derived from it and the group's labels.
    tau_prior_sd
        Scale of the half-normal prior of tau (:mod:`palpbayes.pooling`).
    pooling_settings
        :class:`~palpbayes.bayes.SamplerSettings` of the pooling sampler (default
        :data:`palpbayes.pooling.POOLING_SETTINGS`).
    level
        Probability content of the intervals (0.9).
    write
        Write ``comparison.csv``, ``pooled.csv`` and ``budget.csv`` into ``results_dir``.

    Raises
    ------
    DataFileError
        No ``summary.csv`` in ``results_dir``, or unreadable ground truth.
    """
    res = Path(results_dir)
    summary = _read_summary(res)
    settings = read_settings(res)
    fields = settings.get("options_fields") or {}
    budget = _budget_spec(fields)
    seed = int(settings.get("seed", 0) if seed is None else seed)
    geometry = None
    if (res / outputs.TRACES).is_file():
        geometry = pd.read_csv(res / outputs.TRACES, dtype={"trace_id": str, "material": str,
                                                          "tip": str, "specimen": str})
        geometry = geometry.set_index("trace_id", drop=False)
    camp = _campaign_dir(res, settings)
    gt, gt_source = load_groundtruth(groundtruth, camp)
    truth = None
    if camp is not None and (camp / "truth.csv").is_file():
        truth = pd.read_csv(camp / "truth.csv", dtype={"trace_id": str}).set_index("trace_id")
    paper = paper_estimates()

    order_src = geometry if geometry is not None else summary
    materials = _order(order_src["material"].fillna(""), ["White", "Pink", "Grey"])
    tips = _order(order_src["tip"], list(registered_kinds()))
    rows, pooled_rows, budgets = [], [], []
    for mat in materials:
        for tip in tips:
            grp = summary[(summary["material"] == mat) & (summary["tip"] == tip)]
            for method in ("lsq", "bayes"):
                g = grp[grp["method"] == method]
                if g.empty:
                    continue
                if method == "lsq":
                    row = _lsq_row(g, level)
                else:
                    row, prow, btab = _bayes_group(g, res, geometry, budget, seed,
                                                   tau_prior_sd, pooling_settings, level,
                                                   fields)
                    if prow is not None:
                        pooled_rows.append(prow)
                        budgets.append(btab)
                row = {"material": mat, "tip": tip, "method": method, **row,
                       **_layer_means(g)}
                row["E_new_sd_eq_pa"] = new_specimen_sd(row.get("E_new_lo_pa", np.nan),
                                                        row.get("E_new_hi_pa", np.nan), level)
                row.update(gt_columns(row, gt, mat, level))
                row.update(instron_gt_columns(row, gt, mat))
                row.update(paper_columns(paper, mat, tip))
                if truth is not None and "z_surf_true_m" in truth:
                    ok = g[g["trace_id"].isin(truth.index) & np.isfinite(g["z_surf_m"])]
                    err = np.abs(ok["z_surf_m"].to_numpy(float)
                                 - truth.loc[ok["trace_id"], "z_surf_true_m"].to_numpy(float))
                    row["z_surf_err_mean_m"] = float(err.mean()) if err.size else np.nan
                rows.append(row)
    if not rows:
        raise FitError(f"{res / outputs.SUMMARY} has no lsq or bayes rows to compare")
    comparison = pd.DataFrame(rows, columns=COMPARISON_COLUMNS)
    # header-only when no group has Bayes rows (an lsq-only fit): a file without columns is
    # not a CSV table, and readers reject it
    pooled = pd.DataFrame(pooled_rows) if pooled_rows else pd.DataFrame(columns=POOLED_COLUMNS)
    budget_tab = pd.concat(budgets, ignore_index=True) if budgets else pd.DataFrame(
        columns=BUDGET_COLUMNS)
    stiff = fit_stiffening_tables(summary, materials, tips, seed, level)
    study = (indentation_study(geometry, settings) if "bayes" in set(summary["method"])
             else pd.DataFrame())
    if write:
        write_csv_atomic(comparison, res / outputs.COMPARISON)
        write_csv_atomic(pooled, res / outputs.POOLED)
        write_csv_atomic(budget_tab, res / outputs.BUDGET)
        # a table with no rows now is removed: a previous run's would be stale
        for table, name in ((stiff.rows, outputs.STIFFENING),
                            (stiff.parameters, outputs.STIFFENING_PARAMETERS),
                            (stiff.curves, outputs.STIFFENING_CURVES),
                            (study if len(study) else None, outputs.INDENTATION)):
            if table is not None:
                write_csv_atomic(table, res / name)
            else:
                (res / name).unlink(missing_ok=True)
    return Comparison(comparison=comparison, pooled=pooled, budget=budget_tab, groundtruth=gt,
                      groundtruth_source=gt_source, results_dir=res, stiffening=stiff.rows,
                      indentation=study if len(study) else None)
