"""What the viscoelastic (hereditary-integral) force costs, measured in one run on this machine.

For N = 10^3, 4·10^3, 10^4, 10^5 samples of a measured-like motion (800 Hz with ±30 % jitter in
the time steps; approach from 0.1 mm above the surface to 3 mm, a hold, a retract back out of
contact) prints, per relaxation kernel, the median time of one :func:`hereditary_force` call,
the time per sample and its ratio to the elastic force C·E·d^m on the same samples, timed in the
same run.  The power law's cost grows with its number of exponentials K (printed), ~ log of
duration / shortest step.

Targets (a 4,000-sample approach-hold-retract cycle, one evaluation on this machine): <= 1 ms
for the standard linear solid, <= 5 ms for the power law (:data:`TARGETS_MS`); at N = 4,000 the
last column prints measured / target (<= 1: met).

Run: ``python benchmarks/bench_viscoelastic.py`` (a few seconds).
"""

from __future__ import annotations

import numpy as np
from common import median_time

from palpbayes.contact import (
    PowerLawKernel,
    PronyKernel,
    hereditary_force,
    standard_linear_solid,
)
from palpbayes.contact.soe import power_law_soe

C, M = 4 * np.sqrt(0.01) / (3 * (1 - 0.3**2)), 1.5  # paraboloid R = 10 mm, nu = 0.3
KERNELS = {
    "power law a=0.3": PowerLawKernel(1e5, 0.3),
    "SLS (1 term)": standard_linear_solid(5e4, 5e4, 0.5),
    "Prony 3 terms": PronyKernel(2e4, (3e4, 3e4, 3e4), (0.05, 0.5, 5.0)),
}
#: Targets [ms] of one call at N = 4,000 samples, per kernel (none for the 3-term Prony series).
TARGETS_MS = {"power law a=0.3": 5.0, "SLS (1 term)": 1.0}
TARGET_N = 4_000


def motion(n: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Times [s] and depths [m]: 45 % approach, 15 % hold, 40 % retract to 1 mm above."""
    rng = np.random.default_rng(seed)
    t = np.concatenate([[0.0], np.cumsum(rng.uniform(0.7, 1.3, n - 1) / 800.0)])
    x = t / t[-1]
    d = np.interp(x, [0.0, 0.45, 0.6, 1.0], [-0.1e-3, 3e-3, 3e-3, -1e-3])
    return t, d


def main() -> None:
    print(f"{'N':>7} {'kernel':<16} {'K':>3} {'per call':>11} {'per sample':>11} "
          f"{'elastic/call':>13} {'ratio':>7} {'target':>9} {'meas/target':>11}")
    for n in (1_000, TARGET_N, 10_000, 100_000):
        t, d = motion(n)
        repeat = max(3, 100_000 // n)
        t_el = median_time(lambda d=d: C * 1e5 * np.clip(d, 0.0, None) ** M, 20 * repeat)
        for name, kernel in KERNELS.items():
            k = (power_law_soe(kernel.alpha, np.diff(t).min(), t[-1])[1].size
                 if isinstance(kernel, PowerLawKernel) else len(kernel.E))
            t_ve = median_time(lambda t=t, d=d, kernel=kernel: hereditary_force(t, d, C, M, kernel),
                               repeat)
            target = TARGETS_MS.get(name) if n == TARGET_N else None
            versus = f"{target:>6.1f} ms {t_ve * 1e3 / target:>11.2f}" if target else ""
            print(f"{n:>7} {name:<16} {k:>3} {t_ve * 1e3:>8.2f} ms {t_ve / n * 1e6:>8.2f} us "
                  f"{t_el * 1e6:>10.1f} us {t_ve / t_el:>7.0f} {versus}")


if __name__ == "__main__":
    main()
