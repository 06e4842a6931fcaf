"""Estimate E while the tip is still pressing, and say when to stop.

:class:`OnlineEstimator` takes samples as they arrive (chunks of t, z, F), detects contact,
and after every chunk gives the posterior of E with its interval (:class:`OnlineState`) and a
``should_stop`` from a :class:`StoppingRule`; a chunk can end at the sample that reaches the
rule's max force or max depth (:meth:`OnlineEstimator.limit`), so that the run stops there,
not at the end of the chunk.  The posterior is that of the exact engine
(:mod:`palpbayes.bayes.exact`): the same model and priors as ``palpbayes fit --engine exact``
(Gaussian or AR(1) noise, constant baseline), with two online choices:

* the baseline (level, noise sd, F0 prior centre, noise spec) is read once, at contact, from
  the samples before it (:func:`palpbayes.baseline.estimate_baseline`);
* the surface prior is uniform on [z_c − (z_top − z_c), z_top] (z_c the contact onset, z_top
  the highest sample): the final deepest point, the offline prior's lower end, is not known
  yet; a posterior that reaches the lower end is flagged.  Every loading sample is fitted (no
  fit window), for every tip.

Updates are incremental: each surface node keeps running sums, and the grid of nodes is
refined and pruned as the posterior narrows (:mod:`palpbayes.online.surface`).

The model is elastic: a hold that relaxes flags the state, naming the viscoelastic fit, and
:meth:`OnlineEstimator.model_checks` runs the offline fit's adequacy checks on the samples so
far (:mod:`palpbayes.online.adequacy`).

**Two intervals.**  ``OnlineState.E`` is statistical; ``OnlineState.E_total`` adds the
uncertainty budget, the full interval of the offline summary row, with its floor
(:mod:`palpbayes.online.full_interval`).

**Memory.**  The samples are kept within bounds, however long the stream: the last
:data:`PRE_CONTACT_SAMPLES` before the contact and :data:`MAX_CONTACT_SAMPLES` from it on
(:mod:`palpbayes.online.samples`); the model checks run on at most :data:`CHECK_SAMPLES` of
them.  A press within the bounds is estimated, stopped and checked as by an estimator that
keeps everything.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np

from ..baseline import MIN_BASELINE_POINTS, estimate_baseline
from ..bayes.budget import BudgetSpec
from ..bayes.exact import ExactPosterior, phi_grid
from ..bayes.mixture import MixtureSummary
from ..bayes.priors import PriorSpec, TracePrior, param_names
from ..checks import CheckResult
from ..errors import InputError
from ..fitdata import ModelSpec
from ..intervals import LEVEL
from ..sensor_noise import sigma_from_pp
from . import adequacy
from .adequacy import CHECK_SAMPLES, HOLD_TOLERANCE, HOLD_WINDOW, RELAX_N_SE
from .full_interval import (
    BUDGET_DRAWS,
    full_from_draws,
    full_interval,
    propagate_draws,
    statistical_E,
    warm_up_budget,
)
from .samples import MAX_CONTACT_SAMPLES, PRE_CONTACT_SAMPLES, KeptSamples, checked_samples
from .state import TARGET_ON, OnlineState, StoppingRule, check_noise_options
from .surface import PRUNE, SurfaceNodes

__all__ = ["StoppingRule", "OnlineState", "OnlineEstimator", "PRUNE", "HOLD_WINDOW",
           "HOLD_TOLERANCE", "RELAX_N_SE", "TARGET_ON", "BUDGET_DRAWS", "PRE_CONTACT_SAMPLES",
           "MAX_CONTACT_SAMPLES", "CHECK_SAMPLES", "check_noise_options"]


@dataclass
class OnlineEstimator:
    """Posterior of E updated as samples arrive (module docstring).

    Parameters
    ----------
    model
        Contact model (tip, nu, optional finite-thickness correction).
    noise
        ``"gaussian"`` or ``"ar1"`` (phi on a fixed grid with the prior's bounds,
        :func:`palpbayes.bayes.exact.phi_grid`; not refined online, flagged at its ends).
    noise_pp
        [N] Sensor peak-to-peak noise; None: 6 sd of the pre-contact baseline.
    f_unc
        [N] Contact threshold above the baseline; None: the noise spec.
    rule
        The stopping rule.
    priors
        E* bounds and prior scales (:class:`PriorSpec`; ``surface`` must be "loading").
    level
        Probability content of the intervals.
    persist
        Consecutive samples above the threshold that make a contact.
    total
        Compute E with the budget (``OnlineState.E_total``, ~25 ms an update for a
        half-space with :data:`BUDGET_DRAWS`) at every update; always done when the rule's
        target is on the full interval.
    budget_draws
        Draws behind the full interval of an update that only shows it (default
        :data:`BUDGET_DRAWS`; ``follow``:
        :data:`~palpbayes.online.full_interval.SHOWN_BUDGET_DRAWS`, ~4 times faster); an
        update where a target on the full interval may fire (the statistical interval within
        the target) always takes :data:`BUDGET_DRAWS`.
    budget
        The budget's input distributions (None: :class:`BudgetSpec` defaults, the offline
        fit's).
    seed
        Seed of the posterior and budget draws (the same at every update, so that the full
        interval moves with the data only).
    """

    model: ModelSpec
    noise: str = "gaussian"
    noise_pp: float | None = None
    f_unc: float | None = None
    rule: StoppingRule = field(default_factory=StoppingRule)
    priors: PriorSpec = field(default_factory=PriorSpec)
    level: float = LEVEL
    persist: int = 5
    total: bool = False
    budget: BudgetSpec | None = None
    seed: int = 0
    budget_draws: int = BUDGET_DRAWS

    def __post_init__(self) -> None:
        check_noise_options(self.noise, self.noise_pp, self.f_unc)
        if not (isinstance(self.budget_draws, int) and self.budget_draws >= 100):
            raise InputError(f"online estimation: budget_draws = {self.budget_draws!r} must be "
                             "a whole number >= 100")
        if not (isinstance(self.persist, int) and self.persist >= 1):
            raise InputError(f"online estimation: persist = {self.persist!r} must be a whole "
                             "number of samples >= 1")
        if not 0 < self.level < 1:
            raise InputError(f"online estimation: level = {self.level!r} must lie in (0, 1)")
        # the samples kept (module docstring, "Memory") and the last one (t, z, F)
        self._kept = KeptSamples()
        self._last = (math.nan, math.nan, math.nan)
        self._peak = math.nan
        self._contact: int | None = None
        self._nodes: SurfaceNodes | None = None  # from the contact on
        self._phi = phi_grid(self.priors.phi_bounds) if self.noise == "ar1" else np.zeros(1)
        self.state: OnlineState | None = None
        # what limit() judges against: the last update's state, or the running update's as
        # soon as its surface and stop are known; the updates begun, and those it is from
        self._ref: OnlineState | None = None
        self._updates = self._known = 0
        if self.rule.full:
            self.total = True

    @property
    def baseline_level(self) -> float:
        """[N] Pre-contact force level read at contact (NaN before contact)."""
        return float(self._base.level) if self._contact is not None else float("nan")

    @property
    def n_kept(self) -> int:
        """Samples kept in memory (module docstring, "Memory"): at most
        :data:`PRE_CONTACT_SAMPLES` + a chunk before the contact, and
        :data:`MAX_CONTACT_SAMPLES` more from it on."""
        return self._kept.n

    def limit(self, z, force) -> tuple[int, str] | None:
        """The first of these new samples (tip heights [m], forces [N]) at which the rule's
        max force or max depth is reached, and which: (index, "max force" | "max depth"; the
        force first when both are reached at one sample, as :meth:`StoppingRule.reason`).

        Judged sample by sample, before any posterior work, against the baseline level and
        the median surface height of the last update (:attr:`limit_state`: the force above
        the baseline, the surface minus the tip height), so that a robot can be stopped at
        the sample itself rather than at the end of its chunk: ``replay``
        (:func:`~palpbayes.online.recorded.chunks`) and ``palpbayes follow``
        (:func:`~palpbayes.online.stream.batches`, which asks it in the thread that reads the
        samples, as each arrives) end a chunk there, and the update on that chunk stops with
        this reason (:meth:`update`: its depth is then measured from the surface the update
        gives, which can lie a hair under the max depth).  None when neither limit is
        reached, before the contact, when the baseline and the surface are not known yet (a
        limit passed in the chunk where the contact is found stops the run at that chunk's
        end), and once the rule has fired.
        """
        s, rule = self._ref, self.rule
        if (s is None or not s.in_contact or s.should_stop
                or (rule.max_force is None and rule.max_depth is None)):
            return None
        z, force = np.atleast_1d(np.asarray(z, dtype=float)), np.asarray(force, dtype=float)
        return rule.first_limit(z, force, self._base.level,
                                None if s.z_surf is None else s.z_surf.median)

    @property
    def limit_state(self) -> OnlineState | None:
        """The state :meth:`limit` judges against: the last update's, or the running
        update's as soon as its surface and stop are known (None before the first)."""
        return self._ref

    def limit_current(self, updates: int) -> bool:
        """Whether :meth:`limit` judges a new sample now as it will once ``updates`` updates
        are done: the last of them, even if still running, has set the surface and the stop
        :meth:`limit` judges against (midway, before the budget's draws, unless a target on
        the full interval may still fire), or the rule is a max force alone and the contact
        is known (only the baseline, read once at contact, judges it).
        :func:`~palpbayes.online.stream.batches` asks this to judge a sample that arrives
        while an update runs at once rather than after it, as ``replay`` would judge it."""
        if self._known >= updates:
            return True
        s, rule = self._ref, self.rule
        return (s is not None and s.in_contact and rule.max_force is not None
                and rule.max_depth is None and rule.target is None)

    def update(self, t, z, force,
               on_stop: Callable[[OnlineState], None] | None = None) -> OnlineState:
        """Add samples (times [s], tip heights [m], forces [N], in time order) and return the
        new :class:`OnlineState`.

        A sample that reaches the rule's max force or max depth as :meth:`limit` judges it
        (against the last update, as it arrived) stops the run with that reason, whatever
        the new surface says of its depth.  ``on_stop`` is called with the state once, the
        moment the rule fires: for a max force, a max depth or a target on the statistical
        interval before the full interval (the budget's draws, most of an update) is
        computed, so with ``E_total`` None (the returned state has it); for a target on the
        full interval, with the returned state.
        """
        t, z, force = checked_samples(t, z, force)
        hit = self.limit(z, force)
        self._updates += 1
        if t.size:
            self._last = (float(t[-1]), float(z[-1]), float(force[-1]))
        contact = self._contact is not None
        self._kept.add(t, z, force, self._contact)
        if not contact:
            self._detect()
        elif t.size:  # every sample updates the sums, kept or not
            y = force - self._base.level
            self._nodes.extend(z, y)
            self._peak = max(self._peak, float(y.max()))
        if self._contact is not None:
            _, z_kept, f_kept = self._kept.arrays()
            self._nodes.refresh(z_kept, f_kept, frozen=bool(self._kept.unkept))
        self.state = self._make_state("" if hit is None else hit[1], on_stop)
        self._publish(self.state)
        return self.state

    def _publish(self, state: OnlineState) -> None:
        """``state``'s surface and stop are what :meth:`limit` judges against from now on
        (set before the count, which :meth:`limit_current` reads first)."""
        self._ref = state
        self._known = self._updates

    # ------------------------------------------------------------------ contact
    def _detect(self) -> None:
        _, z, f = self._kept.arrays()
        n, k = z.size, self.persist
        if n < MIN_BASELINE_POINTS + k:
            return
        base = estimate_baseline(z, f)
        if not base.reliable:
            return
        f_unc = self.f_unc if self.f_unc is not None else (
            self.noise_pp if self.noise_pp is not None else base.noise_pp)
        above = f - base.level > f_unc
        if not above[-k:].all():
            return
        inside = np.flatnonzero(np.abs(f - base.level) <= f_unc)
        if inside.size < MIN_BASELINE_POINTS:
            raise InputError("online estimation needs an approach: fewer than "
                             f"{MIN_BASELINE_POINTS} samples before contact")
        self._contact = int(inside[-1]) + 1
        self._base, self._f_unc = base, float(f_unc)
        self._peak = float(np.max(f - base.level))
        pp = self.noise_pp if self.noise_pp is not None else base.noise_pp
        self._sigma_c = sigma_from_pp(pp)
        z_c = float(z[self._contact - 1])
        z_top = float(z.max())
        weights = np.array([(self._sigma_c / self._f_unc) ** 2])
        self._nodes = SurfaceNodes(self.model, self.noise, self._phi, weights, base.level,
                                   z_c - (z_top - z_c), z_top, z, f)

    def posterior(self) -> ExactPosterior:
        """The current posterior as an :class:`ExactPosterior` (draws, summaries)."""
        nodes = self._nodes
        if nodes is None:
            raise InputError("no contact yet: no posterior of E")
        prior = TracePrior(spec=self.priors, names=tuple(param_names(self.noise)),
                           noise=self.noise, baseline="constant",
                           z_bounds=(nodes.z_lo, nodes.z_top), sigma_center=self._sigma_c,
                           f0_center=self._base.level, f0_sd=self._f_unc, f1_sd=np.nan,
                           z_ref=nodes.z_top, f_unc=self._f_unc, data=None)
        return nodes.posterior(prior)

    def _make_state(self, limit: str = "",
                    on_stop: Callable[[OnlineState], None] | None = None) -> OnlineState:
        """The state after an update; ``limit`` the reason :meth:`limit` gave a new sample
        ('' for none), ``on_stop`` as :meth:`update`."""
        said: list[OnlineState] = []

        def say(state: OnlineState) -> None:
            said.append(state)
            if on_stop is not None:
                on_stop(state)

        state = self._state(limit, say)
        if state.should_stop and not said:
            say(state)
        return state

    def _state(self, limit: str, say: Callable[[OnlineState], None]) -> OnlineState:
        n = self._kept.seen
        if n == 0:  # an empty first chunk
            return OnlineState(0, float("nan"), float("nan"), False, 0, 0.0, 0.0, None, None, "")
        t, z, last_force = self._last
        if self._contact is None:
            return OnlineState(n, t, z, False, 0, 0.0, 0.0, None, None, "")
        peak = self._peak
        force = last_force - float(self._base.level)
        n_contact = n - self._kept.dropped - self._contact
        if not np.isfinite(self._nodes.post.logp).any():  # no surface has enough samples in contact
            early = OnlineState(n, t, z, True, n_contact, 0.0, peak, None, None, "",
                                ("no surface height has enough samples in contact yet",),
                                force=force)
            return replace(early, stop=limit or self.rule.reason(early))
        post = self.posterior()
        E = statistical_E(post, self.model.nu, self.level)
        zs = post.z_summary(self.level)
        flags = adequacy.state_flags(post, E, zs, self.model, self._base, self.noise_pp,
                                     self._kept, self._contact)
        rule = self.rule
        partial = OnlineState(n, t, z, True, n_contact, max(zs.median - z, 0.0),
                              peak, E, zs, "", tuple(flags), force=force)
        # a stop that needs no full interval (a limit, a statistical target) is said before
        # the budget's draws are made
        early = limit or rule.reason(partial)
        if early or not rule.full:  # the full interval changes neither the stop nor limit()
            self._publish(replace(partial, stop=early))
        if early and self.total:
            say(replace(partial, stop=early))
        if not self.total:
            return replace(partial, stop=early)
        # the full interval is never narrower than the statistical one: a target on it can
        # only fire where the statistical one is within the target, and is judged there on
        # BUDGET_DRAWS draws; elsewhere the interval is only shown
        deciding = rule.full and E.rel_half_width <= rule.target
        total, floor = self._total(post, E, BUDGET_DRAWS if deciding else self.budget_draws)
        if rule.full and floor > rule.target:
            flags.append(f"the target ±{100 * rule.target:.3g} % is below the ±{100 * floor:.2g} "
                         "% the uncertainty budget alone gives here (nu, tip radius, gain, "
                         "compliance): the precision target cannot stop the run on the full "
                         "interval; give a wider target or test it on the statistical one")
        full = replace(partial, flags=tuple(flags), E_total=total, floor=floor)
        return replace(full, stop=early or rule.reason(full))

    def _total(self, post: ExactPosterior, stat: MixtureSummary, n_draws: int = BUDGET_DRAWS
               ) -> tuple[MixtureSummary, float]:
        """The full interval of E [Pa] and the budget's floor [-], from ``n_draws`` draws
        (:func:`~palpbayes.online.full_interval.full_interval`)."""
        _, z, _ = self._kept.arrays()
        return full_interval(post, stat, self.model, z, self.budget, n_draws, self.seed,
                             self.level)

    def budget_interval(self, budget: BudgetSpec | None = None, n_draws: int = BUDGET_DRAWS,
                        seed: int = 0) -> MixtureSummary:
        """E [Pa] with the uncertainty budget (:mod:`palpbayes.bayes.budget`) at this point
        (``budget`` None: the estimator's): the full interval of
        :func:`~palpbayes.online.full_interval.full_from_draws`."""
        post, (_, z, _) = self.posterior(), self._kept.arrays()
        _, E = propagate_draws(post, self.model, z, budget or self.budget, n_draws, seed)
        return full_from_draws(statistical_E(post, self.model.nu, self.level), E, self.level)

    def warm_up(self) -> None:
        """Build what the budget of a layered model needs once per process (its profile
        tables at the Poisson ratios of the budget: seconds), so that the first update in
        contact does not pay for it.  Nothing to do for a half-space."""
        warm_up_budget(self.model, self.budget)

    def model_checks(self, seed: int = 0) -> list[CheckResult]:
        """The offline fit's adequacy checks (:func:`palpbayes.checks.run_checks`: exponent,
        residual structure, depth consistency, posterior-predictive) on the samples kept (every
        sample of a press: module docstring, "Memory"), at most :data:`CHECK_SAMPLES` of them,
        thinned evenly beyond (the last always in, the noise's lag-one correlation taken to
        the stride's power), at the posterior medians, graded against the statistical
        interval of E*.

        Returns
        -------
        list of CheckResult
            Empty before an estimate, or when the samples are too few for the checks.
        """
        if self.state is None or self.state.E is None:
            return []
        _, z, f = self._kept.arrays()
        return adequacy.model_checks(self.posterior(), z, f, self.model, self._base,
                                     self._nodes.z_top, self.level, seed)
