"""What ``palpbayes fit`` prints under a run: the table, the parts of each interval, the
failed checks in one line each, and the Poisson ratio when it was assumed."""

from __future__ import annotations

from ..bayes.modelform import interval_parts
from ..contact import DEFAULT_NU_NOTE
from ..flagcodes import split_flags
from ..units import format_pressure

__all__ = ["console_lines", "flag_headlines"]


def _interval_part_lines(summary) -> list[str]:
    """Under the table: what E_lo..E_hi of each Bayesian row is made of (90 %: statistical,
    + budget, + model form where a model check found a material misfit)."""
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


def console_lines(summary) -> list[str]:
    """What ``fit`` prints under a run: the table (E with its 90 % interval, convergence and
    the model check), what each Bayesian interval is made of, one line per flag of a fit that
    failed a model check or did not converge, and the Poisson ratio when it was assumed."""
    cols = ["trace_id", "method", "E_pa", "E_sd_pa", "E_lo_pa", "E_hi_pa", "converged",
            "model_ok"]
    show = summary[[c for c in cols if c in summary]].copy()
    for c in ("E_pa", "E_sd_pa", "E_lo_pa", "E_hi_pa"):
        show[c.removesuffix("_pa")] = show.pop(c).map(format_pressure)
    lines = [show.to_string(index=False),
             "E: the Bayesian posterior median or the least-squares estimate; E_sd its sd; "
             "E_lo..E_hi its 90 % interval"]
    lines += _interval_part_lines(summary)
    lines += _instron_lines(summary)
    bad = summary[(summary["converged"] == False)  # noqa: E712
                  | (summary.get("model_ok", True) == False)]  # noqa: E712
    for _, r in bad.iterrows():
        what = ("did not converge" if not r["converged"] else "failed a model check")
        lines.append(f"{r['trace_id']} ({r['method']}): {what}; E may be biased by what the "
                     "model leaves out:")
        notes = r.get("notes")
        lines += [f"  - {h}" for h in flag_headlines(notes if isinstance(notes, str) else "")]
    if len(bad):
        lines.append(f"warning: {len(bad)} fit(s) above failed a check; the full text and "
                     "the effect on E are in summary.csv (columns notes, flag_codes, "
                     "misfit_checks, misfit_effect)")
    if "nu_source" in summary and (summary["nu_source"] == "default").any():
        lines.append(f"note: {DEFAULT_NU_NOTE}")
    return lines
