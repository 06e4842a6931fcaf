"""Coverage of E's full interval on palpations with a misfit the user did not model.

Fits every trace of :mod:`palpbayes.sim.misfit` with the half-space law (the exact engine, the
default budget) and prints, per scenario: the coverage of the true E by the statistical, the
budget and the full interval (with the model form), the median relative error of E, the
median width of each interval, and how many fits found a material misfit.

    python tools/modelform_calibration.py [--n 50] [--n-well 200] [--workers 2]
                                          [--scenarios well onset ...] [--csv out.csv]

The well-specified scenario gets more traces (``--n-well``): its coverage is judged against a
band (86-94 %), which 50 traces cannot resolve (binomial sd 4 %), and its fits are quick.
The slow suite runs this script (``tests/statistical/test_modelform_calibration.py``).
"""

from __future__ import annotations

import argparse
import multiprocessing
import warnings
from concurrent.futures import ProcessPoolExecutor

import pandas as pd

from palpbayes.bayes import fit_bayes
from palpbayes.fitdata import ModelSpec
from palpbayes.procs import lifeline
from palpbayes.sim.misfit import MISFIT_NU, MISFIT_SCENARIOS, misfit_trace


def fit_one(job: tuple[str, int]) -> dict:
    """One trace's row: truth, E and the three intervals."""
    scenario, i = job
    trace, tip = misfit_trace(scenario, i)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        row = fit_bayes(trace, ModelSpec(tip, nu=MISFIT_NU), engine="exact",
                        seed=i).summary_row()
    return {"scenario": scenario, "index": i, "tip": tip.kind,
            "E_true_pa": trace.metadata["E_true"], **{k: row[k] for k in (
                "E_pa", "E_stat_lo_pa", "E_stat_hi_pa", "E_budget_lo_pa", "E_budget_hi_pa",
                "E_lo_pa", "E_hi_pa", "model_ok", "modelform_share_pct", "converged")}}


def run(scenarios, n: int, workers: int, n_well: int | None = None) -> pd.DataFrame:
    """Fit ``n`` traces of each scenario (``n_well`` of ``"well"``) on ``workers`` processes."""
    jobs = [(s, i) for s in scenarios
            for i in range(n_well if s == "well" and n_well is not None else n)]
    if workers > 1:
        ctx = multiprocessing.get_context()  # workers end with this process (procs.lifeline)
        with ProcessPoolExecutor(workers, mp_context=ctx, **lifeline(ctx)) as pool:
            rows = list(pool.map(fit_one, jobs, chunksize=4))
    else:
        rows = [fit_one(j) for j in jobs]
    return pd.DataFrame(rows)


def table(df: pd.DataFrame) -> pd.DataFrame:
    """Per scenario: coverage and median width [%] of each interval, median error [%]."""
    t = df["E_true_pa"]
    out = {}
    for part, (lo, hi) in {"stat": ("E_stat_lo_pa", "E_stat_hi_pa"),
                           "budget": ("E_budget_lo_pa", "E_budget_hi_pa"),
                           "full": ("E_lo_pa", "E_hi_pa")}.items():
        df[f"cov_{part}"] = (df[lo] <= t) & (t <= df[hi])
        df[f"width_{part}_pct"] = 100 * (df[hi] - df[lo]) / df["E_pa"]
    df["err_pct"] = 100 * (df["E_pa"] / t - 1)
    df["material"] = ~df["model_ok"]
    g = df.groupby("scenario", sort=False)
    out = g[["cov_stat", "cov_budget", "cov_full", "material"]].mean()
    out = out.join(g[["err_pct", "width_stat_pct", "width_budget_pct", "width_full_pct",
                      "modelform_share_pct"]].median())
    out.insert(0, "n", g.size())
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=50)
    ap.add_argument("--n-well", type=int, default=200)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--scenarios", nargs="*", default=list(MISFIT_SCENARIOS))
    ap.add_argument("--csv", default=None)
    args = ap.parse_args()
    df = run(args.scenarios, args.n, args.workers, args.n_well)
    if args.csv:
        df.to_csv(args.csv, index=False)
    with pd.option_context("display.width", 200, "display.precision", 3,
                           "display.max_columns", 20):
        print(table(df))


if __name__ == "__main__":
    main()
