"""Reference values a campaign is compared with: the Instron ground truth and the paper.

* :func:`load_groundtruth` finds and reads the per-material ground truth (a
  ``groundtruth_summary.csv`` of ``palpbayes groundtruth``, or compression exports analysed with
  :func:`palpbayes.compression.analyse`);
* :func:`paper_estimates` gives the paper's published robot estimates
  (:data:`palpbayes.paper.PAPER_ROBOT_ESTIMATES`) with the error recomputed from the printed
  E and the paper's Instron means;
* :func:`gt_columns` / :func:`paper_columns` fill the reference columns of one comparison row
  (definitions in :mod:`palpbayes.campaign.comparison`).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pandas as pd

from .. import outputs
from ..errors import DataFileError
from ..intervals import LEVEL, normal_z

__all__ = ["load_groundtruth", "paper_estimates", "gt_columns", "paper_columns",
           "new_specimen_sd"]


def paper_estimates() -> pd.DataFrame:
    """The paper's robot estimates: ``material, tip, paper_E_pa, paper_sd_pa, paper_err_pct``."""
    from ..paper import PAPER_MATERIALS, PAPER_ROBOT_ESTIMATES

    rows = []
    for r in PAPER_ROBOT_ESTIMATES:
        gt = PAPER_MATERIALS[r.material].E_pa
        E = r.E_kPa * 1e3
        rows.append({"material": r.material, "tip": r.tip, "paper_E_pa": E,
                     "paper_sd_pa": r.sd_kPa * 1e3, "paper_err_pct": 100 * (gt - E) / gt})
    return pd.DataFrame(rows)


def _gt_from_file(p: Path) -> pd.DataFrame:
    from ..compression import analyse, summarise

    try:
        cols = {str(c).strip() for c in pd.read_csv(p, nrows=0).columns}
    except (pd.errors.EmptyDataError, pd.errors.ParserError, UnicodeDecodeError) as exc:
        raise DataFileError(p, f"cannot be read as CSV ({exc})") from None
    if {"material", "E_mean_pa"} <= cols:  # groundtruth_summary.csv
        df = pd.read_csv(p, dtype={"material": str})
        df.columns = [str(c).strip() for c in df.columns]
        if "E_sd_pa" not in df.columns:
            raise DataFileError(p, "ground-truth summary lacks column E_sd_pa")
        return df
    if {"material", "E_pa", "file"} <= cols:  # groundtruth.csv, one row per test
        df = pd.read_csv(p, dtype={"material": str})
        return summarise(df)
    return analyse([p])[1]


def load_groundtruth(spec: str | os.PathLike | None, campaign_dir: Path | None
                     ) -> tuple[pd.DataFrame | None, str | None]:
    """Per-material ground truth (``material, E_mean_pa, E_sd_pa`` …) and where it came from.

    ``spec``: a ``groundtruth_summary.csv`` or ``groundtruth.csv`` written by ``palpbayes
    groundtruth``, a ground-truth manifest, a compression export, or a folder of them (analysed
    with :func:`palpbayes.compression.analyse` and its default strain window).  None: the
    ``groundtruth/`` folder of the campaign, if any.  Returns (None, None) when there is none.
    """
    from ..compression import analyse

    if spec is not None:
        p = Path(spec)
        if p.is_dir():
            if (p / outputs.GROUNDTRUTH_SUMMARY).is_file():
                return _gt_from_file(p / outputs.GROUNDTRUTH_SUMMARY), str(
                    p / outputs.GROUNDTRUTH_SUMMARY)
            return analyse([p])[1], f"{p} (analysed)"
        if not p.is_file():
            raise DataFileError(p, "ground truth not found", "give a groundtruth_summary.csv, "
                                "a ground-truth manifest or a folder of compression exports")
        return _gt_from_file(p), str(p)
    if campaign_dir is not None and (campaign_dir / "groundtruth").is_dir():
        folder = campaign_dir / "groundtruth"
        return analyse([folder])[1], f"{folder} (analysed)"
    return None, None


def new_specimen_sd(lo: float, hi: float, level: float = LEVEL) -> float:
    """Normal-equivalent sd of a central ``level`` interval [lo, hi]: (hi - lo)/(2·z).

    z = Phi^-1((1 + level)/2) (1.645 at 90 %).  NaN unless lo and hi are finite.
    """
    if lo is None or hi is None or not (np.isfinite(lo) and np.isfinite(hi)):
        return np.nan
    return float((hi - lo) / (2.0 * normal_z(level)))


def gt_columns(row: dict, gt: pd.DataFrame | None, material: str, level: float = LEVEL
               ) -> dict:
    """The ground-truth columns of one comparison row (definitions in
    :mod:`palpbayes.campaign.comparison`).

    ``row`` needs ``method``, ``E_pa`` and the method's central ``level`` interval for a new
    specimen, ``E_new_lo_pa`` / ``E_new_hi_pa``.  Both methods are treated alike:

    * ``gt_in_new_interval``: E_new_lo <= GT mean <= E_new_hi (the new-specimen interval);
    * ``gt_in_E_interval``: E_lo <= GT mean <= E_hi (the row's own interval: the material's
      median for Bayes, the mean of the traces for least squares);
    * ``gt_z_new`` = (E - GT mean)/sqrt(sd_new² + GT sd²) with sd_new = (E_new_hi - E_new_lo)/
      (2·1.645) (:func:`new_specimen_sd`), the normal-equivalent sd of the new-specimen
      interval -- not the sd over traces (least squares) or the sd of the posterior-predictive
      draws (Bayes, inflated by the heavy right tail of tau).  A missing GT sd counts as 0.

    Returns {} when there is no ground truth for ``material`` (matched exactly, else ignoring
    case); only the GT columns when E is not finite.
    """
    if gt is None or gt.empty:
        return {}
    hit = gt[gt["material"].astype(str) == material]
    if hit.empty:
        hit = gt[gt["material"].astype(str).str.lower() == material.lower()]
    if hit.empty:
        return {}
    g_mean = float(hit["E_mean_pa"].iloc[0])
    g_sd = float(hit["E_sd_pa"].iloc[0]) if pd.notna(hit["E_sd_pa"].iloc[0]) else 0.0
    out = {"gt_E_pa": g_mean, "gt_sd_pa": g_sd,
           "gt_n": int(hit["n"].iloc[0]) if "n" in hit else np.nan}
    E = row.get("E_pa", np.nan)
    if not np.isfinite(E):
        return out
    lo, hi = _float_or_nan(row, "E_new_lo_pa"), _float_or_nan(row, "E_new_hi_pa")
    e_lo, e_hi = _float_or_nan(row, "E_lo_pa"), _float_or_nan(row, "E_hi_pa")
    spread = new_specimen_sd(lo, hi, level)
    out.update({
        "rel_err_pct": 100.0 * (g_mean - E) / g_mean,
        "gt_in_new_interval": _inside(g_mean, lo, hi),
        "gt_in_E_interval": _inside(g_mean, e_lo, e_hi),
        "gt_z_new": (E - g_mean) / np.sqrt(spread**2 + g_sd**2)
        if np.isfinite(spread) and spread**2 + g_sd**2 > 0 else np.nan,
    })
    return out


def _float_or_nan(row: dict, key: str) -> float:
    v = row.get(key, np.nan)
    return np.nan if v is None else float(v)


def _inside(x: float, lo: float, hi: float) -> bool | float:
    """lo <= x <= hi, or NaN when the interval is not finite (no verdict)."""
    return bool(lo <= x <= hi) if np.isfinite(lo) and np.isfinite(hi) else np.nan


def paper_columns(paper: pd.DataFrame, material: str, tip: str) -> dict:
    hit = paper[(paper["material"].str.lower() == str(material).lower())
                & (paper["tip"] == tip)]
    if hit.empty:
        return {}
    return {k: float(hit[k].iloc[0]) for k in ("paper_E_pa", "paper_sd_pa", "paper_err_pct")}
