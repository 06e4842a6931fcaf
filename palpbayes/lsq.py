"""The paper's least-squares baseline (docs/design.md §2, paper eqs. 12-13).

For a trial surface height z_s the force law F = E*·s(z_s − z) is linear in E* (k = E*·g for
power laws), so E* has the closed form

    E*(z_s) = Σ F_j·s_j / Σ s_j²,      L(z_s) = Σ F_j² − (Σ F_j·s_j)² / Σ s_j²,

and z_s is chosen to minimise the profile L(z_s) subject to the paper's constraint that the
measured force where the tip passes z_s lies within ±F_unc: z_s in [z_c, z_top] (see
:mod:`palpbayes.fitdata`).  The search is a 64-point grid over that interval followed by
:func:`scipy.optimize.minimize_scalar` (bounded Brent) between the neighbours of the best grid
point.

Interval for E: the Gauss-Newton covariance of (E*, z_s) from the residuals,
cov = s²·(JᵀJ)⁻¹ with s² = L/(n − 2) and J the Jacobian [s(d), E*·s'(d)]; E = E*·(1 − nu²) and
its central 90 % interval is E ± t(0.95, n − 2)·sd(E).  This is the textbook nonlinear
least-squares interval: it assumes iid Gaussian residuals and ignores the constraint; it is
the baseline's own interval, not a recommendation.

Untared sensors: the paper's model has no force-offset term.  The contact onset (and so the
constraint's range) is read against the pre-contact baseline (:mod:`palpbayes.fitdata`), but
the fit itself is the paper's: when the baseline level exceeds F_unc the row carries a note
(``notes``, the ``flags`` column) that E and z_surf are biased, and ``tare=True``
(``--tare``) subtracts the baseline level first.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy import optimize, stats

from .contact import youngs_factor
from .errors import FitError
from .fitdata import FitData, ModelSpec, prepare_trace
from .flagcodes import flag_columns
from .intervals import LEVEL
from .shapekernel import scale_rss
from .trace import IndentationTrace
from .units import format_force

__all__ = ["LSQResult", "fit_lsq", "fit_lsq_data", "profile_rss", "GRID_POINTS"]

#: Coarse grid size of the surface search.
GRID_POINTS = 64


@dataclass(frozen=True)
class LSQResult:
    """Result of the least-squares baseline (all SI).

    Attributes
    ----------
    E, E_sd, E_lo, E_hi
        [Pa] Young's modulus, its standard error and the central ``level`` interval.
    Estar, Estar_sd
        [Pa] Effective modulus E* = E/(1 − nu²).
    k, m
        F = k·d^m [N/m^m] for power-law tips (None for the exact sphere / thickness model).
    z_surf, z_surf_sd
        [m] Surface height and its standard error.
    rss
        [N²] The paper's objective L = Σ (F_j − k·d_j^m)² (eq. 12) at the optimum: the residual
        the paper tabulates (Table II); ``summary.csv`` column ``rss_n2``, averaged per
        material × tip in the comparison's ``residual_n2``.
    rms
        [N] Root-mean-square residual sqrt(L/n).
    n_points
        Samples fitted.
    z_admissible
        [m] (z_c, z_top): the surface heights allowed by the constraint.
    constraint_active
        True when the unconstrained optimum would violate |F(z_s)| <= F_unc.
    force_at_surface
        [N] Measured force where the tip passed z_surf.
    notes
        Caveats of this fit (e.g. an untared sensor), shown in the ``flags`` column.
    """

    E: float
    E_sd: float
    E_lo: float
    E_hi: float
    Estar: float
    Estar_sd: float
    k: float | None
    m: float | None
    z_surf: float
    z_surf_sd: float
    rss: float
    rms: float
    n_points: int
    z_admissible: tuple[float, float]
    constraint_active: bool
    force_at_surface: float
    level: float
    model: ModelSpec
    trace_id: str = ""
    cov: np.ndarray = field(default_factory=lambda: np.full((2, 2), np.nan), repr=False)
    notes: tuple[str, ...] = ()

    def summary_row(self) -> dict:
        """One row of ``summary.csv`` (docs/design.md §7); Bayesian-only columns are empty."""
        return {
            "trace_id": self.trace_id,
            "method": "lsq",
            "tip": self.model.tip.kind,
            "n_points": self.n_points,
            "E_pa": self.E,
            "E_sd_pa": self.E_sd,
            "E_lo_pa": self.E_lo,
            "E_hi_pa": self.E_hi,
            "Estar_pa": self.Estar,
            "z_surf_m": self.z_surf,
            "z_surf_sd_m": self.z_surf_sd,
            "sigma_n": self.rms,
            "converged": np.nan,
            "rhat_max": np.nan,
            "ess_min": np.nan,
            "nu": self.model.nu,
            "k": np.nan if self.k is None else self.k,
            "m": np.nan if self.m is None else self.m,
            "rss_n2": self.rss,
            "constraint_active": self.constraint_active,
            **flag_columns("; ".join(self.notes)),
        }


def profile_rss(data: FitData, z_surf: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Profile objective L(z_s) [N²] and the closed-form E*(z_s) [Pa] for each trial z_s.

    Vectorised: ``z_surf`` of shape (M,) gives arrays of shape (M,).  L is summed from the
    residuals themselves (no cancellation near a perfect fit), by the compiled loop of
    :func:`palpbayes.shapekernel.scale_rss` (no (M × n) array is formed).
    """
    return scale_rss(z_surf, data.z, data.force, data.model)


def _scalar_rss(data: FitData, z: float) -> float:
    """L(z_s) [N²] at one trial surface height z [m]."""
    return float(profile_rss(data, np.array([z]))[0][0])


def _minimise(data: FitData, lo: float, hi: float) -> float:
    grid = np.linspace(lo, hi, GRID_POINTS)
    rss, _ = profile_rss(data, grid)
    i = int(np.argmin(rss))
    a, b = grid[max(i - 1, 0)], grid[min(i + 1, grid.size - 1)]
    # search in x = (z - a)/(b - a) so Brent's relative tolerance acts on the bracket width
    width = b - a
    res = optimize.minimize_scalar(
        lambda x: _scalar_rss(data, a + x * width), bounds=(0.0, 1.0), method="bounded",
        options={"xatol": 1e-10},
    )
    res.x = a + res.x * width
    best = float(res.x) if res.fun <= rss[i] else float(grid[i])
    return best


def fit_lsq_data(data: FitData, *, level: float = LEVEL, trace_id: str = "") -> LSQResult:
    """Least-squares fit on prepared data (see :func:`fit_lsq`)."""
    lo, hi = data.z_contact, data.z_top
    z_best = _minimise(data, lo, hi)
    # was the constraint binding? search a little below the admissible range too
    span = hi - lo
    z_free = _minimise(data, lo - span, hi)
    rss_best, estar_best = profile_rss(data, np.array([z_best]))
    rss, estar = float(rss_best[0]), float(estar_best[0])
    active = z_free < lo - 1e-12 and _scalar_rss(data, z_free) < rss
    if not estar > 0:
        raise FitError(
            f"{trace_id or 'trace'}: least squares gives a non-positive modulus; the force does "
            "not rise with depth (check sign and units)"
        )
    model = data.model
    depth = z_best - data.z
    n = data.n_points
    J = np.column_stack([model.shape(depth), estar * model.shape_derivative(depth)])
    s2 = rss / max(n - 2, 1)
    try:
        cov = s2 * np.linalg.inv(J.T @ J)
    except np.linalg.LinAlgError:
        cov = np.full((2, 2), np.nan)
    estar_sd = float(np.sqrt(cov[0, 0]))
    scale = youngs_factor(model.nu)
    E, E_sd = estar * scale, estar_sd * scale
    t = stats.t.ppf(0.5 + level / 2, max(n - 2, 1))
    m = model.exponent
    g = None if m is None else float(model.shape(np.array([1.0]))[0])  # s(1 m) = g
    notes = []
    base = data.baseline
    if base is not None and data.tare == 0.0 and abs(base.level) > data.f_unc:
        notes.append(
            f"untared sensor: the pre-contact force is {format_force(base.level)} (beyond "
            f"F_unc = {format_force(data.f_unc)}), and the paper's model has no offset term, so E "
            "and z_surf are biased: refit with --tare (or read the Bayesian row, which fits "
            "the offset)")
    return LSQResult(
        E=E, E_sd=E_sd, E_lo=E - t * E_sd, E_hi=E + t * E_sd,
        Estar=estar, Estar_sd=estar_sd,
        k=None if g is None else estar * g, m=m,
        z_surf=z_best, z_surf_sd=float(np.sqrt(cov[1, 1])),
        rss=rss, rms=float(np.sqrt(rss / n)), n_points=n,
        z_admissible=(lo, hi), constraint_active=bool(active),
        force_at_surface=float(data.measured_force_at(z_best)),
        level=level, model=model, trace_id=trace_id, cov=cov, notes=tuple(notes),
    )


def fit_lsq(
    trace: IndentationTrace,
    model: ModelSpec | None = None,
    *,
    f_unc: float | None = None,
    fit_fraction: float | None = None,
    max_depth: float | None = None,
    level: float = LEVEL,
    tare: bool = False,
) -> LSQResult:
    """Fit E and z_surf to one trace by the paper's constrained least squares.

    Parameters
    ----------
    trace
        The measurement; its ``tip`` is used when ``model`` is None.
    model
        Contact model (tip, nu, thickness correction); default: ``ModelSpec(trace.tip)``.
    f_unc
        [N] Sensor uncertainty of the surface constraint (48 mN in the paper); None: the
        pre-contact baseline's noise read as a peak-to-peak spec.
    fit_fraction
        Fraction of the penetration skipped (default 0.2 for the flat tip, 0 otherwise).
    max_depth
        [m] Ignore samples deeper than this below the contact onset.
    level
        Probability content of the reported interval.
    tare
        Subtract the pre-contact baseline level from the force first (zero the sensor).

    Returns
    -------
    LSQResult
    """
    data = prepare_trace(trace, model, f_unc=f_unc, fit_fraction=fit_fraction,
                         max_depth=max_depth, tare=tare)
    return fit_lsq_data(data, level=level, trace_id=trace.trace_id)
