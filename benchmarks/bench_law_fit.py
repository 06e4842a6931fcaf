"""Fits with a hyperelastic law (issue 56, item 4), measured in one run on this machine.

For each of the issue's cases, ``--n`` traces (fixed seeds) of a hyperelastic block pressed by
the finite-strain twin (the ``--sim-mesh`` mesh, the paper's 48 mN p-p sensor noise) are fitted

* with the law (``--law NAME --specimen L,W,H``, exact engine, the ``--fit-mesh`` mesh, the
  default budget, the block lying free on its plate as simulated),
* linear with the specimen's twin (``--specimen``), and linear as a half-space (the paper's):

and the script prints the coverage of E0 by the law fit's full interval (and its statistical
one), the median error of E0, the linear fits' offsets from E0 and whether their full interval
(with the model form's neo-Hookean reading) covers E0, and the seconds per fit: the first
(cold: the finite elements of a fresh cache solved) and the median of the others (cached).

The cases (E0 60 kPa, a 50 × 50 mm footprint, the block free on its plate):

==================  ==========================================================================
``nh-sphere-0.3``   neo-Hookean nu 0.3, 20 mm high, sphere R 10 mm pressed 3 mm (a/R ≈ 0.55)
``nh-sphere-0.45``  the same at nu 0.45
``foam-flat``       hyperfoam nu 0.1, alpha 8, 20 mm high, flat punch a 10 mm pressed 2 mm:
                    fitted with nu given (``--nu 0.1``) and alpha free over [-10, 25]
``foam-flat-known`` the same with alpha given too (``--law-shape alpha_1=8``)
``nh-paraboloid``   neo-Hookean nu 0.3, 30 mm high, paraboloid R 11.7 mm pressed 3 mm (10 %)
``nh-halfspace``    neo-Hookean nu 0.3 in a block 1 m deep and 4 m wide (a half-space within
                    0.5 %), sphere R 10 mm pressed 3 mm, fitted without a specimen: the law on
                    the half-space proxy against the linear half-space
==================  ==========================================================================

``--proxy`` prints the half-space proxy against Hertz (and Sneddon's sphere) at small depth
(d/L 0.0025-0.01, extrapolated to d = 0) for the sphere, the paraboloid and the flat punch.

Run: ``python benchmarks/bench_law_fit.py [--proxy] [--case NAME ...] [--n 10]`` (every case with 10
traces: about 13 minutes on 2 shared cores from a fresh cache; the finite-element curves are
cached in ``$PALPBAYES_CACHE_DIR``, a temporary folder unless ``--cache`` is given).
``tests/statistical/test_law_fits.py`` runs :func:`run_case` and asserts the issue's figures.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
import warnings
from dataclasses import dataclass

import numpy as np
import pandas as pd

import palpbayes as pb
from palpbayes.contact import Tip
from palpbayes.material import Solid
from palpbayes.sim import simulate_trace
from palpbayes.twin import Specimen

E0 = 60e3


@dataclass(frozen=True)
class Case:
    """One of the issue's cases (module docstring)."""

    solid: Solid
    tip: Tip
    block: Specimen
    depth: float
    nu: float
    law: str
    law_shape: str | None = None
    specimen: bool = True

    @property
    def specimen_text(self) -> str:
        b = self.block
        return f"{b.length},{b.width},{b.height}"


_B20 = Specimen(0.020, length=0.05, width=0.05)
_FOAM = Solid.from_E0("hyperfoam", E0, {"nu": 0.1, "alpha_1": 8.0})
CASES = {
    "nh-sphere-0.3": Case(Solid.from_E0("neo-hookean", E0, nu=0.3), Tip("sphere", radius=0.01),
                          _B20, 3e-3, 0.3, "neo-hookean"),
    "nh-sphere-0.45": Case(Solid.from_E0("neo-hookean", E0, nu=0.45),
                           Tip("sphere", radius=0.01), _B20, 3e-3, 0.45, "neo-hookean"),
    "foam-flat": Case(_FOAM, Tip("flat", radius=0.01), _B20, 2e-3, 0.1, "hyperfoam"),
    "foam-flat-known": Case(_FOAM, Tip("flat", radius=0.01), _B20, 2e-3, 0.1, "hyperfoam",
                            "alpha_1=8"),
    "nh-paraboloid": Case(Solid.from_E0("neo-hookean", E0, nu=0.3),
                          Tip("paraboloid", radius=0.0117), _B20.with_height(0.030), 3e-3,
                          0.3, "neo-hookean"),
    "nh-halfspace": Case(Solid.from_E0("neo-hookean", E0, nu=0.3), Tip("sphere", radius=0.01),
                         Specimen(1.0, diameter=4.0), 3e-3, 0.3, "neo-hookean",
                         specimen=False),
}


def case_trace(case: Case, seed: int, sim_mesh: str = "fine"):
    """Trace ``seed`` of ``case``: the block free on its plate, the paper's noise."""
    return simulate_trace(case.solid, case.tip, block=case.block, depth=case.depth, base="free",
                          rng=seed, twin_resolution=sim_mesh, trace_id=f"law-{seed:03d}")


def _fit(case: Case, trace, law: str | None, fit_mesh: str, half_space: bool = False) -> dict:
    where = ({"half_space": True} if half_space
             else {"specimen": case.specimen_text} if case.specimen else {"half_space": True})
    extra = {} if law is None else {"law": law, "law_shape": case.law_shape,
                                    "law_mesh": fit_mesh}
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        row = pb.fit(trace, nu=case.nu, engine="exact", bonding="free", **where,
                     **extra).summary().iloc[0].to_dict()
    row["seconds"] = time.perf_counter() - t0
    return row


def run_case(name: str, n: int = 10, sim_mesh: str = "fine", fit_mesh: str = "default",
             linear: bool = True) -> pd.DataFrame:
    """One row per trace of case ``name``: the law fit's E0 and intervals, seconds, and (with
    ``linear``) the linear fits' E and full intervals."""
    case = CASES[name]
    rows = []
    for seed in range(n):
        tr = case_trace(case, seed, sim_mesh)
        law = _fit(case, tr, case.law, fit_mesh)
        row = {"case": name, "seed": seed, "E_true": case.solid.E0, "E": law["E_pa"],
               "lo": law["E_lo_pa"], "hi": law["E_hi_pa"], "stat_lo": law["E_stat_lo_pa"],
               "stat_hi": law["E_stat_hi_pa"], "seconds": law["seconds"],
               "law_params": law["law_params"], "E_instron_law": law["E_instron_law_pa"],
               "model_ok": law["model_ok"]}
        if linear:
            for label, half in (("lin", False), ("lin_hs", True)):
                if label == "lin" and not case.specimen:
                    continue
                lin = _fit(case, tr, None, fit_mesh, half_space=half)
                row.update({label: lin["E_pa"], f"{label}_lo": lin["E_lo_pa"],
                            f"{label}_hi": lin["E_hi_pa"],
                            f"{label}_nh": _kept(lin["modelform_models"])})
        rows.append(row)
    return pd.DataFrame(rows)


def _kept(models: str) -> bool:
    """True when the model form's neo-Hookean reading entered the envelope."""
    for part in str(models).split(" | "):
        if part.startswith("neo-Hookean"):
            return "left out" not in part
    return False


def figures(df: pd.DataFrame) -> dict:
    """The case's figures: coverage counts, median errors, linear offsets, seconds."""
    t = df["E_true"]
    out = {"n": len(df), "covered": int(((df.lo <= t) & (t <= df.hi)).sum()),
           "covered_stat": int(((df.stat_lo <= t) & (t <= df.stat_hi)).sum()),
           "median_error_pct": float(100 * np.median(df.E / t - 1)),
           "cold_s": float(df.seconds.iloc[0]),
           "cached_s": float(np.median(df.seconds.iloc[1:])) if len(df) > 1 else np.nan}
    for label in ("lin", "lin_hs"):
        if label in df:
            out[f"{label}_offset_pct"] = float(100 * np.median(df[label] / t - 1))
            out[f"{label}_covered"] = int(((df[f"{label}_lo"] <= t)
                                           & (t <= df[f"{label}_hi"])).sum())
            out[f"{label}_nh_kept"] = int(df[f"{label}_nh"].sum())
    return out


def proxy(mesh: str = "default") -> None:
    """The half-space proxy against Hertz/Sneddon at small depth: the neo-Hookean law's F/E*
    on the proxy (palpbayes.twin.hyper_shape) over the linear half-space's at d/L 0.0025-0.01,
    and its value extrapolated to d = 0 (the finite-strain term is linear in sqrt(d))."""
    from palpbayes.contact import shape
    from palpbayes.fitdata import ModelSpec
    from palpbayes.twin.hyper_shape import LawModel, table_depth

    for tip in (Tip("sphere", radius=0.01), Tip("paraboloid", radius=0.01),
                Tip("flat", radius=0.01)):
        d = np.array([0.0025, 0.005, 0.0075, 0.01]) * 0.01
        for nu in (0.3, 0.45):
            t0 = time.perf_counter()
            law = LawModel("neo-hookean", depth=table_depth(d[-1]), resolution=mesh)
            r = ModelSpec(tip, nu=nu, law=law).shape(d) / shape(d, tip)
            icpt = np.polyfit(np.sqrt(d), r, 1)[1]
            print(f"half-space proxy, {tip.describe()}, nu {nu}, {mesh} mesh: F/F_linear at d/L "
                  f"{', '.join(f'{v:g}' for v in d / 0.01)} = "
                  f"{', '.join(f'{v:.4f}' for v in r)}; extrapolated to d = 0: {icpt:.4f} "
                  f"({time.perf_counter() - t0:.0f} s)", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--proxy", action="store_true",
                    help="the half-space proxy against Hertz at small depth, then the cases")
    ap.add_argument("--case", choices=sorted(CASES), action="append")
    ap.add_argument("--n", type=int, default=10)
    ap.add_argument("--sim-mesh", default="fine")
    ap.add_argument("--fit-mesh", default="default")
    ap.add_argument("--cache", help="the finite elements' cache (default: a fresh folder)")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as fresh:
        os.environ["PALPBAYES_CACHE_DIR"] = args.cache or fresh
        if args.proxy:
            proxy(args.fit_mesh)
        for name in args.case or ([] if args.proxy else CASES):
            t0 = time.perf_counter()
            df = run_case(name, args.n, args.sim_mesh, args.fit_mesh)
            f = figures(df)
            text = (f"{name}: E0 covered {f['covered']}/{f['n']} (statistical alone "
                    f"{f['covered_stat']}/{f['n']}), median error {f['median_error_pct']:+.2f} %")
            for label, what in (("lin", "linear --specimen"), ("lin_hs", "linear half-space")):
                if f"{label}_offset_pct" in f:
                    text += (f"; {what} {f[f'{label}_offset_pct']:+.1f} %, its interval covers "
                             f"{f[f'{label}_covered']}/{f['n']} (neo-Hookean reading kept "
                             f"{f[f'{label}_nh_kept']}/{f['n']})")
            text += (f"; law fit {f['cold_s']:.0f} s cold, {f['cached_s']:.1f} s cached; "
                     f"case {time.perf_counter() - t0:.0f} s; shape {df.law_params.iloc[0]}")
            print(text, flush=True)


if __name__ == "__main__":
    main()
