"""What a press may be: the checks the live loop (``palpbayes follow --map``) makes before a
press, as pure functions of the search state, easy to test without a socket.

A press (x, y [m], depth [m]) is refused, and not made, when

* its position lies off the footprint (x0 <= x <= x1, y0 <= y <= y1 [m]) or inside a
  keep-out disc (distance to its centre <= its radius: the rule the candidates of
  :meth:`~palpbayes.active.search.SearchState.candidates` keep too);
* its depth is not in (0, thickness), or not one of the allowed depths
  (:attr:`PressLimits.depths`, fractions of the block's thickness, matched within
  :data:`DEPTH_TOLERANCE`);
* its predicted peak force exceeds :attr:`PressLimits.max_force`: the contact law's force at
  that depth (a callable the caller gives: the follow command's own tip, nu and layer) for
  the largest plausible modulus of the specimen (:func:`plausible_modulus`).

Each check returns None (the press may go) or one sentence: the position, the rule broken
and what to do.  :func:`check_press` makes them in that order and returns the first refusal.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from ..errors import InputError

__all__ = ["PressLimits", "Refusal", "DEPTH_TOLERANCE", "UPPER_Z", "plausible_modulus",
           "check_position", "check_depth", "check_force", "check_press", "parse_depths"]

#: [m] A press's depth matches an allowed depth within this (a format tolerance: a robot's
#: repeatability is ±0.03 mm, the depth it sends is a number it was told).
DEPTH_TOLERANCE = 1e-6

#: One-sided normal quantile (99 %) of a press's log E taken as its upper end in
#: :func:`plausible_modulus`.
UPPER_Z = 2.3263479


@dataclass(frozen=True)
class PressLimits:
    """The limits of a press beyond the footprint and the keep-out zones.

    Parameters
    ----------
    depths
        Allowed indentation depths as fractions of the block's thickness (e.g. (0.1, 0.2));
        () allows any depth.
    max_force
        [N] Largest force above the baseline a press may reach, predicted before it and
        measured during it; None: no limit.
    depth
        [m] The depth of a press line that gives none (the search state's ``depth_m``);
        None: unknown (any depth then, unless ``depths`` is given).
    """

    depths: tuple[float, ...] = ()
    max_force: float | None = None
    depth: float | None = None

    def __post_init__(self) -> None:
        fr = tuple(float(v) for v in self.depths)
        if not all(math.isfinite(v) and 0 < v < 1 for v in fr):
            raise InputError(f"depths (--depths) {self.depths!r}: each must be a fraction of "
                             "the thickness in (0, 1), e.g. 0.1,0.2")
        object.__setattr__(self, "depths", fr)
        for name, what in (("max_force", "(--max-force) {!r} must be > 0 [N]"),
                           ("depth", "(--depth) {!r} must be > 0 [m]")):
            v = getattr(self, name)
            if v is not None and not (math.isfinite(float(v)) and v > 0):
                raise InputError(f"{name} {what.format(v)}")

    def allowed(self, thickness: float) -> tuple[float, ...]:
        """[m] The allowed depths on a block ``thickness`` [m] thick (() when any)."""
        return tuple(f * thickness for f in self.depths)


@dataclass(frozen=True)
class Refusal:
    """Why a press is refused: ``rule`` (``"footprint"``, ``"keep-out"``, ``"depth"`` or
    ``"force"``) and ``message`` (the position, the rule broken and what to do)."""

    rule: str
    message: str


def parse_depths(text: str) -> tuple[float, ...]:
    """'0.1,0.2' -> (0.1, 0.2): fractions of the thickness (argument of ``--depths``).

    Raises
    ------
    InputError
        Not numbers separated by commas, or one outside (0, 1).
    """
    try:
        vals = tuple(float(v) for v in str(text).split(","))
    except ValueError:
        raise InputError(f"--depths {text!r}: give fractions of the thickness separated by "
                         "commas, e.g. 0.1,0.2") from None
    return PressLimits(depths=vals).depths


def _where(x: float, y: float, depth: float | None = None) -> str:
    at = f"press at ({x:g}, {y:g}) m"
    return at if depth is None else f"{at}, depth {depth:g} m"


def check_position(footprint: Sequence[float], keep_out: Sequence[Sequence[float]],
                   x: float, y: float) -> Refusal | None:
    """None when (x, y) [m] lies on the footprint (x0, x1, y0, y1 [m], edges included) and
    outside every keep-out disc (x, y, r [m]); else the refusal."""
    x0, x1, y0, y1 = (float(v) for v in footprint)
    if not (x0 <= x <= x1 and y0 <= y <= y1):
        return Refusal("footprint", f"{_where(x, y)} is off the footprint x {x0:g} to "
                       f"{x1:g} m, y {y0:g} to {y1:g} m: not pressed, not recorded; press "
                       "inside it (the answer's next press is)")
    for i, (zx, zy, r) in enumerate(keep_out):
        d = math.hypot(x - zx, y - zy)
        if d <= r:
            return Refusal("keep-out", f"{_where(x, y)} is inside keep-out zone {i + 1} "
                           f"(centre ({zx:g}, {zy:g}) m, radius {r:g} m; {d:.3g} m from its "
                           "centre): not pressed, not recorded; press outside it (the "
                           "answer's next press is)")
    return None


def check_depth(limits: PressLimits, thickness: float, x: float, y: float,
                depth: float | None) -> Refusal | None:
    """None when ``depth`` [m] is allowed (any depth in (0, thickness) when no depths are
    given; a press without a depth is at ``limits.depth``); else the refusal."""
    if depth is not None and not 0 < depth < thickness:
        return Refusal("depth", f"{_where(x, y, depth)}: a depth must lie between 0 and the "
                       f"block's thickness {thickness:g} m: not pressed, not recorded; send "
                       "the indentation depth [m] below the surface")
    allowed = limits.allowed(thickness)
    if not allowed:
        return None
    how = ", ".join(f"{d:g} m ({f:g} of {thickness:g} m)"
                    for d, f in zip(allowed, limits.depths, strict=True))
    if depth is None and limits.depth is None:
        return Refusal("depth", f"{_where(x, y)} gives no depth and the search has none: "
                       "not pressed, not recorded; send 'press X Y DEPTH' with DEPTH one of "
                       f"{how}")
    if not any(abs((limits.depth if depth is None else depth) - d) <= DEPTH_TOLERANCE
               for d in allowed):
        if depth is None:
            return Refusal("depth", f"{_where(x, y)} gives no depth, and the search's depth "
                           f"{limits.depth:g} m is not an allowed depth (--depths): not "
                           "pressed, not recorded; send 'press X Y DEPTH' with DEPTH one of "
                           f"{how}")
        return Refusal("depth", f"{_where(x, y, depth)}: the depth is not an allowed depth "
                       f"(--depths): not pressed, not recorded; press again at one of {how}")
    return None


def plausible_modulus(logE_mean: Sequence[float], logE_sd: Sequence[float],
                      max_ratio: float) -> float | None:
    """[Pa] The largest modulus a press may plausibly meet: the stiffest press so far at the
    upper end of its one-sided 99 % interval (exp(mean + :data:`UPPER_Z` × sd)) times the
    search prior's largest apparent lump ratio ``max_ratio`` (a lump not found yet may be
    that much stiffer than the block); None before the first press."""
    m = np.asarray(logE_mean, dtype=float)
    s = np.asarray(logE_sd, dtype=float)
    ok = np.isfinite(m) & np.isfinite(s)
    if not ok.any():
        return None
    return float(max_ratio * np.exp(np.max(m[ok] + UPPER_Z * s[ok])))


def check_force(limits: PressLimits, force_at: Callable[[float, float], float] | None,
                E: float | None, x: float, y: float, depth: float | None) -> Refusal | None:
    """None when the predicted peak force ``force_at(E, depth)`` [N] (E [Pa], depth [m]) is
    within ``limits.max_force``, or cannot be predicted (no limit, no law, no modulus yet,
    no depth); else the refusal."""
    if limits.max_force is None or force_at is None or E is None:
        return None
    d = limits.depth if depth is None else depth
    if d is None:
        return None
    F = float(force_at(E, d))
    if F <= limits.max_force:
        return None
    return Refusal("force", f"{_where(x, y, d)}: its predicted peak force {F:.3g} N exceeds "
                   f"--max-force {limits.max_force:g} N (the contact law at E = {E:.4g} Pa, "
                   "the stiffest press so far times the prior's largest lump ratio): not "
                   "pressed, not recorded; press at a shallower allowed depth")


def check_press(footprint: Sequence[float], keep_out: Sequence[Sequence[float]],
                thickness: float, limits: PressLimits, x: float, y: float,
                depth: float | None, *, E: float | None = None,
                force_at: Callable[[float, float], float] | None = None) -> Refusal | None:
    """The first refusal of a press at (x, y) [m] and ``depth`` [m] (None: the search's
    depth): position, depth, predicted force (module docstring); None when it may go.

    Parameters
    ----------
    footprint, keep_out, thickness
        The search state's (:class:`~palpbayes.active.SearchState`) [m].
    limits
        The allowed depths and the force limit.
    E
        [Pa] The modulus the force is predicted with (:func:`plausible_modulus`).
    force_at
        The contact law: peak force [N] at (E [Pa], depth [m]).
    """
    return (check_position(footprint, keep_out, x, y)
            or check_depth(limits, thickness, x, y, depth)
            or check_force(limits, force_at, E, x, y, depth))
