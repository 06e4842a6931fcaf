"""The stiffening laws and their posterior: E(t) = c1·e^(c2·t) + c3·e^(c4·t) and the simpler two.

Three laws of the modulus E [Pa] versus rest time t [s] (``model`` is their name):
``"double"`` (:func:`double_exponential`), ``"single"`` E = c0 + c1·e^(c2·t) and ``"constant"``
E = c0 (:data:`LAW_TEXT`).  Here are their basis functions, likelihood and log posterior in the
scaled, sampled coordinates θ (amplitudes and sigma_x in units of median(E), time scales as
log T [log s]), the amplitudes' Gaussian conditional, and the conversion of draws to SI.

Model and priors
----------------
    E_i ~ Normal(c1·e^(c2·t_i) + c3·e^(c4·t_i),  s_i² + sigma_x²)

* Rates are decays, c = −1/T with the time scale T log-uniform on [T_lo, T_hi] =
  [min positive t / 5, 100·max t]: a faster decay is over before the first rest time, a slower
  one varies by less than 1 % over the data (a constant; the simulator's default law has
  c2 = 0).  Recovery after an excitation makes E fall with rest, so growth (c > 0) is excluded.
* Label switching is broken by the ordering c2 < c4 (T2 < T4): (c1, c2) is the fast term.
* Amplitudes c1, c3 are uniform on ±10·median(E) (flat over every plausible value).
* sigma_x ≥ 0, an extra scatter beyond the per-trace uncertainties s_i (location-to-location
  variation, unmodelled drift), is half-normal with scale 0.1·median(E).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["double_exponential", "LAW_TEXT", "AMP_BOUND", "N_PARAMS", "PARAM_NAMES", "AMP_IDX",
           "T_IDX", "PARAM_UNITS", "law_basis", "split_theta", "log_like", "log_post", "linear_fit",
           "log_post_collapsed", "physical_draws"]

#: Bound of the amplitudes' flat prior (and of sigma_x) in units of median(E).
AMP_BOUND = 10.0
_SX = 0.1    # half-normal scale of sigma_x in units of median(E)
_LOG2PI = np.log(2 * np.pi)


def double_exponential(t: ArrayLike, c: Sequence[float]) -> np.ndarray:
    """E(t) = c1·e^(c2·t) + c3·e^(c4·t) [Pa] for rest time t [s], c = (c1, c2, c3, c4)."""
    c1, c2, c3, c4 = c
    t = np.asarray(t, dtype=float)
    return c1 * np.exp(c2 * t) + c3 * np.exp(c4 * t)


#: Equation of each law, by the names used in :attr:`StiffeningResult.preferred`.
LAW_TEXT = {
    "double": "E(t) = c1·exp(c2·t) + c3·exp(c4·t)",
    "single": "E(t) = c0 + c1·exp(c2·t)",
    "constant": "E(t) = c0 (no stiffening detected)",
}

# ----------------------------------------------------------------------------- models
# θ in scaled units: amplitudes and sigma_x / E_s, time scales as log T [log s].


def law_basis(model: str, logT: np.ndarray, t: np.ndarray) -> np.ndarray:
    """(W, n, k) basis functions; amplitudes multiply them linearly."""
    ex = np.exp(-t[None, None, :] / np.exp(logT)[:, :, None])  # (W, nT, n)
    if model in ("single", "constant"):
        ones = np.ones((ex.shape[0], 1, t.size))
        ex = np.concatenate([ones, ex], axis=1)
    return np.swapaxes(ex, 1, 2)


def split_theta(model: str, theta: np.ndarray):
    """Rows of θ split into (amplitudes, log time scales, sigma_x) of law ``model``."""
    if model == "double":
        return theta[:, [0, 2]], theta[:, [1, 3]], theta[:, 4]
    if model == "constant":
        return theta[:, [0]], theta[:, 1:1], theta[:, 1]
    return theta[:, [0, 1]], theta[:, [2]], theta[:, 3]


#: Number of parameters (amplitudes, time scales, sigma_x) of each law.
N_PARAMS = {"double": 5, "single": 4, "constant": 2}
#: Sampled coordinates of each law, in θ's order (scaled amplitudes, log T, sigma_x).
PARAM_NAMES = {"double": ["c1", "logT2", "c3", "logT4", "sigma_x"],
               "single": ["c0", "c1", "logT", "sigma_x"], "constant": ["c0", "sigma_x"]}
#: Positions of the amplitudes and of the log time scales in θ.
AMP_IDX = {"double": [0, 2], "single": [0, 1], "constant": [0]}
T_IDX = {"double": [1, 3], "single": [2], "constant": []}


def log_like(model, theta, t, y, s):
    """Gaussian log likelihood of estimates ``y`` with sds ``s`` at rest times ``t`` for each
    row of θ (scaled units, sigma_x linear)."""
    amp, logT, sx = split_theta(model, theta)
    f = np.einsum("wnk,wk->wn", law_basis(model, logT, t), amp)
    v = s[None, :] ** 2 + sx[:, None] ** 2
    return -0.5 * np.sum(_LOG2PI + np.log(v) + (y[None, :] - f) ** 2 / v, axis=1)


def log_post(model, theta, t, y, s, bounds):
    """Log posterior in the *sampled* coordinates: θ with its last entry log sigma_x.

    sigma_x is sampled on the log scale (half-normal prior plus the Jacobian log sigma_x): the
    posterior then has no wall at sigma_x = 0, where precise estimates (least-squares sd's of
    0.03 %) pile it up and a linear sigma_x mixes slowest of all parameters.
    """
    theta = np.atleast_2d(theta)
    amp, logT, log_sx = split_theta(model, theta)
    lo, hi = bounds
    ok = np.all(np.abs(amp) < AMP_BOUND, axis=1) & np.all((logT > lo) & (logT < hi), axis=1)
    ok &= np.isfinite(log_sx) & (log_sx < np.log(AMP_BOUND))
    if model == "double":
        ok &= logT[:, 0] < logT[:, 1]
    lp = np.full(theta.shape[0], -np.inf)
    if ok.any():
        th = theta[ok].copy()
        th[:, -1] = np.exp(th[:, -1])
        sx = th[:, -1]
        lp[ok] = log_like(model, th, t, y, s) - 0.5 * (sx / _SX) ** 2 + np.log(sx)
    return lp


def linear_fit(model, x, t, y, s):
    """Amplitudes' conditional posterior at sampled (log T, log sigma_x) rows ``x``.

    For fixed time scales and sigma_x the amplitudes enter linearly, so with their flat prior
    they are Gaussian: mean â (weighted least squares) and precision G = Bᵀ·V⁻¹·B.  Returns
    (â, G, log L(â)), vectorised over rows.
    """
    sx = np.exp(x[:, -1])
    B = law_basis(model, x[:, :-1], t)                                # (W, n, k)
    v = s[None, :] ** 2 + sx[:, None] ** 2                            # (W, n)
    G = np.einsum("wnk,wn,wnj->wkj", B, 1.0 / v, B)
    h = np.einsum("wnk,wn,n->wk", B, 1.0 / v, y)
    a = np.linalg.solve(G, h[..., None])[..., 0]
    r = y[None, :] - np.einsum("wnk,wk->wn", B, a)
    ll = -0.5 * np.sum(_LOG2PI + np.log(v) + r**2 / v, axis=1)
    return a, G, ll


def log_post_collapsed(model, x, t, y, s, bounds):
    """Log posterior of (log T, log sigma_x) with the amplitudes integrated out (single and
    constant laws): log L(â) + (k/2)·log 2π − ½·log det G, plus the sigma_x prior and its
    Jacobian.  The amplitudes' flat prior is treated as unbounded here; draws outside ±10·median
    are redrawn (:func:`_draw_amplitudes`), which matters only far outside the data's reach.
    """
    x = np.atleast_2d(x)
    lo, hi = bounds
    logT, log_sx = x[:, :-1], x[:, -1]
    ok = np.all((logT > lo) & (logT < hi), axis=1) & np.isfinite(log_sx)
    ok &= log_sx < np.log(AMP_BOUND)
    lp = np.full(x.shape[0], -np.inf)
    if ok.any():
        xo = x[ok]
        _, G, ll = linear_fit(model, xo, t, y, s)
        k = G.shape[-1]
        sign, logdet = np.linalg.slogdet(G)
        sx = np.exp(xo[:, -1])
        val = ll + 0.5 * k * _LOG2PI - 0.5 * logdet - 0.5 * (sx / _SX) ** 2 + np.log(sx)
        lp[ok] = np.where(sign > 0, val, -np.inf)
    return lp


#: Sampled time-scale coordinate -> the rate it is reported as (c = -1/T [1/s]).
_RATES = {"logT2": "c2", "logT4": "c4", "logT": "c2"}
#: Unit of each reported parameter.
PARAM_UNITS = {"c0": "Pa", "c1": "Pa", "c2": "1/s", "c3": "Pa", "c4": "1/s", "sigma_x": "Pa"}


def physical_draws(raw: dict[str, np.ndarray], scale: float) -> dict[str, np.ndarray]:
    """Draws of one law in SI: amplitudes and sigma_x times ``scale`` [Pa], log time scales as
    rates c = -1/T [1/s]; keys in the law's order (c1, c2, c3, c4, sigma_x for the double law)."""
    return {_RATES.get(k, k): (-1.0 / np.exp(v) if k in _RATES else v * scale)
            for k, v in raw.items()}
