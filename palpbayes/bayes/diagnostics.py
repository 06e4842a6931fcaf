"""Convergence diagnostics (R-hat, bulk/tail ESS, HDI) with arviz-stats, plus emcee's tau.

Walkers are treated as chains (as ``arviz.from_emcee`` does).  A fit is *converged* when
min bulk and tail ESS >= 400 over every parameter, max R-hat <= 1.05 (Vehtari et al. 2021,
rank-normalised split R-hat) over every parameter and the log posterior, and the sampler did
not stop at its step cap before tau was stable (its own rule: a chain longer than 50 tau, tau
stable; :mod:`palpbayes.bayes.sampler`).

Why R-hat <= 1.05 and not Vehtari's 1.01: R-hat's threshold is a rule for independent chains,
and an ensemble's walkers are not (each proposal is built from the other walkers).  The
emcee authors' rule is the chain length in autocorrelation times, with the ESS; R-hat stays
a reported diagnostic and a guard, flagged above 1.05 (issue 59).  Measured on the 22 real
AFM curves (``model_form`` off, seed 1): R-hat <= 1.01 was what set the chain length (1,000 to
1,800 steps, median 1,400, at bulk/tail ESS 2,100-3,800, five to nine times the 400 asked);
with 1.05 the chains stop at 600-1,000 steps (median 750, steps summed −44 %), min ESS 1,324,
max R-hat 1.029, every median within 0.04 % and every 90 % bound within 0.17 % of the longer
chains'.  The calibration suite (240 simulated traces, 90 % intervals) covers E*, z_surf,
sigma, F0 0.896, 0.892, 0.904, 0.883 under 1.01 and 0.896, 0.892, 0.913, 0.883 under 1.05
(SBC rank p 0.53/0.42/0.92/0.23 and 0.47/0.29/0.62/0.80; every fit converged, both).

The R-hat of the log posterior (Stan's ``lp__``) catches a walker that lags far below the
others: a start off a long, thin ridge (the flat punch's z_surf-F0 ridge) left one of 24
walkers at log-posterior −64,000 against +7,800 for 1,250 steps while every parameter passed
R-hat <= 1.01, widening sd(E*) threefold; its log-posterior R-hat was far above 1.05.

The figures come from arviz-stats' array functions (``arviz_stats.base.array_stats``, numpy
arrays (chain, draw, ...) in and out), the ArviZ project's own statistics package: importing
them costs ~0.35 s (scipy.signal, and xarray, which ``arviz_stats`` imports first) against
~1-1.5 s for arviz 0.2x, which imports matplotlib.pyplot (a fit's start-up time, issue 59).
R-hat and bulk ESS equal arviz 0.2x's ``az.rhat`` and ``az.ess`` to the last bit; tail ESS is
the same definition (the smaller of the ESS of the 5 % and 95 % quantile indicators) with the
quantile from ``numpy.quantile`` instead of ``scipy.stats.mstats.mquantiles`` (both type 7),
which moves it by up to ~0.4 % on short chains where a draw sits at the quantile.
:func:`import_arviz` is for the figures and the InferenceData (full arviz, with matplotlib).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

__all__ = ["Diagnostics", "RHAT_MAX", "ESS_MIN", "TAIL_PROBS", "import_arviz",
           "compute_diagnostics", "chain_passes", "rhat", "ess_bulk", "ess_tail", "hdi"]

#: R-hat above which a fit is flagged (and the sampler keeps going): a guard, not the stop
#: rule (see the module docstring).
RHAT_MAX = 1.05
ESS_MIN = 400.0
#: The quantiles whose indicators' ESS is the tail ESS (arviz 0.2x's ``method="tail"``).
TAIL_PROBS = (0.05, 0.95)


def import_arviz():
    """Import arviz with its import-time FutureWarning (refactor notice) silenced."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", FutureWarning)
        warnings.simplefilter("ignore", DeprecationWarning)
        import arviz as az
    return az


def _array_stats():
    """arviz-stats' numpy functions (``arviz_stats.base.array_stats``), imported on first use.

    Without arviz-base (Python 3.11: arviz 0.2x does not need it) ``import arviz_stats``
    imports xarray but neither arviz-base nor matplotlib; with arviz-base installed (arviz
    >= 1.0, Python >= 3.12) it also imports arviz-base, which looks for matplotlib.
    """
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", FutureWarning)
        warnings.simplefilter("ignore", DeprecationWarning)
        from arviz_stats.base import array_stats
    return array_stats


def rhat(x: np.ndarray) -> np.ndarray:
    """Rank-normalised split R-hat of ``x`` (chain, draw, ...) over its first two axes
    (arviz-stats); a float array of the trailing shape (a 0-d array for (chain, draw))."""
    with np.errstate(all="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        return np.asarray(_array_stats().rhat(np.asarray(x, dtype=float), chain_axis=0,
                                              draw_axis=1), dtype=float)


def ess_bulk(x: np.ndarray) -> np.ndarray:
    """Bulk ESS (rank-normalised) of ``x`` (chain, draw, ...) over its first two axes."""
    with np.errstate(all="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        return np.asarray(_array_stats().ess(np.asarray(x, dtype=float), chain_axis=0,
                                             draw_axis=1, method="bulk"), dtype=float)


def ess_tail(x: np.ndarray) -> np.ndarray:
    """Tail ESS of ``x`` (chain, draw, ...) over its first two axes: the smaller ESS of the
    indicators of the :data:`TAIL_PROBS` quantiles."""
    with np.errstate(all="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        return np.asarray(_array_stats().ess(np.asarray(x, dtype=float), chain_axis=0,
                                             draw_axis=1, method="tail", prob=TAIL_PROBS),
                          dtype=float)


def hdi(x: np.ndarray, prob: float) -> tuple[float, float]:
    """The narrowest interval holding the fraction ``prob`` of the draws ``x`` (flattened;
    arviz-stats' ``"nearest"`` method, as arviz 0.2x's ``az.hdi`` of a 1-d array)."""
    lo, hi = _array_stats().hdi(np.ravel(np.asarray(x, dtype=float)), prob)
    return float(lo), float(hi)


@dataclass(frozen=True)
class Diagnostics:
    """Per-parameter and overall convergence figures."""

    rhat: dict[str, float]
    ess_bulk: dict[str, float]
    ess_tail: dict[str, float]
    tau: dict[str, float]
    acceptance: float
    n_steps: int
    hit_cap: bool

    @property
    def rhat_max(self) -> float:
        """The largest R-hat; NaN when any is NaN (undefined: not converged), whatever the
        order of the parameters."""
        values = np.array(list(self.rhat.values()), dtype=float)
        return float(np.max(values)) if values.size else float("nan")

    @property
    def ess_min(self) -> float:
        return float(min(min(self.ess_bulk.values()), min(self.ess_tail.values())))

    @property
    def converged(self) -> bool:
        return (np.isfinite(self.rhat_max) and self.rhat_max <= RHAT_MAX
                and self.ess_min >= ESS_MIN and not self.hit_cap)

    def problems(self) -> list[str]:
        """Human-readable reasons why the fit is not converged (empty if it is)."""
        out = []
        if not (self.rhat_max <= RHAT_MAX):
            worst = max(self.rhat, key=self.rhat.get)
            out.append(f"R-hat {self.rhat_max:.4f} > {RHAT_MAX} ({worst})")
        if not (self.ess_min >= ESS_MIN):
            out.append(f"ESS {self.ess_min:.0f} < {ESS_MIN:.0f}")
        if self.hit_cap:
            out.append(f"step cap reached ({self.n_steps} steps) before tau was stable")
        return out


def compute_diagnostics(idata, names: list[str], tau: np.ndarray, acceptance: float,
                        n_steps: int, hit_cap: bool) -> Diagnostics:
    """R-hat, bulk/tail ESS of ``names`` in ``idata.posterior`` plus emcee's figures.

    ``idata`` is anything whose ``posterior`` (and optional ``sample_stats``) maps a name to
    draws (chain, draw, ...): an arviz ``InferenceData`` or a
    :class:`~palpbayes.bayes.posterior_data.PosteriorData`.  A variable with more than two
    axes counts by its largest R-hat and smallest ESS.  When ``idata.sample_stats`` holds the
    log posterior ``lp`` its R-hat is included under the key ``"lp"`` (it enters
    ``rhat_max`` and thus ``converged``).
    """
    draws = {n: np.asarray(idata.posterior[n], dtype=float) for n in names}
    r = {n: float(np.max(rhat(x))) for n, x in draws.items()}
    stats = getattr(idata, "sample_stats", None)
    if stats is not None and "lp" in stats:
        r["lp"] = float(rhat(np.asarray(stats["lp"], dtype=float)))
    return Diagnostics(
        rhat=r,
        ess_bulk={n: float(np.min(ess_bulk(x))) for n, x in draws.items()},
        ess_tail={n: float(np.min(ess_tail(x))) for n, x in draws.items()},
        tau=dict(zip(names, map(float, tau), strict=True)),
        acceptance=acceptance,
        n_steps=n_steps,
        hit_cap=hit_cap,
    )


def chain_passes(chain: np.ndarray, log_prob: np.ndarray | None = None) -> bool:
    """True if every parameter of ``chain`` (walkers, draws, ndim) has bulk and tail ESS >=
    ESS_MIN and R-hat <= RHAT_MAX, and the log posterior ``log_prob`` (walkers, draws), if
    given, has R-hat <= RHAT_MAX (arviz-stats, walkers as chains).  The sampler's stop test,
    checked once the chain is longer than 50 tau with tau stable.
    """
    if log_prob is not None and not rhat(log_prob) <= RHAT_MAX:
        return False
    for k in range(chain.shape[-1]):
        x = chain[..., k]
        if not rhat(x) <= RHAT_MAX:
            return False
        if ess_bulk(x) < ESS_MIN or ess_tail(x) < ESS_MIN:
            return False
    return True
