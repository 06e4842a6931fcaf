"""The flags of a summary row as three columns: words, codes and a level.

A fit's flags are sentences (what was seen, why it matters, what to do).  A table needs more
than the sentences: a column a user can filter on, and the difference between a warning (the
interval may not be honest) and information (a check fired but its effect on E is negligible,
a setting that was used).  A row's ``notes`` hold the sentences joined by ``"; "``,
``flag_codes`` one short code per flag (``";"``-joined, in the same order, repeated codes kept
once) and ``flag_level`` the highest level among them: ``"warning"``, ``"info"`` or ``""``
(no flag).

The column is not called ``flags``: ``DataFrame.flags`` is a pandas attribute, so
``summary.flags`` would not return the column.

Codes (:data:`CODES`): the model checks by their names (``exponent``, ``residual_structure``,
``depth_consistency``, ``ppc``, ``rate``); the sampler's diagnostics (``rhat``, ``ess``,
``step_cap``); the posterior's shape (``bimodal_surface``, ``prior_dominated_surface``,
``prior_bound``); the least squares (``lsq_failed``; ``offset``: an untared sensor biases
the paper's model); the force's scale against the declared sensor noise (``force_scale``: a
wrong ``--force-unit``); a fit that did not run (``fit_failed``); the layer (``layer``: base or
thickness not identified, outside the layer solution's range); ``other`` for anything else.
A flag that starts with ``info:`` is information, every other one a warning.

The viscoelastic tables (``rheology.csv``, ``rheology_pooled.csv``) keep their flags as a list,
joined by :data:`RHEOLOGY_SEPARATOR` (their sentences hold ``"; "``), and code them by words
anywhere in the flag (:data:`RHEOLOGY_CODES`, :data:`POOLED_RHEOLOGY_CODES`) with
:func:`listed_flag_columns`: the same three columns, the same levels.
"""

from __future__ import annotations

__all__ = ["CODES", "CONTAINS", "CHECKS", "LEVELS", "flag_code", "flag_level", "flag_columns",
           "split_flags", "level_and_text", "scoped", "FLAG_COLUMNS", "RHEOLOGY_CODES",
           "POOLED_RHEOLOGY_CODES", "RHEOLOGY_SEPARATOR", "listed_flag_columns"]

#: (how the flag opens, code): a flag's first words say what it is (its explanation may name
#: other checks), after an ``info:`` prefix.
CODES = (
    ("free-exponent", "exponent"),
    ("binned residuals", "residual_structure"),
    ("E* over the shallow half", "depth_consistency"),
    ("posterior-predictive", "ppc"),
    ("rate dependence", "rate"),
    ("R-hat", "rhat"),
    ("ESS ", "ess"),
    ("step cap", "step_cap"),
    ("bimodal z_surf", "bimodal_surface"),
    ("prior-dominated", "prior_dominated_surface"),
    ("least squares failed", "lsq_failed"),
    ("untared sensor", "offset"),
    ("force scale", "force_scale"),
    ("fit failed", "fit_failed"),
    ("no Bayesian posterior", "fit_failed"),
    ("base not identified", "layer"),
    ("no layer needed", "layer"),
    ("thickness not identified", "layer"),
)
#: (words anywhere in the flag's first clause, code), when no opening matches.
CONTAINS = (
    ("prior bound", "prior_bound"),
    ("layer thickness", "layer"),
    ("thin-layer", "layer"),
)
#: Names of the model checks (``info: NAME check fails statistically but is negligible``).
CHECKS = ("exponent", "residual_structure", "depth_consistency", "ppc", "rate")
#: Levels, lowest first.
LEVELS = ("", "info", "warning")
#: The three columns, in the order summary.csv writes them.
FLAG_COLUMNS = ("notes", "flag_codes", "flag_level")


def split_flags(text: str) -> list[str]:
    """The flags of a ``"; "``-joined text (a ``"; "`` inside brackets or parentheses is part
    of its flag)."""
    parts, depth, start = [], 0, 0
    for i, ch in enumerate(text):
        if ch in "([":
            depth += 1
        elif ch in ")]":
            depth = max(depth - 1, 0)
        elif depth == 0 and text.startswith("; ", i):
            parts.append(text[start:i])
            start = i + 2
    parts.append(text[start:])
    return [p.strip() for p in parts if p.strip()]


def flag_code(flag: str) -> str:
    """The short code of one flag (:data:`CODES`, :data:`CONTAINS`, a negligible check's name;
    ``"other"`` if none matches)."""
    text = flag.strip()
    if text.lower().startswith("info:"):
        text = text[5:].strip()
        name = text.split(" ", 1)[0]
        if name in CHECKS and text.startswith(f"{name} check"):
            return name
    for words, code in CODES:
        if text.startswith(words):
            return code
    first = text.split(":", 1)[0]
    for words, code in CONTAINS:
        if words in first:
            return code
    return "other"


def flag_level(flag: str) -> str:
    """``"info"`` for a flag that starts with ``info:``, else ``"warning"``."""
    return "info" if flag.lstrip().lower().startswith("info:") else "warning"


def level_and_text(flag: str) -> tuple[str, str]:
    """(:func:`flag_level`, the flag without its ``info:`` prefix)."""
    level = flag_level(flag)
    return level, flag.lstrip()[5:].strip() if level == "info" else flag


def scoped(scope: str, flag: str) -> str:
    """``"scope: flag"`` (where a flag comes from: a map's ``field`` or ``lump``), with an
    ``info:`` prefix kept in front, where :func:`flag_level` reads it."""
    level, text = level_and_text(flag)
    return f"info: {scope}: {text}" if level == "info" else f"{scope}: {flag}"


def flag_columns(text: object) -> dict[str, str]:
    """``notes``, ``flag_codes`` and ``flag_level`` of a row whose flags are ``text``
    (``"; "``-joined; None, NaN or ``""``: no flag)."""
    flags = split_flags(text) if isinstance(text, str) else []
    codes = list(dict.fromkeys(flag_code(f) for f in flags))
    level = max((flag_level(f) for f in flags), key=LEVELS.index, default="")
    return {"notes": "; ".join(flags), "flag_codes": ";".join(codes), "flag_level": level}


#: Codes of a viscoelastic fit's flags (rheology.csv): (words anywhere in the flag, code).
RHEOLOGY_CODES = (
    ("force scale", "force_scale"),
    ("alpha piles up at 0", "alpha_at_zero"), ("alpha piles up", "alpha_at_bound"),
    ("below one step", "tau_fast"), ("beyond the recorded", "tau_slow"),
    ("phi piles up", "phi_at_bound"), ("surface posterior reaches", "surface_at_bound"),
    ("did not settle", "grid"), ("another basin", "basin"),
    ("effective sample", "ess"), ("contact shrinks", "shrinking_contact"),
    ("takes a half-space", "thickness"), ("viscous drag", "drag"),
    ("tilt with the height", "tilt"), ("adhesion", "adhesion"),
    ("did not converge", "not_converged"), ("posterior-predictive", "ppc"),
)
#: Codes of a pooled power law's flags (rheology_pooled.csv).
POOLED_RHEOLOGY_CODES = (
    ("from the pooled values", "trace_disagrees"), ("edge of its grid", "pool_at_edge"),
    ("own model check failed", "trace_model_check"), ("were not fitted", "missing"),
    ("one speed", "one_speed"),
)
#: How the viscoelastic tables join a row's flags.
RHEOLOGY_SEPARATOR = " | "


def listed_flag_columns(flags: list[str], codes: tuple[tuple[str, str], ...],
                        separator: str = RHEOLOGY_SEPARATOR) -> dict[str, str]:
    """``notes``, ``flag_codes`` and ``flag_level`` of a list of flags coded by ``codes``
    (words anywhere in the flag, first match; ``"other"`` if none)."""
    found = [next((c for words, c in codes if words in f), "other") for f in flags]
    level = max((flag_level(f) for f in flags), key=LEVELS.index, default="")
    return {"notes": separator.join(flags), "flag_codes": ";".join(dict.fromkeys(found)),
            "flag_level": level}
