"""emcee driver: start around the least-squares solution, run until tau is stable.

Moves: by default emcee's ``DEMove`` (differential evolution, ter Braak 2006).  Measured on
paper-like 3,840-point traces (flat, sphere, paraboloid; 32 walkers): tau ~ 13 steps, against
~ 17 for 80 % ``DEMove`` + 20 % ``DESnookerMove`` (``"de-snooker"``, emcee's recommendation for
multimodal targets, kept as an option; its snooker step loops over walkers in Python and costs
~ 60 % more per step) and ~ 35-43 for the stretch move.  The chain length is set by 50·tau
(and ``min_steps``): on the 22 real AFM curves 600-1,000 steps, at bulk/tail ESS >= 1,300.

Stopping rule (emcee's autocorrelation tutorial): every ``check_every`` steps the integrated
autocorrelation time tau of each parameter is estimated; sampling stops once the chain is longer
than ``tau_factor``·tau (default 50: N > 50·tau, docs/design.md §3) for every parameter and tau
changed by less than ``tau_rtol`` since the last check — and, when an ``accept`` test is given (the
fit's bulk and tail ESS >= 400, with R-hat <= 1.05 as a guard:
:func:`palpbayes.bayes.diagnostics.chain_passes`), that test passes — or at ``max_steps``.  Burn-in
``ceil(2·max tau)`` is discarded and the chain thinned by ``max(1, floor(min tau / 2))``.

Stuck walkers: a walker that starts in a poor spot of a narrow, curved posterior can stay
there for good — the differential-evolution proposals are as small as the ensemble's spread,
and none of them climbs (measured: an AR(1) fit of a real AFM curve, two of 32 walkers 90 log
units below the rest for 20,000 steps: R-hat 1.17, ESS 34).  At every check from
``min_steps`` on that leaves the budget for another ``min_steps`` and a check, a walker
whose best log posterior over the last ``check_every`` steps lies
more than chi2_ndim(1 − 1e-6)/2 below the ensemble's median, and which moved in fewer than a
quarter as many of those steps as the median walker, is moved onto a randomly chosen walker
of the rest, and the chain is restarted from that ensemble (:data:`MAX_RESTARTS` times at
most): everything before is burn-in, the kept chain is plain emcee.  Under the posterior a
walker that far down has probability ~1e-6 (the density test), and a walker that explores a
broad mode of its own, lower in density but not in mass, still moves (the second test).  An
ensemble without such walkers runs exactly as before.

Seeding: emcee has no ``seed`` argument and copies NumPy's global state when built, so the
sampler's own ``RandomState`` is replaced by one seeded from ``seed`` (docs/design.md §8).
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..errors import InputError

if TYPE_CHECKING:
    import emcee

# emcee (and with it scipy.stats, which emcee.moves.kde imports) is imported where it samples,
# not here: the command line's parser imports SamplerSettings (``palpbayes --help``, issue 59).

__all__ = ["seed_sampler", "SamplerSettings", "ChainResult", "run_emcee", "stuck_walkers", "MOVES",
           "MAX_RESTARTS"]

#: Most restarts of a chain after stuck walkers were moved (module docstring).
MAX_RESTARTS = 3
#: Probability [-] under the posterior below which a walker's log posterior counts as stuck.
STUCK_P = 1e-6


#: The move schedules (see :class:`SamplerSettings`), name -> description (used in reports).
MOVES = {
    "de": "emcee's differential-evolution move (DEMove) only",
    "de-snooker": "80 % DEMove + 20 % DESnookerMove",
    "stretch": "emcee's affine-invariant stretch move",
}


@dataclass(frozen=True)
class SamplerSettings:
    """emcee settings.

    Parameters
    ----------
    n_walkers
        Ensemble size (at least 2·ndim).
    max_steps
        Step cap.
    min_steps
        Never stop before this many steps.
    check_every
        Steps between autocorrelation checks.
    tau_factor
        Require chain length > tau_factor·tau.
    tau_rtol
        Relative change of tau between checks regarded as stable.
    moves
        ``"de"`` (``DEMove``), ``"de-snooker"`` (80 % ``DEMove`` + 20 % ``DESnookerMove``,
        emcee's recommendation for multimodal targets) or ``"stretch"`` (emcee's default).
    progress
        Show a tqdm progress bar; None: only when stderr is a terminal.
    """

    n_walkers: int = 32
    max_steps: int = 20000
    min_steps: int = 500
    check_every: int = 100
    tau_factor: float = 50.0
    tau_rtol: float = 0.05
    moves: str = "de"
    progress: bool | None = None

    def __post_init__(self) -> None:
        if self.moves not in MOVES:
            raise InputError(f"unknown moves {self.moves!r}; use one of {', '.join(MOVES)}")
        for name in ("n_walkers", "max_steps", "check_every"):
            value = getattr(self, name)
            if not (isinstance(value, int | np.integer) and value >= 1):
                raise InputError(f"sampler setting {name} = {value!r} must be a positive integer")
        if not (isinstance(self.min_steps, int | np.integer) and self.min_steps >= 0):
            raise InputError(f"sampler setting min_steps = {self.min_steps!r} must be >= 0")
        if not (self.tau_factor > 0 and self.tau_rtol > 0):
            raise InputError("sampler settings tau_factor and tau_rtol must be positive")


@dataclass
class ChainResult:
    """Post-burn-in, thinned chains.

    Attributes
    ----------
    samples
        (n_walkers, n_draws, ndim) parameter draws, walkers as chains.
    log_prob
        (n_walkers, n_draws) log-posterior of each draw; None when not computed (the exact
        engine's draws of a fit whose InferenceData is not kept).
    tau
        Integrated autocorrelation time per parameter [steps].
    n_steps, burn, thin
        Steps run, burn-in discarded and thinning applied.
    acceptance
        Mean acceptance fraction of the walkers.
    hit_cap
        True if sampling stopped at ``max_steps`` before tau was stable.
    moved
        Stuck walkers moved during burn-in (module docstring); 0 for a clean run.
    """

    samples: np.ndarray
    log_prob: np.ndarray | None
    tau: np.ndarray
    n_steps: int
    burn: int
    thin: int
    acceptance: float
    hit_cap: bool
    moved: int = 0


def _moves(kind: str):
    import emcee

    if kind == "stretch":
        return None
    if kind == "de":
        return emcee.moves.DEMove()
    if kind == "de-snooker":
        return [(emcee.moves.DEMove(), 0.8), (emcee.moves.DESnookerMove(), 0.2)]
    raise InputError(f"unknown moves {kind!r}; use one of {', '.join(MOVES)}")


def _burn_thin(tau: np.ndarray, n_steps: int) -> tuple[int, int]:
    if np.all(np.isfinite(tau)):
        burn = min(int(np.ceil(2 * float(np.max(tau)))), n_steps // 2)
        thin = max(1, int(np.floor(0.5 * float(np.min(tau)))))
    else:
        burn, thin = n_steps // 4, 1
    return burn, thin


def _with_extra(moves, extra: list | None):
    """The configured moves plus ``extra`` [(move, weight)], the configured ones sharing
    1 − Σ weights."""
    if not extra:
        return moves
    import emcee

    base = [(emcee.moves.StretchMove(), 1.0)] if moves is None else (
        moves if isinstance(moves, list) else [(moves, 1.0)])
    rest = 1.0 - sum(w for _, w in extra)
    return [(m, w * rest) for m, w in base] + list(extra)


def seed_sampler(sampler: emcee.EnsembleSampler, seed: int) -> None:
    """Seed an emcee sampler through its public ``random_state`` (emcee has no seed argument,
    docs/design.md §8): the state of a Mersenne Twister seeded by
    ``SeedSequence(seed)``."""
    rs = np.random.RandomState(np.random.MT19937(np.random.SeedSequence(seed)))
    sampler.random_state = rs.get_state()
    if sampler.random_state[1][0] != rs.get_state()[1][0]:  # emcee's setter fails silently
        raise RuntimeError("emcee did not take the sampler's random state")


def run_emcee(log_prob, p0: np.ndarray, settings: SamplerSettings, seed: int | None,
              accept: Callable[[np.ndarray, np.ndarray], bool] | None = None,
              extra_moves: list | None = None) -> ChainResult:
    """Sample ``log_prob`` (vectorised over walkers) from the initial ensemble ``p0``.

    Parameters
    ----------
    log_prob
        Callable taking (W, ndim) and returning (W,) log-posterior values.
    p0
        (W, ndim) initial walker positions (all with finite log_prob).
    settings
        Sampler settings.
    seed
        Seed of the sampler's random state.
    accept
        Optional extra test ``accept(chain, log_prob)`` on the burnt-in, thinned chain
        (walkers, draws, ndim) and its log-posterior (walkers, draws), e.g. R-hat and ESS
        thresholds; sampling goes on while it fails (up to ``max_steps``).
    extra_moves
        [(move, weight)] added to the configured moves (e.g. the layer's base swap,
        :func:`palpbayes.bayes.layer_likelihood.base_swap_move`).
    """
    import emcee

    n_walkers, ndim = p0.shape
    sampler = emcee.EnsembleSampler(n_walkers, ndim, log_prob, vectorize=True,
                                    moves=_with_extra(_moves(settings.moves), extra_moves))
    seed_sampler(sampler, seed)
    progress = settings.progress
    if progress is None:
        progress = sys.stderr.isatty()
    hit_cap, start, spent, moved = True, p0, 0, 0
    for restart in range(MAX_RESTARTS + 1):
        old_tau = np.full(ndim, np.inf)
        again = None
        # a restart's copies of walkers are not independent rows: emcee's check would refuse
        for state in sampler.sample(start, iterations=settings.max_steps - spent,
                                    progress=progress, skip_initial_state_check=restart > 0):
            it = sampler.iteration
            if it % settings.check_every or it < settings.min_steps:
                continue
            # a restart needs the budget for a whole chain: min_steps and one more check
            room = settings.max_steps - spent - it >= settings.min_steps + settings.check_every
            if restart < MAX_RESTARTS and room:
                window = slice(-settings.check_every, None)
                stuck = stuck_walkers(sampler.get_log_prob()[window], ndim,
                                      sampler.get_chain()[window])
                if stuck.any():  # move them onto the others, restart: all this is burn-in
                    again = state.coords.copy()
                    rs = np.random.RandomState()  # the sampler's stream, drawn on and put back
                    rs.set_state(sampler.random_state)
                    again[stuck] = again[rs.choice(np.flatnonzero(~stuck), int(stuck.sum()))]
                    sampler.random_state = rs.get_state()
                    moved += int(stuck.sum())
                    break
            tau = sampler.get_autocorr_time(tol=0)
            stable = np.all(np.abs(old_tau - tau) / tau < settings.tau_rtol)
            old_tau = tau
            if not (np.all(tau * settings.tau_factor < it) and stable):
                continue
            if accept is not None:
                burn, thin = _burn_thin(tau, it)
                chain = np.swapaxes(sampler.get_chain(discard=burn, thin=thin), 0, 1)
                lp = sampler.get_log_prob(discard=burn, thin=thin).T
                if not accept(chain, lp):
                    continue
            hit_cap = False
            break
        if again is None:
            break
        spent += sampler.iteration
        sampler.reset()
        start = again
    tau = sampler.get_autocorr_time(tol=0)
    burn, thin = _burn_thin(tau, sampler.iteration)
    chain = sampler.get_chain(discard=burn, thin=thin)  # (draws, walkers, ndim)
    lp = sampler.get_log_prob(discard=burn, thin=thin)
    return ChainResult(
        samples=np.ascontiguousarray(np.swapaxes(chain, 0, 1)),
        log_prob=np.ascontiguousarray(lp.T),
        tau=np.asarray(tau, dtype=float),
        n_steps=spent + int(sampler.iteration),
        burn=burn,
        thin=thin,
        acceptance=float(np.mean(sampler.acceptance_fraction)),
        hit_cap=hit_cap,
        moved=moved,
    )


def stuck_walkers(log_prob: np.ndarray, ndim: int, chain: np.ndarray | None = None,
                  p: float = STUCK_P) -> np.ndarray:
    """Walkers (bool, W) stuck over a window of steps: their best log posterior in
    ``log_prob`` (steps, W) lies more than chi2_ndim(1 − p)/2 below the median over walkers of
    their best (under the posterior, 2·(max − lp) of a draw is ~chi2 with ndim degrees of
    freedom near the mode), and, given the window's ``chain`` (steps, W, ndim), they moved in
    fewer than a quarter as many steps as the median walker (a walker exploring a broad mode
    of its own still moves; the stuck ones of real fits moved in 0–1 % of the steps, the others
    in 8–23 %)."""
    from scipy.stats import chi2

    best = np.max(log_prob, axis=0)
    low = best < np.median(best) - 0.5 * float(chi2.isf(p, ndim))
    if chain is None or chain.shape[0] < 2:
        return low
    moves = np.mean(np.any(chain[1:] != chain[:-1], axis=2), axis=0)
    return low & (moves < 0.25 * np.median(moves))
