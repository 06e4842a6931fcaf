"""Priors of the per-trace model (docs/design.md §3, §3.6).

Parameters, in the order of the sampler's vector θ (:func:`param_names`):

================  ==============================================================
``log_Estar``     ln(E*/Pa).  Uniform on [ln 1 Pa, ln 1e12 Pa] by default: the scale-free
                  (Jeffreys) prior 1/E* truncated to twelve decades, so kPa foams and kPa cells
                  measured in µm/nN units (converted to SI) are both inside.
``z_surf``        [m] Uniform over the whole loading range [z_min, z_top] of the trace
                  (``surface="loading"``, the default): the likelihood, with the free offset,
                  places the surface.  The paper's constraint |F(z_surf)| <= F_unc belongs to
                  the least-squares baseline; ``surface="soft"`` adds it as a soft penalty,
                  −½·(max(0, |F_meas(z_s) − F0 − F1·u| − F_unc)/F_unc)², on the same support.
``log_sigma``     ln(sigma/N).  Normal(ln(pp/6), 1): centred on the noise spec read as ±3 sigma
                  (:mod:`palpbayes.sensor_noise`) — the user's ``noise_pp``, or when none is
                  given the pre-contact baseline's own noise (:mod:`palpbayes.baseline`); a factor e
                  either way is 1 sd.
``F0``            [N] Force offset, Normal(b, s): centred on the pre-contact baseline b (an
                  untared sensor is normal input) with s = F_unc (the sensor's peak-to-peak
                  spec: the baseline's own scale).  ``F0_center``/``F0_sd`` override both.
``F1``            (linear baseline only) [N/m] slope of the baseline F0 + F1·(z − z_ref),
                  Normal(0, s1) with s1 = (F_max − b)/(z_top − z_min): a drift that alone would
                  produce the whole contact force over the recorded span is 1 sd.
``phi``           (AR(1) only) lag-one correlation, Uniform(−0.99, 0.99).
``log_nu_t``      (Student-t only) ln of the degrees of freedom, Uniform(ln 2, ln 200).
``bond``          (a layer whose base is unknown) the base condition as a coordinate in
                  [0, 1]: bonded when >= 0.5, free below; uniform within each half with the
                  masses p and 1 − p (``ModelSpec.p_bonded``, 0.5).
``log_h``         (an unknown thickness) ln(h/m), uniform on [ln h_lo, ln h_hi] and, with the
                  same prior mass again, on (ln h_hi, ln h_hi + ln(h_hi/h_lo)]: there the
                  specimen is a half-space (no layer; :data:`P_HALFSPACE` = 0.5).
================  ==============================================================

:class:`PriorSpec` holds the user's settings; :class:`TracePrior` the numbers for one trace
(support, centres and scales read from its data).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..fitdata import FitData
from ..sensor_noise import sigma_from_pp
from .noisemodels import NOISE_MODELS, get_noise_model

__all__ = ["NOISE_MODELS", "BASELINES", "SURFACE_PRIORS", "PriorSpec", "TracePrior",
           "param_names", "layer_names", "LAYER_PARAMETERS", "P_HALFSPACE", "log_posterior"]

#: Prior probability of no layer at all (a half-space) when the thickness is unknown.
P_HALFSPACE = 0.5

#: The layer's sampled parameters (never flagged at their bounds: a base coordinate near 0 or
#: 1 and a thickness in the half-space segment are answers, not prior artefacts).
LAYER_PARAMETERS = ("bond", "log_h")

BASELINES = ("constant", "linear")
SURFACE_PRIORS = ("loading", "soft")


def layer_names(model) -> list[str]:
    """The layer's sampled parameters of a contact model: ``bond`` when the base is unknown,
    ``log_h`` when the thickness is; none for a half-space or a concrete layer."""
    names = []
    if model.has_layer and model.bonding == "unknown":
        names.append("bond")
    if model.thickness_unknown:
        names.append("log_h")
    return names


def param_names(noise: str, baseline: str = "constant", layer: tuple[str, ...] | list[str] = ()
                ) -> list[str]:
    """Names of the sampled parameters for a noise model, a baseline model and the layer's
    unknowns (:func:`layer_names`, appended last)."""
    names = ["log_Estar", "z_surf", "log_sigma", "F0"]
    if baseline == "linear":
        names.append("F1")
    elif baseline != "constant":
        raise InputError(f"unknown baseline {baseline!r}; use one of {', '.join(BASELINES)}")
    extra = get_noise_model(noise).extra
    return names + ([extra] if extra else []) + list(layer)


@dataclass(frozen=True)
class PriorSpec:
    """Prior settings.

    Parameters
    ----------
    Estar_bounds
        [Pa] Bounds of the log-uniform prior of E*.
    noise_pp
        [N] Sensor peak-to-peak noise spec (paper: 48 mN); None: read from the trace's
        pre-contact baseline.
    log_sigma_sd
        Sd of the log-normal prior of sigma.
    F0_sd
        [N] Sd of the force-offset prior (None: the trace's F_unc).
    F0_center
        [N] Centre of the force-offset prior (None: the trace's pre-contact baseline level).
    phi_bounds
        Bounds of the AR(1) coefficient.
    nu_t_bounds
        Bounds of the Student-t degrees of freedom (log-uniform).
    surface
        ``"loading"`` (uniform over the loading range) or ``"soft"`` (plus the paper's
        constraint as a soft penalty).
    """

    Estar_bounds: tuple[float, float] = (1.0, 1e12)
    noise_pp: float | None = None
    log_sigma_sd: float = 1.0
    F0_sd: float | None = None
    F0_center: float | None = None
    phi_bounds: tuple[float, float] = (-0.99, 0.99)
    nu_t_bounds: tuple[float, float] = (2.0, 200.0)
    surface: str = "loading"

    def __post_init__(self) -> None:
        lo, hi = self.Estar_bounds
        if not (0 < lo < hi and math.isfinite(hi)):
            raise InputError(f"E* prior bounds {self.Estar_bounds} must satisfy 0 < lo < hi")
        if self.noise_pp is not None and not (self.noise_pp > 0
                                              and math.isfinite(self.noise_pp)):
            raise InputError(f"noise peak-to-peak {self.noise_pp!r} N must be positive")
        if self.surface not in SURFACE_PRIORS:
            raise InputError(f"unknown surface prior {self.surface!r}; use one of "
                             f"{', '.join(SURFACE_PRIORS)}")

    def for_trace(self, data: FitData, noise: str, baseline: str = "constant") -> TracePrior:
        """The prior of one trace: support, centres and scales read from ``data``."""
        base = data.baseline
        pp = self.noise_pp
        if pp is None:
            pp = base.noise_pp if base is not None and base.reliable else data.f_unc
        if base is not None:
            center = float(base.level) - data.tare
            z_ref = float(base.z_ref)
        else:
            center, z_ref = 0.0, float(data.z_top)
        if self.F0_center is not None:
            center = float(self.F0_center)
        f0_sd = data.f_unc if self.F0_sd is None else float(self.F0_sd)
        span = max(data.z_top - data.z_min, 1e-300)
        rise = max(float(np.max(data.force)) - center, data.f_unc)
        model = data.model
        log_h = None
        if model.thickness_unknown:
            lo, hi = (math.log(v) for v in model.thickness_range)
            log_h = (lo, hi)
        return TracePrior(
            spec=self, names=tuple(param_names(noise, baseline, layer_names(model))),
            noise=noise, baseline=baseline, z_bounds=data.z_prior,
            sigma_center=sigma_from_pp(pp), f0_center=center, f0_sd=f0_sd, f1_sd=rise / span,
            z_ref=z_ref, f_unc=data.f_unc, data=data, p_bonded=model.p_bonded,
            log_h_range=log_h,
        )


@dataclass(frozen=True)
class TracePrior:
    """The prior of one trace (see the module docstring).

    Attributes
    ----------
    names
        Sampled parameter names, in θ order.
    z_bounds
        [m] Support of the surface prior.
    sigma_center
        [N] Median of the sigma prior.
    f0_center, f0_sd
        [N] Centre and sd of the offset prior.
    f1_sd
        [N/m] Sd of the baseline-slope prior (linear baseline).
    z_ref
        [m] Height where the baseline equals F0 (the linear baseline's reference).
    p_bonded
        Prior probability of the bonded base (``bond`` >= 0.5).
    log_h_range
        (ln h_lo, ln h_hi) of an unknown thickness, or None; ``log_h`` beyond ln h_hi (up to
        :attr:`log_h_top`) stands for the half-space.
    """

    spec: PriorSpec
    names: tuple[str, ...]
    noise: str
    baseline: str
    z_bounds: tuple[float, float]
    sigma_center: float
    f0_center: float
    f0_sd: float
    f1_sd: float
    z_ref: float
    f_unc: float
    data: FitData
    p_bonded: float = 0.5
    log_h_range: tuple[float, float] | None = None

    def index(self, name: str) -> int:
        return self.names.index(name)

    @property
    def log_h_top(self) -> float:
        """Upper end of the ``log_h`` coordinate: ln h_hi plus the half-space segment, whose
        length gives it the prior probability :data:`~palpbayes.bayes.layers.P_HALFSPACE`."""
        lo, hi = self.log_h_range
        return hi + (hi - lo) * P_HALFSPACE / (1.0 - P_HALFSPACE)

    def thickness_of(self, log_h: np.ndarray) -> np.ndarray:
        """[m] The thickness of ``log_h`` coordinates (``inf`` in the half-space segment)."""
        x = np.asarray(log_h, dtype=float)
        return np.where(x <= self.log_h_range[1], np.exp(np.minimum(x, 700.0)), np.inf)

    @property
    def bounds(self) -> dict[str, tuple[float, float]]:
        """Hard bounds of the bounded parameters, in θ coordinates."""
        s = self.spec
        out = {"log_Estar": (math.log(s.Estar_bounds[0]), math.log(s.Estar_bounds[1])),
               "z_surf": self.z_bounds}
        if "phi" in self.names:
            out["phi"] = s.phi_bounds
        if "log_nu_t" in self.names:
            out["log_nu_t"] = (math.log(s.nu_t_bounds[0]), math.log(s.nu_t_bounds[1]))
        if "bond" in self.names:
            out["bond"] = (0.0, 1.0)
        if "log_h" in self.names:
            out["log_h"] = (self.log_h_range[0], self.log_h_top)
        return out

    def log_prior(self, theta: np.ndarray) -> np.ndarray:
        """Log prior density (up to a constant) for θ of shape (W, ndim); -inf outside."""
        theta = np.atleast_2d(theta)
        ok = np.ones(theta.shape[0], dtype=bool)
        for name, (lo, hi) in self.bounds.items():
            x = theta[:, self.index(name)]
            ok &= (x >= lo) & (x <= hi) if name == "z_surf" else (x > lo) & (x < hi)
        lp = np.zeros(theta.shape[0])
        if "bond" in self.names:
            b = theta[:, self.index("bond")]
            lp += np.where(b >= 0.5, math.log(2 * self.p_bonded),
                           math.log(2 * (1.0 - self.p_bonded)))
        ls = theta[:, 2]
        lp += -0.5 * ((ls - math.log(self.sigma_center)) / self.spec.log_sigma_sd) ** 2
        f0 = theta[:, 3]
        lp += -0.5 * ((f0 - self.f0_center) / self.f0_sd) ** 2
        if self.baseline == "linear":
            lp += -0.5 * (theta[:, 4] / self.f1_sd) ** 2
        if self.spec.surface == "soft":
            zs = theta[:, 1]
            base = f0 + (theta[:, 4] * (zs - self.z_ref) if self.baseline == "linear" else 0.0)
            excess = np.abs(self.data.measured_force_at(zs) - base) - self.f_unc
            lp += -0.5 * (np.maximum(excess, 0.0) / self.f_unc) ** 2
        return np.where(ok, lp, -np.inf)

    def sample(self, rng: np.random.Generator, n: int) -> np.ndarray:
        """Draw n parameter vectors from the prior (without the soft penalty), shape (n, ndim)."""
        s = self.spec
        cols = {
            "log_Estar": rng.uniform(math.log(s.Estar_bounds[0]), math.log(s.Estar_bounds[1]),
                                     n),
            "z_surf": rng.uniform(*self.z_bounds, n),
            "log_sigma": rng.normal(math.log(self.sigma_center), s.log_sigma_sd, n),
            "F0": rng.normal(self.f0_center, self.f0_sd, n),
            "F1": rng.normal(0.0, self.f1_sd, n),
            "phi": rng.uniform(*s.phi_bounds, n),
            "log_nu_t": rng.uniform(*np.log(s.nu_t_bounds), n),
        }
        if "bond" in self.names:
            bonded = rng.random(n) < self.p_bonded
            cols["bond"] = np.where(bonded, 0.5, 0.0) + 0.5 * rng.random(n)
        if "log_h" in self.names:
            cols["log_h"] = rng.uniform(self.log_h_range[0], self.log_h_top, n)
        return np.column_stack([cols[name] for name in self.names])


def log_posterior(prior: TracePrior, like, to_real=None):
    """The log posterior density of θ (W, ndim) for emcee: ``prior.log_prior`` + ``like``,
    −inf outside the prior (the likelihood is evaluated only inside it).

    ``to_real(theta) -> ln E*`` (W,), if given, is what the prior's E* bounds see when the
    sampled first coordinate is an aligned one (:mod:`palpbayes.bayes.layer_likelihood`: a
    shift with unit Jacobian, so the density is the same).
    """
    def log_prob(theta: np.ndarray) -> np.ndarray:
        real = theta
        if to_real is not None:
            real = np.array(theta, dtype=float, copy=True)
            real[:, 0] = to_real(theta)
        lp = prior.log_prior(real)
        ok = np.isfinite(lp)
        if ok.any():
            lp[ok] += like(theta[ok])
        return lp
    return log_prob
