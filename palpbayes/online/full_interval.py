"""The full interval of an online estimate: E with the uncertainty budget.

**Two intervals.**  ``OnlineState.E`` is statistical (the data's noise and surface, what the
offline fit calls ``E_stat``: :func:`statistical_E`); ``OnlineState.E_total`` adds the
uncertainty budget (:mod:`palpbayes.bayes.budget`: nu ± 0.05, tip radius, force gain,
compliance, a layer's thickness), the full interval of the offline summary row
(``E_lo_pa``/``E_hi_pa``, without the model-form envelope of a failed check): the budget
draws' central interval widened to hold the statistical one, around the statistical median
(:func:`full_from_draws`).  The budget does not shrink as the tip goes deeper, so the full
interval has a floor (``OnlineState.floor``, the budget's width at an exact E*: ~±3.5 % for a
half-space at nu 0.3, ~±7 % for a bonded layer at nu 0.45; :func:`full_interval`).  A
:class:`~palpbayes.online.state.StoppingRule` tests its target on either (``target_on``); a
full target below the floor cannot fire, and the state says so.  The estimator that asks for
them is :class:`palpbayes.online.estimator.OnlineEstimator`.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from ..bayes.budget import BudgetSpec, propagate
from ..bayes.exact import ExactPosterior
from ..bayes.mixture import MixtureSummary
from ..contact import youngs_factor
from ..fitdata import ModelSpec
from ..intervals import central, hull

__all__ = ["BUDGET_DRAWS", "SHOWN_BUDGET_DRAWS", "statistical_E", "draws_summary",
           "propagate_draws", "full_from_draws", "full_interval", "warm_up_budget"]

#: Posterior draws (and budget input draws) behind the full interval of an update.
BUDGET_DRAWS = 4000
#: Fewer draws for an update whose full interval is only shown (``follow``'s lines): the draws
#: cost ~5 ms per 1,000 (:meth:`palpbayes.bayes.exact.ExactPosterior.draws`); an update where
#: a target on the full interval may fire (the statistical interval is within it) takes
#: :data:`BUDGET_DRAWS`.
SHOWN_BUDGET_DRAWS = 1000


def statistical_E(post: ExactPosterior, nu: float, level: float) -> MixtureSummary:
    """E [Pa] with its statistical interval at ``level``: the posterior's E* times
    1 − nu²."""
    s, f = post.estar_summary(level), youngs_factor(nu)
    return MixtureSummary(s.mean * f, s.sd * f, s.median * f, s.lo * f, s.hi * f, s.level)


def draws_summary(x: np.ndarray, level: float) -> MixtureSummary:
    """Mean, sd, median and central interval at ``level`` of the draws ``x``."""
    lo, hi = central(x, level)
    return MixtureSummary(float(x.mean()), float(x.std()), float(np.median(x)), lo, hi, level)


def propagate_draws(post: ExactPosterior, model: ModelSpec, z: np.ndarray,
                    budget: BudgetSpec | None, n_draws: int, seed: int
                    ) -> tuple[np.ndarray, np.ndarray]:
    """Draws of E* [Pa] and of E with the budget [Pa], one budget input draw each, from
    ``n_draws`` posterior draws; ``z`` [m] the tip heights so far (a layer's depth),
    ``budget`` None: :class:`BudgetSpec` defaults."""
    rng = np.random.default_rng(seed)
    d = post.draws(rng, n_draws)
    seen = SimpleNamespace(model=model, z=z)  # what propagate reads
    bud = propagate(d["E_star"], seen, float(np.median(d["z_surf"])), budget or BudgetSpec(),
                    rng)
    return d["E_star"], bud.E


def full_from_draws(stat: MixtureSummary, E: np.ndarray, level: float) -> MixtureSummary:
    """The full interval as the offline fit reports it
    (:meth:`palpbayes.bayes.result.BayesResult.intervals`): the central interval of the
    budget's draws ``E`` [Pa] widened where needed to hold the statistical one, around the
    statistical median (the estimate at the stated inputs: the budget widens the interval and
    does not move it)."""
    b = draws_summary(E, level)
    return MixtureSummary(b.mean, b.sd, stat.median, *hull((b.lo, b.hi), (stat.lo, stat.hi)),
                          level)


def full_interval(post: ExactPosterior, stat: MixtureSummary, model: ModelSpec, z: np.ndarray,
                  budget: BudgetSpec | None, n_draws: int, seed: int, level: float
                  ) -> tuple[MixtureSummary, float]:
    """The full interval of E [Pa] and the budget's floor [-] (the relative half-width of the
    budget's factors alone: E / E* of the same draws), from ``n_draws`` draws
    (:func:`propagate_draws`) around the statistical ``stat``."""
    estar, E = propagate_draws(post, model, z, budget, n_draws, seed)
    return full_from_draws(stat, E, level), draws_summary(E / estar, level).rel_half_width


def warm_up_budget(model: ModelSpec, budget: BudgetSpec | None) -> None:
    """Build what the budget of a layered model needs once per process (its profile tables
    at the Poisson ratios of the budget: seconds).  Nothing to do for a half-space."""
    if not model.has_layer:
        return
    h = float(model.thickness)
    depth = np.geomspace(1e-4, 0.2, 32) * h
    seen = SimpleNamespace(model=model, z=-depth)
    propagate(np.ones(8), seen, 0.0, budget or BudgetSpec(), np.random.default_rng(0))
