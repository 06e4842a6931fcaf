"""Shared set-up of the benchmarks: the paper-like 3,840-point trace."""

from __future__ import annotations

import time

import numpy as np

from palpbayes.contact import Tip
from palpbayes.sim import simulate_trace

TIPS = {
    "flat": Tip("flat", radius=0.010),
    "sphere": Tip("sphere", radius=0.010),
    "paraboloid": Tip("paraboloid", radius=0.0117),
}
E_TRUE = 111e3  # White foam, 30 mm thick -> 3 mm indentation, 3,840 samples at 800 Hz


def paper_trace(kind: str, seed: int = 0):
    tr = simulate_trace(E_TRUE, TIPS[kind], thickness=0.03, rng=seed, base=None)
    assert tr.n_points == 3840, tr.n_points
    return tr


def median_time(fn, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return float(np.median(times))
