"""Real-recording workloads: Bayesian fits of long traces and AFM curves, and the model checks.

Prints, measured in this run on this machine:

* wall time, emcee steps and E error of the Bayesian fit of a paper-like trace at 3,840 and
  15,360 points (800 Hz and 3.2 kHz), and their ratio (16,000-point traces used to
  take up to 55 s and hit the 20,000-step cap);
* CPU time of every model check (:func:`palpbayes.checks.run_checks`, with 200 posterior
  draws) on those traces, as a fraction of the fit;
* for the real AFM curves in ../shared/data/afm-curves (when present): fit time, steps, and
  E* and contact point against their reference.

Run: ``python benchmarks/bench_real.py``.
"""

from __future__ import annotations

import time
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
from common import E_TRUE, TIPS

from palpbayes.campaign.fitjob import FitOptions, fit_trace
from palpbayes.checks import check_fit as model_checks
from palpbayes.contact import Tip
from palpbayes.errors import ConvergenceWarning
from palpbayes.io.trace_csv import read_trace
from palpbayes.sim import simulate_trace

AFM = Path(__file__).resolve().parents[2] / "shared" / "data" / "afm-curves"


def _fit(trace, **kw):
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        out = fit_trace(trace, FitOptions(method="bayes", seed=1, **kw))
    return out, time.perf_counter() - t0


def _checks_cpu(out) -> float:
    b = out.bayes
    med = b.median_theta()
    post = b.idata.posterior
    draws = {n: np.asarray(post[n]).ravel() for n in ("E_star", "z_surf", "F0", "sigma")}
    t0 = time.process_time()
    model_checks(b.data, z_surf=med["z_surf"], estar=med["E_star"], f0=med["F0"],
                 sigma=med["sigma"], draws=draws)
    return time.process_time() - t0


def main() -> None:
    print("Bayesian fit of a paraboloid trace (E = 111 kPa, 3 mm into 30 mm), seed 1")
    times = {}
    for rate in (800.0, 3200.0):
        tr = simulate_trace(E_TRUE, TIPS["paraboloid"], thickness=0.03, rate=rate, rng=3, base=None)
        out, wall = _fit(tr)
        row = out.rows[0]
        times[rate] = wall
        chk = _checks_cpu(out)
        print(f"  {tr.n_points:6d} points: {wall:5.2f} s, {int(row['n_steps'])} steps, "
              f"E error {100 * (row['E_stat_pa'] / E_TRUE - 1):+.3f} %, converged "
              f"{row['converged']}; checks {chk:.3f} s CPU = {chk / wall:.2f} of the fit")
    print(f"  time ratio 15,360 / 3,840 points: {times[3200.0] / times[800.0]:.2f}")
    if not AFM.is_dir():
        print(f"(real AFM curves not found at {AFM}: skipped)")
        return
    ref = pd.read_csv(AFM / "references.csv").set_index("file")
    print("Real AFM curves (raw force, nu = 0.5, paraboloid R = 10 µm, no other option)")
    tip = Tip("paraboloid", radius=10e-6)
    for name in ("force-save-example", "map1d-curve7"):
        tr = read_trace(AFM / f"{name}.csv", tip=tip)
        out, wall = _fit(tr, nu=0.5)
        row = out.rows[0]
        r = ref.loc[f"{name}.csv"]
        de = row["Estar_pa"] / (r["E_pa"] / 0.75) - 1
        dz = (row["z_surf_m"] - r["contact_point_m"]) * 1e9
        print(f"  {name}: {tr.n_points} points, {wall:.1f} s, {int(row['n_steps'])} steps, "
              f"E*/ref - 1 = {de:+.2e}, contact point {dz:+.2f} nm, model_ok "
              f"{row['model_ok']}")


if __name__ == "__main__":
    main()
