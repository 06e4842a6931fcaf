"""What a layer on its plate costs, measured in one run on this machine.

Prints, for the paper's three tips on a 3,840-point trace (3 mm into a 30 mm block, nu 0.3):

* the one-off cost of the layer solution's tables in a fresh process (kernel transform and
  Nyström solves per tip, nu and base; cached for the life of the process);
* the shape function's cost on a layer against the half-space (per evaluation, 10^6 depths);
* the whole Bayesian fit (checks and budget included, the model form not) against the same
  fit as a half-space:
  thickness known with the base known, with the base unknown (the default), and with the
  thickness unknown; exact engine and emcee.

Run: ``python benchmarks/bench_layer.py`` (about 2 minutes).
"""

from __future__ import annotations

import time
import warnings

import numpy as np
from common import E_TRUE, TIPS, median_time

from palpbayes.bayes import BudgetSpec, fit_bayes
from palpbayes.contact import layer, shape
from palpbayes.errors import ConvergenceWarning
from palpbayes.fitdata import ModelSpec
from palpbayes.sim import simulate_trace

H = 0.03


def _tables() -> None:
    print("one-off table cost (fresh process), s:")
    for name, tip in TIPS.items():
        for base in ("bonded", "free"):
            t0 = time.perf_counter()
            shape(np.array([1e-3]), tip, thickness_m=H, nu=0.3, base=base)
            print(f"  {name:<11} {base:<7} {time.perf_counter() - t0:6.3f}")
    layer._profile_table.cache_clear()


def _shape_cost() -> None:
    d = np.random.default_rng(0).uniform(0, 3e-3, 1_000_000)
    print("shape function, 10^6 depths: layer / half-space time")
    for name, tip in TIPS.items():
        t_half = median_time(lambda tip=tip: shape(d, tip), 5)
        t_lay = median_time(lambda tip=tip: shape(d, tip, thickness_m=H, nu=0.3), 5)
        print(f"  {name:<11} {t_half * 1e3:7.1f} ms -> {t_lay * 1e3:7.1f} ms "
              f"({t_lay / t_half:4.1f}x)")


def _fit(tr, model, engine) -> tuple[float, object]:
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        # without the model form: its layer refit would put the layer's cost into the
        # half-space reference (whose fit of a layered block has a material misfit)
        r = fit_bayes(tr, model, engine=engine, seed=1, budget=BudgetSpec(),
                      with_model_form=False)
    return time.perf_counter() - t0, r


def _fits() -> None:
    print("whole Bayesian fit, s (ratio to the half-space fit of the same engine); E error")
    print(f"  {'tip':<11} {'engine':<6} {'half-space':>11} {'h, base known':>15} "
          f"{'h, base unknown':>17} {'h unknown':>14}")
    for name, tip in TIPS.items():
        tr = simulate_trace(E_TRUE, tip, thickness=H, base="free", rng=1)
        models = [ModelSpec(tip), ModelSpec(tip, thickness=H, bonding="free"),
                  ModelSpec(tip, thickness=H), ModelSpec(tip, thickness_range=(4.5e-3, 3.0))]
        for engine in ("exact", "emcee"):
            _fit(tr, models[2], engine)  # warm the tables and imports
            cells, t0 = [], None
            for m in models:
                t, r = _fit(tr, m, engine)
                err = 100 * (float(np.median(r.draws("E"))) / E_TRUE - 1)
                t0 = t0 or t
                cells.append(f"{t:5.2f} ({t / t0:3.1f}x) {err:+5.1f}%")
            print(f"  {name:<11} {engine:<6} " + "  ".join(cells))


def main() -> None:
    _tables()
    _shape_cost()
    _fits()


if __name__ == "__main__":
    main()
