"""Spatial posterior of the log-modulus field from a grid of palpations.

Each palpation i gives a posterior of log E_i [log(E/Pa)], summarised as Normal(y_i, s_i²).
The map is the latent Gaussian model of :mod:`palpbayes.maps.spde`: a mean level beta plus a
Matérn (nu = 1) GMRF u on the palpation lattice, seen through a nugget tau (point-to-point
material heterogeneity and model error) on top of each trace's own s_i.  The hyperparameters
theta = (sigma_f, range, tau) carry PC priors and are integrated over an INLA-style grid
(:mod:`palpbayes.maps.hyper`); beta is integrated analytically; posterior draws are exact and
joint over theta and the field.

Padding
-------
The field lives on the data lattice padded by :func:`default_margin` nodes on each side
(``clip(ceil(0.2·max(nx, ny)), 4, 20)``), which pushes the variance inflation of the free
(Neumann) boundary away from the data; every output is on the data lattice.

Default priors (:class:`FieldPrior`, each with tail probability ``alpha`` = 0.05)
-------------------------------------------------------------------------------
``range_0`` = 2 steps: a field correlated over less than two lattice steps cannot be told from
the nugget on this lattice (prior median range ≈ 8.6 steps, heavy right tail).
``sigma_0`` = max(3·spread, 0.05) and ``tau_0`` = max(2·spread, 0.05), spread = 1.4826·MAD
of y: the field's sd and the nugget rarely exceed the data's own spread (floor: 5 % in E).
beta ~ Normal(median(y), (10·(spread + 1))²), vague.

Search box and flags
--------------------
theta is searched and integrated within sigma_f ∈ [1e-3, 1e2]·sigma_0, range ∈ [step/4,
:data:`RANGE_REACH` × the map's extent] and tau ∈ [min(1e-4·tau_0, 0.01·median(s)),
1e2·tau_0]: beyond them the lattice precision becomes numerically singular or the values mean
nothing on the map.  Posterior mass at an end of the box, at the edge of the integration grid,
or a failed optimiser is never silent: :attr:`FieldPosterior.flags` names it (e.g. pure
nugget data push sigma_f to the bottom of its interval and range to the top).
"""

from __future__ import annotations

import math
import os
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field, replace

import numpy as np
import pandas as pd

from ..errors import FitError, InputError
from ..sensor_noise import mad_sd
from .hyper import HYPER_NAMES, explore, log_pc_prior, weighted_summary
from .lattice import Lattice, lattice_from_positions, pad
from .spde import SpdeModel

__all__ = ["FieldPrior", "FieldPosterior", "fit_field", "default_margin", "robust_spread"]


#: Largest range searched, in map extents (longer ranges: numerically singular precision).
RANGE_REACH = 50.0


def _workers() -> int:
    """Threads for the sparse factorisations (SuperLU releases the GIL)."""
    return min(4, os.cpu_count() or 1)


def default_margin(lattice: Lattice) -> int:
    """Padding [nodes] on each side of the data lattice: clip(ceil(0.2·max(nx, ny)), 4, 20)."""
    return int(min(max(math.ceil(0.2 * max(lattice.nx, lattice.ny)), 4), 20))


def robust_spread(y: np.ndarray) -> float:
    """1.4826·median|y − median(y)|: the sd of normal values, robust to a lump's outliers."""
    return mad_sd(y)


@dataclass(frozen=True)
class FieldPrior:
    """PC priors of the hyperparameters; ``None`` takes the data-based default (module doc).

    Attributes
    ----------
    range_0
        P(range < range_0) = alpha [m].
    sigma_0
        P(sigma_f > sigma_0) = alpha [log E].
    tau_0
        P(tau > tau_0) = alpha [log E].
    alpha
        Tail probability of the three statements.
    """

    range_0: float | None = None
    sigma_0: float | None = None
    tau_0: float | None = None
    alpha: float = 0.05

    def resolved(self, step: float, y: np.ndarray) -> FieldPrior:
        """The prior with every ``None`` replaced by its default for lattice step ``step``
        [m] and observations ``y``; checks every value."""
        spread = robust_spread(y)
        out = replace(self, range_0=2.0 * step if self.range_0 is None else self.range_0,
                      sigma_0=max(3 * spread, 0.05) if self.sigma_0 is None else self.sigma_0,
                      tau_0=max(2 * spread, 0.05) if self.tau_0 is None else self.tau_0)
        for name in ("range_0", "sigma_0", "tau_0"):
            v = getattr(out, name)
            if not (np.isfinite(v) and v > 0):
                raise InputError(f"FieldPrior.{name} must be positive, got {v!r}")
        if not 0 < out.alpha < 1:
            raise InputError(f"FieldPrior.alpha must be in (0, 1), got {out.alpha!r}")
        return out


@dataclass
class FieldPosterior:
    """Posterior of the log-modulus field mu = beta + u on the data lattice.

    Attributes
    ----------
    lattice
        The data lattice (outputs are ``(ny, nx)`` images on it).
    hyper
        The theta grid: ``sigma_f`` [log E], ``range_m`` [m], ``tau`` [log E], ``log_post``
        (log p(theta | y) + const, on the log-theta scale) and ``weight`` (sums to 1).
    flags
        Sentences naming problems: optimiser failure, theta piling up at the edge of its grid.
    prior
        The resolved :class:`FieldPrior`.
    margin
        Padding [nodes] on each side of the data lattice.
    n_obs
        Number of observations per node, ``(ny, nx)`` ints.
    """

    lattice: Lattice
    hyper: pd.DataFrame
    flags: list[str]
    prior: FieldPrior
    margin: int
    n_obs: np.ndarray
    _model: SpdeModel = field(repr=False)
    _index: np.ndarray = field(repr=False)
    _means: np.ndarray = field(repr=False)  # (n_grid, n_data_nodes) conditional means of mu

    def hyper_summary(self) -> pd.DataFrame:
        """Posterior mean, sd, 5 % and 95 % quantiles of the hyperparameters from the grid
        weights (quantiles smoothed on the log scale, see
        :func:`~palpbayes.maps.hyper.weighted_summary`): one row each for ``sigma_f``
        [log E], ``range_m`` [m], ``tau`` [log E]; columns ``parameter, mean, sd, q05, q95``.
        """
        logs = np.log(self.hyper[list(HYPER_NAMES)])
        return weighted_summary(logs, self.hyper["weight"].to_numpy(), log=True)

    def mean(self) -> np.ndarray:
        """Posterior mean of the field [log(E/Pa)], ``(ny, nx)`` (exact mixture over theta)."""
        w = self.hyper["weight"].to_numpy()
        return (w @ self._means).reshape(self.lattice.ny, self.lattice.nx)

    def draws(self, rng: np.random.Generator, n: int) -> dict[str, np.ndarray]:
        """``n`` exact joint posterior draws of theta, beta and the field.

        theta is drawn from the grid with probability its weight; the field given theta
        exactly (one sparse factorisation per distinct theta, shared by its draws; the
        distinct thetas run on parallel threads, each with its own child of ``rng``, so a
        seed gives the same draws whatever the thread count).

        Returns
        -------
        dict
            ``field`` ``(n, ny, nx)`` [log(E/Pa)], ``beta`` ``(n,)`` [log(E/Pa)], and
            ``sigma_f`` [log E], ``range_m`` [m], ``tau`` [log E], each ``(n,)``.
        """
        n = int(n)
        if n < 1:
            raise InputError(f"number of draws must be at least 1, got {n}")
        w = self.hyper["weight"].to_numpy()
        pick = rng.choice(len(w), size=n, p=w / w.sum())
        out = {"field": np.empty((n, self.lattice.ny, self.lattice.nx)),
               "beta": np.empty(n)}
        uniq = np.unique(pick)
        children = rng.spawn(uniq.size)

        def one(k: int, child: np.random.Generator) -> None:
            rows = np.flatnonzero(pick == k)
            h = self.hyper.iloc[k]
            f = self._model.factor(h.sigma_f, h.range_m, h.tau)
            x = self._model.draw(f, child, rows.size)
            out["beta"][rows] = x[-1]
            out["field"][rows] = (x[self._index] + x[-1]).T.reshape(
                rows.size, self.lattice.ny, self.lattice.nx)

        with ThreadPoolExecutor(_workers()) as pool:
            list(pool.map(one, uniq, children))
        for name in HYPER_NAMES:
            out[name] = self.hyper[name].to_numpy()[pick]
        return out

    def marginal_sd(self, n_draws: int = 400, rng: np.random.Generator | None = None
                    ) -> np.ndarray:
        """Posterior sd of the field [log E], ``(ny, nx)``, from ``n_draws`` draws."""
        rng = np.random.default_rng(0) if rng is None else rng
        return self.draws(rng, n_draws)["field"].std(axis=0, ddof=1)


def _check_inputs(x, y, mean, sd) -> tuple[np.ndarray, ...]:
    arrs = [np.asarray(a, dtype=float).ravel() for a in (x, y, mean, sd)]
    if len({a.size for a in arrs}) != 1 or arrs[0].size == 0:
        raise InputError("x, y, mean and sd must be non-empty and of equal length, got "
                         + ", ".join(str(a.size) for a in arrs))
    for name, a in zip(("mean", "sd"), arrs[2:], strict=True):
        bad = np.flatnonzero(~np.isfinite(a) | ((a <= 0) if name == "sd" else False))
        if bad.size:
            i = int(bad[0])
            need = "positive" if name == "sd" else "finite"
            raise InputError(f"{name}[{i}] = {a[i]!r}: every {name} of log E must be {need} "
                             "(drop the observations whose trace fit failed)")
    return tuple(arrs)


# Many parameters: the points (x, y, mean, sd) are the data; the prior, lattice step, grid and
# margin control the field.
def fit_field(x, y, mean, sd, *, prior: FieldPrior | None = None, step: float | None = None,
              grid_points: int = 7, progress: bool = False, margin: int | None = None,
              line: bool = False) -> FieldPosterior:
    """Posterior of the log-modulus field from palpations on a regular grid.

    Parameters
    ----------
    x, y
        Palpation positions [m] (any order; see
        :func:`~palpbayes.maps.lattice.lattice_from_positions`).
    mean, sd
        Each palpation's posterior mean and sd of log(E/Pa).
    prior
        Hyperparameter priors; default :class:`FieldPrior` () (data-based, see module doc).
    step
        Lattice step [m]; default inferred from the positions.
    grid_points
        Odd number of theta grid points per axis across ±3.5 posterior sd.
    progress
        Print the stages and timings to stderr.
    margin
        Padding [nodes] on each side; default :func:`default_margin`.
    line
        Accept palpations on one row or column (a line scan): the field is still the 2-D
        field, observed along that line.

    Returns
    -------
    FieldPosterior
    """
    xs, ys, yv, sv = _check_inputs(x, y, mean, sd)
    lat, node = lattice_from_positions(xs, ys, step=step, line=line)
    m = default_margin(lat) if margin is None else margin
    padded, index = pad(lat, m)
    pr = (prior or FieldPrior()).resolved(lat.step, yv)
    spread = robust_spread(yv)
    model = SpdeModel(padded, index[node], yv, sv, m0=float(np.median(yv)),
                      v0=(10.0 * (spread + 1.0)) ** 2)
    t_start = time.perf_counter()

    def say(msg: str) -> None:
        if progress:
            print(f"fit_field [{time.perf_counter() - t_start:7.1f} s] {msg}", file=sys.stderr)

    say(f"{yv.size} observations on a {lat.nx} × {lat.ny} lattice (step {lat.step:.4g} m), "
        f"padded to {padded.nx} × {padded.ny}")
    means: dict[tuple, np.ndarray] = {}

    def log_post(t: np.ndarray) -> float:
        sig, rng_m, tau = np.exp(t)
        try:
            f = model.factor(sig, rng_m, tau)
        except RuntimeError:  # SuperLU: numerically singular far out in theta
            return -np.inf
        ll, xm = model.log_marginal(f)
        means[tuple(np.round(t, 12))] = xm[index] + xm[-1]
        return ll + log_pc_prior(t, pr.range_0, pr.sigma_0, pr.tau_0, pr.alpha)

    extent = lat.step * max(lat.nx, lat.ny)
    t0 = np.log([max(spread, 0.05), 0.2 * extent, 0.5 * max(spread, 0.05)])
    tau_lo = min(1e-4 * pr.tau_0, 1e-2 * float(np.median(sv)))
    bounds = np.log([[1e-3 * pr.sigma_0, 1e2 * pr.sigma_0],
                     [0.25 * lat.step, RANGE_REACH * extent],
                     [tau_lo, 1e2 * pr.tau_0]])
    notes = {(0, 0): "no spatial variation shows beyond the nugget and the traces' sd",
             (1, 1): f"{RANGE_REACH:g} × the map's extent: the field is smooth across the "
                     "whole map, and longer ranges look alike on it",
             (2, 0): "a nugget this small is below what the traces' own sd can resolve"}
    grid, flags = explore(log_post, t0, bounds, grid_points=grid_points, workers=_workers(),
                          bound_notes=notes, progress=say)
    # a point whose factorisation failed has no mean (and weight 0): leave it out
    grid = grid[np.isfinite(grid["log_post"].to_numpy())].reset_index(drop=True)
    if grid.empty:
        raise FitError("the spatial field: no hyperparameter value could be factorised; check "
                       "the per-point values for outliers or a degenerate lattice")
    grid["weight"] = grid["weight"] / grid["weight"].sum()
    T = grid[[f"t_{n}" for n in HYPER_NAMES]].to_numpy()
    hyper = pd.DataFrame(np.exp(T), columns=list(HYPER_NAMES))
    hyper["log_post"] = grid["log_post"].to_numpy()
    hyper["weight"] = grid["weight"].to_numpy()
    stacked = np.array([means[tuple(np.round(t, 12))] for t in T])
    counts = np.bincount(node, minlength=lat.n_nodes).reshape(lat.ny, lat.nx)
    say(f"done: {len(hyper)} theta points" + (f"; flags: {flags}" if flags else ""))
    return FieldPosterior(lattice=lat, hyper=hyper, flags=flags, prior=pr, margin=m,
                          n_obs=counts, _model=model, _index=index, _means=stacked)
