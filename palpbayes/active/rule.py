"""When an active search has decided: the stopping rule and its verdict on a posterior."""

from __future__ import annotations

from dataclasses import dataclass

from ..errors import InputError
from .posterior import SearchPosterior

__all__ = ["SearchStopRule", "decide"]


@dataclass(frozen=True)
class SearchStopRule:
    """When the search has decided (not :class:`~palpbayes.online.StoppingRule`, which says
    when to stop one press).

    Parameters
    ----------
    p_decide
        A lump is found when P(lump) >= ``p_decide`` and its centre is placed (below);
        there is none when P(lump) <= 1 − ``p_decide``.
    centre_radius, level
        [m] Target radius of the centre's credible disc, and the disc's credibility.
    max_presses
        Stop after this many presses whatever the posterior (None: no budget).
    """

    p_decide: float = 0.95
    centre_radius: float = 2e-3
    level: float = 0.9
    max_presses: int | None = None

    def __post_init__(self) -> None:
        if not 0.5 < self.p_decide < 1.0:
            raise InputError(f"p_decide (--p-decide) {self.p_decide!r} must lie in (0.5, 1)")
        if not (self.centre_radius > 0 and 0 < self.level < 1):
            raise InputError("centre_radius (--centre-radius) must be > 0 [m] and level in "
                             "(0, 1)")
        if self.max_presses is not None and int(self.max_presses) < 1:
            raise InputError(f"max_presses (--budget) {self.max_presses!r} must be >= 1")



def decide(post: SearchPosterior, rule: SearchStopRule) -> tuple[str, str]:
    """(decision, reason) of the stopping rule; ("", "") while undecided."""
    p = post.p_lump
    if p >= rule.p_decide:
        r = post.centre_radius(rule.level)
        if r <= rule.centre_radius:
            return "lump", (f"P(lump) {p:.3f} >= {rule.p_decide:g} and the centre's "
                            f"{100 * rule.level:g} % radius {1e3 * r:.2f} mm <= "
                            f"{1e3 * rule.centre_radius:g} mm")
    elif p <= 1.0 - rule.p_decide:
        return "no lump", f"P(lump) {p:.3f} <= {1 - rule.p_decide:.3g}"
    if rule.max_presses is not None and post.n >= rule.max_presses:
        return "", f"the budget of {rule.max_presses} presses is spent, undecided"
    return "", ""
