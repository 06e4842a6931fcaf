"""A compression test at finite strain: each hyperelastic law fitted to the whole loading curve,
with a posterior of its parameters and of its small-strain modulus E0.

The straight line of :mod:`.fit` reads a slope over a window; a silicone or a foam is not
linear there, so that slope depends on the window (docs/design.md §14: on the phantom database
the initial modulus of the best hyperelastic fit lies 11–20 % below the published linear
modulus).  Here the law of :mod:`palpbayes.material` is fitted to the curve instead, and E0,
its slope at zero strain, is read from it.

The model
---------
The loading branch from twice the linear rule's toe offset (where a quadratic toe has joined
the curve: :func:`~palpbayes.compression.fit_modulus`'s ``skip_toe``) to the largest
compression is reduced to :data:`N_BINS` means equally spaced in strain; the model is averaged
over each bin's samples as the data are.  For the bins b::

    sigma_b = mean over b's samples i of sum_k c_k·g_k(eps_i − eps0; q) + e_b,   e_b AR(1)

* e_b is AR(1) from bin to bin (innovation sd sigma, coefficient phi);
* g_k is the law's compressive nominal stress (:func:`palpbayes.material.compression_stress`)
  with its k-th modulus parameter set to 1 Pa (the stress is linear in a law's moduli, ``Pa``
  parameters, at fixed dimensionless ones ``q``: exponents, b, the foam's nu); the non-foam laws
  are incompressible (free lateral faces, frictionless platens);
* eps0 is the strain at full contact, where the law's stress is 0 (uniform prior between
  −0.02 and the first bin: a test that started preloaded may have it below 0); the platens'
  travel before it is slack, not the block's strain, so the block's strain is eps − eps0 of its
  measured height (the simulator's toe, :func:`~palpbayes.compression.toe_compression`); no
  stress offset is fitted (it would trade off with eps0 along the curve);
* c (flat priors) and sigma (1/sigma) are integrated out in closed form given eps0, q and
  phi (prewhitened least squares); phi is summed over a grid on [−0.9, 0.99]; eps0 and q are
  on a grid when they are at most three, else sampled by emcee
  (:func:`palpbayes.bayes.sampler.run_emcee`);
* each draw of (eps0, q, phi) gets its (c, sigma) from their normal-inverse-gamma
  conditional; E0 = 2·mu0(c)·(1 + nu0) of each draw (linear in c).  Draws whose law is not
  stable along the tested stretches (:attr:`palpbayes.material.MaterialLaw.stable`) or whose
  E0 is not positive are dropped (the constraints the flat priors leave out).

Laws are compared by PSIS-LOO on the bins (Vehtari, Gelman & Gabry 2017, through
:func:`arviz.loo`), each bin's term conditional on the one before (as
:mod:`palpbayes.rheology.choice`): the expected log predictive density of a law, not its
in-sample error, which always favours more parameters.
"""

# Long module: one job, the finite-strain law fit of a compression curve; the collapsed posterior
#   (_Collapsed) and its draws are that fit's inside.

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field

import numpy as np
from scipy.special import logsumexp

from ..bayes.sampler import SamplerSettings, run_emcee
from ..errors import DataFileError, FitError, InputError, PalpbayesError
from ..intervals import LEVEL, central
from ..io.instron import CompressionTest
from ..material import LINEAR, MaterialLaw, chord_modulus, compression_stress, material_law
from .fit import fit_modulus

__all__ = ["N_BINS", "AUTO_LAWS", "LawFit", "CurveBins", "curve_bins", "fit_law",
           "LOO_DRAWS", "N_DRAWS"]

#: Bin means of the loading curve the laws are fitted to.
N_BINS = 48
#: The laws ``--law auto`` compares: the incompressible solids with at most three parameters.
#: A foam (``hyperfoam``) and the many-term Ogden laws are fitted when named: a compression
#: curve alone cannot tell a foam's lateral spreading from the shape of its curve, and two
#: Ogden terms fit it with near-cancelling moduli (EF50_12_5T_A1: mu 149 and −341 kPa).
AUTO_LAWS = ("neo-hookean", "mooney-rivlin", "yeoh-2", "yeoh", "ogden", "exponential")
#: Posterior draws kept per law and test, and those behind PSIS-LOO.
N_DRAWS, LOO_DRAWS = 2000, 400
#: The grid of the AR(1) coefficient of the bin residuals (uniform prior).
PHI_GRID = np.linspace(-0.9, 0.99, 39)
#: Lowest contact strain eps0 allowed (a test that started preloaded).
EPS0_MIN = -0.02
#: [-] Measured strain up to which the small-strain check refits a law (:func:`fit_law`).
LOW_STRAIN = 0.2
#: Most zooms of the grid onto the box that holds the posterior mass.
MAX_ZOOMS = 8
#: Nodes per axis of the grid over eps0 and up to two dimensionless parameters, by dimension.
GRID_NODES = {1: 61, 2: 31, 3: 15}


@dataclass(frozen=True)
class CurveBins:
    """The bin means of a test's loading curve that the laws are fitted to.

    Attributes
    ----------
    strain, stress
        [-], [Pa] Bin means (compressive, positive).
    start
        [-] Measured strain of the first point kept (twice the linear rule's toe offset).
    toe
        [-] The linear rule's toe offset (0 when that rule cannot fit the test).
    source
        The test's file (for messages).
    """

    strain: np.ndarray
    stress: np.ndarray
    start: float
    toe: float
    source: str
    raw: np.ndarray | None = None
    which: np.ndarray | None = None

    def average(self, values: np.ndarray) -> np.ndarray:
        """Bin means of ``values`` given at the raw strains ``raw`` (a model averaged over a bin
        as the data are: no bias from the curve's curvature within a bin)."""
        counts = np.bincount(self.which)
        return np.bincount(self.which, values, counts.size) / counts


def curve_bins(test: CompressionTest, n_bins: int = N_BINS,
               max_strain: float | None = None) -> CurveBins:
    """:class:`CurveBins` of ``test`` (module docstring), up to ``max_strain`` [-] of measured
    strain when given (:data:`LOW_STRAIN`: the small-strain check).

    Raises
    ------
    DataFileError
        Fewer than ``n_bins`` points on the loading branch beyond the toe.
    """
    where = test.source or f"compression test {test.specimen!r}"
    k = int(np.argmax(test.strain))
    eps, sig = test.strain[: k + 1], test.stress_pa[: k + 1]
    try:
        toe = max(float(fit_modulus(test).strain_toe), 0.0)
    except (DataFileError, FitError, InputError):
        toe = 0.0
    start = 2.0 * toe
    keep = (eps >= start) & (eps <= (np.inf if max_strain is None else max_strain))
    if int(keep.sum()) < n_bins:
        raise DataFileError(where, f"only {int(keep.sum())} points of the loading curve lie "
                            f"beyond twice the toe offset ({100 * start:.3g} % strain); a "
                            f"finite-strain fit needs at least {n_bins}",
                            "use the linear rule (--law linear) for so short a test")
    eps, sig = eps[keep], sig[keep]
    edges = np.linspace(eps.min(), eps.max(), n_bins + 1)
    which = np.clip(np.searchsorted(edges, eps, side="right") - 1, 0, n_bins - 1)
    counts = np.bincount(which, minlength=n_bins)
    good = counts > 0
    s_eps = np.bincount(which, eps, n_bins)[good] / counts[good]
    s_sig = np.bincount(which, sig, n_bins)[good] / counts[good]
    dense = np.cumsum(good) - 1  # bin numbers without the empty ones
    return CurveBins(s_eps, s_sig, float(eps.min()), toe, where, raw=eps, which=dense[which])


@dataclass
class LawFit:
    """One law fitted to one test.

    Attributes
    ----------
    law
        The law's name (``"linear"`` for the straight line of :mod:`.fit`).
    E0_pa, E0_sd_pa, E0_lo_pa, E0_hi_pa
        [Pa] Posterior median, sd and central 90 % interval of the small-strain modulus.
    params
        The natural parameters' posterior medians (moduli [Pa], dimensionless ones [-]).
    eps0, phi
        Posterior medians of the contact strain [-] and of the residuals' AR(1) coefficient.
    elpd_loo, elpd_se, p_loo, pareto_k_max
        PSIS-LOO on the bins (nats; NaN for the linear law, fitted over a window).
    pointwise
        The bins' pointwise elpd (for the comparison of laws on one test).
    draws
        Posterior draws of the natural parameters, ``eps0`` and ``E0`` (chord moduli).
    strain_hi
        [-] The largest measured strain fitted.
    n_bins
        Bin means fitted.
    """

    law: str
    E0_pa: float
    E0_sd_pa: float
    E0_lo_pa: float
    E0_hi_pa: float
    params: dict[str, float] = field(default_factory=dict)
    eps0: float = math.nan
    phi: float = math.nan
    elpd_loo: float = math.nan
    elpd_se: float = math.nan
    p_loo: float = math.nan
    pareto_k_max: float = math.nan
    pointwise: np.ndarray | None = None
    draws: dict[str, np.ndarray] = field(default_factory=dict)
    strain_hi: float = math.nan
    n_bins: int = 0
    low: LawFit | None = None

    @property
    def consistent(self) -> bool:
        """E0 over the whole curve and up to :data:`LOW_STRAIN` (``low``) have overlapping
        intervals (True without the check)."""
        return self.low is None or (self.low.E0_lo_pa <= self.E0_hi_pa
                                    and self.E0_lo_pa <= self.low.E0_hi_pa)

    def chord(self, lo: float, hi: float) -> tuple[float, float, float]:
        """(median, lo, hi) [Pa] of the chord modulus between compressive strains ``lo`` and
        ``hi`` (:func:`palpbayes.material.chord_modulus`) over the posterior draws."""
        if self.law == LINEAR:
            return self.E0_pa, self.E0_lo_pa, self.E0_hi_pa
        law = material_law(self.law)
        names = [n for n, _ in law.parameters]
        n = len(self.draws["E0"])
        idx = np.unique(np.linspace(0, n - 1, min(n, 400)).astype(int))
        vals = np.array([chord_modulus(law, {k: self.draws[k][i] for k in names}, lo, hi)
                         for i in idx])
        a, b = central(vals, LEVEL)
        return float(np.median(vals)), a, b


class _Collapsed:
    """The law's posterior on one curve with c and sigma integrated out (module docstring)."""

    def __init__(self, law: MaterialLaw, bins: CurveBins):
        self.law, self.bins = law, bins
        self.moduli = [n for n, u in law.parameters if u == "Pa"]
        self.q_names = [n for n, u in law.parameters if u == "-"]
        self.q_bounds = [self._bounds(n) for n in self.q_names]
        self.y = bins.stress
        n = self.y.size
        # whitening of an AR(1) series for every phi of the grid: rows scale and shift
        self.w0 = np.sqrt(1.0 - PHI_GRID**2)
        self.m = len(self.moduli)
        self.dof = n - self.m
        self.yt = self._whiten(self.y[None, :])[:, 0, :]   # (nphi, n)
        self.eps_max = float(bins.start)

    def _bounds(self, name: str) -> tuple[float, float]:
        shape = {s.name: s.bounds for s in self.law.shape}
        return shape.get(name, (-10.0, 25.0))

    def _whiten(self, a: np.ndarray) -> np.ndarray:
        """(nphi, k, n) whitened rows of (k, n) series ``a``."""
        first = self.w0[:, None, None] * a[None, :, :1]
        rest = a[None, :, 1:] - PHI_GRID[:, None, None] * a[None, :, :-1]
        return np.concatenate([first, rest], axis=2)

    def params(self, q: np.ndarray, c: np.ndarray) -> dict[str, float]:
        return {**dict(zip(self.q_names, map(float, q), strict=True)),
                **dict(zip(self.moduli, map(float, c), strict=True))}

    def design(self, eps0: float, q: np.ndarray) -> np.ndarray | None:
        """(m, n) columns: the unit-modulus curves; None outside the law."""
        strain = self.bins.raw - eps0
        cols = []
        for k in self.moduli:
            p = self.params(q, np.array([1.0 if j == k else 0.0 for j in self.moduli]))
            try:
                with np.errstate(all="ignore"):
                    g = compression_stress(self.law, p, strain)
            except (PalpbayesError, ArithmeticError):  # an exponent of 0 (a grid node)
                return None
            if not np.all(np.isfinite(g)):
                return None
            cols.append(self.bins.average(g))
        return np.array(cols)

    def in_prior(self, eps0: float, q: np.ndarray) -> bool:
        if not EPS0_MIN <= eps0 <= self.eps_max:
            return False
        return all(lo <= v <= hi for v, (lo, hi) in zip(q, self.q_bounds, strict=True))

    def solve(self, x: np.ndarray):
        """Per phi: the normal matrix, the coefficients and the residual sum of squares."""
        xt = self._whiten(x)                                   # (nphi, m, n)
        a = np.einsum("pin,pjn->pij", xt, xt)
        rhs = np.einsum("pin,pn->pi", xt, self.yt)
        try:
            beta = np.linalg.solve(a, rhs[..., None])[..., 0]
        except np.linalg.LinAlgError:
            return None
        resid = self.yt - np.einsum("pin,pi->pn", xt, beta)
        return a, beta, np.einsum("pn,pn->p", resid, resid)

    def log_phi(self, eps0: float, q: np.ndarray):
        """(log posterior per phi, the solve) at (eps0, q); None outside the prior or law."""
        if not self.in_prior(eps0, q):
            return None
        x = self.design(eps0, q)
        if x is None:
            return None
        out = self.solve(x)
        if out is None:
            return None
        a, beta, rss = out
        sign, logdet = np.linalg.slogdet(a)
        if np.any(sign <= 0) or np.any(rss <= 0):
            return None
        lp = np.log(self.w0) - 0.5 * logdet - 0.5 * self.dof * np.log(rss)
        if not self.admissible(q, beta[int(np.argmax(lp))], x, eps0):
            return None
        return lp, (x, a, beta, rss)

    def admissible(self, q: np.ndarray, c: np.ndarray, x: np.ndarray, eps0: float) -> bool:
        """A solid (the law's own limits, E0 > 0) whose compressive stress rises with strain
        over the fitted bins (the constraints the flat priors on c leave out)."""
        p = self.params(q, c)
        if self.law.E0(p) <= 0 or not self.law.stable(p, self._path(eps0)):
            return False
        return bool(np.all(np.diff(c @ x) > 0))

    def _path(self, eps0: float) -> np.ndarray:
        lam = 1.0 - (self.bins.strain - eps0)
        lat = lam ** -0.5
        return np.stack([lam, lat, lat], axis=-1)

    def log_prob(self, theta: np.ndarray) -> float:
        r = self.log_phi(float(theta[0]), np.asarray(theta[1:], dtype=float))
        return -np.inf if r is None else float(logsumexp(r[0]))

    def conditional_draws(self, eps0: float, q: np.ndarray, n: int,
                          rng: np.random.Generator) -> list[tuple]:
        """``n`` draws of (phi, c, sigma, fitted curve) given (eps0, q), each from
        the normal-inverse-gamma conditional; inadmissible ones dropped."""
        r = self.log_phi(eps0, q)
        if r is None:
            return []
        lp, (x, a, beta, rss) = r
        w = np.exp(lp - lp.max())
        out = []
        for i in rng.choice(PHI_GRID.size, n, p=w / w.sum()):
            sigma = math.sqrt(rss[i] / rng.chisquare(self.dof))
            chol = np.linalg.cholesky(np.linalg.inv(a[i]))
            coef = beta[i] + sigma * chol @ rng.standard_normal(self.m)
            if self.admissible(q, coef, x, eps0):
                out.append((PHI_GRID[i], coef, sigma, coef @ x))
        return out


def _theta_draws(model: _Collapsed, rng: np.random.Generator,
                 seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Distinct (eps0, q) points and how many draws each gets (:data:`N_DRAWS` in all): the
    nodes of a grid up to three dimensions (drawn by their posterior mass), else emcee's
    draws."""
    dims = 1 + len(model.q_names)
    if dims <= 3:
        nodes = GRID_NODES[dims]
        lo = np.array([EPS0_MIN] + [b[0] for b in model.q_bounds])
        hi = np.array([model.eps_max] + [b[1] for b in model.q_bounds])
        for _ in range(MAX_ZOOMS):  # the prior's box, then the box that holds the mass
            axes = [np.linspace(lo[j], hi[j], nodes) for j in range(dims)]
            pts = np.array(np.meshgrid(*axes, indexing="ij")).reshape(dims, -1).T
            lp = np.array([model.log_prob(t) for t in pts])
            ok = np.isfinite(lp)
            if not ok.any():
                raise FitError(f"{model.bins.source}: no {model.law.title} fits the curve")
            w = np.exp(lp - lp[ok].max())
            step = (hi - lo) / (nodes - 1)
            mass = pts[ok & (w > 1e-8)]
            new_lo = np.maximum(mass.min(axis=0) - step, lo)
            new_hi = np.minimum(mass.max(axis=0) + step, hi)
            if np.all(new_hi - new_lo > 0.5 * (hi - lo)):
                break  # the mass spans the box: resolved
            lo, hi = new_lo, new_hi
        w = np.where(ok, w, 0.0)
        counts = rng.multinomial(N_DRAWS, w / w.sum())
        return pts[counts > 0], counts[counts > 0]
    # emcee over (eps0, q), started around the defaults
    defaults = {s.name: s.default for s in model.law.shape}
    start = np.array([min(0.5 * model.eps_max, model.eps_max)]
                     + [defaults.get(n, 1.0) for n in model.q_names])
    walkers = max(4 * dims, 16)
    p0, tries = [], 0
    scale = np.array([0.005] + [0.1 * (hi - lo) for lo, hi in model.q_bounds])
    while len(p0) < walkers and tries < 200 * walkers:
        t = start + scale * rng.standard_normal(dims)
        tries += 1
        if np.isfinite(model.log_prob(t)):
            p0.append(t)
    if len(p0) < walkers:
        raise FitError(f"{model.bins.source}: no {model.law.title} near its default "
                       "parameters fits the curve")
    settings = SamplerSettings(n_walkers=walkers, max_steps=6000, min_steps=400,
                               check_every=100, progress=False)
    res = run_emcee(lambda th: np.array([model.log_prob(t) for t in th]), np.array(p0),
                    settings, seed)
    flat = res.samples.reshape(-1, dims)
    picked = flat[rng.choice(flat.shape[0], N_DRAWS // 4)]
    return picked, np.full(picked.shape[0], 4)


def fit_law(test: CompressionTest, law: str | MaterialLaw, *, seed: int = 0,
            bins: CurveBins | None = None, check: bool = True) -> LawFit:
    """Fit ``law`` to the loading curve of ``test`` (module docstring).

    Parameters
    ----------
    test
        A compression test (SI, compressive positive).
    law
        A registered law; ``"linear"`` returns the straight line of :func:`.fit_modulus`
        (E0 = its slope, its interval ±z·sd).
    seed
        Seed of the draws (and of emcee).
    bins
        The curve's bins when already made (:func:`curve_bins`).
    check
        Also fit the law up to :data:`LOW_STRAIN` of measured strain (``LawFit.low``) when the
        test goes past 1.5 times that: the small-strain check.  A law that follows the curve
        gives the same E0 both ways; on the silicone phantoms of ``../shared/data`` every law
        reads E0 20–35 % lower over the whole curve (to 66 %) than up to 20 %, where the laws
        agree with each other and with the linear window (docs/reference.md, "Finite strain").

    Raises
    ------
    DataFileError
        A test too short to fit.
    FitError
        No parameters of the law fit the curve, or no stable draw.
    """
    if law == LINEAR:
        lin = fit_modulus(test)
        z = 1.6448536269514722
        return LawFit(LINEAR, lin.E_pa, lin.E_sd_pa, lin.E_pa - z * lin.E_sd_pa,
                      lin.E_pa + z * lin.E_sd_pa, {"E": lin.E_pa}, eps0=lin.strain_toe,
                      strain_hi=lin.strain_hi, n_bins=0)
    law = material_law(law)
    bins = bins if bins is not None else curve_bins(test)
    model = _Collapsed(law, bins)
    rng = np.random.default_rng([int(seed), 56])
    thetas, counts = _theta_draws(model, rng, seed)
    keep = {n: [] for n, _ in law.parameters} | {"eps0": [], "E0": [], "phi": [],
                                                   "sigma": []}
    fitted = []
    for th, count in zip(thetas, counts, strict=True):
        eps0, q = float(th[0]), th[1:]
        for phi, coef, sigma, curve in model.conditional_draws(eps0, q, int(count), rng):
            p = model.params(q, coef)
            for k, v in p.items():
                keep[k].append(v)
            keep["eps0"].append(eps0)
            keep["E0"].append(law.E0(p))
            keep["phi"].append(phi)
            keep["sigma"].append(sigma)
            fitted.append(curve)
    if len(fitted) < N_DRAWS // 4:
        raise FitError(f"{bins.source}: only {len(fitted)} of {N_DRAWS} draws of the "
                       f"{law.title} law are stable: it does not describe this curve")
    draws = {k: np.asarray(v, dtype=float) for k, v in keep.items()}
    loo = _loo(bins.stress, np.asarray(fitted), draws)
    E0 = draws["E0"]
    lo, hi = central(E0, LEVEL)
    low = None
    if check and bins.strain.max() > 1.5 * LOW_STRAIN:
        try:
            low = fit_law(test, law, seed=seed, check=False,
                          bins=curve_bins(test, max_strain=LOW_STRAIN))
        except (DataFileError, FitError):
            low = None
    return LawFit(
        law=law.name, E0_pa=float(np.median(E0)), E0_sd_pa=float(E0.std(ddof=1)),
        E0_lo_pa=lo, E0_hi_pa=hi,
        params={n: float(np.median(draws[n])) for n, _ in law.parameters},
        eps0=float(np.median(draws["eps0"])), phi=float(np.median(draws["phi"])),
        elpd_loo=loo[0], elpd_se=loo[1], p_loo=loo[2], pareto_k_max=loo[3],
        pointwise=loo[4], draws=draws, strain_hi=float(bins.strain.max()),
        n_bins=int(bins.strain.size), low=low)


def _loo(y: np.ndarray, fitted: np.ndarray, draws: dict[str, np.ndarray]):
    """PSIS-LOO of the bins: (elpd, se, p_loo, k max, pointwise), each bin's term given the one
    before (AR(1))."""
    import arviz as az

    n = fitted.shape[0]
    idx = np.unique(np.linspace(0, n - 1, min(n, LOO_DRAWS)).astype(int))
    e = y[None, :] - fitted[idx]
    sigma, phi = draws["sigma"][idx][:, None], draws["phi"][idx][:, None]
    mean = np.concatenate([np.zeros_like(sigma), phi * e[:, :-1]], axis=1)
    scale = np.concatenate([sigma / np.sqrt(1.0 - phi**2),
                            np.broadcast_to(sigma, (idx.size, y.size - 1))], axis=1)
    z = (e - mean) / scale
    ll = -0.5 * z**2 - np.log(scale) - 0.5 * np.log(2.0 * np.pi)
    idata = az.from_dict(log_likelihood={"y": ll[None]}, posterior={"E0": draws["E0"][idx][None]})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = az.loo(idata, pointwise=True)
    return (float(res.elpd_loo), float(res.se), float(res.p_loo),
            float(np.max(np.asarray(res.pareto_k))), np.asarray(res.loo_i))
