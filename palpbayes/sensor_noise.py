"""Sensor-noise conventions shared by the simulator and the priors, and the AR(1) noise the
simulators draw (:func:`ar1_noise`).

**Peak-to-peak to sigma.**  A force sensor's noise is specified as a peak-to-peak (p-p) value;
palpbayes reads it as ±3 sigma, i.e. sigma = p-p / 6, the range holding 99.7 % of Gaussian
samples.  With the paper's 48 mN this gives sigma = 8 mN, the value used in docs/design.md §3.  (The
range of n iid Gaussian samples grows with n — about 7.2 sigma for 3,840 samples — so the
convention is a specification, not the observed range of a long record.)
"""

from __future__ import annotations

import math

import numpy as np

from .arguments import finite
from .errors import InputError

__all__ = ["PP_TO_SIGMA", "PAPER_NOISE_PP", "MAD_TO_SIGMA", "NOISE_SCALE_FACTOR", "sigma_from_pp",
           "pp_from_sigma", "noise_scale_mismatch", "mad_sd", "acf1", "ar1_noise"]

#: 1/Phi^-1(3/4): the median absolute deviation of normal values times this is their sd.
MAD_TO_SIGMA = 1.4826

#: Peak-to-peak = PP_TO_SIGMA · sigma (±3 sigma).
PP_TO_SIGMA = 6.0
#: [N] The paper's force-sensor noise, peak-to-peak (sigma = 8 mN); the default noise spec.
PAPER_NOISE_PP = 48e-3


def sigma_from_pp(pp: float) -> float:
    """Gaussian standard deviation [N] for a peak-to-peak noise spec ``pp`` [N]: pp/6 (±3 sigma).

    >>> round(sigma_from_pp(PAPER_NOISE_PP), 12)  # the paper's sensor: 48 mN p-p -> 8 mN
    0.008

    Raises
    ------
    InputError
        ``pp`` is not a finite, non-negative number.
    """
    v = finite(pp, "peak-to-peak noise [N]")
    if v < 0:
        raise InputError(f"peak-to-peak noise {pp!r} N must be non-negative")
    return v / PP_TO_SIGMA


def pp_from_sigma(sigma: float) -> float:
    """Peak-to-peak spec [N] of a Gaussian noise with standard deviation ``sigma`` [N]."""
    return float(sigma) * PP_TO_SIGMA


#: How far the measured noise may lie from the declared one before the force's scale is
#: doubted: a sensor's data sheet states a worst case (quieter data are normal, a factor of a
#: few) and a noisier room adds some; a wrong force unit is a factor of 1,000 (N read as mN).
NOISE_SCALE_FACTOR = 30.0


def noise_scale_mismatch(measured_pp: float, declared_pp: float | None) -> float | None:
    """The ratio measured/declared of two peak-to-peak noises [N] when it lies outside
    [1/:data:`NOISE_SCALE_FACTOR`, :data:`NOISE_SCALE_FACTOR`] (a force in another unit than
    the one given, or a wrong noise spec), else None (also when either is unknown).

    >>> noise_scale_mismatch(48e-6, 48e-3)  # a force in N read as mN: 1,000 times too small
    0.001
    >>> noise_scale_mismatch(10e-3, 48e-3) is None  # a sensor quieter than its data sheet
    True
    """
    if declared_pp is None or not (math.isfinite(measured_pp) and measured_pp > 0):
        return None
    ratio = float(measured_pp) / float(declared_pp)
    return ratio if not 1.0 / NOISE_SCALE_FACTOR <= ratio <= NOISE_SCALE_FACTOR else None


def mad_sd(x) -> float:
    """Robust sd [same unit as ``x``]: :data:`MAD_TO_SIGMA` · median|x − median(x)| (the sd of
    normal values, insensitive to a minority of outliers: a lump, a step, an onset)."""
    x = np.asarray(x, dtype=float)
    return float(MAD_TO_SIGMA * np.median(np.abs(x - np.median(x))))


def acf1(x, undefined: float = 0.0) -> float:
    """Lag-1 sample autocorrelation of ``x`` about its mean, Σ x_t·x_(t−1) / Σ x_t² (x centred)
    [-]: the one estimate of the package (residuals, baselines, the AR(1) start, the
    ground truth's residuals).  ``undefined`` for fewer than 2 samples or a constant series:
    0 where a number is needed to go on (an AR(1) coefficient), NaN where a table should say
    "not defined" (``groundtruth.csv``'s ``resid_acf1``).

    >>> round(acf1([1.0, 2.0, 3.0, 4.0]), 3)
    0.25
    >>> acf1([5.0, 5.0, 5.0]), acf1([2.0], undefined=float("nan"))
    (0.0, nan)
    """
    x = np.asarray(x, dtype=float)
    if x.size < 2:
        return float(undefined)
    x = x - x.mean()
    den = float(x @ x)
    return float(x[1:] @ x[:-1]) / den if den > 0 else float(undefined)


def ar1_noise(n: int, sigma: float, phi: float, w: np.ndarray) -> np.ndarray:
    """Stationary Gaussian AR(1) noise from standard normal draws ``w`` (length n).

    e(0) = sigma·w(0), e(t) = phi·e(t-1) + sqrt(1 - phi²)·sigma·w(t), so every e(t) has sd sigma
    whatever phi, and corr(e(t), e(t-k)) = phi^k.
    """
    from scipy.signal import lfilter  # here: importing the conventions stays light

    w = np.asarray(w, dtype=float)[:n]
    if phi == 0:
        return sigma * w
    e = np.empty(n)
    e[0] = sigma * w[0]
    e[1:], _ = lfilter([math.sqrt(1.0 - phi * phi) * sigma], [1.0, -phi], w[1:],
                       zi=[phi * e[0]])
    return e
