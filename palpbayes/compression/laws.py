"""Which hyperelastic law a material's compression tests prefer, and the columns a law adds to
the ground-truth tables (``palpbayes groundtruth --law NAME|auto``, issue 56 item 2).

Every test is fitted with each law asked for (:func:`palpbayes.compression.finite.fit_law`).
A material's law is the one with the highest elpd_loo summed over its tests (PSIS-LOO on each
test's bins; :mod:`.finite`); the difference to it and the difference's standard error,
sqrt(sum over tests of n_t·var(pointwise differences)) as :func:`arviz.compare` computes it for
one data set, say whether the choice is clear (more than two standard errors) or not.

Columns of ``groundtruth.csv`` (:data:`LAW_COLUMNS`): ``law``; ``E0_pa``, ``E0_sd_pa``,
``E0_lo_pa``, ``E0_hi_pa`` (the small-strain modulus of the test's chosen law, median, sd and
90 % interval: for ``linear`` the line's slope ``E_pa`` ± 1.645 sd); ``law_params`` (the
natural parameters' medians, ``name=value`` joined by ``;``); ``eps0`` (the contact strain the
law places); ``E0_low_pa``, ``E0_low_lo_pa``, ``E0_low_hi_pa`` (the same law fitted up to
:data:`~palpbayes.compression.finite.LOW_STRAIN`: the small-strain check) and ``law_ok`` (the
two intervals overlap: the law follows the curve); ``law_note``; with ``--strain LO,HI``
``chord_lo``, ``chord_hi``, ``E_chord_pa``, ``E_chord_lo_pa``, ``E_chord_hi_pa`` (the law's
chord modulus over that window, where two tests — a palpation's and an Instron's — can be set
side by side at one strain).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np
import pandas as pd

from ..errors import FitError, InputError, PalpbayesError
from ..io.instron import CompressionTest
from ..material import LINEAR, law_names, material_law
from .finite import AUTO_LAWS, LawFit, curve_bins, fit_law

__all__ = ["LAW_COLUMNS", "CHORD_COLUMNS", "LAW_TABLE_COLUMNS", "check_law", "check_chord",
           "fit_tests", "law_table", "law_rows", "summary_columns", "describe_laws"]

#: Columns a law adds to every row of ``groundtruth.csv``.
LAW_COLUMNS = ["law", "E0_pa", "E0_sd_pa", "E0_lo_pa", "E0_hi_pa", "law_params", "eps0",
               "E0_low_pa", "E0_low_lo_pa", "E0_low_hi_pa", "law_ok", "law_note"]
#: Columns ``--strain LO,HI`` adds.
CHORD_COLUMNS = ["chord_lo", "chord_hi", "E_chord_pa", "E_chord_lo_pa", "E_chord_hi_pa"]
#: Columns of ``groundtruth_laws.csv``: one row per material × law.
LAW_TABLE_COLUMNS = ["material", "law", "n_tests", "n_fitted", "elpd_loo", "elpd_se",
                     "elpd_diff", "elpd_diff_se", "pareto_k_max", "E0_mean_pa", "E0_sd_pa",
                     "chosen", "clear"]


def check_law(law: str) -> str:
    """``law`` as a registered name, ``"linear"`` or ``"auto"``; InputError otherwise."""
    key = str(law).strip().lower()
    if key in (LINEAR, "auto"):
        return key
    return material_law(key).name


def check_chord(text: str | Sequence[float] | None) -> tuple[float, float] | None:
    """``"0.05,0.20"`` (fractions) as (lo, hi); None for None.

    Raises
    ------
    InputError
        Not two numbers with 0 <= lo < hi < 0.95, or numbers that look like percent.
    """
    if text is None:
        return None
    try:
        parts = [float(v) for v in (text.split(",") if isinstance(text, str) else text)]
    except ValueError:
        raise InputError(f"--strain takes two strains as fractions, LO,HI (e.g. 0.05,0.20), "
                         f"got {text!r}") from None
    if len(parts) != 2 or not all(math.isfinite(v) for v in parts):
        raise InputError(f"--strain takes two strains as fractions, LO,HI (e.g. 0.05,0.20), "
                         f"got {text!r}")
    lo, hi = parts
    if hi >= 1.0:
        raise InputError(f"--strain {text}: strains are fractions (0.05 for 5 %), not percent")
    if not 0.0 <= lo < hi < 0.95:
        raise InputError(f"--strain {text}: need 0 <= LO < HI < 0.95")
    return lo, hi


def fit_tests(tests: Sequence[CompressionTest], laws: Sequence[str], *, seed: int = 0,
              progress: Callable[[int], None] | None = None
              ) -> dict[tuple[int, str], LawFit | PalpbayesError]:
    """Each law fitted to each test: {(test index, law): fit, or the error that stopped it}.

    ``progress(1)`` is called after each fit (a tqdm bar's update).
    """
    out: dict[tuple[int, str], LawFit | PalpbayesError] = {}
    for i, test in enumerate(tests):
        try:
            bins = curve_bins(test)
        except PalpbayesError as exc:
            bins = exc
        for law in laws:
            if law == LINEAR:
                out[i, law] = fit_law(test, LINEAR)
            elif isinstance(bins, PalpbayesError):
                out[i, law] = bins
            else:
                try:
                    out[i, law] = fit_law(test, law, seed=seed + i, bins=bins)
                except (FitError, InputError) as exc:
                    out[i, law] = exc
            if progress is not None:
                progress(1)
    return out


def law_table(tests: Sequence[CompressionTest], fits: dict, laws: Sequence[str]) -> pd.DataFrame:
    """:data:`LAW_TABLE_COLUMNS`: per material and law, the summed elpd_loo and its se, the
    difference to the material's best law with its se, the worst Pareto k, E0's mean and sd
    over the tests; ``chosen`` (the best) and ``clear`` (ahead of every other law by more
    than two se of the difference).  A law that fails on a test is ranked below every law that
    fits all of the material's tests."""
    rows = []
    for material in dict.fromkeys(t.material for t in tests):
        idx = [i for i, t in enumerate(tests) if t.material == material]
        per = {}
        for law in laws:
            got = [fits[i, law] for i in idx if isinstance(fits[i, law], LawFit)]
            per[law] = got
        complete = [law for law in laws if len(per[law]) == len(idx)] or list(laws)
        elpd = {law: sum(f.elpd_loo for f in per[law]) if per[law] else -math.inf
                for law in laws}
        best = max(complete, key=lambda law: elpd[law])
        for law in laws:
            got = per[law]
            diff, dse = 0.0, 0.0
            if law != best and got and len(got) == len(per[best]):
                d = [np.asarray(a.pointwise) - np.asarray(b.pointwise)
                     for a, b in zip(got, per[best], strict=True)]
                diff = float(sum(x.sum() for x in d))
                dse = float(math.sqrt(sum(x.size * x.var() for x in d)))
            elif law != best:
                diff, dse = -math.inf, math.nan
            e0 = np.array([f.E0_pa for f in got])
            rows.append({
                "material": material, "law": law, "n_tests": len(idx), "n_fitted": len(got),
                "elpd_loo": elpd[law] if got else math.nan,
                "elpd_se": float(math.sqrt(sum(f.elpd_se**2 for f in got))) if got else math.nan,
                "elpd_diff": diff, "elpd_diff_se": dse,
                "pareto_k_max": max((f.pareto_k_max for f in got), default=math.nan),
                "E0_mean_pa": float(e0.mean()) if e0.size else math.nan,
                "E0_sd_pa": float(e0.std(ddof=1)) if e0.size > 1 else math.nan,
                "chosen": law == best, "clear": False})
        mine = [r for r in rows if r["material"] == material]
        others = [r for r in mine if not r["chosen"]]
        clear = all(r["elpd_diff"] < -2.0 * r["elpd_diff_se"] or r["elpd_diff"] == -math.inf
                    for r in others)
        for r in mine:
            r["clear"] = bool(r["chosen"] and clear)
    return pd.DataFrame(rows, columns=LAW_TABLE_COLUMNS)


def _params_text(params: dict[str, float]) -> str:
    return ";".join(f"{k}={v:.6g}" for k, v in params.items())


def law_rows(tests: Sequence[CompressionTest], fits: dict, choice: dict[str, str],
             chord: tuple[float, float] | None) -> list[dict]:
    """The :data:`LAW_COLUMNS` (and :data:`CHORD_COLUMNS` with ``chord``) of every test, from
    the fit of its material's law (``choice``: material -> law); a fit that failed leaves NaN
    and its reason in ``law_note``."""
    out = []
    for i, test in enumerate(tests):
        law = choice[test.material]
        fit = fits[i, law]
        row = dict.fromkeys(LAW_COLUMNS + (CHORD_COLUMNS if chord else []), math.nan)
        row["law"] = law
        row["law_note"] = ""
        if isinstance(fit, LawFit):
            row.update(E0_pa=fit.E0_pa, E0_sd_pa=fit.E0_sd_pa, E0_lo_pa=fit.E0_lo_pa,
                       E0_hi_pa=fit.E0_hi_pa, law_params=_params_text(fit.params),
                       eps0=fit.eps0, law_ok=fit.consistent)
            notes = []
            if fit.low is not None:
                row.update(E0_low_pa=fit.low.E0_pa, E0_low_lo_pa=fit.low.E0_lo_pa,
                           E0_low_hi_pa=fit.low.E0_hi_pa)
                if not fit.consistent:
                    notes.append(f"E0 over the whole curve (to {100 * fit.strain_hi:.3g} %) is "
                                 f"{fit.E0_pa / fit.low.E0_pa - 1:+.1%} from E0 up to "
                                 f"{100 * fit.low.strain_hi:.3g} %: the law does not follow "
                                 "the curve, and its E0 is not the small-strain modulus of the "
                                 "data (E0_low_pa is)")
            if chord:
                if chord[1] > fit.strain_hi and law != LINEAR:
                    notes.append(f"the chord's {chord[1]:g} lies beyond the test's "
                                 f"{fit.strain_hi:.3g}: extrapolated by the law")
                m, lo, hi = fit.chord(*chord)
                row.update(chord_lo=chord[0], chord_hi=chord[1], E_chord_pa=m,
                           E_chord_lo_pa=lo, E_chord_hi_pa=hi)
            row["law_note"] = "; ".join(notes)
        else:
            row["law_note"] = f"{law} not fitted: {fit}"
        out.append(row)
    return out


def summary_columns(per_file: pd.DataFrame) -> pd.DataFrame:
    """Per material: ``law``, ``E0_mean_pa``, ``E0_sd_pa`` (over its tests) and, with chords,
    ``E_chord_mean_pa``, ``E_chord_sd_pa``; in order of first appearance."""
    g = per_file.groupby("material", sort=False)
    out = pd.DataFrame({"material": list(g.groups),
                        "law": g["law"].first().to_numpy(),
                        "E0_mean_pa": g["E0_pa"].mean().to_numpy(),
                        "E0_sd_pa": g["E0_pa"].std(ddof=1).to_numpy()})
    if "E_chord_pa" in per_file:
        out["E_chord_mean_pa"] = g["E_chord_pa"].mean().to_numpy()
        out["E_chord_sd_pa"] = g["E_chord_pa"].std(ddof=1).to_numpy()
    return out


def describe_laws() -> str:
    """The names ``--law`` takes, for help texts."""
    return ", ".join(law_names()) + ", auto (the best by PSIS-LOO of " \
        + ", ".join(AUTO_LAWS) + ")"

