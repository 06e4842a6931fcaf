"""What the specimen twin costs, measured in one run on this machine.

Prints, for the paper's three tips on its 50 × 50 mm blocks (nu 0.3):

* the tables one Bayesian fit of a block needs, built from a cold cache: the fit's nu and the
  budget's five nodes of nu, for both bases (the default: base unknown), one geometry × tip,
  with its wall time against the 60 s target (issue 44), then read back from the disk cache;
* the shape function on the twin against the infinite layer's (per evaluation, 10^6 depths);
* the whole Bayesian fit of a 3,840-point trace (3 mm into the 30 mm block; checks and budget
  included, the model form not), with the twin against the same fit with the infinite layer:
  exact engine and emcee, base known (free) and unknown, the target a ratio <= 1 ("no slower
  than today's layer fit"); for emcee its steps and the time per step, which separate the
  cost of an evaluation from the posterior's geometry;
* the compression factor of the block (bonded platens), per nu.

Run: ``python benchmarks/bench_twin.py`` (about 4 minutes; the tables go to a temporary cache
folder, so the cold build is measured whatever the user's cache holds).
"""

from __future__ import annotations

import os
import tempfile
import time
import warnings

import numpy as np
from common import E_TRUE, TIPS, median_time

from palpbayes.bayes import BudgetSpec, fit_bayes
from palpbayes.bayes.budget import nu_nodes
from palpbayes.errors import ConvergenceWarning
from palpbayes.fitdata import ModelSpec
from palpbayes.sim import simulate_trace
from palpbayes.twin import Specimen, compression_factor, prepare_tables
from palpbayes.twin import table as twin_tables

BLOCK = Specimen(0.03, length=0.05, width=0.05)
NU = 0.3


def _tables() -> None:
    nus = [NU, *nu_nodes(BudgetSpec(), NU)]
    print(f"tables one fit needs (nu {sorted(set(nus))} x bonded/free), cold cache, s "
          "(target <= 60 s):")
    for name, tip in TIPS.items():
        twin_tables.clear_memory()
        t0 = time.perf_counter()
        n = prepare_tables(BLOCK, tip, nus, ("bonded", "free"), progress=False)
        cold = time.perf_counter() - t0
        twin_tables.clear_memory()
        t0 = time.perf_counter()
        prepare_tables(BLOCK, tip, nus, ("bonded", "free"), progress=False)
        warm = time.perf_counter() - t0
        print(f"  {name:<11} {n:2d} tables {cold:6.1f} s  ({cold / 60:.2f} of the target); "
              f"from the disk cache {warm * 1e3:6.1f} ms")


def _shape_cost() -> None:
    d = np.random.default_rng(0).uniform(0, 3e-3, 1_000_000)
    print("shape function, 10^6 depths: twin / infinite layer time")
    for name, tip in TIPS.items():
        layer = ModelSpec(tip, nu=NU, thickness=BLOCK.height, bonding="free")
        twin = ModelSpec(tip, nu=NU, specimen=BLOCK, bonding="free")
        twin.shape(d[:10])  # the table, once
        t_layer = median_time(lambda m=layer: m.shape(d), 5)
        t_twin = median_time(lambda m=twin: m.shape(d), 5)
        print(f"  {name:<11} {t_layer * 1e3:7.1f} ms -> {t_twin * 1e3:7.1f} ms "
              f"({t_twin / t_layer:4.2f}x)")


def _fits() -> None:
    print("Bayesian fit of a 3,840-point trace, infinite layer -> twin (target ratio <= 1): "
          "median over 3 traces (seeds), s; emcee also its steps and time per step")
    budget = BudgetSpec()
    for engine in ("exact", "emcee"):
        for bonding in ("free", "unknown"):
            for name, tip in TIPS.items():
                runs = {"layer": [], "twin": []}
                for seed in range(3):
                    tr = simulate_trace(E_TRUE, tip, nu=NU, block=BLOCK, base="free", rng=seed)
                    assert tr.n_points == 3840, tr.n_points
                    for label, model in (
                            ("layer", ModelSpec(tip, nu=NU, thickness=BLOCK.height,
                                                bonding=bonding)),
                            ("twin", ModelSpec(tip, nu=NU, specimen=BLOCK, bonding=bonding))):
                        with warnings.catch_warnings():
                            warnings.simplefilter("ignore", ConvergenceWarning)
                            fit_bayes(tr, model, engine=engine, budget=budget,  # warm
                                      with_model_form=False, seed=seed)
                            t0 = time.perf_counter()
                            r = fit_bayes(tr, model, engine=engine, budget=budget,
                                          with_model_form=False, seed=seed)
                            runs[label].append((time.perf_counter() - t0,
                                                r.diagnostics.n_steps))
                t = {k: float(np.median([x[0] for x in v])) for k, v in runs.items()}
                line = (f"  {engine:<5} base {bonding:<7} {name:<11} {t['layer']:5.2f} -> "
                        f"{t['twin']:5.2f} ({t['twin'] / t['layer']:4.2f}x)")
                if engine == "emcee":
                    steps = {k: int(np.median([x[1] for x in v])) for k, v in runs.items()}
                    per = {k: 1e3 * float(np.median([x[0] / x[1] for x in v]))
                           for k, v in runs.items()}
                    line += (f"  steps {steps['layer']} -> {steps['twin']}, per step "
                             f"{per['layer']:.2f} -> {per['twin']:.2f} ms")
                print(line)


def _compression() -> None:
    print("compression factor c = E_app/E of the 50 x 50 x 30 mm block, bonded platens:")
    for nu in (0.1, 0.3, 0.45, 0.5):
        t0 = time.perf_counter()
        c = compression_factor(BLOCK, nu, "bonded")
        print(f"  nu {nu:<4} c = {c:6.4f}  ({(time.perf_counter() - t0) * 1e3:5.0f} ms)")


def main() -> None:
    with tempfile.TemporaryDirectory() as cache:
        os.environ["PALPBAYES_CACHE_DIR"] = cache
        print(f"cores: {os.cpu_count()}")
        _tables()
        _shape_cost()
        _fits()
        _compression()


if __name__ == "__main__":
    main()
