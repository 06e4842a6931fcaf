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
10 mm across (radius 5 mm), modulus ratio 10, its centre 5-10 mm deep.  For each depth it
prints the apparent modulus ratio a fit of the press reads (least squares of F = k·d^1.5 over
the press, 20 depths per press: k_lump / k_block) at 10 % (2 mm) and 20 % (4 mm), by the
twin and by the screening model (its ratio at the press's contact radius), and writes the
table to ``reports/active/lump_depth.csv``.

Run: ``python benchmarks/bench_lump_depth.py [--resolution coarse|default] [--depths 5,7,9]``
(coarse: ~1 min per lump depth on 2 cores; its ratios within 0.2 % of default's).
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


def row(depth: float, resolution: str) -> dict:
    depths = np.concatenate([np.linspace(0.05, 1.0, 20) * p * H for p in PRESSES])
    depths = np.unique(depths)
    t0 = time.perf_counter()
    shapes = {r: solve_palpation(WIDTH, H, TIP, NU, BASE, depths, resolution,
                                 CentredLump(LUMP_R, depth, r)).shape for r in (RATIO, 1.0)}
    out = {"lump_centre_depth_mm": 1e3 * depth, "seconds": time.perf_counter() - t0}
    for p in PRESSES:
        d = p * H
        V = sensitivity(0.0, radius=LUMP_R, depth=depth, contact_radius=contact_radius(TIP, d),
                        thickness=H)
        tag = f"{round(100 * p)}pct"
        out[f"twin_{tag}"] = fitted_ratio(depths, shapes[RATIO], shapes[1.0], d)
        out[f"screening_{tag}"] = float(apparent_ratio(V, RATIO))
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--resolution", default="coarse", choices=("coarse", "default", "fine"))
    ap.add_argument("--depths", default="5,6,7,8,9,9.6,10",
                    help="lump centre depths [mm], comma-separated")
    ap.add_argument("--out", default=str(ROOT / "reports" / "active" / "lump_depth.csv"))
    args = ap.parse_args(argv)
    rows = []
    print(f"{'centre':>7} {'twin 10%':>9} {'twin 20%':>9} {'screen 10%':>11} "
          f"{'screen 20%':>11} {'twin/screen (log) 10%':>22} {'s':>6}")
    for mm in (float(v) for v in args.depths.split(",")):
        r = row(1e-3 * mm, args.resolution)
        rows.append(r)
        gain = np.log(r["twin_10pct"]) / np.log(r["screening_10pct"])
        print(f"{mm:5.1f}mm {r['twin_10pct']:9.4f} {r['twin_20pct']:9.4f} "
              f"{r['screening_10pct']:11.4f} {r['screening_20pct']:11.4f} {gain:22.1f} "
              f"{r['seconds']:6.1f}", flush=True)
    table = pd.DataFrame(rows)
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    table.to_csv(args.out, index=False)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
