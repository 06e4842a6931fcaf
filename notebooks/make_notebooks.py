"""Write the example notebooks of palpbayes (outputs empty) with nbformat.

Run from anywhere: ``python notebooks/make_notebooks.py``.  The committed ``.ipynb`` files are
this script's output; edit the cells here, not in Jupyter, and regenerate.
``tests/integration/test_notebooks.py`` executes them.
"""

from __future__ import annotations

from pathlib import Path

import nbformat
from nbformat.v4 import new_code_cell, new_markdown_cell, new_notebook

HERE = Path(__file__).resolve().parent

KERNEL = {"display_name": "Python 3", "language": "python", "name": "python3"}


def _nb(cells: list) -> nbformat.NotebookNode:
    nb = new_notebook(cells=cells)
    nb.metadata["kernelspec"] = KERNEL
    nb.metadata["language_info"] = {"name": "python"}
    return nb


def md(text: str):
    return new_markdown_cell(text.strip("\n"))


def code(text: str):
    return new_code_cell(text.strip("\n"))


# ----------------------------------------------------------------------------- 01

NB01 = [
    md("""
# 01 · The paper's uncertainty tables on the shipped campaign

This notebook runs the whole pipeline on the example campaign shipped in `data/example-campaign`
(27 synthetic palpation traces: 3 foams × 3 tips × 3 repetitions, plus 5 simulated Instron
compression tests per foam; see `data/README.md`) and shows the tables the robotic palpation
paper reports — modulus ± sd per material and tip, error against the compression ground truth —
next to what the Bayesian model adds: intervals that cover the ground truth, pooling of the
repetitions and an uncertainty budget.

**Same numbers as the command line.**  The fit options are built by the CLI's own parser with
its defaults and `--seed 0`, so the tables below are exactly those of

```
palpbayes report                      # or, step by step:
palpbayes fit data/example-campaign/manifest.csv --out DIR --method both --seed 0
palpbayes compare DIR
```

(`tests/integration/test_notebooks.py` executes this notebook and checks that its `comparison.csv` equals
the CLI's.)

**Runtime.** Fitting the 27 traces takes about 1.5 min on two cores (about 3 s per trace and
method), pooling and comparing about 30 s.  Nothing is shortened: these are the package
defaults.  Set the environment variable `PALPBAYES_NB_OUT` to keep the results folder (a
folder fitted before with the same options is reused); by default a temporary folder is used.
"""),
    code("""
%matplotlib inline
import os
import tempfile
import time
import warnings
from pathlib import Path

import pandas as pd
from IPython.display import display

import palpbayes
from palpbayes import plots
from palpbayes.cli import build_parser
from palpbayes.cli.fit import options_from_args
from palpbayes.compare import format_comparison, paper_estimates
from palpbayes.pipeline import example_campaign_dir, run_pipeline
from palpbayes.report import summary_table
from palpbayes.results import load_results

from tqdm import TqdmWarning

pd.set_option("display.width", 160)
warnings.simplefilter("ignore", TqdmWarning)  # tqdm.auto without ipywidgets; bars are off
print("palpbayes", palpbayes.__version__)
"""),
    md("""
## Settings

`SEED` is the base seed of every fit (each trace's seed is derived from it and the trace id,
so the results do not depend on the number of worker processes).
"""),
    code("""
SEED = 0
WORKERS = int(os.environ.get("PALPBAYES_NB_WORKERS", "2"))
CAMPAIGN = example_campaign_dir()
OUT = Path(os.environ.get("PALPBAYES_NB_OUT") or tempfile.mkdtemp(prefix="palpbayes-nb01-"))

# exactly the options of `palpbayes report --seed 0` (both methods, package defaults)
args = build_parser().parse_args(["report", "--seed", str(SEED)])
options = options_from_args(args)
print(options)
"""),
    md("""
## Fit, ground truth, pooling and comparison

`run_pipeline` is what `palpbayes report CAMPAIGN` runs: the least-squares baseline and the
Bayesian model on every trace (`palpbayes fit`), the compression tests
(`palpbayes groundtruth`), then pooling and comparison (`palpbayes compare`).
"""),
    code("""
t0 = time.perf_counter()
run_pipeline(CAMPAIGN / "manifest.csv", OUT, options, workers=WORKERS, progress=False)
print(f"fitted, pooled and compared in {time.perf_counter() - t0:.0f} s; results in {OUT}")
res = load_results(OUT)
"""),
    md("""
## Ground truth

Uniaxial compression of five blocks per foam; the modulus is the slope of stress vs strain
over the toe-compensated 0–5 % window, and the material's ground truth is the mean ± sd over
its blocks.
"""),
    code("""
gt = res.groundtruth_summary.copy()
gt_kpa = pd.DataFrame({
    "material": gt["material"], "n": gt["n"],
    "E mean [kPa]": (gt["E_mean_pa"] / 1e3).round(1), "E sd [kPa]": (gt["E_sd_pa"] / 1e3).round(1),
    "window": [f"{100 * a:g}-{100 * b:g} %" for a, b in zip(gt["window_lo"], gt["window_hi"])],
})
display(gt_kpa)
"""),
    md("""
## Table III: ground truth vs least squares vs Bayes

The layout of the paper's Table III, as on the report's summary page.  *LS* is the paper's
constrained least squares, mean ± sd over the three repetitions; *Bayes material E* the
hierarchical pooling of the per-trace posteriors with the uncertainty budget (median ± sd of
the **material's modulus**).  *new specimen 90 %* is the interval for a **new specimen** —
least squares' t prediction interval, Bayes' posterior predictive — which is what should
contain the ground truth: every compression block and every palpated location is one draw from
the material.  `err` = (GT − E)/GT as in the paper; *Paper* are the published robot numbers,
with the paper's error relative to the paper's own Instron ground truth.  *Hertz LS* is the
paper's choice for the sphere (least squares with the Hertz law at the sphere's radius on the
same traces) and its difference from the exact Sneddon law.  `(!)` marks a group whose pooled
chain or a trace fit did not pass the convergence checks.
"""),
    code("""
table3 = summary_table(res)
display(table3)
"""),
    md("""
The two Bayesian quantities side by side: the pooled **material** modulus (what the report's
*Bayes material E ± sd* shows) and the posterior predictive for a **new specimen** (wider: it
adds the scatter between specimens, tau).  The text layout of `palpbayes compare` below prints
the new-specimen prediction in its *Bayes* cells.
"""),
    code("""
bay = res.comparison[res.comparison["method"] == "bayes"]
display(pd.DataFrame({
    "material": bay["material"], "tip": bay["tip"],
    "Bayes material E ± sd [kPa]": [f"{e / 1e3:.1f} ± {s / 1e3:.1f}"
                                    for e, s in zip(bay["E_pa"], bay["E_sd_pa"])],
    "Bayes new specimen E ± sd [kPa]": [f"{e / 1e3:.1f} ± {s / 1e3:.1f}"
                                        for e, s in zip(bay["E_new_pa"], bay["E_new_sd_pa"])],
}))
"""),
    code("""
# the ground truth analysed by run_pipeline: the campaign's compression tests
gt_source = f"{CAMPAIGN / 'groundtruth'} (analysed; {OUT / 'groundtruth_summary.csv'})"
print(format_comparison(res.comparison, groundtruth_source=gt_source))
"""),
    md("""
## How often the intervals cover the ground truth
"""),
    code("""
cmp = res.comparison
cover = (cmp.assign(covered=cmp["gt_in_interval"].astype(str).str.lower() == "true")
            .groupby("method")["covered"].agg(["sum", "count"]))
cover["coverage"] = (cover["sum"] / cover["count"]).round(2)
display(cover)
width = (cmp.assign(width_kPa=(cmp["E_new_hi_pa"] - cmp["E_new_lo_pa"]) / 1e3)
            .pivot_table(index=["material", "tip"], columns="method", values="width_kPa",
                         sort=False).round(1))
display(width.rename(columns=lambda c: f"{c}: new-specimen 90 % width [kPa]"))
"""),
    md("""
## The paper's published robot estimates

For reference (not refitted: the paper's data are not public).  The printed sphere errors do not
follow from the printed values; `paper_err_pct` is recomputed.
"""),
    code("""
paper = paper_estimates()
display(pd.DataFrame({
    "material": paper["material"], "tip": paper["tip"],
    "E [kPa]": paper["paper_E_pa"] / 1e3, "sd [kPa]": paper["paper_sd_pa"] / 1e3,
    "err [%]": paper["paper_err_pct"].round(1)}))
"""),
    md("""
## Pooling and the uncertainty budget

`tau` is the between-trace sd of log E (≈ coefficient of variation).  The budget gives each
input's share of the variance of ln E of the pooled estimate: with three repetitions the
uncertainty of the material's mean (`mu`) dominates; the Poisson ratio is the largest
systematic input.
"""),
    code("""
pooled = res.pooled
display(pd.DataFrame({
    "material": pooled["material"], "tip": pooled["tip"], "n": pooled["n_traces"],
    "tau": pooled["tau"].round(3),
    "E [kPa]": (pooled["E_pa"] / 1e3).round(1),
    "E 90 % [kPa]": [f"[{a / 1e3:.1f}, {b / 1e3:.1f}]"
                     for a, b in zip(pooled["E_lo_pa"], pooled["E_hi_pa"])],
    "new specimen 90 % [kPa]": [f"[{a / 1e3:.1f}, {b / 1e3:.1f}]"
                                for a, b in zip(pooled["E_new_lo_pa"], pooled["E_new_hi_pa"])],
    "R-hat": pooled["rhat_max"].round(4), "converged": pooled["converged"],
}))
budget = res.budget
display(budget.pivot_table(index=["material", "tip"], columns="input", values="share_pct",
                           sort=False).round(1))
"""),
    code("""
fig = plots.plot_comparison(res.comparison)
display(fig)
fig = plots.plot_budget(res.budget)
display(fig)
"""),
    md("""
The complete report of this folder (all pages) is `palpbayes report RESULTS_DIR -o FILE.pdf`;
the repository ships it as `reports/example-report.pdf`.
"""),
    code("""
print(f"comparison table: {OUT / 'comparison.csv'}")
"""),
]

# ----------------------------------------------------------------------------- 02

NB02 = [
    md("""
# 02 · Least squares vs Bayes on the same traces, and what misspecification does

Three simulated traces, each fitted by the paper's least squares (`palpbayes.lsq`) and by the
Bayesian model (`palpbayes.bayes`):

1. a well-specified trace (white noise, Hertz paraboloid): both agree, and the intervals are
   honest about the noise;
2. **correlated noise**: 800 Hz force samples are not independent.  Traces with AR(1) noise
   (phi = 0.9) fitted with the iid model (least squares and Bayes) and with the AR(1) noise
   model;
3. **the wrong contact law**: a sphere (exact Sneddon law) fitted with Hertz, as the paper did,
   and with the exact law.

Only the *statistical* uncertainty is compared here (`BudgetSpec.none()`: Poisson ratio, tip
radius, gain and compliance fixed), because that is the part misspecification distorts; the
budget adds a few per cent on top (notebook 01).

**Runtime** about 2 min on one core: the AR(1) study uses only **4 replicate traces** (small on
purpose, enough to show the effect, not to estimate a coverage probability; the calibration
tests in `tests/statistical/test_calibration.py` do that properly).
"""),
    code("""
%matplotlib inline
import time
import warnings

import numpy as np
import pandas as pd
from IPython.display import display

from palpbayes import plots
from palpbayes.bayes import BudgetSpec, fit_bayes_data
from palpbayes.contact import Tip
from palpbayes.errors import ConvergenceWarning
from palpbayes.fitdata import ModelSpec, prepare
from palpbayes.lsq import fit_lsq_data
from palpbayes.paper import PAPER_TIPS
from palpbayes.sim import simulate_trace

pd.set_option("display.width", 160)
NO_BUDGET = BudgetSpec.none()


def fit_both(trace, tip, noise="gaussian", seed=0):
    \"\"\"Least squares and Bayes on the same fitted points; returns (lsq, bayes).\"\"\"
    data = prepare(trace, ModelSpec(tip))
    lsq = fit_lsq_data(data, trace_id=trace.trace_id)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)  # reported in the table instead
        bayes = fit_bayes_data(data, noise=noise, budget=NO_BUDGET, seed=seed, lsq=lsq,
                               trace_id=trace.trace_id)
    return lsq, bayes


def row(label, E_true, E, lo, hi, converged=None):
    return {"fit": label, "E [kPa]": E / 1e3,
            "90 % interval [kPa]": f"[{lo / 1e3:.2f}, {hi / 1e3:.2f}]",
            "width [kPa]": (hi - lo) / 1e3, "error [%]": 100 * (E - E_true) / E_true,
            "covers truth": lo <= E_true <= hi, "converged": converged}
"""),
    md("""
## 1. A well-specified trace

Pink foam (E = 136 kPa, 20 mm thick), paraboloid tip R = 11.7 mm, 2 mm deep at 50 mm/min,
800 Hz, white noise 48 mN peak-to-peak (sigma = 8 mN) — the package's default model is the true
one.
"""),
    code("""
E_TRUE = 136e3
tip = PAPER_TIPS["paraboloid"]
trace = simulate_trace(E_TRUE, tip, thickness=0.020, rng=1, trace_id="pink_paraboloid")
lsq, bayes = fit_both(trace, tip, seed=1)
s = bayes.summary_row()
display(pd.DataFrame([
    row("least squares", E_TRUE, lsq.E, lsq.E_lo, lsq.E_hi),
    row("Bayes (iid Gaussian)", E_TRUE, s["E_pa"], s["E_lo_pa"], s["E_hi_pa"], s["converged"]),
]).round(3))
display(bayes.summary())
"""),
    code("""
display(plots.plot_force_depth(bayes))
display(plots.plot_residuals(bayes))
display(plots.plot_posterior(bayes, truth={"E": E_TRUE, "z_surf": trace.metadata["z_surf_true"]}))
display(plots.plot_walkers(bayes))
"""),
    md("""
The least-squares surface sits above the Bayesian one: least squares has no force offset, so
the measured offset pushes its contact point; the Bayesian model fits the offset F0 and the
residuals before contact are centred.  Both moduli are within a fraction of a per cent of the
truth, and the strong negative correlation of E with z_surf is what sets the statistical
uncertainty.

## 2. Correlated noise: AR(1) with phi = 0.9, fitted as if iid

The same trace design with AR(1) noise of the same marginal sd.  With phi = 0.9 the effective
number of independent samples is about (1 − phi)/(1 + phi) ≈ 5 % of the samples, so an
interval that assumes independence is too narrow by about a factor sqrt(19) ≈ 4.4.
"""),
    code("""
PHI = 0.9
N_REP = 4   # small on purpose (runtime); not a coverage estimate
rows = []
t0 = time.perf_counter()
for k in range(N_REP):
    tr = simulate_trace(E_TRUE, tip, thickness=0.020, noise_ar1=PHI, rng=100 + k,
                        trace_id=f"ar1_{k}")
    lsq_k, iid = fit_both(tr, tip, "gaussian", seed=k)
    _, ar1 = fit_both(tr, tip, "ar1", seed=k)
    data_k = prepare(tr, ModelSpec(tip))
    resid = data_k.force - lsq_k.Estar * data_k.shape(lsq_k.z_surf - data_k.z)
    rows.append({"trace": k, **row("least squares", E_TRUE, lsq_k.E, lsq_k.E_lo, lsq_k.E_hi),
                 "lag-1 residual corr.": np.corrcoef(resid[1:], resid[:-1])[0, 1]})
    s = iid.summary_row()
    rows.append({"trace": k, **row("Bayes, iid model", E_TRUE, s["E_pa"], s["E_lo_pa"],
                                   s["E_hi_pa"], s["converged"])})
    s = ar1.summary_row()
    rows.append({"trace": k, **row("Bayes, AR(1) model", E_TRUE, s["E_pa"], s["E_lo_pa"],
                                   s["E_hi_pa"], s["converged"]),
                 "phi (posterior median)": float(np.median(ar1.draws("phi")))})
print(f"{3 * N_REP} fits in {time.perf_counter() - t0:.0f} s")
ar = pd.DataFrame(rows)
display(ar.round(3))
"""),
    code("""
summary = ar.groupby("fit", sort=False).agg(
    mean_width_kPa=("width [kPa]", "mean"), covered=("covers truth", "sum"),
    of=("covers truth", "size"), mean_abs_error_pct=("error [%]", lambda e: np.abs(e).mean()))
display(summary.round(3))
"""),
    md("""
The point estimates barely move, but the iid intervals (least squares and Bayes alike) are
several times narrower than the AR(1) ones and miss the truth whenever the correlated noise
shifts the estimate by more than their width.  The AR(1) model recovers phi and widens the
interval by about the factor above.  The lag-one correlation of the least-squares residuals is
the diagnostic: near 0 for white noise, near phi here.  (`palpbayes fit --noise ar1`.)

## 3. The wrong contact law: a sphere fitted with Hertz

The paper fitted its 10 mm sphere with the Hertz (paraboloid) law.  At d/R = 0.2 (2 mm into
a 20 mm foam) the exact Sneddon sphere needs less force than Hertz, so Hertz reads the modulus
low.  Simulated with the exact law, fitted with both:
"""),
    code("""
sphere = Tip("sphere", radius=0.010)
hertz = Tip("paraboloid", radius=0.010)
tr = simulate_trace(E_TRUE, sphere, thickness=0.020, rng=7, trace_id="sphere")
rows = []
fits = {}
for label, model_tip in (("exact sphere (Sneddon)", sphere), ("Hertz, as the paper", hertz)):
    lsq_s, bayes_s = fit_both(tr, model_tip, seed=7)
    fits[label] = bayes_s
    s = bayes_s.summary_row()
    rows.append(row(f"least squares, {label}", E_TRUE, lsq_s.E, lsq_s.E_lo, lsq_s.E_hi))
    rows.append(row(f"Bayes, {label}", E_TRUE, s["E_pa"], s["E_lo_pa"], s["E_hi_pa"],
                    s["converged"]))
display(pd.DataFrame(rows).round(3))
"""),
    code("""
from matplotlib.figure import Figure

fig = Figure(figsize=(11, 3.8), layout="constrained")
axes = fig.subplots(1, 2, sharey=True)
for ax, (label, b) in zip(axes, fits.items()):
    plots.plot_residuals(b, ax=ax)
    ax.set_title(f"fitted with: {label}", fontsize="medium")
display(fig)
"""),
    md("""
With the wrong law the estimate is biased by a few per cent while its interval stays a
fraction of a per cent wide: no amount of data fixes a model error.  The residuals barely hint
at it — a systematic wave of a few mN in the binned mean, well inside the ±2 sigma noise band —
so a good-looking fit is no evidence that the contact law is right.  The tip `sphere` in
palpbayes is the exact law; the paper's choice is `paraboloid` with the sphere's radius.
"""),
]

# ----------------------------------------------------------------------------- 03

NB03 = [
    md("""
# 03 · Stiffening after repeated palpation

Foam palpated again without enough rest is stiffer; the paper describes the modulus after a rest
t since the previous excitation by E(t) = c1·e^(c2·t) + c3·e^(c4·t).  Here a series of
palpations of one specimen is simulated with `simulate_palpation_series` (the default law: the
rested modulus E0 plus 25 % right after an excitation, relaxing with a 30 s time constant,
i.e. c = (E0, 0, 0.25·E0, −1/30 s⁻¹)), each palpation is fitted with the Bayesian model
through the campaign runner, and the law is fitted to the estimates with
`palpbayes.stiffening.fit_stiffening_summary`.

**Settings kept small for runtime** (about 1–2 min on two cores): 13 palpations of one
specimen, paraboloid tip, 2 mm deep, package-default sampler.  The stiffening fit uses the
*statistical* E of each palpation (the budget's systematic inputs scale the whole curve, not
its shape).
"""),
    code("""
%matplotlib inline
import os
import tempfile
import time
import warnings

import numpy as np
import pandas as pd
from IPython.display import display

from palpbayes import plots
from palpbayes.campaign import fit_campaign
from palpbayes.fitjob import FitOptions
from palpbayes.paper import PAPER_TIPS
from palpbayes.sim import rest_modulus, simulate_palpation_series
from palpbayes.stiffening import fit_stiffening_summary
from tqdm import TqdmWarning

pd.set_option("display.width", 160)
warnings.simplefilter("ignore", TqdmWarning)  # tqdm.auto without ipywidgets; bars are off
"""),
    code("""
E0 = 136e3                                   # rested modulus [Pa] (Pink foam)
C_TRUE = (E0, 0.0, 0.25 * E0, -1.0 / 30.0)   # the simulator's default law
REST = [None, 1, 2, 4, 7, 10, 15, 20, 30, 45, 60, 90, 120]   # None: a fully rested specimen
tip = PAPER_TIPS["paraboloid"]
traces = simulate_palpation_series(E0, tip, REST, C_TRUE, rng=3, trace_prefix="pink",
                                   material="Pink", specimen="Pink_1", thickness=0.020)
pd.DataFrame({"trace": [t.trace_id for t in traces], "rest [s]": [t.rest_time for t in traces],
              "true E [kPa]": [t.metadata["E_rest_law"] / 1e3 for t in traces]}).round(2)
"""),
    code("""
OUT = tempfile.mkdtemp(prefix="palpbayes-nb03-")
t0 = time.perf_counter()
summary = fit_campaign(traces, OUT, FitOptions(method="bayes", seed=0),
                       workers=int(os.environ.get("PALPBAYES_NB_WORKERS", "2")), progress=False)
print(f"{len(traces)} Bayesian fits in {time.perf_counter() - t0:.0f} s; "
      f"all converged: {bool(summary['converged'].all())}")
summary[["trace_id", "rest_time_s", "E_stat_pa", "E_stat_sd_pa", "converged"]]
"""),
    code("""
t0 = time.perf_counter()
stiff = fit_stiffening_summary(summary, method="bayes", seed=0)
print(f"stiffening fit in {time.perf_counter() - t0:.0f} s; preferred law: {stiff.preferred}")
print(stiff.message)
"""),
    md("""
With c2 = 0 the true law is one exponential plus a constant, so the double exponential cannot
be identified (its second time scale has nothing to resolve); the fit says so and prefers
E = c0 + c1·e^(c2·t).  Its parameters against the truth (c0 = E0, c1 = 0.25·E0, c2 = −1/30 s⁻¹):
"""),
    code("""
tab = stiff.single.copy()
truth = {"c0": C_TRUE[0], "c1": C_TRUE[2], "c2": C_TRUE[3]}   # sigma_x: true 0, on the bound
tab["true"] = tab["parameter"].map(truth)
tab["covers"] = [(lo <= t <= hi) if np.isfinite(t) else None
                 for lo, t, hi in zip(tab["lo"], tab["true"], tab["hi"])]
display(tab)
display(stiff.double)
"""),
    code("""
rows = summary[np.isfinite(summary["rest_time_s"].astype(float))]
fresh = summary[~np.isfinite(summary["rest_time_s"].astype(float))].iloc[0]
t_grid = np.linspace(0, 130, 300)
fig = plots.plot_stiffening(
    rows["rest_time_s"], rows["E_stat_pa"], E_lo=rows["E_stat_lo_pa"], E_hi=rows["E_stat_hi_pa"],
    fit=stiff, truth=(t_grid, rest_modulus(t_grid, C_TRUE)),
    rested=(fresh["E_stat_pa"], fresh["E_stat_lo_pa"], fresh["E_stat_hi_pa"]))
display(fig)
"""),
    md("""
The grey band is the fully rested palpation (its 90 % interval).  The per-palpation intervals
are the statistical ones of single traces (a fraction of a per cent), so the scatter of the
points about the law is the noise of each trace plus the extra scatter `sigma_x` the model
estimates.
"""),
]


def main() -> None:
    for name, cells in (("01_paper_tables.ipynb", NB01), ("02_lsq_vs_bayes.ipynb", NB02),
                        ("03_stiffening.ipynb", NB03)):
        nb = _nb(cells)
        nbformat.validate(nb)
        nbformat.write(nb, HERE / name)
        print(f"wrote {HERE / name}")


if __name__ == "__main__":
    main()
