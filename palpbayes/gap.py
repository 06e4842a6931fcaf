"""Why does the robot read stiffer than the Instron?  The paper's gap decomposed with the
tool's own models, the specimen as tested among them.

The paper's robot estimates (:data:`palpbayes.paper.PAPER_ROBOT_ESTIMATES`, its least squares
on a half-space) differ from its Instron means tip by tip: the flat punch reads 8–17 % stiffer,
the sphere 4–12 % stiffer, the paraboloid 5–10 % softer.  :func:`gap_table` sets each
material × tip's observed ratio E_robot / E_Instron beside what the tool's models predict the
paper's two tests read on an elastic block of the paper's geometry whose true modulus is E:

* **thickness and base** — the block is a layer of its thickness on a rigid plate
  (:mod:`palpbayes.contact.layer`), bonded to it or lying free on it; the paper's half-space
  least squares (its window, its F_unc, Hertz for the sphere) is fitted to the noise-free
  curve;
* **width** — the block is 50 × 50 mm, not infinitely wide: its finite-element twin
  (:mod:`palpbayes.twin`) under the same tip, whose free sides make it softer than the layer;
* **platens** — the Instron compresses the block between platens that are lubricated (it
  reads E) or bonded (the faces cannot slide; it reads c(nu)·E, c > 1:
  :func:`palpbayes.twin.compression_factor`), so the ratio is divided by c;
* **Poisson ratio** — the paper turns E* into E with a nu it does not state; palpbayes'
  default 0.3 is taken, against a foam's true nu anywhere in [0.1, 0.35] (closed-cell PE foam:
  no measured value found, estimates 0.27–1/3, docs/design.md §8): a factor
  (1 − 0.3²)/(1 − nu²), and the twin and the bonded platens depend on nu too;
* **Hertz approximation** — the paper fitted its sphere with Hertz's law, which gives more
  force than the exact sphere at the same depth: E reads low;
* **series compliance** of robot and sensor, 0 to 2 µm/N (the budget's range): the tip goes
  less deep than recorded, E reads low;
* **depth window** — the paper fitted every sample (the flat punch past 20 % of the
  penetration); fitting only the shallower half shows how much the block's bias depends on
  the window.

The joint prediction runs every combination of base × nu × compliance × platens on the twin;
its range is the predicted interval (``predicted_lo/hi_pct``), and a published ratio inside it
is *explained*.  The same range without the width and the platens (the infinite layer and an
exact Instron: the prediction before the twin) is ``layer_lo/hi_pct``.  The observed interval
is E_robot/E_GT with the two published sd's combined (90 %, ±1.645·sd of the log ratio: the
sd of specimens, not of the means, since the paper does not give its repetition counts).  What
the models leave over (observed ÷ predicted) is the residual; for the curved tips it is also
stated as the tip radius that would explain the published value on the free twin at nu 0.3
between lubricated platens (Hertz: E_read/E = sqrt(R_true/R_nominal), so ``radius_factor`` =
R_true/R_nominal = (observed ÷ that reading)²: below 1 a sharper tip, above 1 a blunter one).
Not modelled: foam nonlinearity (the tests' strains are in ``strain_*_pct``: the Instron's
5 mm reach 17–25 % nominal strain, the palpation's 10 % depth a contact strain of 7–9 % by
Tabor's 0.2·a/R for the curved tips) and rate.  The sentences are :mod:`palpbayes.gap_text`.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np
import pandas as pd

from .contact import DEFAULT_NU, Tip, get_law, youngs_factor
from .fitdata import ModelSpec
from .intervals import Z_LEVEL
from .lsq import fit_lsq
from .paper import PAPER_MATERIALS, PAPER_ROBOT_ESTIMATES, PAPER_TIPS
from .sensor_noise import PAPER_NOISE_PP
from .sim.trace import simulate_trace
from .twin import Specimen, compression_factor

__all__ = ["GapSettings", "gap_table", "GAP_COLUMNS", "paper_fit_ratio", "gap_verdicts",
           "INSTRON_REACH_M"]

#: [m] How far the paper's Instron compressed its blocks (design.md §2: up to 5 mm).
INSTRON_REACH_M = 5e-3

#: Columns of :func:`gap_table`; ratios are in per cent, ``x_pct`` = 100·(ratio − 1).
GAP_COLUMNS = [
    "material", "tip", "thickness_m", "length_m", "width_m", "nu_fit", "nu_true_lo",
    "nu_true_hi", "depth_m", "contact_radius_m", "E_instron_pa",
    "E_robot_pa", "observed_pct", "observed_lo_pct", "observed_hi_pct",
    "thickness_bonded_pct", "thickness_free_pct", "width_bonded_pct", "width_free_pct",
    "platens_bonded_pct", "nu_lo_pct", "nu_hi_pct", "hertz_pct", "compliance_pct",
    "window_bonded_pct", "window_free_pct", "layer_lo_pct", "layer_hi_pct",
    "predicted_lo_pct", "predicted_hi_pct", "explained_layer", "explained", "consistent",
    "residual_lo_pct", "residual_hi_pct", "radius_factor", "sharper_tip_pct",
    "blunter_tip_pct", "strain_instron_pct", "strain_palpation_pct", "strain_contact_pct",
]


@dataclass(frozen=True)
class GapSettings:
    """The ranges the prediction runs over.

    Parameters
    ----------
    nu_fit
        Poisson ratio the paper's E = E*·(1 − nu²) is taken to assume.
    nu_range
        True Poisson ratios of the foam, as a grid.
    compliance_max
        [m/N] Largest series compliance.
    platens
        The Instron's platens the prediction spans.
    approach
        [m] Approach before contact (the pre-contact samples the fit sees).
    rate
        [Hz] Sample rate of the noise-free curves (the paper's 800 Hz changes no figure by more
        than 0.05 %: without noise the curve's shape, not its sampling, sets the fit).
    resolution
        Mesh of the blocks' twins (:data:`palpbayes.twin.mesh.RESOLUTIONS`).
    """

    nu_fit: float = DEFAULT_NU
    nu_range: tuple[float, ...] = (0.1, 0.2, 0.3, 0.35)
    compliance_max: float = 2e-6
    platens: tuple[str, ...] = ("lubricated", "bonded")
    approach: float = 1e-3
    rate: float = 200.0
    resolution: str = "default"


# Many parameters: one case of the gap: modulus, tip, block, base, nu and the paper's fit settings,
# each a physical setting.
def paper_fit_ratio(E: float, tip: Tip, thickness: float, *, base: str | None, nu: float,
                    settings: GapSettings = GapSettings(), compliance: float = 0.0,
                    window: float | None = None, block: Specimen | None = None,
                    true_tip: Tip | None = None) -> float:
    """E_paper / E [-]: the paper's least squares on a noise-free palpation of the paper's
    protocol (10 % of the thickness at 50 mm/min) into an elastic block of modulus ``E``
    [Pa], Poisson ratio ``nu``, thickness [m] on a plate (``base`` bonded/free; None a
    half-space), series ``compliance`` [m/N]; ``window`` the depth fitted as a fraction of the
    maximum (None: the paper's every sample); ``block``: the block's footprint (its twin),
    None a layer of infinite width; ``true_tip``: the tip that pressed, when it is not the
    ``tip`` the fit assumes (a tip printed sharper or blunter than its nominal radius)."""
    tr = simulate_trace(E, true_tip or tip, nu=nu, thickness=thickness, base=base,
                        noise_pp=0.0,
                        compliance=compliance, approach=settings.approach,
                        rate=settings.rate, rng=0, block=block if base is not None else None,
                        twin_resolution=settings.resolution)
    law = get_law(tip)
    fit_tip = law.hertz_approximation(tip) if law.hertz_approximation is not None else tip
    max_depth = None if window is None else window * 0.1 * thickness
    res = fit_lsq(tr, ModelSpec(fit_tip, nu=settings.nu_fit), f_unc=PAPER_NOISE_PP,
                  max_depth=max_depth)
    return float(res.E / E)


def _pct(r: float) -> float:
    return 100.0 * (r - 1.0)


def _group_row(material: str, tip_name: str, settings: GapSettings) -> dict:
    mat = PAPER_MATERIALS[material]
    tip = PAPER_TIPS[tip_name]
    h, E = mat.thickness_m, mat.E_pa
    block = Specimen(h, length=mat.length_m, width=mat.width_m)
    rob = next(r for r in PAPER_ROBOT_ESTIMATES if r.material == material
               and r.tip == tip_name)
    e_rob, sd_rob = rob.E_kPa * 1e3, rob.sd_kPa * 1e3
    ratio = e_rob / E
    s_log = math.hypot(sd_rob / e_rob, mat.E_sd_pa / E)
    nu0 = settings.nu_fit

    def fit(**kw) -> float:
        return paper_fit_ratio(E, tip, h, settings=settings, **kw)

    def platen(nu: float, platens: str) -> float:
        return 1.0 if platens == "lubricated" else compression_factor(block, nu, platens)

    half = fit(base=None, nu=nu0)
    exact_half = half
    law = get_law(tip)
    if law.hertz_approximation is not None:  # the exact law's own fit: what Hertz changes
        tr = simulate_trace(E, tip, nu=nu0, thickness=h, base=None, noise_pp=0.0,
                            approach=settings.approach, rate=settings.rate, rng=0)
        exact_half = float(fit_lsq(tr, ModelSpec(tip, nu=nu0), f_unc=PAPER_NOISE_PP).E / E)
    bases = ("bonded", "free")
    layer = {b: fit(base=b, nu=nu0) for b in bases}
    twin = {b: fit(base=b, nu=nu0, block=block) for b in bases}
    shallow = {b: fit(base=b, nu=nu0, window=0.5, block=block)
               / fit(base=None, nu=nu0, window=0.5) for b in bases}
    comp = fit(base=None, nu=nu0, compliance=settings.compliance_max)
    cases = [(b, nu, c) for b in bases for nu in settings.nu_range
             for c in (0.0, settings.compliance_max)]
    joint_layer = [fit(base=b, nu=nu, compliance=c) for b, nu, c in cases]
    joint = [fit(base=b, nu=nu, compliance=c, block=block) / platen(nu, p)
             for b, nu, c in cases for p in settings.platens]
    nu_terms = [youngs_factor(nu0) / youngs_factor(nu) for nu in settings.nu_range]
    lo, hi = min(joint), max(joint)
    o_lo, o_hi = ratio * math.exp(-Z_LEVEL * s_log), ratio * math.exp(Z_LEVEL * s_log)
    res_lo, res_hi = o_lo / hi, o_hi / lo  # what the models leave over
    n = law.profile_exponent(tip)
    curved = law.contact_radius is not None and not math.isinf(n)
    a = float(law.contact_radius(np.array([0.1 * h]), tip)[0])
    return {
        "material": material, "tip": tip_name, "thickness_m": h, "length_m": mat.length_m,
        "width_m": mat.width_m, "nu_fit": nu0, "nu_true_lo": min(settings.nu_range),
        "nu_true_hi": max(settings.nu_range), "depth_m": 0.1 * h,
        "contact_radius_m": a, "E_instron_pa": E, "E_robot_pa": e_rob,
        "observed_pct": _pct(ratio), "observed_lo_pct": _pct(o_lo), "observed_hi_pct": _pct(o_hi),
        "thickness_bonded_pct": _pct(layer["bonded"] / half),
        "thickness_free_pct": _pct(layer["free"] / half),
        "width_bonded_pct": _pct(twin["bonded"] / layer["bonded"]),
        "width_free_pct": _pct(twin["free"] / layer["free"]),
        "platens_bonded_pct": _pct(1.0 / platen(nu0, "bonded")),
        "nu_lo_pct": _pct(min(nu_terms)), "nu_hi_pct": _pct(max(nu_terms)),
        "hertz_pct": _pct(half / exact_half), "compliance_pct": _pct(comp / half),
        "window_bonded_pct": _pct(shallow["bonded"]), "window_free_pct": _pct(shallow["free"]),
        "layer_lo_pct": _pct(min(joint_layer)), "layer_hi_pct": _pct(max(joint_layer)),
        "predicted_lo_pct": _pct(lo), "predicted_hi_pct": _pct(hi),
        # the published point inside the predicted range (before the twin: the layer's); its
        # 90 % interval overlapping it
        "explained_layer": bool(min(joint_layer) <= ratio <= max(joint_layer)),
        "explained": bool(lo <= ratio <= hi), "consistent": bool(o_lo <= hi and o_hi >= lo),
        "residual_lo_pct": _pct(res_lo), "residual_hi_pct": _pct(res_hi),
        # Hertz: E_read/E = sqrt(R_true/R_nominal), against the free twin at nu 0.3 between
        # lubricated platens
        "radius_factor": (ratio / twin["free"]) ** 2 if curved else np.nan,
        # the direction of that hypothesis, tested: the same fit of a tip of half and of
        # twice the nominal radius (the free twin at nu 0.3)
        **({"sharper_tip_pct": _pct(fit(base="free", nu=nu0, block=block,
                                        true_tip=tip.scaled(0.5)) / twin["free"]),
            "blunter_tip_pct": _pct(fit(base="free", nu=nu0, block=block,
                                        true_tip=tip.scaled(2.0)) / twin["free"])}
           if curved else {"sharper_tip_pct": np.nan, "blunter_tip_pct": np.nan}),
        "strain_instron_pct": 100.0 * INSTRON_REACH_M / h,
        "strain_palpation_pct": 10.0,
        # Tabor's representative strain of a sphere, 0.2·a/R (a curved tip's radius at its
        # apex: the paraboloid's and the sphere's R)
        "strain_contact_pct": 100.0 * 0.2 * a / tip.radius if curved and tip.radius
        else np.nan,
    }


def gap_table(settings: GapSettings = GapSettings(),
              materials: Iterable[str] | None = None,
              tips: Iterable[str] | None = None) -> pd.DataFrame:
    """The decomposition of the paper's robot-vs-Instron gap (module docstring), one row per
    material × tip (:data:`GAP_COLUMNS`).  About 10 s on one core, plus ~25 s the first time
    to solve the blocks' twins (cached on disk after)."""
    mats = list(materials or PAPER_MATERIALS)
    tps = list(tips or PAPER_TIPS)
    rows = [_group_row(m, t, settings) for t in tps for m in mats]
    return pd.DataFrame(rows, columns=GAP_COLUMNS)


def gap_verdicts(table: pd.DataFrame) -> dict[str, str]:
    """One plain sentence per tip (:func:`palpbayes.gap_text.gap_verdicts`)."""
    from .gap_text import gap_verdicts as verdicts

    return verdicts(table)
