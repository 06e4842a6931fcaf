"""``palpbayes fit`` of one real AFM curve as a user runs it: process start to files written.

For every approach curve of ``../shared/data/afm-files`` that palpbayes fits (the 22 of
``bench_peer.py``), runs ``palpbayes fit FILE --curve I --tip paraboloid --radius 10e-6 --nu
0.5 --out DIR`` in a new process — the default options (engine emcee, model form on) and, with
``--engine exact``, the exact engine — and prints the wall time of each, the median and the
90th percentile against issue 47's goal (p90 <= 2 s).  The first run after an install also
compiles Python's bytecode: run the script twice to see both.

Run: ``python benchmarks/bench_cli.py [--engines emcee,exact] [--limit N]``.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from bench_peer import FILES, curves

ROOT = Path(__file__).resolve().parents[1]
GOAL_P90 = 2.0


def run(path: Path, index: int, engine: str | None, out: Path) -> tuple[float, int]:
    """(wall seconds, exit status) of one ``palpbayes fit`` process."""
    cmd = [sys.executable, "-m", "palpbayes", "fit", str(path), "--curve", str(index),
           "--tip", "paraboloid", "--radius", "10e-6", "--nu", "0.5", "--out", str(out),
           "--force", "--no-progress"] + (["--engine", engine] if engine else [])
    t0 = time.perf_counter()
    rc = subprocess.run(cmd, cwd=ROOT, stdout=subprocess.DEVNULL,
                        stderr=subprocess.DEVNULL).returncode
    return time.perf_counter() - t0, rc


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--engines", default="default,exact",
                    help="comma-separated: default (emcee) and/or exact")
    ap.add_argument("--limit", type=int, default=0, help="only the first N curves")
    args = ap.parse_args()
    if not FILES.is_dir():
        print(f"no {FILES}: nothing to time")
        return
    todo = curves()
    with tempfile.TemporaryDirectory() as tmp:
        for engine in args.engines.split(","):
            times = []
            for name, index in todo:
                t, rc = run(FILES / name, index, None if engine == "default" else engine,
                            Path(tmp) / "out")
                if rc == 0:  # curves palpbayes refuses (no contact, too deep) are not timed
                    times.append(t)
                if args.limit and len(times) >= args.limit:
                    break
            t = np.array(times)
            print(f"palpbayes fit, engine {engine}: {t.size} curves, median {np.median(t):.2f} s,"
                  f" p90 {np.percentile(t, 90):.2f} s (goal <= {GOAL_P90:g} s), "
                  f"max {t.max():.2f} s; each: {' '.join(f'{x:.1f}' for x in t)}")


if __name__ == "__main__":
    main()
