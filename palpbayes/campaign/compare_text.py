"""Plain-text rendering of the comparison table in the paper's layout (no plotting)."""

from __future__ import annotations

import numpy as np
import pandas as pd

from ..io.tabular import parse_bool

__all__ = ["format_comparison"]


def _pm(e, sd) -> str:
    if e is None or not np.isfinite(e):
        return "-"
    return f"{e / 1e3:.1f} ± {sd / 1e3:.1f}" if sd is not None and np.isfinite(sd) else \
        f"{e / 1e3:.1f}"


def _interval(e, lo, hi) -> str:
    if e is None or not np.isfinite(e):
        return "-"
    if lo is None or hi is None or not (np.isfinite(lo) and np.isfinite(hi)):
        return f"{e / 1e3:.1f}"
    return f"{e / 1e3:.1f} [{lo / 1e3:.1f}, {hi / 1e3:.1f}]"


def _tau_prior_line(df: pd.DataFrame, tau_prior_sd: float | None) -> str | None:
    if "bayes" not in set(df["method"]):
        return None
    values = []
    if "tau_prior_sd" in df.columns:
        values = sorted({float(v) for v in df.loc[df["method"] == "bayes", "tau_prior_sd"]
                         if pd.notna(v)})
    if not values and tau_prior_sd is not None:
        values = [float(tau_prior_sd)]
    prior = (" or ".join(f"HalfNormal({v:g})" for v in values) if values
             else "half-normal (scale not recorded)")
    return ("Bayes pooling: log E_i ~ Normal(mu, tau²) over the traces of a material × tip; flat "
            f"prior on mu, tau ~ {prior} on the log-E scale; the systematic budget is applied "
            "once per group.")


def format_comparison(df: pd.DataFrame, groundtruth_source: str | None = None,
                      tau_prior_sd: float | None = None) -> str:
    """The comparison as text in the paper's layout: rows material, columns tip × method.

    Cells [kPa]: least squares mean ± sd over traces (the paper's convention); Bayes the
    posterior-predictive median for a new specimen with its central 90 % interval
    ``[E_new_lo, E_new_hi]`` -- not ± sd: with few traces the predictive draws have a heavy
    right tail from tau, and their sd overstates the spread of a new specimen.  A second block
    gives the error (GT − E)/GT [%] with ``*`` when GT lies outside the 90 % interval for a new
    specimen; a third the paper's published robot estimates where the labels match.  A line
    states the prior of tau: the ``tau_prior_sd`` column of the Bayesian rows, else the
    ``tau_prior_sd`` argument.
    """
    if df.empty:
        return "(no rows)"
    mats = list(dict.fromkeys(df["material"]))
    tips = list(dict.fromkeys(df["tip"]))
    methods = [m for m in ("lsq", "bayes") if m in set(df["method"])]
    label = {"lsq": "LSQ", "bayes": "Bayes"}

    def cell(mat, tip, method, kind):
        r = df[(df["material"] == mat) & (df["tip"] == tip) & (df["method"] == method)]
        if r.empty:
            return "-"
        r = r.iloc[0]
        if kind == "E":
            return _interval(r["E_new_pa"], r["E_new_lo_pa"], r["E_new_hi_pa"]) \
                if method == "bayes" else _pm(r["E_pa"], r["E_sd_pa"])
        if kind == "layer":  # lsq only: the same fits read as a free and a bonded layer
            if not {"E_free_pa", "E_bonded_pa"} <= set(r.index) or not (
                    np.isfinite(r["E_free_pa"]) and np.isfinite(r["E_bonded_pa"])):
                return "-"
            return f"{r['E_bonded_pa'] / 1e3:.1f}-{r['E_free_pa'] / 1e3:.1f}"
        if kind == "err":
            if not np.isfinite(r["rel_err_pct"]):
                return "-"
            covered = r["gt_in_new_interval"]
            miss = "*" if covered is False or covered == 0 else " "
            return f"{r['rel_err_pct']:+.1f}{miss}"
        return _pm(r["paper_E_pa"], r["paper_sd_pa"]) if method == "lsq" else ""

    def block(kind, with_gt):
        cols = pd.MultiIndex.from_tuples(
            ([("GT", "Instron")] if with_gt else [])
            + [(t, label[m]) for t in tips for m in methods
               if kind not in ("paper", "layer") or m == "lsq"])
        body = []
        for mat in mats:
            line = []
            if with_gt:
                g = df[df["material"] == mat].iloc[0]
                line.append(_pm(g["gt_E_pa"], g["gt_sd_pa"]))
            line += [cell(mat, t, m, kind) for t in tips for m in methods
                     if kind not in ("paper", "layer") or m == "lsq"]
            body.append(line)
        return pd.DataFrame(body, index=pd.Index(mats, name="material"), columns=cols
                            ).to_string()

    out = ["E [kPa]: GT and LSQ mean ± sd (LSQ over traces: the paper's method, a half-space); "
           "Bayes posterior-predictive median [90 % interval] for a new specimen, pooled with "
           "the uncertainty budget (a layer wherever the thickness is known)", block("E", True)]
    prior = _tau_prior_line(df, tau_prior_sd)
    if prior:
        out.append(prior)
    if df["rel_err_pct"].notna().any():
        out += ["", "error (GT - E)/GT [%]; * = GT outside the 90 % interval for a new specimen",
                block("err", False)]
    if "lsq" in methods and "E_free_pa" in df and df["E_free_pa"].notna().any():
        out += ["", "LSQ read as a layer of the specimen's thickness [kPa]: bonded to free base "
                "(what the finite thickness changes in the paper's half-space estimate)",
                block("layer", False)]
    src = groundtruth_source or "none found (give --groundtruth)"
    out += ["", f"ground truth: {src}"]
    if df["paper_E_pa"].notna().any():
        out += ["", "paper's robot estimates (least squares) [kPa]", block("paper", False)]
    bad = df[~df["converged_all"].map(parse_bool)]
    for _, r in bad.iterrows():
        out.append(f"warning: {r['material']} {r['tip']} {r['method']}: not every fit converged"
                   + (f" ({r['notes']})" if isinstance(r.get("notes"), str) and r["notes"]
                      else ""))
    return "\n".join(out)
