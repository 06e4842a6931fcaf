"""Benchmark: simulate a 3 × 3 × 10 campaign (90 traces) and fit it end to end.

Fits with ``method="both"`` (least squares + Bayes, default sampler) on all cores and prints
the wall time of each stage and the throughput.  Goal: fitting in <= 60 s on 2 cores.  Only
prints; no assertions.

    python benchmarks/bench_campaign.py [--repetitions 10] [--workers N] [--compare]
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

from palpbayes.campaign import fit_campaign
from palpbayes.fitjob import FitOptions
from palpbayes.sim import simulate_campaign


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--repetitions", type=int, default=10)
    p.add_argument("--workers", type=int, default=None)
    p.add_argument("--seed", type=int, default=2026)
    p.add_argument("--compare", action="store_true", help="also time 'compare' (pooling)")
    args = p.parse_args()
    workers = args.workers or os.cpu_count() or 1
    with tempfile.TemporaryDirectory() as tmp:
        camp, res = Path(tmp) / "campaign", Path(tmp) / "results"
        t0 = time.perf_counter()
        simulate_campaign(camp, seed=args.seed, repetitions=args.repetitions)
        t1 = time.perf_counter()
        summary = fit_campaign(camp / "manifest.csv", res,
                               FitOptions(method="both", seed=args.seed), workers=workers,
                               progress=False)
        t2 = time.perf_counter()
        n = summary["trace_id"].nunique()
        bayes = summary[summary["method"] == "bayes"]
        print(f"simulate: {n} traces in {t1 - t0:.1f} s")
        print(f"fit (both, {workers} worker(s), {os.cpu_count()} core(s)): {t2 - t1:.1f} s, "
              f"{n / (t2 - t1):.2f} traces/s, {(t2 - t1) * workers / n:.2f} core-s per trace")
        print(f"converged: {int(bayes['converged'].astype(bool).sum())}/{len(bayes)}, median "
              f"steps {bayes['n_steps'].median():.0f}")
        if args.compare:
            from palpbayes.compare import compare_campaign

            cmp = compare_campaign(res)
            t3 = time.perf_counter()
            print(f"compare (pooling {len(cmp.pooled)} groups): {t3 - t2:.1f} s")
            print(cmp.format())


if __name__ == "__main__":
    main()
