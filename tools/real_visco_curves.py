"""How many of the 24 real viscoelastic AFM curves pass every check, and why the rest fail.

The curves with a hold or a retract in ``../shared/data/afm-files/``: the stress-relaxation
cell, the two creep curves (brain, polymer gel), spot3, afmformats' 2 × 2 map and PyFMRheo's
4 × 4 map.  Each is fitted with the power law as a new user would (every recorded segment, a
5 µm paraboloid, nu 0.5, the defaults: drag fitted with the retract, constant baseline), then
with the options the failed checks point to: ``--baseline linear`` and, where there is a
retract, ``--adhesion cut``.  Prints one line per curve and the counts::

    python tools/real_visco_curves.py [--workers 2]
"""

from __future__ import annotations

import argparse
import sys
from collections import Counter
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

from palpbayes.contact import Tip
from palpbayes.errors import PalpbayesError
from palpbayes.io.afm import read_afm
from palpbayes.rheology import fit_rheology

SHARED = Path(__file__).resolve().parents[2] / "shared" / "data" / "afm-files"
FILES = {  # file: curves (None: all)
    "fmt-jpk-sr_cell1-0008.jpk-force": None,
    "fmt-jpk-cc_pr14-brain-2021.06.30.jpk-force": None,
    "fmt-jpk-cc_pr14-polymergel-2021.06.30.jpk-force": None,
    "fmt-jpk-fd_spot3-0192.jpk-force": None,
    "fmt-jpk-fd_map2x2_extracted.jpk-force-map": None,
    "pyfmrheo-map-data-2022.10.29-12.27.34.564.jpk-force-map": None,
}
TIP = Tip("paraboloid", radius=5e-6)


def _reason(flag: str) -> str:
    """A short name for a flag (the first words before its colon)."""
    for key, name in (("phi piles up", "residual drift (phi at its bound)"),
                      ("tilt with the height", "tilted baseline"),
                      ("lets go", "adhesion at pull-off"),
                      ("predictive", "posterior-predictive check"),
                      ("alpha piles up", "alpha at its bound"),
                      ("contact shrinks", "contact shrinks in the hold"),
                      ("another basin", "other basins of the surface"),
                      ("surface", "surface at its bound")):
        if key in flag:
            return name
    return flag.split(":")[0][:50]


def _fit(job: tuple[str, int]) -> dict:
    name, i = job
    tr = read_afm(SHARED / name, tip=TIP, curves=[i], segments="all")[0]
    segs = ",".join(tr.segment_names)
    out = {"curve": f"{name[:28]}#{i}", "segments": segs}
    for label, kw in (("default", {}),
                      ("tuned", {"baseline": "linear",
                                 **({"adhesion": "cut"} if "retract" in segs else {})})):
        try:
            fit = fit_rheology(tr, "power-law", nu=0.5, segments=segs, **kw)
        except PalpbayesError as exc:
            out[label] = {"error": str(exc)[:80]}
            continue
        ppc_failed = not fit.ppc.passed if hasattr(fit.ppc, "passed") else False
        reasons = sorted({_reason(f) for f in fit.flags}
                         | ({"posterior-predictive check"} if ppc_failed else set()))
        out[label] = {"ok": bool(fit.model_ok), "E0s": float(np.median(fit.draws["E0"])),
                      "alpha": float(np.median(fit.draws["alpha"])), "reasons": reasons}
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--workers", type=int, default=2)
    a = ap.parse_args(argv)
    if not SHARED.exists():
        print(f"no {SHARED}", file=sys.stderr)
        return 2
    from palpbayes.io.afm import describe_afm
    jobs = []
    for name in FILES:
        n = len(describe_afm(SHARED / name))
        jobs += [(name, i) for i in range(n)]
    with ProcessPoolExecutor(a.workers) as ex:
        rows = list(ex.map(_fit, jobs))
    counts = {k: Counter() for k in ("default", "tuned")}
    for r in rows:
        line = [f"{r['curve']:34s} {r['segments']:24s}"]
        for k in ("default", "tuned"):
            f = r[k]
            if "error" in f:
                line.append(f"{k}: error {f['error']}")
                counts[k]["error"] += 1
                continue
            line.append(f"{k}: E0* {f['E0s']:7.4g} Pa alpha {f['alpha']:.3f} "
                        f"{'PASS' if f['ok'] else 'fail (' + '; '.join(f['reasons']) + ')'}")
            counts[k]["pass" if f["ok"] else "fail"] += 1
            for reason in ([] if f["ok"] else f["reasons"]):
                counts[k][reason] += 1
        print(" | ".join(line))
    for k, c in counts.items():
        print(f"{k}: {c['pass']}/{len(rows)} pass every check; failures: "
              + ", ".join(f"{n} {r}" for r, n in c.most_common() if r not in ("pass", "fail")))
    return 0


if __name__ == "__main__":
    sys.exit(main())
