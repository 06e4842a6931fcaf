"""How a lump's signature changes from a 10 % to a 20 % press: screening model against the twin.

Issue 60 asks how the signature of a lump ~9 mm deep grows when the press goes from 10 % to
20 % of the block's thickness, by the search's forward model and by a simulator.  The forward
model is :mod:`palpbayes.inclusion` (a Boussinesq-weighted Reuss average: the model the map
simulator, the bench's phantoms and the search's profiles all use).  The simulator here is the
finite-element twin (:func:`palpbayes.twin.palpation.solve_palpation` with a
:class:`~palpbayes.twin.palpation.CentredLump`): linear elasticity with the lump meshed, the
contact solved — the one independent answer, for a press straight above the lump's centre
(the only axisymmetric placement).

The block is the bench's phantom (:class:`palpbayes.sim.phantom.MapPhantom`): 20 mm thick,
bonded to its plate, nu 0.3, the paper's paraboloid (R = 11.7 mm); 120 mm across; the lump
10 mm across (radius 5 mm), modulus ratio 10 (``--ratio``: any positive ratio, < 1 a soft
lump), its centre 5-10 mm deep.  For each depth it prints the apparent modulus ratio a fit of
the press reads (least squares of F = k·d^1.5 over the press, 20 depths per press:
k_lump / k_block) at 10 % (2 mm) and 20 % (4 mm), by the twin (``twin_*``) and by the
screening model at the press's contact radius, with two averages of the same
stress-weighted volume fraction V: the Reuss (series) average the model uses
(:func:`palpbayes.inclusion.apparent_ratio`, ``screening_*``) and, as a tried alternative, the
Hill average, the mean of the Reuss and the Voigt (parallel) 1 + (ratio − 1)·V (``hill_*``;
R. Hill 1952, Proc. Phys. Soc. A 65, 349–354): it matched the twin at ratio 10 only.  Per row
it also prints each average's error in log excess against the twin, log(model)/log(twin) − 1
(0: the same signature; −0.7: 70 % too little).  It writes the table
to ``reports/active/lump_depth.csv`` for ratio 10 and to
``reports/active/lump_depth_ratio{R:g}.csv`` for another ratio R (``--out`` overrides).

Run: ``python benchmarks/bench_lump_depth.py [--ratio 10] [--resolution coarse|default|fine]
[--depths 5,7,9]`` (a few seconds per lump depth: coarse ~1.5 s, default ~4 s, fine ~10 s;
coarse's ratios within 0.2 % of default's and fine's).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
import pandas as pd

from palpbayes.contact import Tip
from palpbayes.inclusion import apparent_ratio, contact_radius, sensitivity
from palpbayes.twin.palpation import CentredLump, solve_palpation

ROOT = Path(__file__).resolve().parents[1]
TIP = Tip("paraboloid", radius=0.0117)
H, NU, WIDTH, BASE = 0.020, 0.3, 0.060, "bonded"
LUMP_R, RATIO = 5e-3, 10.0
PRESSES = (0.10, 0.20)  # of the thickness


def fitted_ratio(depths: np.ndarray, lump: np.ndarray, block: np.ndarray, to: float) -> float:
    """k_lump / k_block of least-squares fits F = k·d^1.5 over the depths up to ``to``."""
    m = depths <= to * (1 + 1e-9)
    w = depths[m] ** 1.5
    return float(np.dot(lump[m], w) / np.dot(block[m], w))


def row(depth: float, resolution: str, ratio: float = RATIO) -> dict:
    depths = np.concatenate([np.linspace(0.05, 1.0, 20) * p * H for p in PRESSES])
    depths = np.unique(depths)
    t0 = time.perf_counter()
    shapes = {r: solve_palpation(WIDTH, H, TIP, NU, BASE, depths, resolution,
                                 CentredLump(LUMP_R, depth, r)).shape for r in (ratio, 1.0)}
    out = {"lump_centre_depth_mm": 1e3 * depth, "seconds": time.perf_counter() - t0}
    for p in PRESSES:
        d = p * H
        V = sensitivity(0.0, radius=LUMP_R, depth=depth, contact_radius=contact_radius(TIP, d),
                        thickness=H)
        tag = f"{round(100 * p)}pct"
        out[f"twin_{tag}"] = fitted_ratio(depths, shapes[ratio], shapes[1.0], d)
        out[f"screening_{tag}"] = float(apparent_ratio(V, ratio))
        reuss = out[f"screening_{tag}"]  # Hill: the mean of Reuss and Voigt on the same V
        out[f"hill_{tag}"] = 0.5 * (reuss + 1.0 + (ratio - 1.0) * V)
    return out


def log_error(model: float, twin: float) -> float:
    """Error of ``model`` in log excess against ``twin``: log(model)/log(twin) − 1."""
    return float(np.log(model) / np.log(twin) - 1.0)


def default_out(ratio: float) -> Path:
    """``reports/active/lump_depth.csv`` for ratio 10, ``lump_depth_ratio{R:g}.csv`` else."""
    name = "lump_depth.csv" if ratio == RATIO else f"lump_depth_ratio{ratio:g}.csv"
    return ROOT / "reports" / "active" / name


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--ratio", type=float, default=RATIO,
                    help="the lump's modulus ratio E_lump/E_block (default 10; < 1: soft)")
    ap.add_argument("--resolution", default="coarse", choices=("coarse", "default", "fine"))
    ap.add_argument("--depths", default="5,6,7,8,9,9.6,10",
                    help="lump centre depths [mm], comma-separated")
    ap.add_argument("--out", default=None,
                    help="output CSV (default reports/active/lump_depth.csv for ratio 10, "
                         "lump_depth_ratio{R:g}.csv for another)")
    args = ap.parse_args(argv)
    if not (np.isfinite(args.ratio) and args.ratio > 0 and args.ratio != 1.0):
        ap.error(f"--ratio must be positive, finite and not 1, got {args.ratio:g}")
    out_path = Path(args.out) if args.out else default_out(args.ratio)
    rows = []
    print(f"lump modulus ratio {args.ratio:g}; log-excess error = log(model)/log(twin) - 1")
    print(f"{'centre':>7} {'twin10':>7} {'reuss10':>7} {'hill10':>7} {'twin20':>7} "
          f"{'reuss20':>7} {'hill20':>7} {'errR10':>7} {'errH10':>7} {'errR20':>7} "
          f"{'errH20':>7} {'s':>6}")
    for mm in (float(v) for v in args.depths.split(",")):
        r = row(1e-3 * mm, args.resolution, args.ratio)
        rows.append(r)
        errs = [log_error(r[f"{m}_{t}"], r[f"twin_{t}"])
                for t in ("10pct", "20pct") for m in ("screening", "hill")]
        print(f"{mm:5.1f}mm {r['twin_10pct']:7.4f} {r['screening_10pct']:7.4f} "
              f"{r['hill_10pct']:7.4f} {r['twin_20pct']:7.4f} {r['screening_20pct']:7.4f} "
              f"{r['hill_20pct']:7.4f} " + " ".join(f"{e:+7.3f}" for e in errs)
              + f" {r['seconds']:6.1f}", flush=True)
    table = pd.DataFrame(rows)
    out_path.parent.mkdir(parents=True, exist_ok=True)
    table.to_csv(out_path, index=False)
    print(f"wrote {out_path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
