"""Shared pieces of the model-adequacy checks (:mod:`palpbayes.checks`).

:class:`CheckResult`, :data:`THRESHOLDS`, the AR(1) noise factors
(:func:`ar1_mean_variance_factor`, :func:`noise_lag1`), input validation, the linear
least-squares and covariance helpers of the fits, and a tabulated shape function.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import FitError, InputError
from ..fitdata import ModelSpec
from ..sensor_noise import acf1
from ..shapekernel import compiled_shape

#: Pass/fail thresholds (statistical and physical) of the checks; see :mod:`palpbayes.checks`.
THRESHOLDS: dict[str, float] = {
    "exponent_n_se": 3.0,        # |m - m_law| > 3 standard errors ...
    "exponent_rel": 0.03,        # ... and > 3 % of m_law
    "residual_alpha": 0.01,      # binned chi² p-value below 1 % ...
    "residual_amp": 0.2,         # ... and the largest |bin mean| above 0.2 sigma
    "ppc_alpha": 0.01,           # posterior-predictive p below 1 %
    "depth_n_se": 3.0,           # |E*_shallow/E*_all - 1| > 3 standard errors ...
    "depth_rel": 0.05,           # ... and > 5 %
    "rate_n_se": 5.0,            # hold relaxation or retract modulus beyond 5 standard errors
}

#: Fewest samples in a bin of the binned-residual check.
MIN_BIN = 8

#: What a check says when a half-space fit stiffens with depth as a layer on a base would.
FINITE_THICKNESS = ("finite thickness -> give the specimen's thickness (--thickness H, the "
                    "manifest's thickness_m) or --thickness unknown: the Bayesian model then "
                    "includes the layer (least squares stays the paper's half-space)")


@dataclass(frozen=True)
class CheckResult:
    """Outcome of one adequacy check.

    Attributes
    ----------
    name
        ``"exponent"``, ``"residual_structure"``, ``"ppc"``, ``"depth_consistency"`` or
        ``"rate"``.
    statistic
        The check's number: fitted m, binned chi², posterior-predictive p-value, or
        E*_shallow/E*_all.
    passed
        False when the check flags the model.
    flag
        ``""`` when passed, else one line naming the likely cause and the fix.
    details
        Numbers for tables (all SI).
    """

    name: str
    statistic: float
    passed: bool
    flag: str
    details: dict = field(default_factory=dict)


# ----------------------------------------------------------------------------- helpers


def validated_arrays(z, force) -> tuple[np.ndarray, np.ndarray]:
    """``z`` and ``force`` as flat float arrays; :class:`InputError` unless they have the same
    length, at least 20 samples and only finite values."""
    z = np.asarray(z, dtype=float).ravel()
    f = np.asarray(force, dtype=float).ravel()
    if z.shape != f.shape:
        raise InputError(f"z ({z.size}) and force ({f.size}) differ in length")
    if z.size < 20:
        raise InputError(f"a model check needs at least 20 samples, got {z.size}")
    if not (np.all(np.isfinite(z)) and np.all(np.isfinite(f))):
        raise InputError("z and force must be finite")
    return z, f


def clip_phi(phi: float) -> float:
    """An AR(1) coefficient clipped to [-0.99, 0.999], where the AR(1) factors stay finite."""
    return float(np.clip(phi, -0.99, 0.999))


def ar1_mean_variance_factor(n, phi: float) -> np.ndarray:
    """Variance of the mean of n consecutive AR(1) samples, in units of sigma²/n [-].

    g(n, phi) = (1+phi)/(1-phi) - 2·phi·(1-phi^n)/(n·(1-phi)²): 1 for white noise, tending to
    the long-run factor (1+phi)/(1-phi) for n >> 1/(1-phi) (Box & Jenkins, AR(1) sample mean).

    Parameters
    ----------
    n
        Number of samples per mean (array or scalar, >= 1).
    phi
        Lag-1 autocorrelation, |phi| < 1.
    """
    n = np.asarray(n, dtype=float)
    phi = clip_phi(phi)
    if phi == 0:
        return np.ones_like(n)
    return (1 + phi) / (1 - phi) - 2 * phi * (1 - phi**n) / (n * (1 - phi) ** 2)


def phi_from_differences(r: np.ndarray) -> float:
    """AR(1) coefficient from the lag-1 correlation of first differences: phi = 1 + 2·rho_Δ."""
    dr = np.diff(r)
    if dr.size < 3:
        return 0.0
    return clip_phi(1.0 + 2.0 * acf1(dr))


def noise_lag1(z, force, z_surf: float, *, margin: float = 0.05) -> float | None:
    """Lag-1 autocorrelation [-] of the force noise from the pre-contact baseline.

    Uses the samples above z_surf + margin·(z_surf - min z) (clear of a gradual onset), in time
    order, after removing a straight line in time (drift); None with fewer than 32 of them.

    Parameters
    ----------
    z, force
        [m], [N] samples in time order.
    z_surf
        [m] Fitted surface height.
    margin
        Fraction of the contact depth kept clear above the surface.
    """
    z, f = validated_arrays(z, force)
    dmax = max(z_surf - float(z.min()), 0.0)
    sel = z > z_surf + margin * dmax
    if sel.sum() < 32:
        return None
    y = f[sel]
    t = np.arange(y.size, dtype=float)
    y = y - np.polyval(np.polyfit(t, y, 1), t)
    return clip_phi(acf1(y))


def design_matrix(z, dp_term, baseline: str, z_ref: float) -> np.ndarray:
    """Columns of a linear contact fit: the contact term ``dp_term``, a constant and, for a
    ``'linear'`` baseline, z - z_ref."""
    cols = [dp_term, np.ones_like(z)]
    if baseline == "linear":
        cols.append(z - z_ref)
    elif baseline != "constant":
        raise InputError(f"baseline must be 'constant' or 'linear', got {baseline!r}")
    return np.column_stack(cols)


# Tall-skinny products go through einsum, not BLAS: a threaded BLAS on a loaded machine makes
# a (16000 x 5)ᵀ(16000 x 5) product 100x slower than the arithmetic needs.
def _gram(J: np.ndarray) -> np.ndarray:
    return np.einsum("ij,ik->jk", J, J)


def _tdot(J: np.ndarray, r: np.ndarray) -> np.ndarray:
    return np.einsum("ij,i->j", J, r)


def lstsq(X: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Linear least squares (scaled normal equations; few columns); (coefficients, residuals)."""
    scale = np.sqrt(np.einsum("ij,ij->j", X, X))
    scale[scale == 0] = 1.0
    Xs = X / scale
    beta = np.linalg.lstsq(_gram(Xs), _tdot(Xs, y), rcond=None)[0] / scale
    return beta, y - np.einsum("ij,j->i", X, beta)


def contact_inputs(z, force, z_surf: float, z_ref: float | None, no_contact: str
                    ) -> tuple[np.ndarray, np.ndarray, float, float]:
    """Samples of a contact fit: validated ``z``, ``force``, the baseline's reference height
    (default the highest z) and the contact depth d_max = z_surf - min z [m].

    Raises :class:`FitError` with the message ``no_contact`` when d_max is not positive.
    """
    z, f = validated_arrays(z, force)
    z_ref = float(z.max()) if z_ref is None else float(z_ref)
    dmax = z_surf - float(z.min())
    if not dmax > 0:
        raise FitError(no_contact)
    return z, f, z_ref, dmax


def residual_cov(J: np.ndarray, r: np.ndarray, phi: float | None
                  ) -> tuple[np.ndarray, float, float]:
    """Covariance of least-squares parameters from their Jacobian ``J`` and residuals ``r``.

    s²·(JᵀJ)⁻¹ with s² = RSS/(n - p), times the AR(1) long-run factor of the noise lag-1
    autocorrelation ``phi`` (None: white noise).  Returns (covariance, RSS, s²).
    """
    n, p = r.size, J.shape[1]
    rss = float(np.dot(r, r))
    s2 = rss / max(n - p, 1)
    return _cov(J, s2, _long_run(phi)), rss, s2


def _cov(J: np.ndarray, s2: float, infl: float) -> np.ndarray:
    scale = np.sqrt(np.einsum("ij,ij->j", J, J))
    scale[scale == 0] = 1.0
    Js = J / scale
    cov = np.linalg.pinv(_gram(Js)) / np.outer(scale, scale)
    return cov * s2 * infl


class ShapeTable:
    """s(d) and ds/dd of a model for the checks' searches and posterior draws.

    The exact shape function (e.g. Sneddon's sphere, solved by Halley iterations) is too slow
    to call for every posterior draw and every step of a search.  s(d) is the compiled core's
    law (:func:`palpbayes.shapekernel.compiled_shape`: exact for a power law, else its cubic
    table, error below 5e-8·s(d_top)); ds/dd is tabulated on d_i = d_top·(i/N)² (exact at its
    4,097 nodes, denser near d = 0 where s is least smooth) and linearly interpolated.  Depths
    beyond the tables fall back to the exact law.
    """

    def __init__(self, model: ModelSpec, d_top: float, n: int = 4096):
        self.model = model
        self.d_top = float(d_top)
        self.law = compiled_shape(model, self.d_top)
        self.grid = self.d_top * (np.arange(n + 1) / n) ** 2
        self.ds = model.shape_derivative(self.grid)

    def shape(self, d) -> np.ndarray:
        d = np.asarray(d, dtype=float)
        far = d > self.law.d_top
        out = self.law(np.where(far, 0.0, d))
        if np.any(far):
            out[far] = self.model.shape(d[far])
        return out

    def shape_derivative(self, d) -> np.ndarray:
        d = np.asarray(d, dtype=float)
        out = np.interp(d, self.grid, self.ds, left=0.0)
        far = d > self.d_top
        if np.any(far):
            out[far] = self.model.shape_derivative(d[far])
        return out


def _long_run(phi: float | None) -> float:
    phi = 0.0 if phi is None else clip_phi(phi)
    return (1 + phi) / (1 - phi)
