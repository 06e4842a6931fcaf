# ruff: noqa: E402  (BLAS threads are set before numpy is imported)
"""Coverage of the viscoelastic fit's 90 % intervals on simulated ramp–hold palpations.

Draws ``--n`` records per relaxation model (power law, standard linear solid) with known
moduli, fits each with :func:`palpbayes.rheology.fit_rheology` and prints, per model and
parameter: the share of 90 % intervals that hold the truth, the mean and sd of the z-score
(truth − median)/sd, and the median relative error; then how many posterior-predictive checks
passed and the median fit time.  Per record it also fits the other relaxation model and the
elastic law twice (a constant E* on the same block means, and the exact engine on the loading
only): the share of records where PSIS-LOO (:func:`palpbayes.rheology.compare_rheology`, over the
three models of the same block means) prefers the true model beyond two standard errors,
prefers a wrong one, or none; and the share of exact-engine elastic fits that the rate check
(:mod:`palpbayes.checks.rate`) flags as materially rate dependent.

Records (seeded by index): paraboloid (3 mm deep) or flat punch (2 mm) of the paper, at 5, 50
or 500 mm/min, a 5–15 s hold, AR(1) sensor noise of 8 mN with lag-one correlation 0–0.6, an
offset of ±50 mN, the surface anywhere in ±1 mm; power law E0* 30–150 kPa, alpha 0.05–0.4;
SLS E_inf* 20–100 kPa, E1* 10–100 kPa, tau 0.3–5 s (log-uniform).

    python tools/rheology_calibration.py [--n 100] [--start 0] [--workers 2] [--csv out.csv]
        [--retract] [--coverage-only]

``--start S`` fits records S … S + n − 1 (fresh indices: the calibration tests use 0–99, and
of those from 1000 on only sls-1220 and power-law-1058 are in a test);
``--coverage-only`` fits the true model alone (coverage, checks and time; no model choice, no
elastic fit: a third of the time).

``--retract`` also fits the power-law records over the whole cycle, the retract by Ting's
rule, with the viscous drag term that the retract brings (rows labelled "power-law, with
retract"; no model choice or elastic fit for those).

The slow suite runs this (``tests/statistical/test_rheology_calibration.py``).
"""

from __future__ import annotations

import multiprocessing
import os

if __name__ == "__main__":
    # one BLAS thread per worker process (the workers share the cores; oversubscribed BLAS
    # threads made each fit 3-4 times slower); set before numpy is imported, and only when
    # run as a script (importing table() must not change the importer's threads)
    for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(_var, "1")

import argparse
import warnings
from concurrent.futures import ProcessPoolExecutor

import numpy as np
import pandas as pd

from palpbayes.bayes import fit_bayes
from palpbayes.checks import material
from palpbayes.contact.viscoelastic import PowerLawKernel, standard_linear_solid
from palpbayes.fitdata import ModelSpec
from palpbayes.paper import PAPER_TIPS
from palpbayes.procs import lifeline
from palpbayes.rheology import fit_rheology
from palpbayes.rheology.choice import compare_rheology
from palpbayes.sim import simulate_viscoelastic

#: Parameters checked per model, with the names of the draws.
PARAMETERS = {"power-law": ("E0", "alpha", "z_surf"), "sls": ("E_inf", "E1", "tau", "z_surf")}
SPEEDS = (5.0, 50.0, 500.0)  # [mm/min]


def record(model: str, i: int):
    """The ``i``-th simulated record of ``model`` and its truth (dict of parameter values)."""
    rng = np.random.default_rng([17, i, 0 if model == "power-law" else 1])
    if model == "power-law":
        truth = {"E0": rng.uniform(30e3, 150e3), "alpha": rng.uniform(0.05, 0.4)}
        kernel = PowerLawKernel(truth["E0"], truth["alpha"])
    else:
        truth = {"E_inf": rng.uniform(20e3, 100e3), "E1": rng.uniform(10e3, 100e3),
                 "tau": float(np.exp(rng.uniform(np.log(0.3), np.log(5.0))))}
        kernel = standard_linear_solid(truth["E_inf"], truth["E1"], truth["tau"])
    tip_name = ("paraboloid", "flat")[int(rng.integers(2))]
    truth["z_surf"] = rng.uniform(-1e-3, 1e-3)
    trace = simulate_viscoelastic(
        kernel, PAPER_TIPS[tip_name], depth=3e-3 if tip_name == "paraboloid" else 2e-3,
        speed=SPEEDS[int(rng.integers(3))] / 6e4, hold_time=rng.uniform(5.0, 15.0),
        rate=800.0, z_surf=truth["z_surf"], noise_sd=0.008, phi=rng.uniform(0.0, 0.6),
        offset=rng.uniform(-0.05, 0.05), rng=rng, trace_id=f"{model}-{i}")
    return trace, truth, tip_name


#: Label of the power-law records fitted over the whole cycle (the retract by Ting's rule).
WHOLE = "power-law, with retract"


def fit_whole(i: int) -> list[dict]:
    """The ``i``-th power-law record fitted over approach, hold and retract: its rows."""
    trace, truth, tip_name = record("power-law", i)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fit = fit_rheology(trace, "power-law", segments="approach,hold,retract", rng=i)
    return _rows(WHOLE, i, tip_name, truth, fit, "power-law",
                 {"choice": "", "elastic_rate_flag": float("nan")})


def _rows(label, i, tip_name, truth, fit, model, per_record) -> list[dict]:
    rows = []
    for name in PARAMETERS[model]:
        d = fit.draws[name]
        lo, med, hi = np.percentile(d, [5.0, 50.0, 95.0])
        rows.append({"model": label, "index": i, "tip": tip_name, "parameter": name,
                     "truth": truth[name], "median": med, "sd": float(np.std(d)), "lo": lo,
                     "hi": hi, "ppc_passed": bool(fit.ppc.passed),
                     "settled": bool(fit.grid.converged),
                     "model_ok": fit.model_ok, "block": fit.data.block,
                     "seconds": fit.seconds, **per_record})
    return rows


def fit_one(job: tuple[str, int] | tuple[str, int, bool]) -> list[dict]:
    """One record's rows: per parameter, the truth, median, sd and 90 % interval; per record,
    the model PSIS-LOO prefers (``"none"`` within two se) and whether the elastic fit's rate
    check fails materially (neither when the job's third item, coverage only, is true)."""
    model, i, alone = (*job, False)[:3]
    if model == WHOLE:
        return fit_whole(i)
    trace, truth, tip_name = record(model, i)
    if alone:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            fit = fit_rheology(trace, model, rng=i)
        return _rows(model, i, tip_name, truth, fit, model,
                     {"choice": "", "elastic_rate_flag": np.nan})
    other = "sls" if model == "power-law" else "power-law"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fit = fit_rheology(trace, model, rng=i)
        rival = fit_rheology(trace, other, rng=i)
        constant = fit_rheology(trace, "elastic", rng=i)  # the same block means, E*(t) = E*
        elastic = fit_bayes(trace, ModelSpec(trace.tip, nu=0.3), engine="exact", seed=i)
    table = compare_rheology({model: fit, other: rival, "elastic": constant})
    preferred = table.loc[table["preferred"], "rheology"]
    rate = next((c for c in elastic.checks if c.name == "rate"), None)
    per_record = {"choice": preferred.iloc[0] if len(preferred) else "none",
                  "elastic_rate_flag": rate is not None and material(rate)}
    return _rows(model, i, tip_name, truth, fit, model, per_record)


def run(n: int, workers: int, models=tuple(PARAMETERS), start: int = 0,
        coverage_only: bool = False) -> pd.DataFrame:
    """Fit records ``start`` … ``start + n − 1`` of each model on ``workers`` processes; one
    row per parameter (``models`` may include :data:`WHOLE`; ``coverage_only``: the true
    model alone)."""
    jobs = [(m, i, coverage_only) for m in models for i in range(start, start + n)]
    if workers > 1:
        ctx = multiprocessing.get_context()  # workers end with this process (procs.lifeline)
        with ProcessPoolExecutor(workers, mp_context=ctx, **lifeline(ctx)) as pool:
            rows = list(pool.map(fit_one, jobs, chunksize=2))
    else:
        rows = [fit_one(j) for j in jobs]
    return pd.DataFrame([r for rs in rows for r in rs])


def table(df: pd.DataFrame) -> pd.DataFrame:
    """Per model and parameter: coverage of the 90 % interval, z-score mean and sd, median
    |relative error| [%], share of passed posterior-predictive checks, of model_ok (the
    check passed and phi not at its bound) and of grids that settled, median fit time [s];
    per model (the same on each of its rows): shares of records where PSIS-LOO prefers the
    true model
    (``choice_true``), the other (``choice_wrong``), and of elastic fits flagged rate
    dependent (``elastic_flagged``)."""
    z = (df["truth"] - df["median"]) / df["sd"]
    df = df.assign(choice=df["choice"].fillna(""))  # "" (NaN once read back): not compared
    df = df.assign(covered=(df["lo"] <= df["truth"]) & (df["truth"] <= df["hi"]), z=z,
                   err_pct=100 * ((df["median"] - df["truth"]) / df["truth"]).abs(),
                   choice_true=(df["choice"] == df["model"]).where(df["choice"] != ""),
                   choice_wrong=((df["choice"] != "none") & (df["choice"] != df["model"])
                                 ).where(df["choice"] != ""))
    g = df.groupby(["model", "parameter"], sort=False)
    return pd.DataFrame({"n": g.size(), "coverage90": g["covered"].mean(),
                         "z_mean": g["z"].mean(), "z_sd": g["z"].std(),
                         "median_err_pct": g["err_pct"].median(),
                         "ppc_passed": g["ppc_passed"].mean(),
                         "model_ok": g["model_ok"].mean(),
                         "settled": g["settled"].mean(),
                         "choice_true": g["choice_true"].mean(),
                         "choice_wrong": g["choice_wrong"].mean(),
                         "elastic_flagged": g["elastic_rate_flag"].mean(),
                         "median_seconds": g["seconds"].median()}).round(3)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=100, help="records per model")
    ap.add_argument("--start", type=int, default=0, help="index of the first record")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--csv", help="write the per-record rows here")
    ap.add_argument("--retract", action="store_true",
                    help="also fit the power-law records over the whole cycle (Ting's rule)")
    ap.add_argument("--coverage-only", action="store_true",
                    help="fit the true model alone (no model choice, no elastic fit)")
    a = ap.parse_args(argv)
    if a.n < 1 or a.start < 0:
        ap.error(f"--n {a.n} must be >= 1 and --start {a.start} >= 0")
    df = run(a.n, a.workers, tuple(PARAMETERS) + ((WHOLE,) if a.retract else ()), a.start,
             a.coverage_only)
    if a.csv:
        df.to_csv(a.csv, index=False)
    with pd.option_context("display.width", 120):
        print(table(df).to_string())


if __name__ == "__main__":
    main()
