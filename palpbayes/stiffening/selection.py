"""Which stiffening law the data support: the checks of each law and the verdict's message.

Identifiability and the three outcomes
--------------------------------------
Three laws are fitted (same priors): the double law, the single exponential plus constant
E = c0 + c1·e^(c2·t) and a constant E = c0 (no stiffening).  The *simplest law that passes its
checks* is reported (``preferred``), starting from the double law.

A sum of two exponentials is notoriously ill-conditioned (Lanczos' example): the double law is
reported as *identifiable* only when all of these hold, otherwise ``identifiable`` is False and
``message`` says which failed:

1. at least six distinct rest times (five parameters);
2. the Bayesian information criterion prefers the double law by more than 2
   (BIC = k·ln n − 2·ln L_max, k = 5 vs 4; Kass & Raftery 1995 "positive evidence");
3. both amplitudes' 90 % intervals exclude zero;
4. the time scales are separated: the 5 % quantile of T4/T2 exceeds :data:`MIN_RATIO` (1.5);
5. the slow time scale is resolved: its 95 % quantile is below 10·max t (else the slow term
   is a constant over the data);
6. its sampler converged (R-hat, ESS; :mod:`palpbayes.bayes.diagnostics`).

The single exponential is the fallback only when it passes the same kind of checks
(``single_identifiable``):

1. at least four distinct rest times (four parameters);
2. BIC prefers it over the constant by more than 2 (k = 4 vs 2);
3. the 90 % interval of its amplitude c1 excludes zero;
4. its time scale T = −1/c2 is resolved within the observed rest times: its 90 % interval lies
   inside [smallest positive t, largest t] (a faster decay is over before the first rest
   time, a slower one is a straight line or a constant over the data);
5. its sampler converged.

Otherwise the outcome is **no stiffening detected**: ``preferred = "constant"``, and the
message gives E = mean ± sd of the estimates (with the 90 % interval of the constant law's
c0).  Before the single law was checked it was recommended whenever the double law failed:
on constant data (100 kPa, 10 % scatter, eight rest times) an audit got c0 = 183 kPa,
c1 = −97 kPa and a 20,500 s time scale, far beyond the data.
"""

from __future__ import annotations

import numpy as np

from ..intervals import central
from ..units import format_pressure
from .result import draw_summary

__all__ = ["MIN_RATIO", "double_law_reasons", "single_law_reasons", "selection_message"]

#: Minimum ratio T4/T2 (5 % quantile) for the two time scales to count as distinct.
MIN_RATIO = 1.5


def double_law_reasons(draws, bic_d, bic_s, n_distinct, t_max, diag, level) -> list[str]:
    """Why the double exponential is not identifiable (empty when it is), one reason each."""
    reasons = []
    if n_distinct < 6:
        reasons.append(f"only {n_distinct} distinct rest times; five parameters need six or more")
    d_bic = float(bic_s - bic_d)
    if d_bic <= 2:
        reasons.append(f"BIC does not prefer two exponentials over one plus a constant "
                       f"(BIC_single - BIC_double = {d_bic:.1f} <= 2)")
    for name in ("c1", "c3"):
        _, _, lo, hi = draw_summary(draws[name], level)
        if lo <= 0 <= hi:
            reasons.append(f"the {int(level * 100)} % interval of amplitude {name} includes 0")
    T2, T4 = -1.0 / draws["c2"], -1.0 / draws["c4"]
    ratio = np.quantile(T4 / T2, 0.05)
    if ratio < MIN_RATIO:
        reasons.append(f"the rates are not separated (5 % quantile of c2/c4 = {ratio:.2f} < "
                       f"{MIN_RATIO}, i.e. c2 ≈ c4)")
    slow = float(np.quantile(T4, 0.95))
    if slow > 10 * t_max:
        reasons.append(f"the slow term is indistinguishable from a constant over rest times up "
                       f"to {t_max:g} s (its time scale reaches {slow:.3g} s)")
    if not diag.converged:
        reasons.append("its sampler did not converge (" + "; ".join(diag.problems()) + "), a "
                       "usual symptom of a degenerate double exponential")
    return reasons


def single_law_reasons(draws, bic_s, bic_c, n_distinct, t_min, t_max, diag, level
                       ) -> list[str]:
    """Why the single exponential is not identifiable (empty when it is), one reason each."""
    reasons = []
    if n_distinct < 4:
        reasons.append(f"only {n_distinct} distinct rest times; four parameters need four or "
                       "more")
    d_bic = float(bic_c - bic_s)
    if d_bic <= 2:
        reasons.append(f"BIC does not prefer one exponential over a constant "
                       f"(BIC_constant - BIC_single = {d_bic:.1f} <= 2)")
    _, _, lo, hi = draw_summary(draws["c1"], level)
    if lo <= 0 <= hi:
        reasons.append(f"the {int(level * 100)} % interval of amplitude c1 includes 0")
    T_lo, T_hi = central(-1.0 / draws["c2"], level)
    if T_lo < t_min or T_hi > t_max:
        reasons.append(f"its time scale is not resolved within the rest times {t_min:g}-{t_max:g}"
                       f" s (its {int(level * 100)} % interval is {T_lo:.3g}-{T_hi:.3g} s)")
    if not diag.converged:
        reasons.append("its sampler did not converge (" + "; ".join(diag.problems()) + ")")
    return reasons


# Many parameters: the numbers a model-selection sentence reports (BICs, reasons, the rested
# level), each a fact the text names.
def selection_message(n: int, draws: dict, single: dict, constant: dict, bic_d: float, bic_s: float,
             bic_c: float, reasons: list[str], single_reasons: list[str], mean: float, sd: float,
             level: float) -> str:
    """One paragraph: what was found and, for a simpler law, why the richer ones failed."""
    pct = f"{int(level * 100)} %"
    if not reasons:
        med = {k: float(np.median(v)) for k, v in draws.items()}
        return (f"two exponentials resolved from {n} estimates: time scales "
                f"{-1 / med['c2']:.3g} s and {-1 / med['c4']:.3g} s, amplitudes "
                f"{format_pressure(med['c1'], 4)} and {format_pressure(med['c3'], 4)} (BIC "
                "favours them by "
                f"{float(bic_s - bic_d):.1f})")
    message = ("E(t) = c1·e^(c2·t) + c3·e^(c4·t) is not identifiable from these data: "
               + "; ".join(reasons) + ".")
    if not single_reasons:
        q = {k: draw_summary(v, level) for k, v in single.items()}
        T = -1.0 / single["c2"]
        T_lo, T_hi = central(T, level)
        message += (f" Use the single exponential E = c0 + c1·e^(c2·t): c0 = "
                    f"{format_pressure(q['c0'][0], 4)}, c1 = {format_pressure(q['c1'][0], 4)} "
                    f"({pct} interval {format_pressure(q['c1'][2], 4)} to "
                    f"{format_pressure(q['c1'][3], 4)}), time scale "
                    f"{float(np.median(T)):.3g} s ({pct} interval {T_lo:.3g}-{T_hi:.3g} s); "
                    f"BIC favours it over a constant by {float(bic_c - bic_s):.1f}.")
    else:
        _, _, c_lo, c_hi = draw_summary(constant["c0"], level)
        message += (" A single exponential E = c0 + c1·e^(c2·t) is not supported either: "
                    + "; ".join(single_reasons) + f". No stiffening detected: E = "
                    f"{format_pressure(mean, 4)} ± {format_pressure(sd)} (mean ± sd of {n} "
                    f"estimates; {pct} interval of the constant {format_pressure(c_lo, 4)} to "
                    f"{format_pressure(c_hi, 4)}).")
    return message
