"""Formatting of numbers, cells, paths and paragraphs for the report's pages (no drawing)."""

from __future__ import annotations

import math
import os
import textwrap
from pathlib import Path
from typing import Any

#: Pa -> kPa.
KPA = 1e-3
#: Decimals of a modulus in kPa wherever the report prints one (a value, an sd, an interval's
#: ends): one quantity, one printed form on every page and on the console.
KPA_DIGITS = 1


def fmt(v: Any, digits: int = 1) -> str:
    try:
        x = float(v)
    except (TypeError, ValueError):
        return "–"
    return "–" if not math.isfinite(x) else f"{x:.{digits}f}"


def kpa(v: Any) -> str:
    """A modulus [Pa] as the report prints it: kPa with :data:`KPA_DIGITS` decimals, "–" when
    it is missing."""
    return fmt(float(v) * KPA if isnum(v) else v, KPA_DIGITS)


def pm(e: Any, sd: Any, digits: int = KPA_DIGITS) -> str:
    a, b = fmt(float(e) * KPA if isnum(e) else e, digits), \
        fmt(float(sd) * KPA if isnum(sd) else sd, digits)
    if a == "–":
        return "–"
    return a if b == "–" else f"{a} ± {b}"


def isnum(v: Any) -> bool:
    try:
        return math.isfinite(float(v))
    except (TypeError, ValueError):
        return False


def yesno(v: Any) -> str:
    if isinstance(v, str):
        v = {"true": True, "false": False}.get(v.strip().lower(), v)
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return "–"
    return "yes" if bool(v) else "NO"


def interval(lo: Any, hi: Any, digits: int = KPA_DIGITS) -> str:
    """An interval [Pa] as "[lo, hi]" in kPa (:data:`KPA_DIGITS` decimals), "–" when an end
    is missing."""
    if not (isnum(lo) and isnum(hi)):
        return "–"
    return f"[{float(lo) * KPA:.{digits}f}, {float(hi) * KPA:.{digits}f}]"


def fmt_range(lo: Any, hi: Any, digits: int = 0) -> str:
    """'lo–hi', or a single number when both are equal ('1500', not '1500–1500')."""
    a, b = fmt(lo, digits), fmt(hi, digits)
    return a if a == b else f"{a}–{b}"


def shown_path(path: str | os.PathLike | None) -> str:
    """A path as shown in the report: relative to the working folder when it is inside it or
    beside it (at most one '..'), else absolute."""
    if not path:
        return "(none)"
    p = Path(path).resolve()
    try:
        rel = Path(os.path.relpath(p, Path.cwd().resolve()))
    except ValueError:  # another drive (Windows)
        return str(p)
    if rel.parts[:2] == ("..", ".."):
        return str(p)
    return str(rel)


def force_setting(v: Any) -> str:
    """A force option of the run [N] with an SI prefix, or what None means (read per trace)."""
    from ..units import format_force

    if v is None:
        return "read from each trace's pre-contact baseline (6 sd)"
    return format_force(float(v))


def wrap(text: str, width: int) -> list[str]:
    out: list[str] = []
    for para in text.split("\n"):
        # no breaks inside 'R-hat', 'post-burn-in', 'de-snooker'
        out.extend(textwrap.wrap(para, width, break_on_hyphens=False) or [""])
    return out
