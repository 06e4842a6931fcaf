"""How long a block may be before its twin's equal-area cylinder stops standing for it.

The specimen twin models a block L × W × H as the cylinder of equal footprint area.  For a
square 50 × 50 mm footprint that is within 0.2-0.7 % of the block itself
(``bench_twin_3d.py``); an elongated footprint of the same area is softer than its cylinder
(the near sides are nearer).  For footprints of 2,500 mm² at L/W = 1, 1.44, 2 and 3 (H 20 mm,
nu 0.3, free base; the paper's sphere R 10 mm and flat punch a = 10 mm, 2 mm deep) this prints
the width effect F(block)/F(8 × wider) − 1 in 3-D (:mod:`palpbayes.twin.solid3d`, its
``coarse`` mesh) and for the cylinders (:func:`palpbayes.twin.solve_palpation`, ``fine``), and
their ratio − 1: the equivalence's error.  It sets :data:`palpbayes.twin.MAX_ASPECT` (3:1,
refused beyond) and the note beyond 1.5:1 (:data:`palpbayes.bayes.layer_fit.ELONGATED`).

Run: ``python benchmarks/bench_twin_aspect.py`` (about 4 minutes on 2 cores).
"""

from __future__ import annotations

import math
import time

import numpy as np
from common import TIPS

from palpbayes.twin.palpation import solve_palpation
from palpbayes.twin.solid3d import palpation_force_3d

H, NU, AREA, DEPTH = 0.02, 0.3, 0.05 * 0.05, 2e-3


def main() -> None:
    print(f"width effect (block / 8x wider - 1) and the equal-area cylinder's error, "
          f"H {1e3 * H:g} mm, nu {NU}, free base, depth {1e3 * DEPTH:g} mm")
    print(f"  {'L/W':>5} {'tip':<7} {'3-D':>8} {'cylinder':>9} {'error':>8} {'time':>6}")
    for aspect in (1.0, 1.44, 2.0, 3.0):
        length, width = math.sqrt(AREA * aspect), math.sqrt(AREA / aspect)
        for name in ("sphere", "flat"):
            tip = TIPS[name]
            t0 = time.perf_counter()
            block = palpation_force_3d(length, width, H, tip, NU, "free", DEPTH, "coarse")
            wide = palpation_force_3d(8 * length, 8 * length, H, tip, NU, "free", DEPTH,
                                      "coarse")
            radius = math.sqrt(AREA / math.pi)
            cyl = solve_palpation(radius, H, tip, NU, "free", np.array([DEPTH]), "fine")
            far = solve_palpation(8 * math.sqrt(length * length / math.pi), H, tip, NU, "free",
                                  np.array([DEPTH]), "fine")
            w3, wa = block / wide, cyl.shape[0] / far.shape[0]
            print(f"  {aspect:5.2f} {name:<7} {100 * (w3 - 1):+7.2f}% {100 * (wa - 1):+8.2f}% "
                  f"{100 * (w3 / wa - 1):+7.2f}% {time.perf_counter() - t0:5.0f}s")


if __name__ == "__main__":
    main()
