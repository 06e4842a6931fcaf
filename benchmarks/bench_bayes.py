"""Efficiency of the Bayesian fit, measured in one run:

(a) Bayes time / LS time on the same 3,840-point trace (target <= 10);
(b) posterior sd(E*) / Cramér-Rao bound (target <= 1.2).

The Cramér-Rao bound is computed at the true parameters from the Fisher information of the
mean parameters (E*, z_surf, F0) under iid Gaussian noise, I = JᵀJ/sigma² with
J = [s(d), E*·s'(d), 1] (sigma decouples, docs/design.md §8).
Run: ``python benchmarks/bench_bayes.py``.
"""

from __future__ import annotations

import numpy as np
from common import E_TRUE, TIPS, median_time, paper_trace

from palpbayes.bayes import BudgetSpec, fit_bayes
from palpbayes.bayes.diagnostics import import_arviz
from palpbayes.fitdata import ModelSpec, prepare
from palpbayes.lsq import fit_lsq


def cramer_rao_sd_estar(tr, nu: float = 0.3) -> float:
    data = prepare(tr, ModelSpec(tr.tip, nu=nu))
    estar = E_TRUE / (1 - nu**2)
    d = tr.metadata["z_surf_true"] - data.z
    J = np.column_stack([data.model.shape(d), estar * data.model.shape_derivative(d),
                         np.ones_like(d)])
    sigma = tr.metadata["sigma_true"]
    fisher = J.T @ J / sigma**2
    return float(np.sqrt(np.linalg.inv(fisher)[0, 0]))


def main() -> None:
    import_arviz()  # one-off import cost (~1 s) is not part of a fit
    print(f"{'tip':<11} {'LS':>9} {'Bayes':>9} {'ratio':>7} {'sd(E*)':>10} {'CRB':>10} "
          f"{'sd/CRB':>7} {'steps':>6}")
    for kind in TIPS:
        ratios_sd = []
        tr = paper_trace(kind, seed=1)
        t_ls = median_time(lambda tr=tr: fit_lsq(tr), repeat=11)
        res = None

        def run(tr=tr):
            nonlocal res
            res = fit_bayes(tr, seed=1, budget=BudgetSpec.none())

        t_b = median_time(run, repeat=3)
        for seed in range(3):  # average the sd ratio over a few noise draws
            trs = paper_trace(kind, seed=10 + seed)
            r = fit_bayes(trs, seed=seed, budget=BudgetSpec.none())
            ratios_sd.append(r.draws("E_star").std() / cramer_rao_sd_estar(trs))
        crb = cramer_rao_sd_estar(tr)
        sd = res.draws("E_star").std()
        print(f"{kind:<11} {t_ls * 1e3:7.1f}ms {t_b:8.2f}s {t_b / t_ls:7.1f} {sd:10.2f} "
              f"{crb:10.2f} {np.mean(ratios_sd):7.3f} {res.diagnostics.n_steps:6d}")


if __name__ == "__main__":
    main()
