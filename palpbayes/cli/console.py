"""What ``palpbayes fit`` prints under a run: the table, the parts of each interval, E read
with the other layer models, the failed checks in one line each, and the Poisson ratio when it
was assumed.

Every line fits in :data:`WIDTH` characters (a terminal's 100): a long trace id is shortened in
its middle (the whole id is in ``summary.csv``, which holds every column of a row) and the
sentences are wrapped.
"""

from __future__ import annotations

import math
import re
import textwrap

from ..contact import DEFAULT_NU_NOTE
from ..flagcodes import split_flags
from ..units import format_pressure

__all__ = ["WIDTH", "console_lines", "flag_headlines", "short_ids"]

#: The widest line ``fit`` prints [characters].
WIDTH = 100
#: The narrowest a shortened trace id gets [characters].
MIN_ID_WIDTH = 12


#: A number and its unit ("55.8 kPa", "3 nN", "20 mm"), kept on one line by :func:`_wrap`.
_VALUE_UNIT = re.compile(r"(\d) (?=[pnµmkMG]?(?:Pa|N|m|s)\b)")


def _wrap(text: str, indent: str = "", width: int = WIDTH) -> list[str]:
    """``text`` wrapped at ``width``, continuation lines indented by two more spaces; a
    number stays on the line of its unit."""
    glued = _VALUE_UNIT.sub("\\1\0", text)
    lines = textwrap.wrap(glued, width, initial_indent=indent,
                          subsequent_indent=indent + "  ", break_on_hyphens=False)
    return [line.replace("\0", " ") for line in lines] or [indent.rstrip()]


def _cut(text: str, width: int, head: int) -> str:
    """``text`` as its first ``head`` characters, "…" and its last ones, ``width`` in all."""
    if len(text) <= width:
        return text
    return text[:head] + "…" + text[len(text) - (width - 1 - head):]


def short_ids(ids, width: int) -> tuple[dict[str, str], list[str]]:
    """Each trace id as the console shows it: whole when it fits ``width``, else cut to it
    with "…" where the cut is — in the middle, or nearer an end where the middle is what
    tells two ids apart; when no cut tells them apart, ``trace 1``, ``trace 2`` ... with a key.

    Returns
    -------
    dict, list of str
        Id -> shown id, and the key's lines (empty unless ids were numbered).
    """
    ids = list(dict.fromkeys(str(i) for i in ids))
    width = max(width, MIN_ID_WIDTH)
    for head in sorted(range(width), key=lambda h: (abs(h - width // 2), -h)):
        shown = {i: _cut(i, width, head) for i in ids}
        if len(set(shown.values())) == len(ids):
            return shown, []
    shown = {i: f"trace {k}" for k, i in enumerate(ids, 1)}
    return shown, ["trace ids:"] + [f"  {shown[i]} = {i}" for i in ids]


def _interval_part_lines(summary, shown: dict[str, str]) -> list[str]:
    """Under the table: what E_lo..E_hi of each Bayesian row is made of (90 %: statistical,
    + budget, + model form where a model check found a material misfit)."""
    from ..bayes.modelform import interval_parts  # here: the parser does not load it

    rows = summary[summary["method"] == "bayes"]
    if rows.empty or "E_budget_lo_pa" not in rows:
        return []
    lines = _wrap("bayes E_lo..E_hi is the full 90 % interval: statistical + budget (+ model "
                  "form: with a material misfit, the envelope of the alternatives' 90 % "
                  "intervals); its parts (% of E):")
    for _, r in rows.iterrows():
        parts = interval_parts(r["E_pa"], (r["E_stat_lo_pa"], r["E_stat_hi_pa"]),
                               (r["E_budget_lo_pa"], r["E_budget_hi_pa"]),
                               (r["E_lo_pa"], r["E_hi_pa"]))
        misfit = ("" if r["model_ok"] or not isinstance(r.get("misfit_checks"), str)
                  else f"; material misfit: {r['misfit_checks'].replace(';', ', ')}")
        lines += _wrap(f"{shown[str(r['trace_id'])]}: {parts}{misfit}", "  ")
    return lines


def _finite(v) -> bool:
    try:
        return math.isfinite(float(v))
    except (TypeError, ValueError):
        return False


def _layer_lines(summary, shown: dict[str, str]) -> list[str]:
    """Under the table, when a row has a layer (a thickness, or the specimen's twin): its
    fitted curve read as a half-space, a bonded and a free layer (``E_halfspace_pa``,
    ``E_bonded_pa``, ``E_free_pa``)."""
    cols = ("E_halfspace_pa", "E_bonded_pa", "E_free_pa")
    if not all(c in summary for c in cols):
        return []
    layered = summary[[_finite(b) or _finite(f) for b, f in
                       zip(summary["E_bonded_pa"], summary["E_free_pa"], strict=True)]]
    if layered.empty:
        return []
    lines = _wrap("E of the same fitted curve read as a half-space, a bonded and a free layer "
                  "(summary.csv E_halfspace_pa, E_bonded_pa, E_free_pa):")
    for _, r in layered.iterrows():
        read = ", ".join(f"{name} {format_pressure(r[c])}" for name, c in
                         zip(("half-space", "bonded", "free"), cols, strict=True)
                         if _finite(r[c]))
        layer = f" [{r['layer']}]" if isinstance(r.get("layer"), str) and r["layer"] else ""
        lines += _wrap(f"{shown[str(r['trace_id'])]} {r['method']}{layer}: {read}", "  ")
    return lines


def _instron_lines(summary, shown: dict[str, str]) -> list[str]:
    """Under the table, for Bayesian rows fitted with the specimen's twin: what a compression
    test of the block would read (``E_instron_pa`` and its 90 % interval)."""
    if "E_instron_pa" not in summary:
        return []
    rows = summary[(summary["method"] == "bayes") & summary["E_instron_pa"].notna()]
    if rows.empty:
        return []
    lines = _wrap("E_instron: what a compression test of the block would read (the block's "
                  "twin; set it beside your Instron, like for like):")
    for _, r in rows.iterrows():
        lines += _wrap(f"{shown[str(r['trace_id'])]}: {format_pressure(r['E_instron_pa'])} "
                       f"[{format_pressure(r['E_instron_lo_pa'])}, "
                       f"{format_pressure(r['E_instron_hi_pa'])}] ({r['platens']} platens; "
                       f"{r['layer']})", "  ")
    return lines


def _law_lines(summary, shown: dict[str, str]) -> list[str]:
    """Under the table, for Bayesian rows fitted with a hyperelastic law (``--law``): E is the
    law's small-strain modulus E0, its shape parameters, and what a compression test would
    read at the Instron's strain (``E_instron_law_pa``)."""
    if "law" not in summary:
        return []
    rows = summary[(summary["method"] == "bayes") & summary["law"].notna()
                   & (summary["law"].astype(str) != "linear")]
    if rows.empty:
        return []
    lines = _wrap("law: E is the hyperelastic law's small-strain modulus E0; E_instron_law what "
                  "a compression test of the block would read at the strain given (the chord "
                  "of the law's curve):")
    for _, r in rows.iterrows():
        text = f"{shown[str(r['trace_id'])]}: {r['law']}, {r['law_params']}"
        if _finite(r.get("E_instron_law_pa")):
            text += (f"; E_instron_law to {100 * r['instron_strain']:g} % "
                     f"{format_pressure(r['E_instron_law_pa'])} "
                     f"[{format_pressure(r['E_instron_law_lo_pa'])}, "
                     f"{format_pressure(r['E_instron_law_hi_pa'])}]")
        lines += _wrap(text, "  ")
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


#: The table's columns after the trace id: summary.csv column -> header.
_COLUMNS = (("method", "method"), ("E_pa", "E"), ("E_lo_pa", "E_lo"), ("E_hi_pa", "E_hi"),
            ("E_sd_pa", "E_sd"), ("E_hertz_pa", "E_hertz"), ("converged", "converged"),
            ("model_ok", "model_ok"))


def _cells(summary) -> dict[str, list[str]]:
    """The table's cells after the trace id, as strings, by header."""
    out: dict[str, list[str]] = {}
    sampled = summary["method"] != "lsq"
    for col, head in _COLUMNS:
        if col not in summary:
            continue
        values = summary[col].tolist()
        if col.endswith("_pa"):
            if col == "E_hertz_pa" and not any(_finite(v) for v in values):
                continue
            out[head] = [format_pressure(v) if _finite(v) else "n/a" for v in values]
        elif col == "converged":  # n/a for a least-squares row: nothing is sampled
            out[head] = [str(bool(c)) if s and c == c else "n/a"
                         for c, s in zip(values, sampled, strict=True)]
        else:
            out[head] = [str(v) for v in values]
    return out


def _table(summary, shown: dict[str, str]) -> str:
    """The run's table, at most :data:`WIDTH` wide: the trace id (shortened as ``shown``
    says), the method, E with its 90 % interval and sd, the Hertz law's E for a sphere (the
    paper's choice, ``E_hertz_pa``), convergence and the model check."""
    cells = _cells(summary)
    ids = [shown[str(i)] for i in summary["trace_id"]]
    id_width = max(len("trace_id"), *(len(i) for i in ids))
    widths = {h: max(len(h), *(len(v) for v in vals)) for h, vals in cells.items()}
    lines = ["trace_id".ljust(id_width) + "".join(f" {h:>{w}}" for h, w in widths.items())]
    for k, i in enumerate(ids):
        lines.append(i.ljust(id_width)
                     + "".join(f" {cells[h][k]:>{w}}" for h, w in widths.items()))
    return "\n".join(line.rstrip() for line in lines)


def _id_width(summary) -> int:
    """Room the table leaves for the trace id within :data:`WIDTH`."""
    cells = _cells(summary)
    rest = sum(1 + max(len(h), *(len(v) for v in vals)) for h, vals in cells.items())
    return WIDTH - rest


def _legend(summary) -> list[str]:
    hertz = "E_hertz_pa" in summary and summary["E_hertz_pa"].map(_finite).any()
    return _wrap(
        "E: the Bayesian posterior median or the least-squares estimate; E_lo..E_hi its 90 % "
        "interval (bayes: the full one, its parts below; lsq: statistical only); E_sd: bayes, "
        "the sd of E with the budget, i.e. of the statistical + budget part of E_lo..E_hi "
        "(summary.csv E_sd_pa; the model form, an envelope, has no sd); lsq, its standard "
        "error"
        + ("; E_hertz: E with the Hertz (paraboloid) law, the paper's choice for a sphere"
           if hertz else "")
        + "; every column in summary.csv")


def _warned(summary):
    """Rows flagged with a warning outside the model checks and convergence: the force's
    scale against the declared sensor noise (``force_scale``)."""
    if "flag_codes" not in summary:
        return summary["method"] != summary["method"]
    codes = summary["flag_codes"].fillna("").astype(str).str.split(";")
    return codes.map(lambda c: "force_scale" in c)


def console_lines(summary) -> list[str]:
    """What ``fit`` prints under a run, every line at most :data:`WIDTH` characters: the
    table (E with its 90 % interval and sd, convergence and the model check), what each
    Bayesian interval is made of, E read with the other layer models, one line per flag of a
    fit that failed a model check, did not converge or carries a warning on its input, and
    the Poisson ratio when it was assumed; a law fit's shape and Instron-equivalent."""
    shown, key = short_ids(summary["trace_id"], _id_width(summary))
    lines = [_table(summary, shown), *key, *_legend(summary)]
    lines += _interval_part_lines(summary, shown)
    lines += _layer_lines(summary, shown)
    lines += _instron_lines(summary, shown)
    lines += _law_lines(summary, shown)
    not_converged = summary["converged"] == False  # noqa: E712
    misfit = summary.get("model_ok", True) == False  # noqa: E712
    bad = summary[not_converged | misfit | _warned(summary)]
    for i, r in bad.iterrows():
        who = f"{shown[str(r['trace_id'])]} ({r['method']})"
        if not_converged[i] or misfit[i]:
            what = "did not converge" if not_converged[i] else "failed a model check"
            lines += _wrap(f"{who}: {what}; E may be biased by what the model leaves out:")
        else:
            lines += _wrap(f"{who}: carries a warning on its input; E may be off by the factor "
                           "it names:")
        notes = r.get("notes")
        for h in flag_headlines(notes if isinstance(notes, str) else ""):
            lines += _wrap(f"- {h}", "  ")
    if len(bad):
        lines += _wrap(f"warning: {len(bad)} fit(s) above failed a check; the full text and "
                       "the effect on E are in summary.csv (columns notes, flag_codes, "
                       "misfit_checks, misfit_effect)")
    if "nu_source" in summary and (summary["nu_source"] == "default").any():
        lines += _wrap(f"note: {DEFAULT_NU_NOTE}")
    return lines
