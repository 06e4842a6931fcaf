"""``pb.next_presses``: the active search's front door (a state object or a folder)."""

from __future__ import annotations

import os
from dataclasses import replace

from .files import read_state
from .search import NextPresses, SearchState, SearchStopRule
from .search import next_presses as _next

__all__ = ["next_presses"]


def next_presses(state: SearchState | str | os.PathLike, k: int = 1, *,
                 criterion: str = "eig", rule: SearchStopRule | None = None,
                 **overrides) -> NextPresses:
    """The next ``k`` presses of an active search for a lump, or the decision to stop.

    Parameters
    ----------
    state
        A :class:`~palpbayes.active.SearchState`, or a folder: a search state
        (``palpbayes next DIR --init``) or the output folder of ``palpbayes map``.
    k
        Presses to return (a batch, chosen greedily; :mod:`palpbayes.active.search`).
    criterion
        ``"eig"`` (expected information gain on presence and centre, the default), ``"lse"``
        (level-set estimation) or ``"ucb"`` (upper confidence bound, the baseline).
    rule
        The :class:`~palpbayes.active.SearchStopRule` (default: P(lump) >= 0.95 with the centre's
        90 % radius <= 2 mm, or P(lump) <= 0.05).
    overrides
        :class:`~palpbayes.active.SearchState` fields to replace (``footprint``,
        ``keep_out``, ``min_spacing`` [m], ...).

    Returns
    -------
    NextPresses
        ``presses`` (a DataFrame: order, x_m, y_m, score, criterion, and depth_m when the
        state has press depths, :class:`~palpbayes.active.depth.PressDepths`), ``stop``,
        ``decision`` ("lump", "no lump" or ""), ``reason`` and ``summary`` (P(lump), the
        centre [m] and its 90 % radius [m], the apparent diameter [m], ...).

    Examples
    --------
    >>> import palpbayes as pb
    >>> ans = pb.next_presses("search-dir")          # doctest: +SKIP
    >>> ans.presses[["x_m", "y_m"]], ans.summary["p_lump"]  # doctest: +SKIP
    """
    overrides = {k: v for k, v in overrides.items() if v is not None}
    if isinstance(state, SearchState):
        if overrides:  # a new grid for the new specimen: not the one the state has built
            state = replace(state, **overrides, _hyp=[])
    else:
        state = read_state(state, **overrides)
    return _next(state, k, criterion=criterion, rule=rule)
