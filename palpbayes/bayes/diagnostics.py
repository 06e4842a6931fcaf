"""Convergence diagnostics with arviz (R-hat, bulk/tail ESS, HDI) plus emcee's tau.

Walkers are treated as chains (as ``arviz.from_emcee`` does).  A fit is *converged* when
max R-hat <= 1.01 (Vehtari et al. 2021, rank-normalised split R-hat) over every parameter and
the log posterior, min bulk and tail ESS >= 400 over every parameter, and the sampler did not
stop at its step cap before tau was stable.

The R-hat of the log posterior (Stan's ``lp__``) catches a walker that lags far below the
others: a start off a long, thin ridge (the flat punch's z_surf-F0 ridge) left one of 24
walkers at log-posterior −64,000 against +7,800 for 1,250 steps while every parameter passed
R-hat <= 1.01, widening sd(E*) threefold; its log-posterior R-hat was far above 1.01.

Written against arviz 0.2x (Python 3.11, InferenceData API: ``az.from_dict``, ``az.rhat``,
``az.ess``, ``az.hdi``); on arviz >= 1.0 the same calls are made through the compatibility of
``arviz`` with ``xarray`` Datasets (values are read as plain numpy arrays).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

__all__ = ["Diagnostics", "RHAT_MAX", "ESS_MIN", "import_arviz", "compute_diagnostics",
           "chain_passes"]

RHAT_MAX = 1.01
ESS_MIN = 400.0


def import_arviz():
    """Import arviz with its import-time FutureWarning (refactor notice) silenced."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", FutureWarning)
        warnings.simplefilter("ignore", DeprecationWarning)
        import arviz as az
    return az


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


def _values(ds, name: str) -> float:
    return float(np.asarray(ds[name]).max())


def compute_diagnostics(idata, names: list[str], tau: np.ndarray, acceptance: float,
                        n_steps: int, hit_cap: bool) -> Diagnostics:
    """R-hat, bulk/tail ESS of ``names`` in ``idata.posterior`` plus emcee's figures.

    When ``idata.sample_stats`` holds the log posterior ``lp`` its R-hat is included under the
    key ``"lp"`` (it enters ``rhat_max`` and thus ``converged``).
    """
    az = import_arviz()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        rhat = az.rhat(idata, var_names=names)
        bulk = az.ess(idata, var_names=names, method="bulk")
        tail = az.ess(idata, var_names=names, method="tail")
        r = {n: _values(rhat, n) for n in names}
        stats = getattr(idata, "sample_stats", None)
        if stats is not None and "lp" in stats:
            r["lp"] = float(az.rhat(np.asarray(stats["lp"])))
    return Diagnostics(
        rhat=r,
        ess_bulk={n: float(np.asarray(bulk[n]).min()) for n in names},
        ess_tail={n: float(np.asarray(tail[n]).min()) for n in names},
        tau=dict(zip(names, map(float, tau), strict=True)),
        acceptance=acceptance,
        n_steps=n_steps,
        hit_cap=hit_cap,
    )


def chain_passes(chain: np.ndarray, log_prob: np.ndarray | None = None) -> bool:
    """True if every parameter of ``chain`` (walkers, draws, ndim) has R-hat <= RHAT_MAX and
    bulk and tail ESS >= ESS_MIN, and the log posterior ``log_prob`` (walkers, draws), if
    given, has R-hat <= RHAT_MAX (arviz, walkers as chains).  The sampler's stop test.
    """
    az = import_arviz()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        if log_prob is not None and not az.rhat(np.asarray(log_prob)) <= RHAT_MAX:
            return False
        for k in range(chain.shape[-1]):
            x = chain[..., k]
            if not az.rhat(x) <= RHAT_MAX:
                return False
            if az.ess(x, method="bulk") < ESS_MIN or az.ess(x, method="tail") < ESS_MIN:
                return False
    return True
