"""Stiffness maps at scale, and the Bayesian map against the naive least-squares map.

Run from the repository root (takes ~30-50 min on 2 cores with the defaults)::

    python benchmarks/bench_map.py                 # 100 x 100 map, scaling, ROC
    python benchmarks/bench_map.py --n 30 --roc 6  # a quick look
    python benchmarks/bench_map.py --n 30 --scaling 0 --roc 0  # stage 1 alone, in minutes

Prints, all measured in this one run:

1. **End to end, n × n map** (default 100 × 100 = 10,000 traces): simulate the phantom, fit
   every point on a 2-worker LocalCluster, the spatial field, the lump; wall time per stage,
   traces/s, and the peak resident memory of the whole process tree (this process and the
   Dask workers, sampled every 0.2 s).  The map's wall time is split into its stages (checks,
   per-point fits with the cluster's start-up, lump, field, files, figure and report; the
   rest is the field's draws and the node table).  Target: <= 3 min, memory bounded.
2. **Scaling 1 -> 2 workers**: traces/s of the per-point fits of the first ``--scaling``
   traces on 1 and on 2 workers, and the speed-up.
3. **Detection and localisation** over ``--roc`` phantoms with a lump drawn as in the
   coverage test and as many without (15 × 15, heterogeneity 3 %): ROC AUC of the Bayesian
   score (the lump model's P(apparent peak ratio > 1.05)) and of the naive score (largest
   least-squares E over its median);
   the distance from the true centre [grid steps] of the lump model's centre and of the naive
   map's largest value.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np
import pandas as pd

from palpbayes.inclusion import Inclusion
from palpbayes.io.manifest import read_manifest
from palpbayes.maps.pertrace import PointOptions, fit_points
from palpbayes.maps.run import MapOptions, map_from_points
from palpbayes.paper import PAPER_TIPS
from palpbayes.sim.map import read_map_truth, simulate_map

#: (module, function, stage) timed by :class:`StageClock`: the stages of ``palpbayes map``.
STAGES = [
    ("palpbayes.maps.run", "check_map_manifest", "checks (manifest, trace headers)"),
    ("palpbayes.maps.run", "fit_points", "per-point fits (cluster start-up included)"),
    ("palpbayes.maps.run", "fit_lump", "lump model"),
    ("palpbayes.maps.run", "fit_field", "field (GMRF, hyperparameters)"),
    ("palpbayes.maps.files", "write_map", "files (csv, netCDF, json)"),
    ("palpbayes.reporting.map_pages", "write_map_figure", "figure"),
    ("palpbayes.reporting.map_pages", "write_map_report", "report (PDF)"),
]


class StageClock:
    """Wall time [s] of each stage of ``palpbayes map``, by wrapping the functions of
    :data:`STAGES` for the duration of a ``with`` block (restored after it)."""

    def __init__(self) -> None:
        self.seconds: dict[str, float] = {}
        self._saved: list[tuple[object, str, object]] = []

    def __enter__(self) -> StageClock:
        import importlib

        for mod_name, fn_name, label in STAGES:
            mod = importlib.import_module(mod_name)
            fn = getattr(mod, fn_name)
            self._saved.append((mod, fn_name, fn))

            def timed(*a, _fn=fn, _label=label, **k):
                t0 = time.perf_counter()
                try:
                    return _fn(*a, **k)
                finally:
                    self.seconds[_label] = (self.seconds.get(_label, 0.0)
                                            + time.perf_counter() - t0)

            setattr(mod, fn_name, timed)
        return self

    def __exit__(self, *exc) -> None:
        for mod, fn_name, fn in self._saved:
            setattr(mod, fn_name, fn)


class PeakMemory:
    """Peak total RSS [bytes] of this process and all its descendants, sampled in a thread."""

    def __init__(self, every: float = 0.2) -> None:
        import psutil

        self._proc, self._every, self.peak = psutil.Process(), every, 0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def _run(self) -> None:
        import psutil

        while not self._stop.is_set():
            total = 0
            try:
                for p in [self._proc, *self._proc.children(recursive=True)]:
                    try:
                        total += p.memory_info().rss
                    except psutil.Error:
                        pass
            except psutil.Error:
                pass
            self.peak = max(self.peak, total)
            time.sleep(self._every)

    def __enter__(self) -> PeakMemory:
        self._thread.start()
        return self

    def __exit__(self, *exc) -> None:
        self._stop.set()
        self._thread.join()


def _auc(pos: np.ndarray, neg: np.ndarray) -> float:
    """Area under the ROC curve = P(score of a lump phantom > score of a clean one)."""
    pos, neg = np.asarray(pos, float), np.asarray(neg, float)
    gt = (pos[:, None] > neg[None, :]).mean()
    eq = (pos[:, None] == neg[None, :]).mean()
    return float(gt + 0.5 * eq)


def end_to_end(n: int, root: Path, workers: int) -> dict:
    """``simulate --map`` then ``palpbayes map`` (fits, field, lump, every file and the PDF)."""
    from palpbayes.cli import main as cli

    folder, out = root / f"map{n}", root / f"map{n}-out"
    t0 = time.perf_counter()
    simulate_map(folder, nx=n, ny=n, seed=1, workers=workers)
    t_sim = time.perf_counter() - t0
    truth = read_map_truth(folder)
    with PeakMemory() as mem, StageClock() as clock:
        t0 = time.perf_counter()
        rc = cli(["map", str(folder / "manifest.csv"), "--out", str(out), "--workers",
                  str(workers), "--force"])
        t_all = time.perf_counter() - t0
    if rc != 0:
        raise SystemExit(f"palpbayes map failed with exit status {rc}")
    settings = json.loads((out / "settings.json").read_text())
    n_traces = n * n
    res = {"n_traces": n_traces, "simulate_s": t_sim, "map_s": t_all,
           "traces_per_s": n_traces / t_all, "peak_rss_gb": mem.peak / 1e9,
           "detection": settings["detection"], "p_lump": settings["p_lump"],
           "flags": settings["flags"], "stages": clock.seconds}
    if (out / "lump.csv").exists():
        s = pd.read_csv(out / "lump.csv").set_index("quantity")
        step = truth["step_m"]
        res["centre_error_steps"] = float(np.hypot(s.loc["x_m", "median"] - truth["x_m"],
                                                   s.loc["y_m", "median"] - truth["y_m"]) / step)
        for q, t in (("ratio", truth["ratio"]), ("apparent_ratio", truth["peak_apparent_ratio"])):
            res[q] = (s.loc[q, "median"], s.loc[q, "lo"], s.loc[q, "hi"], t)
    return res


def scaling(n_traces: int, root: Path) -> dict:
    """Traces/s of the per-point fits once the cluster is up: from the first finished chunk to
    the last (cluster start-up, ~3 s, is excluded and reported apart)."""
    folder = root / "map100"
    manifest = read_manifest(folder / "manifest.csv").iloc[:n_traces]
    rates, startup = {}, {}
    for w in (1, 2):
        stamps: list[tuple[float, int]] = []
        t0 = time.perf_counter()
        fit_points(manifest, PointOptions(), workers=w, progress=False, chunk=25,
                   on_done=lambda n, st=stamps: st.append((time.perf_counter(), n)))
        (t1, n1), (t2, n2) = stamps[0], stamps[-1]
        rates[w] = (n2 - n1) / (t2 - t1)
        startup[w] = t1 - t0 - 25 / rates[w]
    return {"rates": rates, "startup": startup}


def detection(n_each: int, root: Path, workers: int) -> dict:
    bayes_pos, bayes_neg, naive_pos, naive_neg, loc_b, loc_n = [], [], [], [], [], []
    rng = np.random.default_rng(7)
    tip = PAPER_TIPS["paraboloid"]
    for k in range(2 * n_each):
        has = k < n_each
        step, nx = 3e-3, 15
        inc = None
        if has:  # the distribution of the coverage test (tests/statistical/test_map_lump.py)
            radius = float(rng.uniform(3.5e-3, 6e-3))
            x, y = rng.uniform(3 * step, (nx - 4) * step, 2)
            inc = Inclusion(x=float(x), y=float(y),
                            depth=radius + float(rng.uniform(0.5e-3, 3e-3)), radius=radius,
                            ratio=float(np.exp(rng.uniform(np.log(3), np.log(30)))))
        folder = root / f"roc{k}"
        simulate_map(folder, nx=nx, ny=nx, step=step, seed=100 + k, inclusion=inc)
        m = read_manifest(folder / "manifest.csv")
        pts = fit_points(m, PointOptions(), workers=workers, progress=False)
        res = map_from_points(pts, tip=tip, thickness=0.02,
                              options=MapOptions(threshold=1.05, detect=0.5))
        e = pts["E_lsq_pa"].to_numpy()
        naive = float(np.nanmax(e) / np.nanmedian(e))
        (bayes_pos if has else bayes_neg).append(res.p_lump)
        (naive_pos if has else naive_neg).append(naive)
        if has:
            j = int(np.nanargmax(e))
            loc_n.append(np.hypot(pts["x_m"][j] - inc.x, pts["y_m"][j] - inc.y) / step)
            if res.lump_found:
                d = res.lump.draws
                loc_b.append(np.hypot(d["x_m"].median() - inc.x, d["y_m"].median() - inc.y)
                             / step)
        print(f"  phantom {k + 1}/{2 * n_each}: lump={has} bayes={res.p_lump:.3f} "
              f"naive={naive:.3f}", file=sys.stderr)
    return {"auc_bayes": _auc(bayes_pos, bayes_neg), "auc_naive": _auc(naive_pos, naive_neg),
            "loc_bayes_steps": loc_b, "loc_naive_steps": loc_n,
            "n_lump_model": len(loc_b), "n_each": n_each}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--n", type=int, default=100, help="map side (default 100: 10,000 traces)")
    ap.add_argument("--scaling", type=int, default=1000, help="traces of the scaling run")
    ap.add_argument("--roc", type=int, default=15, help="phantoms with a lump (and without)")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--keep", default=None, help="keep the simulated folders here")
    args = ap.parse_args(argv)
    root = Path(args.keep) if args.keep else Path(tempfile.mkdtemp(prefix="bench_map_"))
    root.mkdir(parents=True, exist_ok=True)
    print(f"bench_map: {os.cpu_count()} cores, folders in {root}")
    e2e = end_to_end(args.n, root, args.workers)
    print(f"\n1. end to end, {args.n} x {args.n} = {e2e['n_traces']} traces, {args.workers} "
          "workers")
    print(f"   simulate the phantom: {e2e['simulate_s']:.0f} s")
    print(f"   palpbayes map (fits, field, lump, files, report): {e2e['map_s']:.0f} s = "
          f"{e2e['map_s'] / 60:.1f} min, {e2e['traces_per_s']:.1f} traces/s; with the "
          f"simulation {(e2e['map_s'] + e2e['simulate_s']) / 60:.1f} min; target <= 180 s: "
          f"ratio {e2e['map_s'] / 180:.2f} of the budget")
    for label, sec in e2e["stages"].items():
        print(f"     {label:<44} {sec:7.1f} s")
    other = e2e["map_s"] - sum(e2e["stages"].values())
    print(f"     {'the rest (read, field draws, node table)':<44} {other:7.1f} s")
    print(f"   peak memory, process tree: {e2e['peak_rss_gb']:.2f} GB")
    print(f"   largest P(E > 1.1 x background) {e2e['detection']:.3f}, P(lump) "
          f"{e2e['p_lump']:.3f}; centre error "
          f"{e2e.get('centre_error_steps', float('nan')):.2f} grid steps")
    for q in ("apparent_ratio", "ratio"):
        if q in e2e:
            med, lo, hi, t = e2e[q]
            print(f"   {q}: {med:.3g} [{lo:.3g}, {hi:.3g}] (90 %), truth {t:.3g}")
    for f in e2e["flags"]:
        print(f"   flag: {f}")
    if args.n >= 10 and args.scaling:
        src = root / "map100"
        if not src.exists():
            os.symlink(root / f"map{args.n}", src)
        n_sc = min(args.scaling, args.n * args.n)
        sc = scaling(n_sc, root)
        r, st = sc["rates"], sc["startup"]
        print(f"\n2. per-point fits of {n_sc} traces, once the cluster is up: 1 worker "
              f"{r[1]:.1f} traces/s, 2 workers {r[2]:.1f} traces/s: speed-up {r[2] / r[1]:.2f}x "
              f"(cluster start-up {st[1]:.1f} s / {st[2]:.1f} s)")
    if args.roc:
        d = detection(args.roc, root, args.workers)
        lb, ln = np.array(d["loc_bayes_steps"]), np.array(d["loc_naive_steps"])
        print(f"\n3. detection over {d['n_each']} phantoms with a lump and {d['n_each']} "
              "without (15 x 15)")
        print(f"   ROC AUC: Bayes {d['auc_bayes']:.3f}, naive least squares {d['auc_naive']:.3f}")
        if lb.size:
            print(f"   centre error [grid steps], lump model ({lb.size} fitted): median "
                  f"{np.median(lb):.2f}, within one step {np.mean(lb <= 1):.0%}")
        print(f"   centre error [grid steps], naive largest value: median {np.median(ln):.2f}, "
              f"within one step {np.mean(ln <= 1):.0%}")
    pd.set_option("display.width", 120)
    return 0


if __name__ == "__main__":
    sys.exit(main())
