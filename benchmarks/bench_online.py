"""The exact engine and the online estimator, measured in one run.

Run: ``python benchmarks/bench_online.py [--traces 200]``.  Prints, on paper-like 3,840-point
traces (30 mm specimen, 3 mm indentation, 800 Hz):

1. the whole-trace exact posterior (``exact_posterior``) against one least-squares fit of the
   same trace, and the full ``fit_bayes(engine='exact')`` (draws, budget, checks, arviz) and
   ``fit_bayes`` with emcee against it — ratios, median of repeated runs;
2. one online update with 100 new samples (a UR robot streams at 500 Hz: 0.2 s of data), median
   and 95th percentile over a replay of the whole trace;
3. on ``--traces`` simulated palpations (three tips, moduli over a decade, random offsets)
   stopped at a ±2 % target: coverage of the 90 % intervals at the stop, and the median depth
   and peak force saved against the paper's fixed 10 % protocol.
"""

from __future__ import annotations

import argparse
import time
import warnings

import numpy as np
from common import TIPS, median_time, paper_trace

from palpbayes.bayes import BudgetSpec, PriorSpec, fit_bayes
from palpbayes.bayes.exact import exact_posterior
from palpbayes.fitdata import ModelSpec, prepare_trace
from palpbayes.lsq import fit_lsq
from palpbayes.online import OnlineEstimator, StoppingRule, chunks, run_to_stop
from palpbayes.sim import simulate_trace


def engine_vs_lsq() -> None:
    print("1. whole-trace posterior vs one least-squares fit (median of repeats)")
    print(f"{'tip':<11} {'noise':<8} {'LS':>8} {'exact':>8} {'ratio':>6} {'fit exact':>10} "
          f"{'ratio':>6} {'emcee':>8} {'ratio':>6}")
    for kind in TIPS:
        for noise in ("gaussian", "ar1"):
            tr = paper_trace(kind)
            data = prepare_trace(tr)
            prior = PriorSpec().for_trace(data, noise)
            fit_lsq(tr)
            t_ls = median_time(lambda tr=tr: fit_lsq(tr), repeat=11)
            t_ex = median_time(lambda d=data, p=prior: exact_posterior(d, p), repeat=11)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                t_fit = median_time(lambda tr=tr, n=noise: fit_bayes(
                    tr, noise=n, engine="exact", budget=BudgetSpec()), repeat=5)
                t_mc = median_time(lambda tr=tr, n=noise: fit_bayes(tr, noise=n), repeat=1)
            print(f"{kind:<11} {noise:<8} {t_ls * 1e3:>6.1f}ms {t_ex * 1e3:>6.1f}ms "
                  f"{t_ex / t_ls:>6.1f} {t_fit * 1e3:>8.0f}ms {t_fit / t_ls:>6.1f} "
                  f"{t_mc:>7.2f}s {t_mc / t_ls:>6.0f}")


def update_times() -> None:
    print("\n2. one online update with 100 new samples (3,840-sample trace)")
    print(f"{'tip':<11} {'median':>8} {'p95':>8} {'max':>8} {'updates':>8}")
    for kind in TIPS:
        tr = paper_trace(kind)
        times = []
        for rep in range(3):
            est = OnlineEstimator(ModelSpec(TIPS[kind]))
            for t, z, f in chunks(tr, 100):
                t0 = time.perf_counter()
                s = est.update(t, z, f)
                if s.in_contact and rep:
                    times.append(time.perf_counter() - t0)
        t = np.array(times) * 1e3
        print(f"{kind:<11} {np.median(t):>6.2f}ms {np.quantile(t, 0.95):>6.2f}ms "
              f"{t.max():>6.2f}ms {t.size // 2:>8}")


def stopped_runs(n: int) -> None:
    print(f"\n3. {n} simulated palpations stopped at a ±2 % target (90 % intervals)")
    rng = np.random.default_rng(314)
    hits, depth_saved, force_saved, stops = 0, [], [], 0
    for i in range(n):
        tip = list(TIPS.values())[i % 3]
        E = float(np.exp(rng.uniform(np.log(4e4), np.log(4e5))))
        tr = simulate_trace(E, tip, thickness=0.025, force_offset=float(rng.normal(0, 0.1)),
                            rng=rng, base=None)
        seg = tr.loading_segment()
        full_depth = tr.metadata["z_surf_true"] - seg.z.min()
        full_force = seg.force.max() - np.median(seg.force[:100])
        s = run_to_stop(tr, OnlineEstimator(ModelSpec(tip, nu=0.3),
                                            rule=StoppingRule(target=0.02)))
        stops += s.should_stop
        hits += s.E.lo <= E <= s.E.hi
        depth_saved.append(1 - s.depth / full_depth)
        force_saved.append(1 - s.peak_force / full_force)
    print(f"stopped by the rule: {stops}/{n}; coverage at the stop: {hits / n:.3f} "
          f"(binomial sd {np.sqrt(0.09 / n):.3f})")
    print(f"median depth saved: {100 * np.median(depth_saved):.1f} %, median peak force "
          f"saved: {100 * np.median(force_saved):.1f} % (against the full 10 % indentation)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--traces", type=int, default=200)
    args = parser.parse_args()
    engine_vs_lsq()
    update_times()
    stopped_runs(args.traces)


if __name__ == "__main__":
    main()
