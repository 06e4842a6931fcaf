""""How much indentation did we need?": each recorded trace replayed through the online
estimator with a precision target (``indentation.csv``, written by ``palpbayes compare``:
:mod:`palpbayes.campaign.indentation`), per material × tip."""

from __future__ import annotations

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from ..campaign.indentation import REPLAY_CHUNK, REPLAY_TARGET, online_noise
from ..campaign.results import ResultsFolder
from ..units import format_force, format_length
from .format import wrap
from .layout import Page, text_lines
from .tables import continued, draw_table, page_chunks

__all__ = ["online_pages"]


def _group_table(study: pd.DataFrame) -> pd.DataFrame:
    rows = []
    for (mat, tip), g in study.groupby(["material", "tip"], sort=False):
        ok = g[g["stopped"].astype(bool)]
        frac_d = ok["depth_stop_m"] / ok["depth_full_m"]
        frac_f = ok["peak_force_stop_n"] / ok["peak_force_full_n"]
        rows.append({
            "Material": mat, "Tip": tip, "Traces": len(g), "Stopped": len(ok),
            "Depth at stop": format_length(float(np.median(ok["depth_stop_m"])))
            if len(ok) else "–",
            "Depth, % of recorded": f"{100 * float(np.median(frac_d)):.0f} %" if len(ok) else "–",
            "Peak force at stop": format_force(float(np.median(ok["peak_force_stop_n"])))
            if len(ok) else "–",
            "Force, % of recorded": f"{100 * float(np.median(frac_f)):.0f} %" if len(ok) else "–",
        })
    return pd.DataFrame(rows)


def online_pages(res: ResultsFolder) -> list[Page]:
    """The table of ``indentation.csv`` per material × tip (split over pages like the other
    tables), or no page at all when the compare step wrote none."""
    study = res.indentation
    if study is None or study.empty:
        return []
    table = _group_table(study)
    n_stop = int(study["stopped"].sum())
    text = (f"Each recorded trace replayed as if live (palpbayes.online, chunks of "
            f"{REPLAY_CHUNK} samples), stopped when the 90 % interval of E is within "
            f"±{100 * REPLAY_TARGET:g} % (statistical, exact posterior, "
            f"{online_noise(res.options)} noise): {n_stop} of {len(study)} "
            "traces reached it. Medians per "
            "material and tip: the depth below the estimated surface and the peak force above "
            "the baseline at the stop, and their fractions of the recorded indentation. "
            "One trace: palpbayes replay TRACE --tip ... --target 2% --out DIR.")
    intro = [("t", line) for line in wrap(text, 150)]
    pages = []
    parts = page_chunks(len(table))
    for k, part in enumerate(parts):
        def build(fig: Figure, part=part) -> None:
            text_lines(fig, intro, top=0.9, left=0.05, size=9.0)
            ax = fig.add_axes((0.05, 0.08, 0.9, 0.7))
            draw_table(ax, table.iloc[part].reset_index(drop=True))
        pages.append(Page(continued("How much indentation did we need?", k, len(parts)),
                           build, rows=part.stop - part.start))
    return pages
