"""Viscoelastic pages: the table of every trace × relaxation model (``rheology.csv``) and, per
trace and model, force against time with the fit's band, E*(t) with its band, force against
depth per segment (the hysteresis) and the flags in words (``rheology/<trace>_<model>.nc``).

Every number is read from the results folder that ``palpbayes fit --rheology`` wrote: the
table's medians and intervals, the stored block means, force band and E*(t) band
(:func:`palpbayes.rheology.load_rheology_fit`); nothing is fitted or evaluated here.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from .. import __version__, plots
from ..errors import InputError
from ..intervals import LEVEL
from ..io.tabular import parse_bool
from ..rheology.fit import PARAMETERS
from ..rheology.results import UNIT_SUFFIXES
from ..rheology.store import StoredRheologyFit, load_rheology_fit
from ..units import FORCE_PREFIXES, LENGTH_PREFIXES, PRESSURE_PREFIXES, si_scale
from .format import isnum, shown_path, wrap, yesno
from .layout import PAGE_SIZE, Page, fit_text_lines, text_lines
from .pages_title import toc_lines
from .tables import continued, draw_table, page_chunks

__all__ = ["rheology_parameters", "TABLE_TITLE", "RHEOLOGY_LABELS", "rheology_pages",
           "rheology_title_page", "row_failed"]

#: Title of the table page(s).
TABLE_TITLE = "Viscoelastic fits (rheology.csv)"
#: Printed name of each relaxation model.
RHEOLOGY_LABELS = {"power-law": "power law", "sls": "SLS"}
#: Table column suffix -> unit (the inverse of :mod:`palpbayes.rheology.results`' naming).
_SUFFIX_UNIT = {suffix: unit for unit, suffix in UNIT_SUFFIXES.items()}
_PREFIXES = {"Pa": PRESSURE_PREFIXES, "N": FORCE_PREFIXES, "m": LENGTH_PREFIXES}
#: Parameters of the overview table: each model's own, a drag and the compression modulus.
_OVERVIEW = tuple(dict.fromkeys(
    [name + ("_star" if modulus else "") for params in PARAMETERS.values()
     for name, _, modulus in params] + ["drag", "E_compression"]))
_CHOICE = ("Model choice (PSIS-LOO): elpd_diff is a model's expected log predictive density "
           "minus the best's, ± its standard error; a difference within about 2 standard errors "
           "does not tell the models apart.")


def rheology_parameters(table: pd.DataFrame) -> list[tuple[str, str, str, str, str]]:
    """The parameters of a ``rheology.csv`` table, in column order: (name, unit, median column,
    lower column, upper column), for every column that has its ``_lo``/``_hi`` pair
    (``E0_star_pa``, ``alpha``, ``z_surf_m``, ``E_compression_pa`` ...)."""
    cols, out = set(table.columns), []
    suffixes = sorted(_SUFFIX_UNIT, key=len, reverse=True)  # '' last: 'alpha'
    for c in table.columns:
        for suffix in suffixes:
            if suffix and not c.endswith("_" + suffix):
                continue
            name = c[:-len(suffix) - 1] if suffix else c
            lo, hi = ((f"{name}_lo_{suffix}", f"{name}_hi_{suffix}") if suffix
                      else (f"{name}_lo", f"{name}_hi"))
            if lo in cols and hi in cols:
                out.append((name, _SUFFIX_UNIT[suffix], c, lo, hi))
                break
    return out


def _label(name: str) -> str:
    return name.replace("_star", "*")


def _scale(values, unit: str) -> tuple[float, str]:
    prefixes = _PREFIXES.get(unit)
    v = pd.to_numeric(pd.Series(values), errors="coerce").abs()
    if prefixes is None or not v.notna().any():
        return 1.0, "" if unit == "-" else unit
    return si_scale(float(v.max()), unit, prefixes)


def _cell(row, med: str, lo: str, hi: str, k: float) -> str:
    if not isnum(row.get(med)):
        return "–"
    m = f"{float(row[med]) * k:.4g}"
    if isnum(row.get(lo)) and isnum(row.get(hi)):
        return f"{m} [{float(row[lo]) * k:.4g}, {float(row[hi]) * k:.4g}]"
    return m


def row_failed(row) -> bool:
    return bool(str(row.get("error", "") or "").strip())


def _overview(table: pd.DataFrame) -> pd.DataFrame:
    """The table page's rows: trace, model, each model parameter with its 90 % interval, the
    model check, flag codes and, with several models, the PSIS-LOO columns."""
    params = [p for p in rheology_parameters(table) if p[0] in _OVERVIEW]
    scales = {p[0]: _scale(table[p[2]], p[1]) for p in params}
    choice = "elpd_diff" in table and table["elpd_diff"].notna().any()
    rows = []
    for _, r in table.iterrows():
        row = {"Trace": r["trace_id"],
               "Model": RHEOLOGY_LABELS.get(r["rheology"], r["rheology"])}
        for name, _, med, lo, hi in params:
            k, unit = scales[name]
            row[f"{_label(name)} [{unit}]" if unit else _label(name)] = _cell(r, med, lo, hi, k)
        row["Model check"] = "–" if row_failed(r) else ("passed" if parse_bool(r.get("model_ok"))
                                                       else "FAILED")
        row["Flags"] = "not fitted" if row_failed(r) else (r.get("flag_codes") or "none")
        if choice:
            d, se = r.get("elpd_diff"), r.get("elpd_diff_se")
            row["elpd_diff ± se"] = (f"{float(d):.1f} ± {float(se):.1f}" if isnum(d)
                                     and isnum(se) else "–")
            row["Preferred"] = yesno(r.get("preferred")) if isnum(d) else "–"
        rows.append(row)
    return pd.DataFrame(rows)


def _pages_table(table: pd.DataFrame) -> list[Page]:
    show = _overview(table)
    intro = ("Posterior medians [central 90 % intervals] of each viscoelastic fit; moduli are "
             "reduced moduli E* = E/(1 − nu²). Model check: the posterior-predictive check of "
             "the residuals binned in time passed and the noise correlation phi is not at its "
             "bound. Flags: short codes; in words on each trace's page (and in rheology.csv's "
             "notes).")
    lines = [("t", ln) for ln in wrap(intro, 160)]
    if "elpd_diff ± se" in show:
        lines += [("t", ln) for ln in wrap(_CHOICE, 160)]
    failed = [(r["trace_id"], r["rheology"], str(r["error"])) for _, r in table.iterrows()
              if row_failed(r)]
    notes = [("t", ln) for tid, m, err in failed
             for ln in wrap(f"{tid} ({m}) not fitted: {err}", 160)]
    pages = []
    parts = page_chunks(len(show))
    for k, part in enumerate(parts):
        def build(fig: Figure, part: slice = part, k: int = k) -> None:
            text_lines(fig, lines, top=0.91, left=0.04, size=8.5)
            sub = show.iloc[part].reset_index(drop=True)
            top = 0.91 - len(lines) * 8.5 * 1.45 / 72 / PAGE_SIZE[1] - 0.03
            ax = fig.add_axes((0.03, 0.2, 0.94, top - 0.2))
            draw_table(ax, sub, fontsize=7, row_height=min(0.06, 1.0 / (len(sub) + 2)),
                        wrap_header=18)
            if notes and k == len(parts) - 1:
                text_lines(fig, notes[:8], top=0.17, left=0.04, size=8)
        pages.append(Page(continued(TABLE_TITLE, k, len(parts)), build,
                           rows=part.stop - part.start))
    return pages


def _fit_table(row: pd.Series) -> pd.DataFrame:
    """One fit's parameters from its table row: the model's (each modulus E* with its E), a
    drag, then the others (surface, offset, noise), the compression modulus last."""
    params = [p for p in rheology_parameters(row.to_frame().T) if isnum(row.get(p[2]))]
    order = [n for o in _OVERVIEW for n in (o, o.removesuffix("_star"))]

    def rank(p) -> tuple[int, int]:
        if p[0] == "E_compression":
            return (2, 0)
        return (0, order.index(p[0])) if p[0] in order else (1, 0)

    out = []
    for name, unit, med, lo, hi in sorted(params, key=rank):
        k, shown = _scale([row[med]], unit)
        out.append({"parameter": _label(name), "unit": shown or "-",
                    "median [90 % interval]": _cell(row, med, lo, hi, k)})
    return pd.DataFrame(out)


def _fit_lines(row, fit: StoredRheologyFit, rows: pd.DataFrame) -> list[tuple[str, str]]:
    nu = "" if fit.nu is None else f"; nu = {fit.nu:g} (E = E*·(1 − nu²))"
    lines = [("t", f"Tip: {fit.tip or '?'}; fitted segments: {', '.join(fit.data.segments)}; "
                   f"t0 = {fit.t0:g} s{nu}"),
             ("t", f"Model check: {'passed' if fit.model_ok else 'FAILED'}")]
    if len(rows) > 1 and "elpd_diff" in rows and isnum(row.get("elpd_diff")):
        best = rows[rows["preferred"].map(parse_bool)] if "preferred" in rows else rows[:0]
        pref = best["rheology"].iloc[0] if len(best) else "?"
        lines.append(("t", f"PSIS-LOO prefers {RHEOLOGY_LABELS.get(pref, pref)}; this model's "
                           f"elpd_diff = {float(row['elpd_diff']):.1f} ± "
                           f"{float(row.get('elpd_diff_se', np.nan)):.1f}"))
    flags = list(fit.flags)
    lines.append(("h", "Flags" if flags else "Flags: none"))
    for f in flags:
        wrapped = wrap(f, 92)
        lines += [("t", ("• " if i == 0 else "   ") + ln) for i, ln in enumerate(wrapped)]
    return lines


def _page_fit(results: Path, row, rows: pd.DataFrame) -> Page:
    """One trace and model: force against time with the band, E*(t) of every model of the
    trace, the hysteresis, the parameters and the flags in words."""
    from ..outputs import rheology_fit_path

    tid, model = str(row["trace_id"]), str(row["rheology"])
    label = RHEOLOGY_LABELS.get(model, model)

    def build(fig: Figure) -> None:
        try:
            fit = load_rheology_fit(rheology_fit_path(results, tid, model))
            others = {RHEOLOGY_LABELS.get(m, m): load_rheology_fit(rheology_fit_path(
                results, tid, m)) for m in rows["rheology"] if m != model
                and not row_failed(rows[rows["rheology"] == m].iloc[0])}
        except InputError as exc:
            text_lines(fig, [("t", ln) for ln in wrap(str(exc), 150)], top=0.85)
            return
        plots.plot_cycle_fit(fit, fig.add_axes((0.07, 0.53, 0.55, 0.36)),
                             title=f"Force against time: block means, fit and its "
                                   f"{100 * fit.level:g} % band")
        plots.plot_relaxation({label: fit, **others}, fig.add_axes((0.71, 0.53, 0.26, 0.36)),
                              level=fit.level, title="Relaxation modulus E*(t)")
        plots.plot_hysteresis(fit, fig.add_axes((0.07, 0.1, 0.36, 0.33)),
                              title="Force against depth per segment (hysteresis)")
        tab = _fit_table(row)
        height = min(0.022 * (len(tab) + 1), 0.22)
        draw_table(fig.add_axes((0.5, 0.43 - height, 0.47, height)), tab, fontsize=7.5,
                    row_height=1.0 / (len(tab) + 1))
        lines = _fit_lines(row, fit, rows)
        room = int((0.41 - height - 0.07) * PAGE_SIZE[1] * 72 / (8 * 1.45))
        if len(lines) > room:
            lines = [*lines[:room - 1], ("t", "… (every flag in rheology.csv's notes)")]
        text_lines(fig, lines, top=0.41 - height, left=0.5, size=8)
    return Page(f"Viscoelastic fit: {tid} · {label}", build)


def rheology_pages(results: str | os.PathLike, table: pd.DataFrame | None) -> list[Page]:
    """The table page(s), then a page per fitted trace and model (none without a table)."""
    if table is None or table.empty:
        return []
    pages = _pages_table(table)
    for _, rows in table.groupby("trace_id", sort=False):
        for _, row in rows.iterrows():
            if not row_failed(row):
                pages.append(_page_fit(Path(results), row, rows))
    return pages


def rheology_title_page(results: str | os.PathLike, table: pd.DataFrame, created: str,
                         contents: list[str]) -> Page:
    """Title page of a results folder with viscoelastic fits only."""
    path = Path(results)

    def build(fig: Figure) -> None:
        fig.text(0.5, 0.78, "palpbayes report", ha="center", fontsize=30, fontweight="bold")
        fig.text(0.5, 0.71, f"Viscoelastic fits: {path.resolve().name}", ha="center",
                 fontsize=18)
        fig.text(0.5, 0.66, "Relaxation modulus from palpation: power law and standard linear "
                 "solid, with 90 % intervals", ha="center", fontsize=11, color="0.3")
        fig.text(0.5, 0.62, f"Built from the results folder {shown_path(path)}", ha="center",
                 fontsize=11, fontweight="bold", color="0.2")
        models = ", ".join(RHEOLOGY_LABELS.get(m, m) for m in dict.fromkeys(table["rheology"]))
        ok = table[~table.apply(row_failed, axis=1)]
        segs = ", ".join(sorted({s for s in ok.get("segments", pd.Series(dtype=str)) if s}))
        info = [("t", f"Date: {created}"), ("t", f"palpbayes version: {__version__}"),
                ("t", f"Results folder: {shown_path(path)}"),
                ("t", f"{table['trace_id'].nunique()} trace(s); models: {models}"),
                ("t", f"{len(ok)} fits, {len(table) - len(ok)} not fitted; model check "
                      f"passed: {int(ok['model_ok'].map(parse_bool).sum())} of {len(ok)}"),
                ("t", f"Fitted segments: {segs.replace(',', ', ') or '–'}; bands: central "
                      f"{100 * LEVEL:g} %")]
        fit_text_lines(fig, info, top=0.56, bottom=0.06, left=0.06, width=0.58, size=10)
        size = 8.5
        fits = int((0.56 - 0.06) * PAGE_SIZE[1] * 72 / (size * 1.45)) - 2
        text_lines(fig, [("h", "Contents"), *toc_lines(contents, fits)], top=0.56,
                    left=0.66, size=size)
    return Page("", build)
