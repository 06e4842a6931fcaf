"""Median wall time of one least-squares fit on a 3,840-point paper-like trace.

Run: ``python benchmarks/bench_lsq.py``.  This is the reference the Bayesian fit is compared
with in ``bench_bayes.py``.
"""

from __future__ import annotations

from common import TIPS, median_time, paper_trace

from palpbayes.lsq import fit_lsq


def main() -> dict[str, float]:
    out = {}
    print(f"{'tip':<11} {'points':>6} {'median LS time':>15}")
    for kind in TIPS:
        tr = paper_trace(kind)
        fit_lsq(tr)  # warm-up
        t = median_time(lambda tr=tr: fit_lsq(tr), repeat=21)
        out[kind] = t
        print(f"{kind:<11} {tr.n_points:>6} {t * 1e3:>12.2f} ms")
    return out


if __name__ == "__main__":
    main()
