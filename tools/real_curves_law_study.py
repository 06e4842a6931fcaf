#!/usr/bin/env python
"""Real AFM curves: the linear half-space against a law that stiffens with strain.

Every real AFM curve stiffens with depth: E* over the shallow half of the depth is 21–56 %
below E* over all of it (issue 56).  This script fits every curve that the readers return from
``<shared>/afm-curves`` and ``<shared>/afm-files`` (as ``tools/real_curves_layer_study.py``
reads them: a paraboloid of R = 5 µm for PyFMRheo's map, 10 µm for the others, nu = 0.5, the
exact engine) twice:

(a) linear, the half-space (``FitOptions(layer="off")``);
(b) ``--law NAME`` (default ``exponential``: Demiray's W = mu/(2b)(exp(b(I1 − 3)) − 1), b free
    on the law's grid) on the finite-strain twin's half-space proxy (coarse mesh by default).

One CSV row per curve and model (``--out``): E (E0 under the law), its 90 % interval, the
statistical interval, model_ok, the failed checks, the depth-consistency ratio (E* of the
shallow half over all), the law's parameters and the fit time.  Then it prints how many curves
pass every check under each model, how many pass the depth check, and how E0 moves against
the linear E.

Run from the repository root (the first run solves the twin's curves: minutes)::

    .venv/bin/python tools/real_curves_law_study.py --out /tmp/laws.csv
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parent))
from real_curves_layer_study import DEFAULT_SHARED, FOLDERS, NOT_DATA, curves_of  # noqa: E402

from palpbayes.campaign.fitjob import FitOptions, fit_trace  # noqa: E402
from palpbayes.campaign.options import LawOptions  # noqa: E402
from palpbayes.errors import PalpbayesError  # noqa: E402

NU = 0.5


def fit_one(curve, law: str, mesh: str) -> dict:
    tr = curve.trace
    row = {"file": curve.file, "curve": curve.index, "trace_id": tr.trace_id,
           "tip_radius_m": curve.tip_radius, "model": law}
    opts = FitOptions(method="bayes", nu=NU, layer="off", engine="exact", seed=0,
                      law=LawOptions(name=law, mesh=mesh))
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            out = fit_trace(tr, opts)
        except PalpbayesError as exc:
            row.update(status="refused", message=f"{type(exc).__name__}: {exc}",
                       fit_s=time.perf_counter() - t0)
            return row
    r = out.rows[0]
    checks = {c.name: c for c in out.bayes.checks}
    row.update(
        status="ok", fit_s=time.perf_counter() - t0, E_pa=r["E_pa"], E_lo_pa=r["E_lo_pa"],
        E_hi_pa=r["E_hi_pa"], E_stat_lo_pa=r["E_stat_lo_pa"], E_stat_hi_pa=r["E_stat_hi_pa"],
        converged=r["converged"], model_ok=r["model_ok"],
        failed_checks="+".join(c.name for c in out.bayes.checks if not c.passed),
        depth_ratio=float(checks["depth_consistency"].statistic)
        if "depth_consistency" in checks else np.nan,
        depth_ok=bool(checks["depth_consistency"].passed) if "depth_consistency" in checks
        else None,
        law_params=r.get("law_params", ""), depth_m=float(out.bayes.data.z_contact
                                                          - out.bayes.data.z_min))
    return row


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--shared", type=Path, default=DEFAULT_SHARED)
    p.add_argument("--out", type=Path, required=True)
    p.add_argument("--law", default="exponential")
    p.add_argument("--mesh", default="coarse")
    p.add_argument("--limit", type=int, default=None, help="at most N curves per file")
    args = p.parse_args(argv)
    rows = []
    for folder in FOLDERS:
        for path in sorted((args.shared / folder).iterdir()):
            if path.name in NOT_DATA or path.suffix == ".txt":
                continue
            for curve in curves_of(path, args.limit):
                if curve.trace is None:
                    continue
                for law in ("linear", args.law):
                    row = fit_one(curve, law, args.mesh)
                    rows.append(row)
                    print(f"{row['file']}#{row['curve']} {law}: {row['status']} "
                          f"E {row.get('E_pa', np.nan):.4g} ok {row.get('model_ok')} "
                          f"depth {row.get('depth_ratio', np.nan):.3f} "
                          f"{row.get('failed_checks', row.get('message', ''))} "
                          f"({row['fit_s']:.1f} s)", flush=True)
    df = pd.DataFrame(rows)
    df.to_csv(args.out, index=False)
    ok = df[df["status"] == "ok"]
    lin = ok[ok["model"] == "linear"].set_index(["file", "curve"])
    law = ok[ok["model"] == args.law].set_index(["file", "curve"])
    both = lin.index.intersection(law.index)
    print(f"\n{len(both)} curves fitted both ways")
    for name, d in (("linear", lin.loc[both]), (args.law, law.loc[both])):
        print(f"  {name}: every check passes on {int(d['model_ok'].sum())}, the depth check "
              f"on {int(d['depth_ok'].sum())}; depth ratio median {d['depth_ratio'].median():.3f}")
    shift = law.loc[both, "E_pa"] / lin.loc[both, "E_pa"] - 1
    print(f"  E0 ({args.law}) against the linear E: median {shift.median():+.1%}, range "
          f"{shift.min():+.1%} .. {shift.max():+.1%}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
