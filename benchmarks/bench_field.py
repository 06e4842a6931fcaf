"""The map's field stage alone (``maps.fit_field``) on a synthetic phantom input.

Run from the repository root::

    python benchmarks/bench_field.py                  # 100 x 100, after and before
    python benchmarks/bench_field.py --n 30 60 100    # the scaling
    python benchmarks/bench_field.py --n 30 --no-before

The input is what ``palpbayes map`` hands the field on ``bench_map.py``'s phantom (default
:func:`~palpbayes.sim.map.simulate_map`: E_b = 50 kPa, 3 mm step, the default lump,
heterogeneity 3 %), built with numpy instead of 10,000 trace fits: per point, log E_app (the
smooth apparent modulus of :func:`~palpbayes.inclusion.apparent_modulus`'s model) plus the
3 % nugget plus the fit's own error, minus the lump's log excess (the field is fitted to what
the lump model leaves), and an sd of 0.0015 in log E (what the exact engine gives on this
phantom).  No spatial variation shows beyond the nugget.

For each size it prints the wall and CPU time (both threads) of ``fit_field`` (on a shared
machine the CPU time is the steadier measure), the theta points of its grid, the
log-posterior evaluations (sparse factorisations) by stage, and, with ``before``, the same
fit with the factorisation as it was before issue 59 (the whole posterior precision P,
beta's dense row and column included, ordered afresh at every theta) and the largest
differences of the results (hyperparameter summaries, field mean and sd at the nodes, flags).

Measured in one run each on the shared 2-core machine (load 3-4 from other work: wall times
are upper bounds, CPU the steadier measure), before -> after:

* 30 x 30: 11.3 -> 9.4 s wall, 1061 evaluations, 827 theta points;
* 60 x 60: 42.3 -> 35.6 s wall, 52.9 -> 35.5 s CPU, 779 evaluations, 517 theta points;
* 100 x 100: 237.8 -> 226.4 s wall, 288 -> 215 s CPU, 786 / 793 evaluations (252 / 259 in the
  mode search, 18 Hessian, 516 skewness + grid), 510 theta points, 0.37 -> 0.27 s CPU per
  evaluation; results within 7e-6 (hyperparameter summaries, relative), 6e-10 (field mean,
  log E) and 1e-6 (field sd, relative), the same flags.
"""

from __future__ import annotations

import argparse
import time
from contextlib import contextmanager

import numpy as np
from scipy.sparse.linalg import splu

from palpbayes.inclusion import apparent_ratio, contact_radius, sensitivity
from palpbayes.maps import gmrf, hyper
from palpbayes.maps.spde import SpdeModel, spde_scales
from palpbayes.paper import PAPER_TIPS
from palpbayes.sim.map import default_inclusion

__all__ = ["phantom_input", "main"]

STEP, E_B, THICKNESS, NUGGET, POINT_SD = 3e-3, 50e3, 0.02, 0.03, 0.0015


def phantom_input(n: int, seed: int = 0) -> tuple[np.ndarray, ...]:
    """``x, y`` [m], ``mean``, ``sd`` [log(E/Pa)] of an ``n`` × ``n`` phantom (module doc)."""
    inc = default_inclusion(n, n, STEP)
    a = contact_radius(PAPER_TIPS["paraboloid"], 0.1 * THICKNESS)
    X, Y = np.meshgrid(np.arange(n) * STEP, np.arange(n) * STEP)
    V = sensitivity(np.hypot(X - inc.x, Y - inc.y), radius=inc.radius, depth=inc.depth,
                    contact_radius=a, thickness=THICKNESS)
    log_app = np.log(E_B * apparent_ratio(V, inc.ratio))
    rng = np.random.default_rng(seed)
    sd = POINT_SD * np.exp(0.05 * rng.standard_normal(X.shape))
    mean = log_app + NUGGET * rng.standard_normal(X.shape) + sd * rng.standard_normal(X.shape)
    mean -= log_app - np.log(E_B)  # the lump model takes its excess out
    return X.ravel(), Y.ravel(), mean.ravel(), sd.ravel()


class _WholeP:
    """The factorisation before issue 59: SuperLU of the whole P, beta included."""

    def __init__(self, model: SpdeModel, sigma_f: float, range_m: float, tau: float):
        P, self.w = model.posterior_precision(sigma_f, range_m, tau)
        self.lu = splu(P, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                       options={"SymmetricMode": True})
        self.sigma_f, self.range_m, self.tau = sigma_f, range_m, tau
        self.kh2, self.c = spde_scales(sigma_f, range_m, model.lattice.step)

    def solve(self, b: np.ndarray) -> np.ndarray:
        return self.lu.solve(b)

    def log_det(self) -> float:
        return float(np.sum(np.log(np.abs(self.lu.U.diagonal()))))


@contextmanager
def _counting(before: bool):
    """Count the factorisations by stage; with ``before``, factorise the whole P."""
    counts = {"total": 0}
    saved = SpdeModel.factor, hyper._mode, hyper._hessian

    def factor(self, *theta):
        counts["total"] += 1
        return _WholeP(self, *theta) if before else saved[0](self, *theta)

    def staged(name, fn):
        def run(*a, **k):
            c0 = counts["total"]
            try:
                return fn(*a, **k)
            finally:
                counts[name] = counts["total"] - c0
        return run

    SpdeModel.factor = factor
    hyper._mode, hyper._hessian = staged("mode", saved[1]), staged("hessian", saved[2])
    try:
        yield counts
    finally:
        SpdeModel.factor, hyper._mode, hyper._hessian = saved


def _fit(n: int, before: bool) -> dict:
    x, y, mean, sd = phantom_input(n)
    with _counting(before) as counts:
        t0, c0 = time.perf_counter(), time.process_time()
        fp = gmrf.fit_field(x, y, mean, sd)
        seconds, cpu = time.perf_counter() - t0, time.process_time() - c0
        fit_evals = counts["total"]
        t0 = time.perf_counter()
        node_sd = fp.marginal_sd(100, np.random.default_rng(0))
        draw_s = time.perf_counter() - t0
    return {"seconds": seconds, "cpu": cpu, "draw_s": draw_s, "points": len(fp.hyper),
            "evals": fit_evals, "mode": counts.get("mode", 0),
            "hessian": counts.get("hessian", 0), "flags": fp.flags,
            "summary": fp.hyper_summary()[["mean", "sd", "q05", "q95"]].to_numpy(),
            "mean": fp.mean(), "sd": node_sd}


def _rel(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.max(np.abs(a - b) / np.maximum(np.abs(b), 1e-300)))


def main(argv: list[str] | None = None) -> int:
    """Time the field stage at each ``--n`` (after, and before unless ``--no-before``)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, nargs="+", default=[100], help="map sides")
    ap.add_argument("--no-before", action="store_true", help="skip the before-style fit")
    args = ap.parse_args(argv)
    for n in args.n:
        runs = {"after": _fit(n, before=False)}
        if not args.no_before:
            runs["before"] = _fit(n, before=True)
        for name, r in runs.items():
            grid = r["evals"] - r["mode"] - r["hessian"]
            print(f"{n} x {n} {name:>6}: fit_field {r['seconds']:6.1f} s (CPU {r['cpu']:6.1f} "
                  f"s), {r['points']} theta points, {r['evals']} evaluations ({r['mode']} "
                  f"mode search, {r['hessian']} Hessian, {grid} skewness + grid), CPU "
                  f"{r['cpu'] / r['evals']:.3f} s each; 100 draws {r['draw_s']:.1f} s")
        if "before" in runs:
            a, b = runs["after"], runs["before"]
            rel_summary = _rel(a["summary"], b["summary"])
            d_mean = float(np.max(np.abs(a["mean"] - b["mean"])))
            same = "equal" if a["flags"] == b["flags"] else "DIFFER"
            print(f"   after/before: hyperparameter summaries {rel_summary:.1e} (max rel), "
                  f"field mean {d_mean:.1e} (max abs, log E), field sd "
                  f"{_rel(a['sd'], b['sd']):.1e} (max rel), flags {same}; speed-up "
                  f"{b['seconds'] / a['seconds']:.2f}x wall, {b['cpu'] / a['cpu']:.2f}x CPU")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
