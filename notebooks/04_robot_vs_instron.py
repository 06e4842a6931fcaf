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
# # 04 · Why does the robot read stiffer than the Instron?
#
# The paper's robot estimates differ from its Instron values tip by tip: the flat punch reads
# 8–17 % stiffer, the sphere 4–12 % stiffer, the paraboloid 5–10 % softer.  Its foam blocks are
# only 20–30 mm thick under tips of 10–11.7 mm pressed 10 % deep, and the paper fitted them as
# half-spaces.  This notebook asks how much of that gap the tool's own models explain:
#
# 1. **the layer**: how much a block of finite thickness on its plate stiffens each tip's
#    reading, from the exact layer solution (`palpbayes.contact.layer`), for a block bonded to
#    its plate and one lying free on it, checked against the literature's formulas;
# 2. **the decomposition** of the paper's published gap (`palpbayes.gap`): thickness and base,
#    the blocks' finite width and the Instron's platens (the specimen as tested, below), the
#    foam's Poisson ratio, series compliance, the Hertz fit of the sphere, the depth window,
#    against the observed error with its interval — and a verdict per tip;
# 3. **the shipped campaign**, simulated with the paper's 50 × 50 mm blocks lying on a plate:
#    the paper's half-space least squares carries the bottom effect, the Bayesian model with
#    each block's twin (base unknown) recovers E;
# 4. **the specimen as tested**: the finite-element twin of the palpated block and of its
#    compression test (`palpbayes.twin`), and the campaign's palpation set beside its
#    compression tests like for like.
#
# Runtime: about two minutes on two cores (the campaign is fitted with the exact engine; the
# blocks' twins are solved once and cached on disk).

# %%
# %matplotlib inline
import os
import tempfile
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
from IPython.display import display
from matplotlib.figure import Figure
from tqdm import TqdmWarning

import palpbayes as pb
from palpbayes import plots
from palpbayes.contact import dimitriadis_factor, garcia_factor, shape, thickness_factor
from palpbayes.gap import gap_table, gap_verdicts
from palpbayes.paper import PAPER_TIPS
from palpbayes.twin import Specimen, compression_factor, twin_shape

pd.set_option("display.width", 160)
pd.set_option("display.precision", 3)
warnings.simplefilter("ignore", TqdmWarning)
print("palpbayes", pb.__version__)

# %% [markdown]
# ## 1 · How much does a layer stiffen the reading?
#
# The factor F_layer/F_half-space at the paper's depth (10 % of the thickness) for each tip,
# bonded and free, at nu = 0.3 (a foam) and 0.5 (silicone, tissue).  A flat punch's factor does
# not depend on depth (its whole curve is scaled: a shape check cannot see it), a curved tip's
# grows with depth (its curve stiffens: the free-exponent check sees it).

# %%
rows = []
for name, tip in PAPER_TIPS.items():
    for h in (0.02, 0.03):
        d = np.array([0.1 * h])
        for nu in (0.3, 0.5):
            rows.append({"tip": name, "h [mm]": 1e3 * h, "nu": nu,
                         "bonded": thickness_factor(d, tip, h, nu, "bonded")[0],
                         "free": thickness_factor(d, tip, h, nu, "free")[0]})
display(pd.DataFrame(rows))

# %% [markdown]
# The literature's closed forms against the exact solution, for a paraboloid: Garcia & Garcia
# (2018) fitted their polynomial at nu = 0.5 (bonded) and it holds there; Dimitriadis et al.
# (2002) is a small-chi series that falls below as chi = sqrt(R·d)/h grows.

# %%
R, h = 0.0117, 0.02
chi = np.linspace(0.0, 0.6, 121)
d = (chi * h) ** 2 / R
para = pb.Tip("paraboloid", radius=R)
fig = Figure(figsize=(7, 3.6), layout="constrained")
ax = fig.add_subplot()
for nu, ls in ((0.5, "-"), (0.3, "--")):
    ax.plot(chi, thickness_factor(d, para, h, nu, "bonded"), "k", ls=ls,
            label=f"exact layer solution, bonded, nu {nu}")
    ax.plot(chi, dimitriadis_factor(d, R, h, nu, "bonded"), "C0", ls=ls,
            label=f"Dimitriadis 2002, bonded, nu {nu}")
ax.plot(chi, thickness_factor(d, para, h, 0.3, "free"), "C2", label="exact, free (any nu)")
ax.plot(chi, garcia_factor(chi, "paraboloid"), "C1:", lw=2, label="Garcia & Garcia 2018 (nu 0.5)")
ax.set_xlabel("chi = sqrt(R d)/h")
ax.set_ylabel("F_layer / F_half-space")
ax.legend(fontsize="x-small", frameon=False)
fig

# %% [markdown]
# ## 2 · The paper's gap, decomposed
#
# `gap_table()` fits the paper's method (half-space least squares, Hertz for the sphere, the
# flat punch past 20 % of the penetration) to noise-free palpations of elastic blocks with the
# Instron's modulus and the paper's geometry — the 50 × 50 mm blocks' finite-element twins —
# over every combination of base (bonded, free), the foam's nu (0.1–0.35 against the 0.3
# assumed), series compliance (0–2 µm/N) and the Instron's platens (lubricated: it reads E;
# bonded: it reads c(nu)·E).  `layer_lo/hi_pct` is the same range for a layer of infinite
# width and an exact Instron, the prediction before the twin.  The observed interval combines
# the two published sd's.  Nothing is tuned to the published numbers: the ranges are the
# physics' own.

# %%
gap = gap_table()
cols = ["material", "tip", "observed_pct", "observed_lo_pct", "observed_hi_pct",
        "thickness_free_pct", "thickness_bonded_pct", "width_free_pct", "width_bonded_pct",
        "platens_bonded_pct", "hertz_pct", "compliance_pct", "layer_lo_pct", "layer_hi_pct",
        "predicted_lo_pct", "predicted_hi_pct", "explained_layer", "explained",
        "radius_factor"]
display(gap[cols].round(1))
print(f"published values inside the prediction: {int(gap['explained'].sum())} of {len(gap)} "
      f"with the specimen as tested, {int(gap['explained_layer'].sum())} with the infinite "
      "layer and an exact Instron")
plots.plot_gap(gap)

# %% [markdown]
# What the tool says, tip by tip:

# %%
for verdict in gap_verdicts(gap).values():
    print(verdict, end="\n\n")

# %% [markdown]
# * **Flat punch**: a layer of infinite width predicts far more stiffening than the paper saw
#   (+31 to +62 % against +8 to +17 %).  The blocks' free sides take 2–5 % off, and between
#   bonded platens the Instron itself reads 10–14 % high, so the ratio falls: Grey's +17 % is
#   now inside the prediction, White's and Pink's lie 1 and 4 points below its lower end.
# * **Sphere**: all three published values lie inside the prediction (one did with the
#   infinite layer): the plate's bottom effect, less the free sides and the platens'
#   friction; the paper's Hertz fit of its sphere reads a further 2–4 % low.
# * **Paraboloid**: every elastic block reads this tip stiffer, so neither thickness nor width
#   nor platens explain a *softer* reading.  The direction is tested in the table: a tip
#   sharper than its nominal profile reads softer (R/2 reads about −34 % on the free block), a
#   blunter one stiffer (2R: +51 to +56 %).  The published values need R_true/R ≈ 0.53–0.66,
#   for example a profile printed as z = r²/R where z = r²/(2R) was assumed (R_true = R/2).
# * What no elastic model here covers: the foam's nonlinearity.  The Instron's 5 mm is 17–25 %
#   nominal strain, the palpation's 10 % depth a contact strain of 8–10 % (Tabor's 0.2·a/R),
#   both beyond the ~5 % where foams stay linear, and both tests at one rate.  Section 5
#   presses the blocks at finite strain.

# %% [markdown]
# ## 3 · The shipped campaign: half-space and layer side by side
#
# The example campaign is simulated from the paper's protocol with the 50 × 50 mm blocks lying
# free on a plate at the paper's thicknesses, their force from each block's finite-element
# twin, and compression tests between bonded platens (`data/README.md`).  The manifest gives
# each block's footprint, so `run_pipeline` fits it as `palpbayes report` does (here with the
# exact engine, for speed): the least-squares rows are the paper's half-space method, the
# Bayesian rows model each block's twin with its base unknown.

# %%
out = Path(os.environ.get("PALPBAYES_NB04_OUT") or tempfile.mkdtemp(prefix="palpbayes-nb04-"))
options = pb.fit_options(method="both", seed=0, engine="exact")
pb.run_pipeline(pb.example_campaign_dir() / "manifest.csv", out, options,
             workers=int(os.environ.get("PALPBAYES_NB_WORKERS", "2")), progress=False)
res = pb.load_results(out)
cmp_ = res.comparison
show = cmp_[["material", "tip", "method", "E_pa", "E_new_lo_pa", "E_new_hi_pa", "gt_E_pa",
             "gt_in_new_interval", "E_free_pa", "E_bonded_pa", "p_bonded"]].copy()
for c in ("E_pa", "E_new_lo_pa", "E_new_hi_pa", "gt_E_pa", "E_free_pa", "E_bonded_pa"):
    show[c] = show[c] / 1e3
show.columns = [c.replace("_pa", " [kPa]") for c in show.columns]
display(show.round(3))
print("Instron inside the new-specimen interval:",
      {m: f"{int(g['gt_in_new_interval'].sum())}/{len(g)}" for m, g in cmp_.groupby("method")})

# %%
plots.plot_halfspace_vs_layer(cmp_)

# %% [markdown]
# The least-squares rows read far above E (the paper's method on blocks of the paper's
# thickness: the bottom effect), and their `E_free`–`E_bonded` columns say what reading the
# same fits with the blocks' twins would change.  The Bayesian rows model the twin; the
# posterior probability of a bonded base is 0 for the curved tips (the data show the blocks
# lie free) and 0.5 for the flat punch (its curve is a straight line whatever the base: the
# interval spans both).  The Instron columns above are what the compression tests *read*:
# between bonded platens that is not E, which is why the next section sets the palpation
# beside them like for like.

# %% [markdown]
# ## 4 · The specimen as tested
#
# `palpbayes.twin` models the block the user tested: an axisymmetric finite-element model
# (scikit-fem, Taylor–Hood elements, so nothing locks up to nu = 0.5) of the cylinder of equal
# footprint area on its plate, pressed by the tip with its contact radius solved, and the same
# block between two platens.  First, what the finite width does to the infinite layer's
# bottom effect (the factor w = F_twin/F_layer over the depth, at nu 0.3): the free sides
# soften the block, more as the contact grows.

# %%
fig = Figure(figsize=(9, 3.4), layout="constrained")
ax1, ax2 = fig.subplots(1, 2)
for (name, tip), color in zip(PAPER_TIPS.items(), ("C0", "C1", "C2"),
                              strict=True):
    for h, ls in ((0.02, "-"), (0.03, "--")):
        block = Specimen(h, length=0.05, width=0.05)
        d = np.linspace(0.002, 0.12, 40) * h
        for base, lw in (("free", 1.6), ("bonded", 0.8)):
            w = (twin_shape(d, tip, block, 0.3, base)
                 / (thickness_factor(d, tip, h, 0.3, base) * shape(d, tip)))
            ax1.plot(100 * d / h, w, color=color, ls=ls, lw=lw,
                     label=f"{name}, {1e3 * h:g} mm" if base == "free" else None)
ax1.set_xlabel("depth / thickness [%]")
ax1.set_ylabel("F_twin / F_layer (free: thick, bonded: thin)")
ax1.legend(fontsize="x-small", frameon=False)
nus = np.linspace(0.0, 0.49, 25)
for h, ls in ((0.02, "-"), (0.03, "--")):
    block = Specimen(h, length=0.05, width=0.05)
    ax2.plot(nus, [compression_factor(block, v, "bonded") for v in nus], "k", ls=ls,
             label=f"50 × 50 × {1e3 * h:g} mm, bonded platens")
ax2.axhline(1.0, color="0.5", lw=0.8, label="lubricated platens (E)")
ax2.set_xlabel("Poisson ratio nu")
ax2.set_ylabel("what the Instron reads / E")
ax2.legend(fontsize="x-small", frameon=False)
fig

# %% [markdown]
# Each Bayesian row of a fit with a specimen (`--specimen L,W,H` or a manifest's footprint)
# carries `E_instron`, what a compression test of that block would read, with its interval:
# each posterior draw of E (with the budget) times c(nu) of its own Poisson ratio, for the
# platens given (`--platens`, default unknown: the interval spans lubricated to bonded).  The
# campaign's comparison pools it per material × tip; here it is set beside the Instron's
# reading, like for like:

# %%
bay = cmp_[cmp_["method"] == "bayes"]
like = bay[["material", "tip", "E_pa", "E_instron_pa", "E_instron_new_lo_pa",
            "E_instron_new_hi_pa", "gt_E_pa", "gt_in_instron_interval"]].copy()
for c in ("E_pa", "E_instron_pa", "E_instron_new_lo_pa", "E_instron_new_hi_pa", "gt_E_pa"):
    like[c] = like[c] / 1e3
like.columns = [c.replace("_pa", " [kPa]") for c in like.columns]
display(like.round(1))
summ = res.summary
truth = pd.read_csv(pb.example_campaign_dir() / "truth.csv")
rows = summ[summ["method"] == "bayes"].merge(truth, on="trace_id")
cover_E = rows["E_true_pa"].between(rows["E_lo_pa"], rows["E_hi_pa"]).sum()
cover_i = rows["E_instron_true_pa"].between(rows["E_instron_lo_pa"], rows["E_instron_hi_pa"]).sum()
print(f"per trace, the 90 % interval covers the true E in {cover_E}/{len(rows)}, and E_instron "
      f"covers what a bonded-platen test of the block reads in {cover_i}/{len(rows)}")
plots.plot_specimen_as_tested(cmp_)

# %% [markdown]
# The compression tests of the example were run between bonded platens: they read 11–17 %
# above E (grey bands).  The Bayesian E (blue) is the material's; what its blocks' compression
# tests would read (vermilion) is the number to set beside an Instron.  A user who knows the
# platens were lubricated, or bonded, says so (`--platens`) and the interval narrows; one who
# wants the Instron's E back corrects the compression export instead:
# `palpbayes groundtruth FILES --platens bonded --nu 0.3` (`E_corrected_pa`).

# %% [markdown]
# ## 5 · Strain: the gap at finite strain
#
# A foam is not linear to 17–25 % strain.  `palpbayes.gap_strain` makes each of the paper's
# blocks of a foam that softens into a plateau (one-term Ogden–Hill hyperfoam, `nu` 0.1 or 0.3,
# `alpha` 2–20; `palpbayes.material`) or of a compressible neo-Hookean solid, presses it with
# each tip on its **finite-strain twin** (`palpbayes.twin.hyper_table`: total Lagrangian, the
# tip's true surface), and reads the curve and the Instron's 5 mm as the paper did.
# `strain_factor` is what finite strain multiplies the linear prediction above by.  The 198 cases
# take minutes of finite elements (`python -m palpbayes.gap_strain OUT.csv`), so the table is
# shipped in `data/gap-strain/` and read here.

# %%
from palpbayes.gap_strain import shipped_table, strain_paragraph, strain_verdicts

strain = shipped_table()
factors = strain.pivot_table(index="foam", columns="tip", values="strain_factor",
                             aggfunc=["min", "max"]).round(3)
display(factors)
verdicts = strain_verdicts(gap, strain)
print(strain_paragraph(verdicts, strain, gap))
plots.plot_strain_factors(strain)

# %% [markdown]
# * A foam that **softens** (the Instron's line over its plateau reads low) raises every
#   robot/Instron ratio, the more the larger `alpha`: it widens the paper's gap and cannot make
#   the paraboloid read softer.
# * A compressible **neo-Hookean** solid, whose nominal stress stiffens in compression, lowers
#   every ratio by 9–17 %; with the blocks' other terms it puts 8 of the 9 published ratios
#   inside the prediction (the linear blocks: 4).
# * Finite strain moves the **paraboloid and the sphere together** (0.98–1.03): the
#   paraboloid's 15–17 points below the sphere still need a tip sharper than nominal.
# * The other half of the story is the Instron's own reading: `palpbayes groundtruth --law
#   auto` fits a hyperelastic law to a whole compression curve (docs/reference.md, "Finite
#   strain"); on the real silicone phantoms the whole-curve E0 of every law is 16–32 % below
#   the same law's E0 up to 20 % strain, which agrees with the linear window.
