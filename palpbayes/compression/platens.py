"""A compression test corrected for its platens: Young's modulus from what the Instron read.

A compression test reads E_app = (F/A)/(delta/H).  Between lubricated (frictionless) platens
that is E; between bonded ones (no slip: a foam or a gel on dry steel) the faces cannot expand
sideways and E_app = c·E, c(nu, block) > 1 (the block's finite-element twin,
:func:`palpbayes.twin.platen_factor`: +1 % at nu 0.1, +11-17 % at nu 0.3, +34-60 % at nu
0.45 for 50 × 50 mm blocks 30 and 20 mm high).  Given the platens and nu,
:func:`correct_for_platens` divides each test's E by its c, computed for the test's own block:
its cross-section and height (from the export's header, a ground-truth manifest or the
command line), as the cylinder of equal area (the twin's axisymmetric model).
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from ..contact import check_nu
from ..errors import InputError
from ..twin import platen_factor

__all__ = ["correct_for_platens", "CORRECTED_COLUMNS", "CORRECTED_SUMMARY_COLUMNS",
           "summarise_corrected"]

#: Per-file columns :func:`correct_for_platens` adds.
CORRECTED_COLUMNS = ["platens", "nu", "platen_factor", "E_corrected_pa", "E_corrected_sd_pa"]
#: Per-material columns :func:`summarise_corrected` adds to the summary.
CORRECTED_SUMMARY_COLUMNS = ["platens", "nu", "E_corrected_mean_pa", "E_corrected_sd_pa"]


def correct_for_platens(per_file: pd.DataFrame, platens: str, nu: float) -> pd.DataFrame:
    """``per_file`` (with ``area_m2`` and ``height_m``) with E corrected for ``platens``
    (``"lubricated"``: c = 1, or ``"bonded"``) at Poisson ratio ``nu``: the columns of
    :data:`CORRECTED_COLUMNS` added, ``E_pa`` (what the test read) kept.

    Raises
    ------
    InputError
        Unknown platens, a bad nu, or a test without its cross-section and height.
    """
    if platens not in ("lubricated", "bonded"):
        raise InputError(f"platens {platens!r}: use 'lubricated' or 'bonded'")
    nu = check_nu(nu)
    out = per_file.copy()
    factors = []
    for _, row in out.iterrows():
        area, height = float(row.get("area_m2", math.nan)), float(row.get("height_m", math.nan))
        if not (math.isfinite(area) and math.isfinite(height) and area > 0 and height > 0):
            raise InputError(f"{row.get('file', 'a test')}: the platen correction needs the "
                             "block's cross-section and height (the export's header, a "
                             "ground-truth manifest, or --area-m2 and --height-m)")
        factors.append(platen_factor(math.sqrt(area / math.pi) / height, nu, platens))
    c = np.array(factors)
    out["platens"] = platens
    out["nu"] = nu
    out["platen_factor"] = c
    out["E_corrected_pa"] = out["E_pa"].to_numpy(float) / c
    out["E_corrected_sd_pa"] = out["E_sd_pa"].to_numpy(float) / c
    return out


def summarise_corrected(per_file: pd.DataFrame, summary: pd.DataFrame) -> pd.DataFrame:
    """``summary`` with the corrected per-material mean and sd (:data:`
    CORRECTED_SUMMARY_COLUMNS`) of a ``per_file`` table from :func:`correct_for_platens`."""
    g = per_file.groupby("material", sort=False)
    extra = pd.DataFrame({
        "material": g.size().index.astype(str),
        "platens": g["platens"].first().to_numpy(),
        "nu": g["nu"].first().to_numpy(),
        "E_corrected_mean_pa": g["E_corrected_pa"].mean().to_numpy(),
        "E_corrected_sd_pa": g["E_corrected_pa"].std(ddof=1).to_numpy(),
    })
    return summary.merge(extra, on="material", how="left")
