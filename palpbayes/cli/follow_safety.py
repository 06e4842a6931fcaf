"""The limits of a press in the live loop (``palpbayes follow --listen PORT --map DIR``):
where they come from (the search state's ``search.json``, follow's ``--depths`` and
``--max-force``), the force law a press's peak force is predicted with, and the checks made
before each press (:mod:`palpbayes.active.safety`, pure functions of the state).  The loop
itself is :mod:`palpbayes.cli.follow_map`.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable

from ..active import SearchState
from ..active.files import read_limits
from ..active.safety import PressLimits, Refusal, check_press, parse_depths, plausible_modulus

__all__ = ["map_limits", "force_law", "state_modulus", "note_limits", "PressChecks",
           "deepest_allowed"]


def map_limits(args: argparse.Namespace) -> PressLimits:
    """The limits of a press in the live loop: the state's (``search.json``, from ``next
    --init``), each replaced by follow's ``--depths`` or ``--max-force`` when given (said on
    stderr where they differ).

    Raises
    ------
    InputError
        A bad ``--depths``; DataFileError: limits in ``search.json`` that cannot be read.
    """
    rec = read_limits(args.map)
    depths = rec.depths if args.depths is None else parse_depths(args.depths)
    force = rec.max_force if args.max_force is None else args.max_force
    said = [f"{what} {new} (search.json: {old})" for what, old, new in (
        ("--depths", ",".join(map(str, rec.depths)), ",".join(map(str, depths))),
        ("--max-force", rec.max_force, force)) if old and old != new]
    if said:
        print(f"note: follow's {'; '.join(said)} replace(s) the limits the search in {args.map}"
              " was set up with", file=sys.stderr, flush=True)
    return PressLimits(depths=depths, max_force=force, depth=rec.depth)


def force_law(model) -> Callable[[float, float], float]:
    """The peak force [N] of a press at (E [Pa], depth [m]) by the contact model ``model``
    (a concrete :class:`~palpbayes.modelspec.ModelSpec`: follow's tip, nu and layer, the one
    its E comes from): E/(1 − nu²) × F/E*(depth)."""
    import numpy as np

    from ..contact import youngs_factor

    def force_at(E: float, depth: float) -> float:
        return float(E / youngs_factor(model.nu) * model.shape(np.array([depth]))[0])

    return force_at


def state_modulus(state: SearchState) -> float | None:
    """[Pa] The largest plausible E of the next press (:func:`~palpbayes.active.safety.
    plausible_modulus` of the presses so far)."""
    p = state.presses
    return plausible_modulus(p["logE_mean"], p["logE_sd"], state.max_ratio)


def deepest_allowed(state: SearchState, limits: PressLimits, force_at) -> float | None:
    """[m] The deepest of the search's press depths whose predicted peak force (at
    :func:`state_modulus`) is within ``--max-force``, so that the search does not name a press
    the loop would refuse; the shallowest when none is; None when there is nothing to limit
    (one depth, no force limit, or no press yet)."""
    pd_ = state.press_depths
    if pd_ is None or limits.max_force is None or force_at is None:
        return None
    E = state_modulus(state)
    if E is None:
        return None
    ok = [d for d in pd_.depths if force_at(E, d) <= limits.max_force]
    return max(ok) if ok else min(pd_.depths)


def note_limits(state: SearchState, limits: PressLimits, force_at) -> None:
    """The limits the loop enforces, on stderr (and each allowed depth's predicted force)."""
    if not limits.depths and limits.max_force is None:
        return
    E = state_modulus(state)
    depths = limits.allowed(state.thickness) or ((limits.depth,) if limits.depth else ())
    said = [f"depths {', '.join(f'{d:g}' for d in depths)} m" if limits.depths else
            "any depth"]
    if limits.max_force is not None:
        said.append(f"max force {limits.max_force:g} N")
        if force_at is None:
            said.append("the force is not predicted: the stop line guards it")
        elif E is None:
            said.append("no press yet to predict the force from: the stop line guards it")
        else:
            said.append("predicted peak force at E = " f"{E:.4g} Pa: " + ", ".join(
                f"{force_at(E, d):.3g} N at {d:g} m" for d in depths))
    print(f"limits of a press: {'; '.join(said)}", file=sys.stderr, flush=True)


class PressChecks:
    """A press's checks before it (:func:`~palpbayes.active.safety.check_press`) with the
    loop's limits and force law."""

    def __init__(self, limits: PressLimits, force_at) -> None:
        self.limits, self.force_at = limits, force_at

    def __call__(self, state: SearchState, x: float, y: float, depth: float | None
                 ) -> tuple[Refusal | None, float | None, float | None]:
        """(refusal or None, the press's depth [m] or None, its predicted force [N] or
        None)."""
        E = state_modulus(state)
        refusal = check_press(state.footprint, state.keep_out, state.thickness, self.limits,
                              x, y, depth, E=E, force_at=self.force_at)
        d = self.limits.depth if depth is None else depth
        F = (None if refusal or E is None or d is None or self.force_at is None
             or self.limits.max_force is None else self.force_at(E, d))
        return refusal, d, F
