"""What one update of the online estimate says, and when to stop pressing.

:class:`OnlineState` is the estimate after a chunk of samples (E with its statistical and full
intervals, the depth and force so far, the flags); :class:`StoppingRule` says when to stop
(a precision target on either interval, a force or depth limit); :func:`check_noise_options`
checks the estimator's noise options before a stream or a file is read.  The estimator that
makes the states is :class:`palpbayes.online.estimator.OnlineEstimator`.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass

import numpy as np

from ..bayes.mixture import MixtureSummary
from ..bayes.noisemodels import EXACT_NOISE_MODELS
from ..errors import InputError

__all__ = ["TARGET_ON", "StoppingRule", "OnlineState", "check_noise_options"]

#: The intervals a precision target can be tested on: with the budget, or statistical only.
TARGET_ON = ("full", "stat")


@dataclass(frozen=True)
class StoppingRule:
    """When to stop pressing (the first condition met).

    Parameters
    ----------
    target
        Relative half-width (hi − lo)/(2·median) of the E interval (at the estimator's level)
        to reach, e.g. 0.02 for ±2 %; None: no precision target.
    max_force
        [N] Largest force above the baseline.
    max_depth
        [m] Largest depth below the estimated surface.
    min_contact
        Fewest samples in contact before the precision target may stop the run.
    target_on
        The interval the target is tested on: ``"stat"`` (statistical, ``OnlineState.E``;
        the library's default, as before) or ``"full"`` (with the uncertainty budget,
        ``OnlineState.E_total``; ``palpbayes replay`` and ``follow`` default to it).
    """

    target: float | None = None
    max_force: float | None = None
    max_depth: float | None = None
    min_contact: int = 20
    target_on: str = "stat"

    def __post_init__(self) -> None:
        for name in ("target", "max_force", "max_depth"):
            v = getattr(self, name)
            if v is not None and not (isinstance(v, numbers.Real) and not isinstance(v, bool)
                                      and math.isfinite(v) and v > 0):
                raise InputError(f"stopping rule: {name} = {v!r} must be a positive number")
        if (isinstance(self.min_contact, bool)
                or not isinstance(self.min_contact, int | np.integer) or self.min_contact < 1):
            raise InputError(f"stopping rule: min_contact = {self.min_contact!r} must be a "
                             "whole number of samples >= 1")
        if self.target_on not in TARGET_ON:
            raise InputError(f"stopping rule: target_on = {self.target_on!r} must be one of "
                             f"{', '.join(TARGET_ON)}")

    @property
    def full(self) -> bool:
        """A precision target tested on the full interval (it needs the budget)."""
        return self.target is not None and self.target_on == "full"

    def reason(self, state: OnlineState) -> str:
        """Why to stop now ('' to go on)."""
        if self.max_force is not None and state.peak_force >= self.max_force:
            return "max force"
        if self.max_depth is not None and state.depth >= self.max_depth:
            return "max depth"
        E = state.E_total if self.target_on == "full" else state.E
        if (self.target is not None and state.n_contact >= self.min_contact
                and E is not None and E.rel_half_width <= self.target):
            return "target precision"
        return ""

    def first_limit(self, z: np.ndarray, force: np.ndarray, level: float,
                    z_surf: float | None) -> tuple[int, str] | None:
        """The first of the samples (tip heights ``z`` [m], forces [N]) at which the max force
        or the max depth is reached, and which: (index, "max force" | "max depth"; the force
        first when both are reached at one sample, as :meth:`reason`), the force taken above
        the baseline ``level`` [N] and the depth below the surface ``z_surf`` [m] (None: not
        known yet, no depth judged); None when neither is reached."""
        hits = {}
        if self.max_force is not None:
            hits["max force"] = force - level >= self.max_force
        if self.max_depth is not None and z_surf is not None:
            hits["max depth"] = z_surf - z >= self.max_depth
        first = [(int(np.argmax(h)), rank, why)
                 for rank, (why, h) in enumerate(hits.items()) if h.any()]
        return min(first)[::2] if first else None


def check_noise_options(noise: str = "gaussian", noise_pp: float | None = None,
                        f_unc: float | None = None) -> None:
    """The online estimator's checks of its noise model, the sensor's peak-to-peak noise [N]
    and the contact threshold [N] (:class:`OnlineEstimator` runs them; ``palpbayes replay``
    and :func:`palpbayes.replay` run them on their options before the trace is read).

    Raises
    ------
    InputError
        A force that is not a positive number, or a noise model the exact engine does not
        take (:data:`~palpbayes.bayes.noisemodels.EXACT_NOISE_MODELS`).
    """
    for name, v in (("noise_pp", noise_pp), ("f_unc", f_unc)):
        if v is not None and not (isinstance(v, numbers.Real) and not isinstance(v, bool)
                                  and math.isfinite(v) and v > 0):
            raise InputError(f"online estimation: {name} = {v!r} must be a positive force "
                             "in newtons (the sensor's peak-to-peak noise), or None to "
                             "read it from the baseline")
    if noise not in EXACT_NOISE_MODELS:
        raise InputError(f"online estimation takes noise "
                         f"{' or '.join(map(repr, EXACT_NOISE_MODELS))}, not {noise!r}")


@dataclass(frozen=True)
class OnlineState:
    """The estimate after one update.

    Attributes
    ----------
    n, t, z
        Samples so far, time [s] and tip height [m] of the last one.
    in_contact, n_contact
        Contact detected; samples since the contact onset.
    depth
        [m] Median surface height minus the current tip height (0 before contact).
    peak_force
        [N] Largest force above the baseline so far.
    E, z_surf
        Posterior summaries of E [Pa] (statistical) and z_surf [m]; None before contact.
    stop
        The stopping rule's reason ('' to go on).
    flags
        Posterior at a bound of the online surface prior, refinement cut short, a full
        target below the budget's floor.
    E_total
        E [Pa] with the uncertainty budget (the full interval); None when the estimator does
        not compute it (:attr:`OnlineEstimator.total`) or before the first estimate.
    floor
        [-] Relative half-width of the budget alone (E* exact): the narrowest the full
        interval can get at this depth; NaN with ``E_total`` None.
    force
        [N] Force above the baseline of the last sample (NaN before contact).
    """

    n: int
    t: float
    z: float
    in_contact: bool
    n_contact: int
    depth: float
    peak_force: float
    E: MixtureSummary | None
    z_surf: MixtureSummary | None
    stop: str
    flags: tuple[str, ...] = ()
    E_total: MixtureSummary | None = None
    floor: float = float("nan")
    force: float = float("nan")

    @property
    def should_stop(self) -> bool:
        return bool(self.stop)
