"""The straight line of a ground-truth fit and the standard error of its slope.

:func:`linfit` is ordinary least squares (slope, intercept, OLS standard error, R²);
:func:`hac_slope_se` the heteroskedasticity- and autocorrelation-consistent (HAC) standard error
that :mod:`palpbayes.compression.fit` reports as ``E_sd_pa``.

Uncertainty
-----------
``E_sd_pa`` is a heteroskedasticity- and autocorrelation-consistent (HAC) standard error of
the slope: the Newey & West (1987) estimator with the Bartlett kernel, prewhitened by an AR(1)
filter (Andrews & Monahan 1992) and with the bandwidth of Andrews' (1991) AR(1) plug-in rule.
With ``v_t = (eps_t - mean eps)·u_t`` (``u`` the residuals, in time order):

1. prewhiten: ``rho = sum v_t v_(t-1) / sum v_(t-1)²``, clipped to [0, 0.97], and
   ``e_t = v_t - rho·v_(t-1)``.  0.97 is the bound Andrews & Monahan put on the prewhitening
   filter against near-unit roots; a negative estimate is set to 0 (no prewhitening) because
   in a short window it is mostly noise and would shrink the estimate below the white-noise
   value (with 37 points and white noise, (E - E_true)/E_sd_pa then has sd 1.24 instead of
   1.02);
2. bandwidth: ``L = floor(1.1447·(alpha·m)^(1/3))`` with ``alpha = 4 r² / ((1 - r)²(1 + r)²)``,
   ``r`` the lag-1 autocorrelation of ``e`` (clipped likewise) and ``m = n - 1``; at most
   ``m - 1``;
3. ``S_e = sum_(|j| <= L) (1 - |j|/(L + 1)) sum_t e_t e_(t-j)`` (times ``n/m``), recoloured:
   ``S = S_e / (1 - rho)²``;
4. ``E_sd_pa = sqrt(S · n/(n - 2)) / sum((eps - mean eps)²)``.

Why: the residuals of a 0-5 % line through a curve sampled at 10 Hz are mostly curvature
(lag-1 autocorrelation ``resid_acf1`` 0.80-0.93 on the EF30 and EF50 phantoms, up to 0.89 on
EF10), so the ordinary-least-squares standard error ``sqrt(s² / sum((eps - mean eps)²))``,
``s² = RSS/(n - 2)``, which assumes independent residuals, is too small.  It is kept as
``E_ols_sd_pa``; on the shipped phantoms ``E_sd_pa / E_ols_sd_pa`` has median 4.3 (1.1-10.0;
EF50 4.3-6.5, EF30 1.9-10.0, EF10 1.1-7.2) and ``E_sd_pa`` is 0.1-4.0 % of E.  Calibration
(tests/unit/test_groundtruth.py): on straight lines with AR(1) residuals, the 90 % interval
``E ± 1.645·E_sd_pa`` covers the true slope in 87 % of 200-point lines at phi = 0.6 (the OLS
interval: 59 %); with 90 points (the phantoms' 0-5 % windows) it covers 85 % at phi = 0.5,
79 % at phi = 0.8 and 72 % at phi = 0.9 (2000 replicates each): with few effectively
independent points no HAC estimate is reliable, so treat ``E_sd_pa`` as an order of magnitude
when ``resid_acf1`` is above ~0.9.

What it does not contain: the choice of window (see ``E_window_spread_pa``), the
non-linearity, and the geometry (area, height).  The specimen-to-specimen scatter of a
material (``E_sd_pa`` of the summary, ddof = 1) is the number to compare with palpation
estimates.

References: Newey, W.K. & West, K.D. (1987), Econometrica 55(3), 703-708; Andrews, D.W.K.
(1991), Econometrica 59(3), 817-858; Andrews, D.W.K. & Monahan, J.C. (1992), Econometrica
60(4), 953-966.
"""

from __future__ import annotations

import math

import numpy as np

from ..sensor_noise import acf1

__all__ = ["hac_slope_se", "resid_acf1", "linfit"]

#: Bound on the AR(1) prewhitening coefficient and the bandwidth's autocorrelation.
_RHO_MAX = 0.97


def _clip_rho(r: float) -> float:
    return float(min(max(r, 0.0), _RHO_MAX)) if math.isfinite(r) else 0.0


def _lag1(a: np.ndarray) -> float:
    """Lag-1 autoregression coefficient sum a_t a_(t-1) / sum a_(t-1)² (0 if undefined)."""
    den = float(a[:-1] @ a[:-1]) if a.size > 1 else 0.0
    return float(a[1:] @ a[:-1]) / den if den > 0 else 0.0


def resid_acf1(u: np.ndarray) -> float:
    """Lag-1 autocorrelation of residuals (:func:`palpbayes.sensor_noise.acf1`), NaN where it is not
    defined (a table column)."""
    return acf1(u, undefined=math.nan)


def hac_slope_se(x: np.ndarray, resid: np.ndarray) -> tuple[float, int]:
    """Prewhitened Newey-West standard error of an OLS slope and its bandwidth (lags).

    Bartlett kernel, AR(1) prewhitening of the scores ``(x - mean x)·resid`` (coefficient
    clipped to [0, 0.97]; Andrews & Monahan 1992) and Andrews' (1991) AR(1) plug-in bandwidth
    ``floor(1.1447·(alpha·m)^(1/3))``, ``alpha = 4 r²/((1 - r)²(1 + r)²)``; small-sample factor
    n/(n - 2).  Steps in the module docstring.

    Parameters
    ----------
    x
        Regressor, in the order the samples were taken.
    resid
        OLS residuals of the fit, same order.

    Returns
    -------
    se : float
        Standard error of the slope (0 for an exact line).
    lags : int
        The bandwidth L.
    """
    x = np.asarray(x, dtype=float)
    n = x.size
    if n < 4:
        return math.nan, 0
    dx = x - x.mean()
    sxx = float(dx @ dx)
    v = dx * np.asarray(resid, dtype=float)
    rho = _clip_rho(_lag1(v))
    e = v[1:] - rho * v[:-1]
    m = e.size
    r = _clip_rho(_lag1(e))
    alpha = 4.0 * r * r / ((1.0 - r) ** 2 * (1.0 + r) ** 2)
    lags = int(min(math.floor(1.1447 * (alpha * m) ** (1.0 / 3.0)), m - 1))
    s_e = float(e @ e)
    for j in range(1, lags + 1):
        s_e += 2.0 * (1.0 - j / (lags + 1.0)) * float(e[j:] @ e[:-j])
    s = max(s_e, 0.0) * (n / m) / (1.0 - rho) ** 2
    return math.sqrt(s * n / (n - 2)) / sxx, lags


def linfit(x: np.ndarray, y: np.ndarray) -> tuple[float, float, float, float, np.ndarray]:
    """Slope, intercept, OLS slope standard error, R² and residuals of a least-squares line."""
    n = x.size
    xm, ym = x.mean(), y.mean()
    dx, dy = x - xm, y - ym
    sxx = float(dx @ dx)
    slope = float(dx @ dy) / sxx
    intercept = ym - slope * xm
    resid = y - (intercept + slope * x)
    rss = float(resid @ resid)
    tss = float(dy @ dy)
    se = math.sqrt(rss / (n - 2) / sxx) if n > 2 else math.nan
    r2 = 1.0 - rss / tss if tss > 0 else math.nan
    return slope, float(intercept), se, r2, resid
