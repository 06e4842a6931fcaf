""""How much indentation did we need?": each recorded trace replayed through the online
estimator (:mod:`palpbayes.online`) with a precision target, per material × tip."""

from __future__ import annotations

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from ..campaign.fitjob import FitOptions, trace_model
from ..campaign.results import ResultsFolder
from ..errors import PalpbayesError
from ..io.manifest import load_trace
from ..online import StoppingRule, needed_indentation
from ..units import format_force, format_length
from .format import wrap
from .layout import Page, text_lines
from .tables import continued, draw_table, page_chunks

__all__ = ["REPLAY_TARGET", "indentation_study", "online_noise", "online_pages"]

#: Relative half-width of the 90 % interval of E at which the replay stops (±2 %).
REPLAY_TARGET = 0.02


def indentation_study(res: ResultsFolder, target: float = REPLAY_TARGET) -> pd.DataFrame:
    """Per trace with a readable file: where a ±``target`` rule would have stopped
    (:func:`palpbayes.online.needed_indentation`), with its material and tip; empty when no
    trace file can be read (a results folder moved without its traces)."""
    if res.traces is None or "file" not in res.traces:
        return pd.DataFrame()
    opts = res.options
    traces, models, meta = [], [], []
    for _, row in res.traces.iterrows():
        try:  # the model the fit used (tip, the row's or the run's nu, layer)
            trace = load_trace(row, **res.settings.get("read_options", {}))
            model = trace_model(trace, FitOptions(
                nu=opts.get("nu"), layer=opts.get("layer", "off"),
                bonding=opts.get("bonding", "unknown")), depth=np.nan)
            if not model.is_concrete:  # the online estimator takes one shape function
                model = (model.variant(base="bonded") if model.thickness is not None
                         else model.half_space())
        except (PalpbayesError, OSError):
            continue
        traces.append(trace)
        models.append(model)
        meta.append({"material": str(row.get("material", "")), "tip": trace.tip.kind})
    if not traces:
        return pd.DataFrame()
    study = needed_indentation(traces, models, StoppingRule(target=target),
                               noise=online_noise(opts))
    return pd.concat([pd.DataFrame(meta), study], axis=1)


def online_noise(options: dict) -> str:
    """The campaign's noise model when the online estimator has it (gaussian, ar1), else
    gaussian (Student-t noise is emcee's alone)."""
    noise = str(options.get("noise", "gaussian"))
    return noise if noise in ("gaussian", "ar1") else "gaussian"


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


def online_pages(res: ResultsFolder, target: float = REPLAY_TARGET) -> list[Page]:
    """The study's table (split over pages like the other tables), or no page at all."""
    study = indentation_study(res, target)
    if study.empty:
        return []
    table = _group_table(study)
    n_stop = int(study["stopped"].sum())
    text = (f"Each recorded trace replayed as if live (palpbayes.online, chunks of 100 samples), "
            f"stopped when the 90 % interval of E is within ±{100 * target:g} % (statistical, "
            f"exact posterior, {online_noise(res.options)} noise): {n_stop} of {len(study)} "
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
