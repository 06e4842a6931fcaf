"""Repeated palpation of one specimen with rest-time stiffening (docs/design.md §2).

:func:`rest_modulus` is the law E(t) = c1·exp(c2·t) + c3·exp(c4·t) of the modulus after a rest t
since the previous excitation; :func:`simulate_palpation_series` draws one trace per rest time
from it.  The law is fitted back by :mod:`palpbayes.stiffening`.  (The *strain* stiffening of a
single trace is a different knob: :func:`palpbayes.sim.force.stiffening_factor`.)
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from ..arguments import positive
from ..contact import Tip
from ..errors import InputError
from ..trace import IndentationTrace
from ..units import format_pressure
from .trace import simulate_trace

__all__ = ["rest_modulus", "simulate_palpation_series"]


def rest_modulus(rest_time: ArrayLike, c: Sequence[float]) -> np.ndarray:
    """E(t) = c1·exp(c2·t) + c3·exp(c4·t) [Pa], t the rest time since the last excitation [s].

    The repeated-palpation stiffening law of docs/design.md §2 (c1, c3 in Pa; c2, c4 in 1/s).
    """
    c1, c2, c3, c4 = (float(v) for v in c)
    t = np.asarray(rest_time, dtype=float)
    return c1 * np.exp(c2 * t) + c3 * np.exp(c4 * t)


def simulate_palpation_series(
    E0: float,
    tip: Tip,
    rest_times: Sequence[float | None],
    c: Sequence[float] | None = None,
    *,
    rng: np.random.Generator | int | None = None,
    trace_prefix: str = "series",
    specimen: str = "",
    material: str = "",
    **trace_options,
) -> list[IndentationTrace]:
    """Repeated palpations of one specimen with rest-time dependent stiffening.

    Palpation i has modulus E_i = c1·exp(c2·t_i) + c3·exp(c4·t_i) (:func:`rest_modulus`) with
    t_i = ``rest_times[i]`` the rest since the previous excitation; a rest time of None or inf
    marks a fresh (fully rested) specimen with modulus ``E0``.  The default
    c = (E0, 0, 0.25·E0, -1/30 s⁻¹) is E0 plus 25 % right after an excitation, relaxing with
    a 30 s time constant; with explicit c, E0 should equal the law's limit for consistency.

    Parameters
    ----------
    E0
        [Pa] Modulus of the rested specimen.
    tip
        The indenter.
    rest_times
        [s] Rest before each palpation.
    c
        (c1 [Pa], c2 [1/s], c3 [Pa], c4 [1/s]).
    rng
        Generator or seed; palpation i uses the i-th child stream (``Generator.spawn``).
    trace_prefix
        Trace ids are ``<prefix>_p01``, ``_p02`` ...
    specimen, material
        Labels.
    **trace_options
        Passed to :func:`~palpbayes.sim.trace.simulate_trace` (thickness or depth required).

    Returns
    -------
    list of IndentationTrace
        ``rest_time`` set; ``metadata`` adds ``stiffening_c`` (c1..c4) and ``E_rest_law``.
    """
    E0 = positive(E0, "rested modulus E0 [Pa]")
    if c is None:
        c = (E0, 0.0, 0.25 * E0, -1.0 / 30.0)
    c = tuple(float(v) for v in c)
    if len(c) != 4 or not all(math.isfinite(v) for v in c):
        raise InputError(f"stiffening coefficients c must be four finite numbers, got {c!r}")
    times = list(rest_times)
    if not times:
        raise InputError("give at least one rest time")
    gens = np.random.default_rng(rng).spawn(len(times))
    out = []
    for i, (t, gen) in enumerate(zip(times, gens, strict=True), start=1):
        fresh = t is None or math.isinf(float(t))
        if not fresh and (not math.isfinite(float(t)) or float(t) < 0):
            raise InputError(f"rest time {t!r} s must be non-negative (None for a fresh specimen)")
        E = E0 if fresh else float(rest_modulus(float(t), c))
        if E <= 0:
            raise InputError(f"the stiffening law gives E = {format_pressure(E, 6)} at rest "
                             f"time {t} s; "
                             "check the coefficients c")
        trace = simulate_trace(E, tip, rng=gen, trace_id=f"{trace_prefix}_p{i:02d}",
                               specimen=specimen, material=material, repetition=i,
                               rest_time=None if fresh else float(t), **trace_options)
        trace.metadata.update({"stiffening_c": c, "E_rest_law": E, "E0": E0})
        out.append(trace)
    return out
