"""How deep to press: the depths a search may choose, what each costs, and the choice.

A press is (x, y, depth).  The depths come from a set the user gives (``palpbayes next --init
--depths 0.1,0.2``, fractions of the block's thickness); each has its contact radius (the tip's
contact law, :func:`palpbayes.inclusion.contact_radius`) and so its own lump profiles
(:mod:`~.profiles`), and a cost in time::

    t(depth) = overhead + 2·depth / speed    [s]

(down and up at the indentation speed, the paper's 50 mm/min by default, plus the move and
approach ``overhead``).  The expected information gain of a press (:func:`~.criteria.eig`) is
computed at every candidate and depth, and the press chosen is the one with the most
information per second, EIG(x, y, d) / t(d) [nat/s] — a one-step cost-aware design (as the
"expected improvement per second" of Snoek, Larochelle & Adams 2012, NIPS).  The other
criteria (``lse``, ``ucb``) score no information and press at the first depth.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import InputError

__all__ = ["PAPER_SPEED", "PRESS_OVERHEAD", "PressDepths", "press_seconds"]

#: [m/s] The paper's indentation speed, 50 mm/min.
PAPER_SPEED = 50e-3 / 60.0
#: [s] Default time of a press besides its indentation (the move and the approach).
PRESS_OVERHEAD = 3.0
_MATCH = 1e-6  # [m] a press's depth is one of the set when within this (or 1 %) of it


@dataclass(frozen=True)
class PressDepths:
    """The press depths a search may choose (the first is the reference), and their cost.

    Parameters
    ----------
    depths
        [m] Indentation depths, the reference (of the posterior's amplitude) first.
    contact_radii
        [m] The tip's contact radius at each depth.
    overhead
        [s] Time of a press besides the indentation: the move to the point and the approach.
    speed
        [m/s] Indentation speed (down and up).
    """

    depths: tuple[float, ...]
    contact_radii: tuple[float, ...]
    overhead: float = PRESS_OVERHEAD
    speed: float = PAPER_SPEED

    def __post_init__(self) -> None:
        d = tuple(float(v) for v in self.depths)
        a = tuple(float(v) for v in self.contact_radii)
        if not d or len(d) != len(a) or not all(
                math.isfinite(v) and v > 0 for v in (*d, *a)):
            raise InputError(f"press depths {self.depths!r} and contact radii "
                             f"{self.contact_radii!r} [m] need one positive value each, at "
                             "least one depth")
        if len(set(d)) != len(d):
            raise InputError(f"press depths {d!r} [m] repeat a depth")
        if not (math.isfinite(self.overhead) and self.overhead >= 0
                and math.isfinite(self.speed) and self.speed > 0):
            raise InputError(f"press overhead {self.overhead!r} s must be >= 0 and speed "
                             f"{self.speed!r} m/s > 0")
        object.__setattr__(self, "depths", d)
        object.__setattr__(self, "contact_radii", a)

    @classmethod
    def for_tip(cls, tip, depths, **kw) -> PressDepths:
        """The set for ``tip`` (:class:`palpbayes.contact.Tip`) at ``depths`` [m]."""
        from ..inclusion import contact_radius

        return cls(tuple(depths), tuple(contact_radius(tip, d) for d in depths), **kw)

    def seconds(self) -> np.ndarray:
        """[s] The time of a press at each depth (:func:`press_seconds`)."""
        return press_seconds(np.asarray(self.depths), self.overhead, self.speed)

    def usable(self, deepest: float | None = None) -> list[int]:
        """Indices of the depths at most ``deepest`` [m] (None: all); the first always."""
        return [j for j, d in enumerate(self.depths)
                if j == 0 or deepest is None or d <= deepest * (1 + 1e-9)]

    def index(self, depth_m) -> np.ndarray:
        """Each press depth's index in :attr:`depths` (NaN: the reference, 0).

        Raises
        ------
        InputError
            A depth that is none of the set (the message names the press and the set).
        """
        v = np.asarray(depth_m, dtype=float).ravel()
        d = np.asarray(self.depths)
        dist = np.abs(v[:, None] - d[None, :])
        j = np.argmin(np.where(np.isnan(dist), np.inf, dist), axis=1)
        ok = np.isnan(v) | (dist[np.arange(v.size), j] <= np.maximum(_MATCH, 0.01 * d[j]))
        if not ok.all():
            i = int(np.flatnonzero(~ok)[0])
            raise InputError(f"presses: press {i + 1} has depth_m {v[i]:g} m, none of the "
                             f"search's depths ({', '.join(f'{x:g}' for x in d)} m); record "
                             "presses at the depths the state was created with")
        return np.where(np.isnan(v), 0, j).astype(np.intp)


def press_seconds(depth, overhead: float = PRESS_OVERHEAD, speed: float = PAPER_SPEED):
    """[s] The time of a press to ``depth`` [m]: ``overhead`` [s] + 2·depth/``speed`` (down
    and up at ``speed`` [m/s])."""
    return overhead + 2.0 * depth / speed


def choose(scores: list[np.ndarray], seconds: np.ndarray) -> tuple[int, int, float]:
    """The (depth index, candidate index, score per second) of the most information per
    second among ``scores`` (one array over the candidates per depth)."""
    rate = np.vstack(scores) / np.asarray(seconds)[:, None]
    j, i = np.unravel_index(int(np.argmax(rate)), rate.shape)
    return int(j), int(i), float(rate[j, i])
