"""Benchmark: simulate a 3 × 3 × 10 campaign (90 traces) and fit it end to end.

Fits with ``method="both"`` (least squares + Bayes, default sampler) on all cores and prints
the wall time of each stage and the throughput.  Goal: fitting in <= 60 s on 2 cores.  Only
prints; no assertions.

    python benchmarks/bench_campaign.py [--repetitions 10] [--workers N] [--compare]
                                        [--base free|bonded|none] [--engine emcee|exact]

The blocks lie free on a plate (the package's default simulation) and are fitted with the
package's default model (a layer of known thickness, base unknown); ``--base none`` simulates
half-spaces, which the default model then fits as half-spaces too (the paper's setting).
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

from palpbayes.campaign.fitjob import FitOptions
from palpbayes.campaign.run import fit_campaign
from palpbayes.sim import simulate


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--repetitions", type=int, default=10)
    p.add_argument("--workers", type=int, default=None)
    p.add_argument("--seed", type=int, default=2026)
    p.add_argument("--compare", action="store_true", help="also time 'compare' (pooling)")
    p.add_argument("--base", default="free", choices=("free", "bonded", "none"))
    p.add_argument("--engine", default="emcee", choices=("emcee", "exact"))
    args = p.parse_args()
    workers = args.workers or os.cpu_count() or 1
    with tempfile.TemporaryDirectory() as tmp:
        camp, res = Path(tmp) / "campaign", Path(tmp) / "results"
        t0 = time.perf_counter()
        base = None if args.base == "none" else args.base
        simulate(camp, seed=args.seed, repetitions=args.repetitions, base=base)
        t1 = time.perf_counter()
        layer = "off" if base is None else "auto"
        summary = fit_campaign(camp / "manifest.csv", res,
                               FitOptions(method="both", seed=args.seed, layer=layer,
                                          engine=args.engine),
                               workers=workers, progress=False)
        t2 = time.perf_counter()
        n = summary["trace_id"].nunique()
        bayes = summary[summary["method"] == "bayes"]
        print(f"simulate: {n} traces in {t1 - t0:.1f} s (base {args.base}; fitted with the "
              f"{'half-space' if base is None else 'layer, base unknown'}, {args.engine})")
        print(f"fit (both, {workers} worker(s), {os.cpu_count()} core(s)): {t2 - t1:.1f} s, "
              f"{n / (t2 - t1):.2f} traces/s, {(t2 - t1) * workers / n:.2f} core-s per trace")
        print(f"converged: {int(bayes['converged'].astype(bool).sum())}/{len(bayes)}, median "
              f"steps {bayes['n_steps'].median():.0f}")
        if args.compare:
            from palpbayes.campaign.comparison import compare

            cmp = compare(res)
            t3 = time.perf_counter()
            print(f"compare (pooling {len(cmp.pooled)} groups): {t3 - t2:.1f} s")
            print(cmp.format())


if __name__ == "__main__":
    main()
