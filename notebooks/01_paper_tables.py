# ---
# jupyter:
#   jupytext:
#     formats: ipynb,py:percent
#     text_representation:
#       extension: .py
#       format_name: percent
#       format_version: '1.3'
#       jupytext_version: 1.19.6
#   kernelspec:
#     display_name: Python 3
#     language: python
#     name: python3
# ---

# %% [markdown]
# # 01 · The paper's uncertainty tables on the shipped campaign
#
# This notebook runs the whole pipeline on the example campaign shipped in `data/example-campaign`
# (27 synthetic palpation traces: 3 foams × 3 tips × 3 repetitions, plus 5 simulated Instron
# compression tests per foam; see `data/README.md`) and shows the tables the robotic palpation
# paper reports — modulus ± sd per material and tip, error against the compression ground truth —
# next to what the Bayesian model adds: intervals that cover the ground truth, pooling of the
# repetitions and an uncertainty budget.
#
# **Same numbers as the command line.**  The fit options are built by the CLI's own parser with
# its defaults and `--seed 0`, so the tables below are exactly those of
#
# ```
# palpbayes report                      # or, step by step:
# palpbayes fit data/example-campaign/manifest.csv --out DIR --method both --seed 0
# palpbayes compare DIR
# ```
#
# (`tests/integration/test_notebooks.py` executes this notebook and checks that its `comparison.csv` equals
# the CLI's.)
#
# **Runtime.** Fitting the 27 traces takes about 1.5 min on two cores (about 3 s per trace and
# method), pooling and comparing about 30 s.  Nothing is shortened: these are the package
# defaults.  Set the environment variable `PALPBAYES_NB_OUT` to keep the results folder (a
# folder fitted before with the same options is reused); by default a temporary folder is used.

# %%
# %matplotlib inline
import os
import tempfile
import time
import warnings
from pathlib import Path

import pandas as pd
from IPython.display import display

import palpbayes as pb
from palpbayes import plots
from palpbayes.reporting import format_comparison, paper_estimates, summary_table

from tqdm import TqdmWarning

pd.set_option("display.width", 160)
warnings.simplefilter("ignore", TqdmWarning)  # tqdm.auto without ipywidgets; bars are off
print("palpbayes", pb.__version__)

# %% [markdown]
# ## Settings
#
# `SEED` is the base seed of every fit (each trace's seed is derived from it and the trace id,
# so the results do not depend on the number of worker processes).

# %%
SEED = 0
WORKERS = int(os.environ.get("PALPBAYES_NB_WORKERS", "2"))
CAMPAIGN = pb.example_campaign_dir()
OUT = Path(os.environ.get("PALPBAYES_NB_OUT") or tempfile.mkdtemp(prefix="palpbayes-nb01-"))

# the options of `palpbayes report --seed 0` (both methods, package defaults): the command
# line builds its options with the same function
options = pb.fit_options(method="both", seed=SEED)
print(options)

# %% [markdown]
# ## Fit, ground truth, pooling and comparison
#
# `run_pipeline` is what `palpbayes report CAMPAIGN` runs: the least-squares baseline and the
# Bayesian model on every trace (`palpbayes fit`), the compression tests
# (`palpbayes groundtruth`), then pooling and comparison (`palpbayes compare`).

# %%
t0 = time.perf_counter()
pb.run_pipeline(CAMPAIGN / "manifest.csv", OUT, options, workers=WORKERS, progress=False)
print(f"fitted, pooled and compared in {time.perf_counter() - t0:.0f} s; results in {OUT}")
res = pb.load_results(OUT)

# %% [markdown]
# ## Ground truth
#
# Uniaxial compression of five blocks per foam; the modulus is the slope of stress vs strain
# over the toe-compensated 0–5 % window, and the material's ground truth is the mean ± sd over
# its blocks.  As in a real laboratory without lubricant, the example's blocks were compressed
# between **bonded platens** (`data/README.md`): their faces cannot expand, so the tests read
# c·E with c = 1.11 (30 mm) and 1.16 (20 mm) at nu 0.3, not E.  The fits know each block's
# footprint and report beside E what such a test would read (`E_instron`); the last table
# below compares the two like for like (notebook 04 shows how).

# %%
gt = res.groundtruth_summary.copy()
gt_kpa = pd.DataFrame({
    "material": gt["material"], "n": gt["n"],
    "E mean [kPa]": (gt["E_mean_pa"] / 1e3).round(1), "E sd [kPa]": (gt["E_sd_pa"] / 1e3).round(1),
    "window": [f"{100 * a:g}-{100 * b:g} %" for a, b in zip(gt["window_lo"], gt["window_hi"])],
})
display(gt_kpa)

# %% [markdown]
# ## Table III: ground truth vs least squares vs Bayes
#
# The layout of the paper's Table III, as on the report's summary page.  *LS* is the paper's
# constrained least squares, mean ± sd over the three repetitions; *Bayes material E* the
# hierarchical pooling of the per-trace posteriors with the uncertainty budget (median ± sd of
# the **material's modulus**).  *new specimen 90 %* is the interval for a **new specimen** —
# least squares' t prediction interval, Bayes' posterior predictive — which is what should
# contain the ground truth: every compression block and every palpated location is one draw from
# the material.  `err` = (GT − E)/GT as in the paper; *Paper* are the published robot numbers,
# with the paper's error relative to the paper's own Instron ground truth.  *Hertz LS* is the
# paper's choice for the sphere (least squares with the Hertz law at the sphere's radius on the
# same traces) and its difference from the exact Sneddon law.  `(!)` marks a group whose pooled
# chain or a trace fit did not pass the convergence checks.

# %%
table3 = summary_table(res)
display(table3)

# %% [markdown]
# The two Bayesian quantities side by side: the pooled **material** modulus (what the report's
# *Bayes material E ± sd* shows) and the posterior predictive for a **new specimen** (wider: it
# adds the scatter between specimens, tau).  The text layout of `palpbayes compare` below prints
# the new-specimen prediction in its *Bayes* cells.

# %%
bay = res.comparison[res.comparison["method"] == "bayes"]
display(pd.DataFrame({
    "material": bay["material"], "tip": bay["tip"],
    "Bayes material E ± sd [kPa]": [f"{e / 1e3:.1f} ± {s / 1e3:.1f}"
                                    for e, s in zip(bay["E_pa"], bay["E_sd_pa"])],
    "Bayes new specimen E ± sd [kPa]": [f"{e / 1e3:.1f} ± {s / 1e3:.1f}"
                                        for e, s in zip(bay["E_new_pa"], bay["E_new_sd_pa"])],
}))

# %%
# the ground truth analysed by run_pipeline: the campaign's compression tests
gt_source = f"{CAMPAIGN / 'groundtruth'} (analysed; {OUT / 'groundtruth_summary.csv'})"
print(format_comparison(res.comparison, groundtruth_source=gt_source))

# %% [markdown]
# ## How often the intervals cover the ground truth

# %%
cmp = res.comparison
cover = (cmp.assign(covered=cmp["gt_in_new_interval"].astype(str).str.lower() == "true")
            .groupby("method")["covered"].agg(["sum", "count"]))
cover["coverage"] = (cover["sum"] / cover["count"]).round(2)
display(cover)
like = cmp[cmp["method"] == "bayes"]
print("like for like: the Bayesian Instron-equivalent interval of a new specimen covers the "
      f"Instron's reading in {int(like['gt_in_instron_interval'].astype(bool).sum())}"
      f"/{len(like)} groups (E itself, against a reading made between bonded platens: "
      f"{int(like['gt_in_new_interval'].astype(bool).sum())}/{len(like)})")
width = (cmp.assign(width_kPa=(cmp["E_new_hi_pa"] - cmp["E_new_lo_pa"]) / 1e3)
            .pivot_table(index=["material", "tip"], columns="method", values="width_kPa",
                         sort=False).round(1))
display(width.rename(columns=lambda c: f"{c}: new-specimen 90 % width [kPa]"))

# %% [markdown]
# ## The paper's published robot estimates
#
# For reference (not refitted: the paper's data are not public).  The printed sphere errors do not
# follow from the printed values; `paper_err_pct` is recomputed.

# %%
paper = paper_estimates()
display(pd.DataFrame({
    "material": paper["material"], "tip": paper["tip"],
    "E [kPa]": paper["paper_E_pa"] / 1e3, "sd [kPa]": paper["paper_sd_pa"] / 1e3,
    "err [%]": paper["paper_err_pct"].round(1)}))

# %% [markdown]
# ## Pooling and the uncertainty budget
#
# `tau` is the between-trace sd of log E (≈ coefficient of variation).  The budget gives each
# input's share of the variance of ln E of the pooled estimate: with three repetitions the
# uncertainty of the material's mean (`mu`) dominates; the Poisson ratio is the largest
# systematic input.

# %%
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

# %%
fig = plots.plot_comparison(res.comparison)
display(fig)
fig = plots.plot_budget(res.budget)
display(fig)

# %% [markdown]
# The complete report of this folder (all pages) is `palpbayes report RESULTS_DIR -o FILE.pdf`;
# the repository ships it as `reports/example-report.pdf`.

# %%
print(f"comparison table: {OUT / 'comparison.csv'}")
