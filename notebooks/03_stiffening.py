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
# # 03 · Stiffening after repeated palpation
#
# Foam palpated again without enough rest is stiffer; the paper describes the modulus after a rest
# t since the previous excitation by E(t) = c1·e^(c2·t) + c3·e^(c4·t).  Here a series of
# palpations of one specimen is simulated with `simulate_palpation_series` (the default law: the
# rested modulus E0 plus 25 % right after an excitation, relaxing with a 30 s time constant,
# i.e. c = (E0, 0, 0.25·E0, −1/30 s⁻¹)), each palpation is fitted with the Bayesian model
# through the campaign runner, and the law is fitted to the estimates with
# `palpbayes.stiffening.fit_stiffening_summary`.
#
# **Settings kept small for runtime** (about 1–2 min on two cores): 13 palpations of one
# specimen, paraboloid tip, 2 mm deep, package-default sampler.  The stiffening fit uses the
# *statistical* E of each palpation (the budget's systematic inputs scale the whole curve, not
# its shape).

# %%
# %matplotlib inline
import os
import tempfile
import time
import warnings

import numpy as np
import pandas as pd
from IPython.display import display

import palpbayes as pb
from palpbayes import plots
from palpbayes.paper import PAPER_TIPS
from palpbayes.sim import rest_modulus, simulate_palpation_series
from palpbayes.stiffening import fit_stiffening_summary
from tqdm import TqdmWarning

pd.set_option("display.width", 160)
warnings.simplefilter("ignore", TqdmWarning)  # tqdm.auto without ipywidgets; bars are off

# %%
E0 = 136e3                                   # rested modulus [Pa] (Pink foam)
C_TRUE = (E0, 0.0, 0.25 * E0, -1.0 / 30.0)   # the simulator's default law
REST = [None, 1, 2, 4, 7, 10, 15, 20, 30, 45, 60, 90, 120]   # None: a fully rested specimen
tip = PAPER_TIPS["paraboloid"]
traces = simulate_palpation_series(E0, tip, REST, C_TRUE, rng=3, trace_prefix="pink",
                                   material="Pink", specimen="Pink_1", thickness=0.020)
pd.DataFrame({"trace": [t.trace_id for t in traces], "rest [s]": [t.rest_time for t in traces],
              "true E [kPa]": [t.metadata["E_rest_law"] / 1e3 for t in traces]}).round(2)

# %%
OUT = tempfile.mkdtemp(prefix="palpbayes-nb03-")
t0 = time.perf_counter()
summary = pb.fit_campaign(traces, OUT, pb.fit_options(method="bayes", seed=0),
                       workers=int(os.environ.get("PALPBAYES_NB_WORKERS", "2")), progress=False)
print(f"{len(traces)} Bayesian fits in {time.perf_counter() - t0:.0f} s; "
      f"all converged: {bool(summary['converged'].all())}")
summary[["trace_id", "rest_time_s", "E_stat_pa", "E_stat_sd_pa", "converged"]]

# %%
t0 = time.perf_counter()
stiff = fit_stiffening_summary(summary, method="bayes", seed=0)
print(f"stiffening fit in {time.perf_counter() - t0:.0f} s; preferred law: {stiff.preferred}")
print(stiff.message)

# %% [markdown]
# With c2 = 0 the true law is one exponential plus a constant, so the double exponential cannot
# be identified (its second time scale has nothing to resolve); the fit says so and prefers
# E = c0 + c1·e^(c2·t).  Its parameters against the truth (c0 = E0, c1 = 0.25·E0, c2 = −1/30 s⁻¹):

# %%
tab = stiff.single.copy()
truth = {"c0": C_TRUE[0], "c1": C_TRUE[2], "c2": C_TRUE[3]}   # sigma_x: true 0, on the bound
tab["true"] = tab["parameter"].map(truth)
tab["covers"] = [(lo <= t <= hi) if np.isfinite(t) else None
                 for lo, t, hi in zip(tab["lo"], tab["true"], tab["hi"])]
display(tab)
display(stiff.double)

# %%
rows = summary[np.isfinite(summary["rest_time_s"].astype(float))]
fresh = summary[~np.isfinite(summary["rest_time_s"].astype(float))].iloc[0]
t_grid = np.linspace(0, 130, 300)
fig = plots.plot_stiffening(
    rows["rest_time_s"], rows["E_stat_pa"], E_lo=rows["E_stat_lo_pa"], E_hi=rows["E_stat_hi_pa"],
    fit=stiff, truth=(t_grid, rest_modulus(t_grid, C_TRUE)),
    rested=(fresh["E_stat_pa"], fresh["E_stat_lo_pa"], fresh["E_stat_hi_pa"]))
display(fig)

# %% [markdown]
# The grey band is the fully rested palpation (its 90 % interval).  The per-palpation intervals
# are the statistical ones of single traces (a fraction of a per cent), so the scatter of the
# points about the law is the noise of each trace plus the extra scatter `sigma_x` the model
# estimates.
