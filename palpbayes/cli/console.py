"""What ``palpbayes fit`` prints under a run: the table, the parts of each interval, the
failed checks in one line each, and the Poisson ratio when it was assumed."""

from __future__ import annotations

from ..contact import DEFAULT_NU_NOTE
from ..flagcodes import split_flags
from ..units import format_pressure

__all__ = ["console_lines", "flag_headlines"]


def _interval_part_lines(summary) -> list[str]:
    """Under the table: what E_lo..E_hi of each Bayesian row is made of (90 %: statistical,
    + budget, + model form where a model check found a material misfit)."""
    from ..bayes.modelform import interval_parts  # here: the parser does not load it

    rows = summary[summary["method"] == "bayes"]
    if rows.empty or "E_budget_lo_pa" not in rows:
        return []
    lines = ["bayes E_lo..E_hi: 90 % interval, statistical + budget (+ model form: with a "
             "material misfit, the envelope of the alternatives' 90 % intervals); its parts "
             "(% of E):"]
    for _, r in rows.iterrows():
        parts = interval_parts(r["E_pa"], (r["E_stat_lo_pa"], r["E_stat_hi_pa"]),
                               (r["E_budget_lo_pa"], r["E_budget_hi_pa"]),
                               (r["E_lo_pa"], r["E_hi_pa"]))
        misfit = "" if r["model_ok"] else f"; material misfit: {r['misfit_checks']}"
        lines.append(f"  {r['trace_id']}: {parts}{misfit}")
    return lines


def _instron_lines(summary) -> list[str]:
    """Under the table, for Bayesian rows fitted with the specimen's twin: what a compression
    test of the block would read (``E_instron_pa`` and its 90 % interval)."""
    if "E_instron_pa" not in summary:
        return []
    rows = summary[(summary["method"] == "bayes") & summary["E_instron_pa"].notna()]
    if rows.empty:
        return []
    lines = ["E_instron: what a compression test of the block would read (the block's twin; "
             "set it beside your Instron, like for like):"]
    for _, r in rows.iterrows():
        lines.append(f"  {r['trace_id']}: {format_pressure(r['E_instron_pa'])} "
                     f"[{format_pressure(r['E_instron_lo_pa'])}, "
                     f"{format_pressure(r['E_instron_hi_pa'])}] ({r['platens']} platens; "
                     f"{r['layer']})")
    return lines


def flag_headlines(text: str, width: int = 110) -> list[str]:
    """The flags of a summary row (``notes``: messages joined by "; ") as one short line each:
    a message up to its first parenthesis or bracket (the explanation and the effect on E stay
    in summary.csv), at most ``width`` characters."""
    out = []
    for p in split_flags(text):
        cut = min((i for i in (p.find(" ("), p.find(" [")) if i > 0), default=len(p))
        head = p[:cut].rstrip(" :;,")
        if head:
            out.append(head if len(head) <= width else head[:width - 3].rstrip() + "...")
    return out


def _table(summary):
    """The run's table: E with its 90 % interval, the Hertz law's E for a sphere (the paper's
    choice, ``E_hertz_pa``), convergence (``n/a`` for a least-squares row: nothing is sampled)
    and the model check."""
    cols = ["trace_id", "method", "E_pa", "E_sd_pa", "E_lo_pa", "E_hi_pa", "E_hertz_pa",
            "converged", "model_ok"]
    show = summary[[c for c in cols if c in summary]].copy()
    if "E_hertz_pa" in show and show["E_hertz_pa"].isna().all():
        show = show.drop(columns="E_hertz_pa")
    for c in ("E_pa", "E_sd_pa", "E_lo_pa", "E_hi_pa", "E_hertz_pa"):
        if c in show:
            show[c.removesuffix("_pa")] = [format_pressure(v) if v == v else "n/a"
                                           for v in show.pop(c)]
    if "converged" in show:
        sampled = summary["method"] != "lsq"
        show["converged"] = [str(bool(c)) if s and c == c else "n/a"
                             for c, s in zip(show.pop("converged"), sampled, strict=True)]
        if "model_ok" in show:
            show["model_ok"] = show.pop("model_ok")
    return show


def _warned(summary):
    """Rows flagged with a warning outside the model checks and convergence: the force's
    scale against the declared sensor noise (``force_scale``)."""
    if "flag_codes" not in summary:
        return summary["method"] != summary["method"]
    codes = summary["flag_codes"].fillna("").astype(str).str.split(";")
    return codes.map(lambda c: "force_scale" in c)


def console_lines(summary) -> list[str]:
    """What ``fit`` prints under a run: the table (E with its 90 % interval, convergence and
    the model check), what each Bayesian interval is made of, one line per flag of a fit that
    failed a model check, did not converge or carries a warning on its input, and the Poisson
    ratio when it was assumed."""
    lines = [_table(summary).to_string(index=False),
             "E: the Bayesian posterior median or the least-squares estimate; E_sd its sd; "
             "E_lo..E_hi its 90 % interval"
             + ("; E_hertz: E with the Hertz (paraboloid) law, the paper's choice for a sphere"
                if "E_hertz_pa" in summary and summary["E_hertz_pa"].notna().any() else "")]
    lines += _interval_part_lines(summary)
    lines += _instron_lines(summary)
    not_converged = summary["converged"] == False  # noqa: E712
    misfit = summary.get("model_ok", True) == False  # noqa: E712
    bad = summary[not_converged | misfit | _warned(summary)]
    for i, r in bad.iterrows():
        what = ("did not converge" if not_converged[i] else "failed a model check"
                if misfit[i] else "carries a warning on its input")
        lines.append(f"{r['trace_id']} ({r['method']}): {what}; E may be biased by what the "
                     "model leaves out:" if what != "carries a warning on its input" else
                     f"{r['trace_id']} ({r['method']}): {what}; E may be off by the factor "
                     "it names:")
        notes = r.get("notes")
        lines += [f"  - {h}" for h in flag_headlines(notes if isinstance(notes, str) else "")]
    if len(bad):
        lines.append(f"warning: {len(bad)} fit(s) above failed a check; the full text and "
                     "the effect on E are in summary.csv (columns notes, flag_codes, "
                     "misfit_checks, misfit_effect)")
    if "nu_source" in summary and (summary["nu_source"] == "default").any():
        lines.append(f"note: {DEFAULT_NU_NOTE}")
    return lines
