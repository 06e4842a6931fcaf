"""The paper's robot-vs-Instron gap at finite strain: what a foam that softens past its linear
range does to the nine ratios (issue 56, item 5).

:mod:`palpbayes.gap` explains the gap with a linear elastic block.  Its two tests do not reach
the same strain: the Instron compresses 5 mm (17–25 % nominal strain), the palpation goes 10 %
of the thickness deep (a contact strain of 7–9 % for the curved tips).  A foam that softens
past its linear range (cell walls buckling into a plateau, Gibson & Ashby 1997) then reads
softer in the Instron than under the tip.  Here each block of the paper is an Ogden–Hill foam
(:mod:`palpbayes.material.hyperfoam`, one term: small-strain E0, Poisson ratio nu, exponent
alpha; alpha = 2 is close to linear, larger alphas soften into a plateau) or a compressible
neo-Hookean solid, pressed by each of the paper's tips on the finite-strain twin of the block
(:mod:`palpbayes.twin.hyper_table`, bonded or free base) and read as the paper read it:

* **robot**: the paper's least squares on a half-space (Hertz for the sphere, nu 0.3, its
  F_unc) fitted to the noise-free force curve of the protocol (10 % of the thickness);
* **Instron**: the least-squares line of the foam's nominal stress on strain over the
  Instron's reach, 0 to 5 mm, between lubricated platens (the paper does not state its window;
  the whole reach is assumed, a window of 0–5 % strain reads closer to E0).

``strain_factor`` = (robot ÷ Instron) of the foam over (robot ÷ E) of the linear twin of the
same block, base and small-strain nu: what softening multiplies the linear prediction of
:func:`palpbayes.gap.gap_table` by.  :func:`strain_verdicts` answers the issue's questions: how
many of the nine ratios a softening foam explains with :mod:`palpbayes.gap`'s other knobs,
which single law (one set of parameters per foam, all three tips) explains most, and whether a
softening foam can make the paraboloid read softer without a sharper tip.

The finite elements take minutes (``python -m palpbayes.gap_strain OUT.csv``: ~250 curves at
the coarse resolution, cached on disk); the table the report shows is the one shipped in
:data:`SHIPPED_TABLE` (:func:`shipped_table`), and a slow test recomputes rows of it.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from .contact import DEFAULT_NU, Tip, get_law
from .fitdata import ModelSpec
from .gap_text import strain_paragraph  # public here: the verdicts in sentences
from .lsq import fit_lsq
from .material import Solid
from .outputs import SHIPPED_GAP_STRAIN
from .paper import PAPER_MATERIALS, PAPER_TIPS
from .sensor_noise import PAPER_NOISE_PP
from .specimen import Specimen
from .trace import IndentationTrace

__all__ = ["StrainSettings", "FOAMS", "STRAIN_COLUMNS", "strain_row", "strain_table",
           "strain_verdicts", "strain_paragraph", "shipped_table", "SHIPPED_TABLE",
           "INSTRON_REACH_M"]

#: The table shipped with the source checkout (``python -m palpbayes.gap_strain`` writes it;
#: minutes of finite elements), relative to the repository root.
SHIPPED_TABLE = SHIPPED_GAP_STRAIN

#: [m] How far the paper's Instron compressed its blocks (design.md §2).
INSTRON_REACH_M = 5e-3
#: The foams tried: (label, law, shape, nu of a law that is not a foam).
FOAMS: tuple[tuple[str, str, dict, float | None], ...] = (
    ("neo-Hookean nu 0.3", "neo-hookean", {}, 0.3),
    *((f"hyperfoam nu {nu:g} alpha {a:g}", "hyperfoam", {"nu": nu, "alpha_1": a}, None)
      for nu in (0.1, 0.3) for a in (2.0, 5.0, 8.0, 12.0, 20.0)),
)
#: Columns of :func:`strain_table`.
STRAIN_COLUMNS = ["material", "tip", "base", "foam", "law", "nu0", "alpha", "robot_read",
                  "instron_read", "ratio", "linear_ratio", "strain_factor", "strain_instron"]


@dataclass(frozen=True)
class StrainSettings:
    """How the study runs: the twin's mesh, the approach and sampling of the noise-free
    curves, the Poisson ratio the paper's fit assumes."""

    resolution: str = "coarse"
    approach: float = 1e-3
    rate: float = 200.0
    nu_fit: float = DEFAULT_NU


def _paper_read(force_of_depth, tip: Tip, depth_max: float, s: StrainSettings) -> float:
    """The paper's least-squares E of the noise-free curve ``force_of_depth(d)`` (E of the
    fit's scale: a unit curve reads a factor)."""
    speed = 50 / 60e3
    n = int(round((s.approach + depth_max) / speed * s.rate))
    z = 0.1 + s.approach - speed * np.arange(n + 1) / s.rate
    d = np.clip(0.1 - z, 0.0, depth_max)
    scale = 1e5  # forces of a 100 kPa block: the fit's F_unc is in newtons
    tr = IndentationTrace(np.arange(n + 1) / s.rate, z, scale * force_of_depth(d), tip=tip)
    law = get_law(tip)
    fit_tip = law.hertz_approximation(tip) if law.hertz_approximation is not None else tip
    return float(fit_lsq(tr, ModelSpec(fit_tip, nu=s.nu_fit), f_unc=PAPER_NOISE_PP).E) / scale


def strain_row(material: str, tip_name: str, base: str, foam: tuple,
               settings: StrainSettings = StrainSettings()) -> dict:
    """One :data:`STRAIN_COLUMNS` row: the foam ``foam`` (an item of :data:`FOAMS`) pressed
    by the paper's tip into the paper's block of ``material`` on a ``base``."""
    from .sim.force import true_force
    from .twin.hyper_table import hyper_table

    label, law, shape, nu_law = foam
    mat, tip = PAPER_MATERIALS[material], PAPER_TIPS[tip_name]
    block = Specimen(mat.thickness_m, length=mat.length_m, width=mat.width_m)
    solid = Solid.from_E0(law, 1.0, shape, nu=nu_law)
    nu0 = solid.nu0
    d_max = 0.1 * mat.thickness_m
    nodes = {k: [v] for k, v in shape.items()}
    table = hyper_table(law, block, tip, 0.5 if nu_law is None else nu_law, base,
                        shape_nodes=nodes or None, max_depth=d_max,
                        resolution=settings.resolution)
    robot = _paper_read(lambda d: table.force(d, 1.0, shape), tip, d_max, settings)
    strain = INSTRON_REACH_M / mat.thickness_m
    eps = np.linspace(0.0, strain, 201)
    instron = float(np.polyfit(eps, solid.compression_stress(eps), 1)[0])
    linear = _paper_read(
        lambda d: true_force(d, 1.0, nu0, tip, thickness=mat.thickness_m, base=base,
                             block=block), tip, d_max, settings)
    ratio = robot / instron
    return {"material": material, "tip": tip_name, "base": base, "foam": label, "law": law,
            "nu0": nu0, "alpha": shape.get("alpha_1", math.nan), "robot_read": robot,
            "instron_read": instron, "ratio": ratio, "linear_ratio": linear,
            "strain_factor": ratio / linear, "strain_instron": strain}


def strain_table(settings: StrainSettings = StrainSettings(),
                 materials: Iterable[str] | None = None, tips: Iterable[str] | None = None,
                 bases: Iterable[str] = ("free", "bonded"), foams: Iterable[tuple] = FOAMS,
                 progress: bool | None = None) -> pd.DataFrame:
    """Every material × tip × base × foam (:data:`STRAIN_COLUMNS`), the twin's curves cached
    on disk."""
    from .progress import progress_bar

    jobs = [(m, t, b, f) for m in (materials or PAPER_MATERIALS) for t in (tips or PAPER_TIPS)
            for b in bases for f in foams]
    rows = []
    with progress_bar(len(jobs), progress, desc="finite-strain gap", unit="case") as bar:
        for job in jobs:
            rows.append(strain_row(*job, settings=settings))
            bar.update(1)
    return pd.DataFrame(rows, columns=STRAIN_COLUMNS)


def strain_verdicts(gap: pd.DataFrame, strain: pd.DataFrame) -> dict[str, object]:
    """What the finite-strain rows say against :func:`palpbayes.gap.gap_table`'s nine rows.

    Returns
    -------
    dict
        ``explained_linear`` and ``explained_softening``: how many of the nine published
        ratios lie in the joint linear prediction, and in it widened by every foam's
        ``strain_factor`` (both bases); ``best``: per material, the foam (one parameter set,
        all three tips) that puts most of its tips' published ratios inside the linear
        prediction times that foam's factor, with the count; ``best_total``; ``paraboloid``:
        the largest amount by which any foam makes the paraboloid read softer than the sphere
        on the same block and base (the paraboloid's factor over the sphere's, below 1: softer);
        ``paraboloid_softer``: whether some foam puts the paraboloid's published ratio inside
        its prediction with the nominal tip.
    """
    g = gap.set_index(["material", "tip"])
    obs = g["E_robot_pa"] / g["E_instron_pa"]
    lo = 1.0 + g["predicted_lo_pct"] / 100.0
    hi = 1.0 + g["predicted_hi_pct"] / 100.0
    f = strain.groupby(["material", "tip"])["strain_factor"]
    f_min, f_max = f.min().reindex(obs.index), f.max().reindex(obs.index)
    soft_lo, soft_hi = lo * np.minimum(f_min, 1.0), hi * np.maximum(f_max, 1.0)
    explained_linear = int(((lo <= obs) & (obs <= hi)).sum())
    explained_soft = int(((soft_lo <= obs) & (obs <= soft_hi)).sum())
    best, total = {}, 0
    for material in dict.fromkeys(strain["material"]):
        counts = {}
        for foam, rows in strain[strain["material"] == material].groupby("foam", sort=False):
            fk = rows.groupby("tip")["strain_factor"]
            n = 0
            for tip in fk.groups:
                key = (material, tip)
                if key in obs.index:
                    n += bool(lo[key] * fk.min()[tip] <= obs[key] <= hi[key] * fk.max()[tip])
            counts[foam] = n
        name = max(counts, key=counts.get)
        best[material] = (name, counts[name], len(strain[strain["material"] == material]
                                                   ["tip"].unique()))
        total += counts[name]
    piv = strain.pivot_table(index=["material", "base", "foam"], columns="tip",
                             values="strain_factor")
    para_vs_sphere = (piv["paraboloid"] / piv["sphere"]) if {"paraboloid", "sphere"} <= set(
        piv.columns) else pd.Series(dtype=float)
    para = [(m, t) for m, t in obs.index if t == "paraboloid"]
    softer = any(lo[k] * strain[(strain["material"] == k[0]) & (strain["tip"] == k[1])]
                 ["strain_factor"].min() <= obs[k] for k in para)
    return {"explained_linear": explained_linear, "explained_softening": explained_soft,
            "best": best, "best_total": total,
            "paraboloid_over_sphere_min": float(para_vs_sphere.min()) if len(
                para_vs_sphere) else math.nan,
            "paraboloid_over_sphere_max": float(para_vs_sphere.max()) if len(
                para_vs_sphere) else math.nan,
            "paraboloid_softer": bool(softer)}


def shipped_table() -> pd.DataFrame:
    """The shipped table (:data:`SHIPPED_TABLE`, beside the package in a source checkout).

    Raises
    ------
    DataFileError
        It is not there (an installed wheel ships the package only): compute it with
        ``python -m palpbayes.gap_strain OUT.csv``.
    """
    from .errors import DataFileError

    path = Path(__file__).resolve().parents[1] / SHIPPED_TABLE
    if not path.is_file():
        raise DataFileError(f"the finite-strain gap table is not at {path} (it comes with a "
                            "source checkout); compute it with 'python -m palpbayes.gap_strain "
                            "OUT.csv' (minutes of finite elements) and read that file")
    return pd.read_csv(path)


def main(argv: list[str] | None = None) -> int:
    """``python -m palpbayes.gap_strain OUT.csv``: compute the table (minutes) and write it."""
    from .io.atomic import write_csv_atomic

    args = sys.argv[1:] if argv is None else argv
    if len(args) != 1:
        print("usage: python -m palpbayes.gap_strain OUT.csv", file=sys.stderr)
        return 2
    write_csv_atomic(strain_table(progress=True), args[0], float_format="%.10g")
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
