"""The title page: campaign, date, version, results folder, settings and contents."""

from __future__ import annotations

import textwrap
from collections.abc import Sequence

from matplotlib.figure import Figure

from .. import __version__
from ..campaign.results import ResultsFolder
from ..contact import DEFAULT_NU
from ..sensor_noise import PAPER_NOISE_PP
from ..units import format_length
from .format import fmt, fmt_range, force_setting, shown_path
from .layout import PAGE_SIZE, Page, fit_text_lines, text_lines
from .methods import MOVES_TEXT, layer_setting_text, sampler_settings


def _settings_lines(res: ResultsFolder) -> list[tuple[str, str]]:
    """The fit settings of ``settings.json`` as lines of text."""
    o = res.options
    s = res.settings
    pri = o.get("priors") or {}
    bud = o.get("budget") or {}
    smp, _ = sampler_settings(o.get("settings"))
    thick = layer_setting_text(o)
    frac = o.get("fit_fraction")
    if frac is None:
        from ..contact import default_fit_fraction_text

        frac = f"paper default ({default_fit_fraction_text()})"
    else:
        frac = f"{frac:g}"
    depth = o.get("max_depth")
    depth = "none" if depth is None else format_length(float(depth), 6)
    nu_b = bud.get("nu_range") or f"nu ± {bud.get('nu_half_width')}"
    n_tr = s.get("n_traces", res.summary["trace_id"].nunique())
    return [
        ("t", f"Methods fitted: {s.get('method', '?')};  base seed: {s.get('seed', '?')};  "
              f"traces: {n_tr}"),
        ("t", "Contact model: Poisson ratio nu = " + (
            f"{o['nu']}" if o.get("nu") is not None
            else f"{DEFAULT_NU} (not given: the default, a foam value)") + f"; {thick}"),
        ("t", f"Fit window: F_unc = {force_setting(o.get('f_unc', PAPER_NOISE_PP))}; fit "
              f"fraction {frac}; max depth {depth}"),
        ("t", f"Noise model: {o.get('noise', 'gaussian')}; baseline "
              f"{o.get('baseline', 'constant')}{'; tared' if o.get('tare') else ''}; sensor "
              f"noise {force_setting(pri.get('noise_pp', PAPER_NOISE_PP))} peak-to-peak (sigma "
              "prior centred on pp/6)"),
        ("t", f"Budget: Poisson ratio {nu_b}; tip radius "
              f"±{fmt(100 * float(bud.get('radius_tolerance', 0)), 1)} %; force gain sd "
              f"{fmt(100 * float(bud.get('gain_sd', 0)), 1)} %; compliance "
              f"0–{bud.get('compliance_max')} m/N"),
        ("t", f"Sampler: emcee, {smp.get('n_walkers')} walkers, moves '{smp.get('moves')}' "
              f"({MOVES_TEXT.get(str(smp.get('moves')), 'see emcee')}), "
              f"{fmt_range(smp.get('min_steps'), smp.get('max_steps'))} steps, chain longer than "
              f"{float(smp.get('tau_factor')):g}·tau, R-hat and ESS checked before stopping "
              "(the stopping rule in full on the Methods page)"),
    ]


def title_page(res: ResultsFolder, created: str, contents: list[str]) -> Page:
    def build(fig: Figure) -> None:
        fig.text(0.5, 0.78, "palpbayes report", ha="center", fontsize=30, fontweight="bold")
        fig.text(0.5, 0.71, f"Campaign: {res.name}", ha="center", fontsize=18)
        fig.text(0.5, 0.66, "Elastic modulus from robotic palpation: least squares vs Bayes, "
                 "compared with compression ground truth", ha="center", fontsize=11,
                 color="0.3")
        fig.text(0.5, 0.62, f"Built from the results folder {shown_path(res.path)}", ha="center",
                 fontsize=11, fontweight="bold", color="0.2")
        s = res.settings
        n_tr = res.summary["trace_id"].nunique()
        groups = res.groups()
        info = [
            ("t", f"Date: {created}"),
            ("t", f"palpbayes version: {__version__} (results written by "
                  f"{s.get('palpbayes_version', '?')})"),
            ("t", f"Results folder: {shown_path(res.path)}"),
            ("t", "Campaign source: " + (shown_path(s["source"]) if s.get("source")
                                         else "(traces given in code)")),
            ("t", f"{n_tr} traces, {len(groups)} material × tip groups; ground truth: "
                  f"{'yes' if _has_gt(res) else 'none'}"),
            ("", ""),
            ("h", "Settings"),
            *_settings_lines(res),
        ]
        fit_text_lines(fig, info, top=0.56, bottom=0.06, left=0.06, width=0.58, size=10)
        size = 8.5
        fits = int((0.56 - 0.06) * PAGE_SIZE[1] * 72 / (size * 1.45)) - 2
        toc = [("h", "Contents")] + toc_lines(contents, fits)
        text_lines(fig, toc, top=0.56, left=0.66, size=size)
    return Page("", build)


def toc_lines(contents: Sequence[str], max_lines: int) -> list[tuple[str, str]]:
    """Contents lines: page number and title (wrapped, never cut), the title page left out.

    When they do not fit in ``max_lines``, each run of material × tip pages is given as one
    line ('7–33  27 material × tip pages: A · flat … B · cone'); if that is still too long, the
    list is cut with a line giving the number of pages.
    """
    def entries(collapse: bool) -> list[tuple[str, str]]:
        items: list[tuple[str, str]] = []
        i = 1
        while i < len(contents):
            t = contents[i]
            j = i
            if collapse and " · " in t and ":" not in t:
                while j + 1 < len(contents) and " · " in contents[j + 1] \
                        and ":" not in contents[j + 1]:
                    j += 1
            if j > i:
                items.append((f"{i + 1}–{j + 1}", f"{j - i + 1} material × tip pages: {t} … "
                                                  f"{contents[j]}"))
            else:
                items.append((str(i + 1), t))
            i = j + 1
        out: list[tuple[str, str]] = []
        for num, t in items:
            for k, ln in enumerate(textwrap.wrap(t, 50, break_on_hyphens=False) or [""]):
                out.append(("t", f"{num:>5}   {ln}" if k == 0 else f"{'':>5}   {ln}"))
        return out

    lines = entries(False)
    if len(lines) > max_lines:
        lines = entries(True)
    if len(lines) > max_lines:
        lines = [*lines[:max_lines - 1], ("t", f"{'':>5}   … {len(contents)} pages in all")]
    return lines


def _has_gt(res: ResultsFolder) -> bool:
    c = res.comparison
    return bool(c is not None and "gt_E_pa" in c and c["gt_E_pa"].notna().any())
