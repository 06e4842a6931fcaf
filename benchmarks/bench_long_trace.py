"""Wall time and peak memory of ``palpbayes fit --method both`` against trace length.

Each size runs in a fresh process (``python -m palpbayes fit``) so its peak resident set size
(``ru_maxrss`` of the child) is measured alone; the 3,840-row paper trace is the baseline, so
the growth column is what the long trace itself costs.  Memory stays bounded because least
squares and the likelihood table work in blocks of at most 2^22 (trial surface × sample)
elements (:meth:`palpbayes.fitdata.FitData.blocks`).

    python benchmarks/bench_long_trace.py [--sizes 3840 100000 1000000]
"""

from __future__ import annotations

import argparse
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from palpbayes.contact import Tip
from palpbayes.io.trace_csv import write_trace
from palpbayes.sim import simulate_trace

SPEED = 50 / 60e3  # [m/s] 50 mm/min
DEPTH = 3e-3  # [m] 10 % of the White foam's 30 mm
APPROACH = 1e-3  # [m] the simulator's default approach


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--sizes", type=int, nargs="+", default=[3840, 100_000, 1_000_000])
    args = p.parse_args()
    print(f"{'rows':>9} {'file MB':>8} {'wall s':>7} {'peak RSS MB':>12} {'growth MB':>10}")
    base = None
    with tempfile.TemporaryDirectory() as tmp:
        for n in args.sizes:
            # sample rate giving ~n rows over the 4 mm of travel (approach + indentation)
            rate = n * SPEED / (DEPTH + APPROACH)
            tr = simulate_trace(111e3, Tip("paraboloid", radius=0.0117), thickness=0.03,
                                rate=rate, rng=1, base=None)
            path = write_trace(tr, Path(tmp) / f"trace{n}.csv")
            before = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
            t0 = time.perf_counter()
            subprocess.run([sys.executable, "-m", "palpbayes", "fit", str(path), "--tip",
                            "paraboloid", "--radius", "0.0117", "--method", "both", "--out",
                            str(Path(tmp) / f"res{n}")], check=True, capture_output=True)
            wall = time.perf_counter() - t0
            peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024  # kB -> MB
            if peak * 1024 <= before:  # ru_maxrss of children is a running maximum
                peak = float("nan")
            base = peak if base is None else base
            print(f"{tr.n_points:9d} {path.stat().st_size / 1e6:8.1f} {wall:7.1f} "
                  f"{peak:12.0f} {peak - base:10.0f}")


if __name__ == "__main__":
    main()
