"""Priors of the per-trace model (DESIGN §3).

Parameters, in the order of the sampler's vector θ:

================  ==============================================================
``log_Estar``     ln(E*/Pa).  Uniform on [ln 1 Pa, ln 1e12 Pa] by default: the scale-free
                  (Jeffreys) prior 1/E* truncated to twelve decades, so kPa foams and kPa cells
                  measured in µm/nN units (converted to SI) are both inside.
``z_surf``        [m] Uniform over the admissible range [z_c, z_top] of the trace: the paper's
                  constraint |F(z_surf)| <= F_unc (see :mod:`palpbayes.fitdata`).
``log_sigma``     ln(sigma/N).  Normal(ln(pp/6), 1): centred on the sensor's peak-to-peak
                  spec read as ±3 sigma (:mod:`palpbayes.noise`); a factor e either way is 1 sd.
``F0``            [N] Force offset, Normal(0, F_unc): the sensor is tared to within its spec.
``phi``           (AR(1) only) lag-one correlation, Uniform(−0.99, 0.99).
``log_nu_t``      (Student-t only) ln of the degrees of freedom, Uniform(ln 2, ln 200).
================  ==============================================================
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..noise import sigma_from_pp

__all__ = ["NOISE_MODELS", "PriorSpec", "param_names"]

NOISE_MODELS = ("gaussian", "ar1", "student")


def param_names(noise: str) -> list[str]:
    """Names of the sampled parameters for a noise model."""
    names = ["log_Estar", "z_surf", "log_sigma", "F0"]
    if noise == "ar1":
        names.append("phi")
    elif noise == "student":
        names.append("log_nu_t")
    elif noise != "gaussian":
        raise InputError(f"unknown noise model {noise!r}; use one of {', '.join(NOISE_MODELS)}")
    return names


@dataclass(frozen=True)
class PriorSpec:
    """Prior settings.

    Parameters
    ----------
    Estar_bounds
        [Pa] Bounds of the log-uniform prior of E*.
    noise_pp
        [N] Sensor peak-to-peak noise spec (paper: 48 mN).
    log_sigma_sd
        Sd of the log-normal prior of sigma.
    F0_sd
        [N] Sd of the force-offset prior (default: equal to ``noise_pp``, the paper's F_unc).
    phi_bounds
        Bounds of the AR(1) coefficient.
    nu_t_bounds
        Bounds of the Student-t degrees of freedom (log-uniform).
    """

    Estar_bounds: tuple[float, float] = (1.0, 1e12)
    noise_pp: float = 48e-3
    log_sigma_sd: float = 1.0
    F0_sd: float | None = None
    phi_bounds: tuple[float, float] = (-0.99, 0.99)
    nu_t_bounds: tuple[float, float] = (2.0, 200.0)

    def __post_init__(self) -> None:
        lo, hi = self.Estar_bounds
        if not (0 < lo < hi and math.isfinite(hi)):
            raise InputError(f"E* prior bounds {self.Estar_bounds} must satisfy 0 < lo < hi")
        if not (self.noise_pp > 0 and math.isfinite(self.noise_pp)):
            raise InputError(f"noise peak-to-peak {self.noise_pp!r} N must be positive")

    @property
    def sigma_center(self) -> float:
        """[N] Median of the sigma prior, pp/6."""
        return sigma_from_pp(self.noise_pp)

    @property
    def f0_sd(self) -> float:
        return self.noise_pp if self.F0_sd is None else self.F0_sd

    def log_prior(self, theta: np.ndarray, z_bounds: tuple[float, float], noise: str
                  ) -> np.ndarray:
        """Log prior density (up to a constant) for θ of shape (W, ndim); -inf outside."""
        theta = np.atleast_2d(theta)
        lo, hi = np.log(self.Estar_bounds[0]), np.log(self.Estar_bounds[1])
        ok = (theta[:, 0] > lo) & (theta[:, 0] < hi)
        ok &= (theta[:, 1] >= z_bounds[0]) & (theta[:, 1] <= z_bounds[1])
        ls = theta[:, 2]
        lp = -0.5 * ((ls - np.log(self.sigma_center)) / self.log_sigma_sd) ** 2
        lp += -0.5 * (theta[:, 3] / self.f0_sd) ** 2
        if noise == "ar1":
            ok &= (theta[:, 4] > self.phi_bounds[0]) & (theta[:, 4] < self.phi_bounds[1])
        elif noise == "student":
            a, b = np.log(self.nu_t_bounds[0]), np.log(self.nu_t_bounds[1])
            ok &= (theta[:, 4] > a) & (theta[:, 4] < b)
        return np.where(ok, lp, -np.inf)

    def sample(self, rng: np.random.Generator, n: int, z_bounds: tuple[float, float],
               noise: str = "gaussian") -> np.ndarray:
        """Draw n parameter vectors from the prior, shape (n, ndim)."""
        cols = [
            rng.uniform(np.log(self.Estar_bounds[0]), np.log(self.Estar_bounds[1]), n),
            rng.uniform(z_bounds[0], z_bounds[1], n),
            rng.normal(np.log(self.sigma_center), self.log_sigma_sd, n),
            rng.normal(0.0, self.f0_sd, n),
        ]
        if noise == "ar1":
            cols.append(rng.uniform(*self.phi_bounds, n))
        elif noise == "student":
            cols.append(rng.uniform(*np.log(self.nu_t_bounds), n))
        return np.column_stack(cols)
