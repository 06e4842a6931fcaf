"""Ground truth: Young's modulus from uniaxial compression tests (Instron exports).

Engineering quantities: strain eps = compression / initial height [-], stress sigma = load /
initial cross-section [Pa], both positive in compression.

The rule
--------
1. Only the loading branch is used: samples up to the first maximum of the compression.
2. A straight line ``sigma = E·(eps - eps0)`` is fitted by ordinary least squares to the points
   whose *toe-compensated* strain ``eps - eps0`` lies in the window ``[lo, hi]``
   (default 0-5 %).  ``eps0``, the toe offset, is where the fitted line reaches zero stress
   (the zero-point construction of ASTM D638 Annex A1: the linear part is extended to zero
   stress and strains are measured from there); because the window depends on ``eps0`` the
   fit is iterated from ``eps0 = 0`` until the set of points no longer changes (a fixed point;
   typically 2-4 iterations).  The line's intercept absorbs a load offset, so neither the toe
   nor a tare error biases the slope the way a fit through the measured origin would (-13 %
   on the EF50 phantom).
3. ``toe_compensation=False`` applies the window to the measured strain instead (the fitted line
   still has an intercept).  ``skip_toe=True`` further drops the points below ``2·eps0`` in
   measured strain: that is where a toe that grows quadratically and joins the line tangentially
   ends (the simulator's toe model, :func:`palpbayes.simulate.toe_compression`), so on such
   curves the slope is exact, whereas the default keeps the upper half of the toe and reads a
   slope 1-2.3 % low when the toe spans 1.3-2 % strain (the simulator's 0.2 mm slack on its
   30 / 20 mm blocks; its campaigns are analysed exactly with ``skip_toe=True``).

Every test also gets, from :func:`analyse`:

* ``E_plain_pa`` (``E_plain_sd_pa``): the plain fit, the same window applied to the *measured*
  strain, i.e. from the first sample of the export, toe included.  This is the convention of
  the phantom dataset: its README says the authors' window is not stated and that a linear fit
  over 0-5 % strain lands within a few percent of their table;
* ``E_window_spread_pa``: max - min of E over three nearby windows
  (:func:`sensitivity_windows`: 0-3, 0-5 and 1-6 % for the default), with the options of
  ``E_pa``.  The summary gives the mean of the per-test spreads.

Which number to compare with what
---------------------------------
The silicone phantoms stiffen with strain (their tangent modulus grows ~2 % per 1 % strain, as
a neo-Hookean solid does), so a "linear modulus" depends on which part of the curve the window
covers, and toe compensation moves the window up the curve by eps0.  On the shipped Instron
5900 exports (mean ± sd of ten tests; published value, then difference):

=============  ========================  ========================  ============  ============
phantom        E_pa (toe-compensated)    E_plain_pa (plain)        published     window spread
=============  ========================  ========================  ============  ============
EF10_50T       15.98 ± 0.39 kPa, +3.0 %  15.94 ± 0.44 kPa, +2.7 %  15.52 ± 0.40  0.76 kPa (4.8 %)
EF30_0T        103.5 ± 4.9 kPa, +6.4 %   101.8 ± 3.9 kPa, +4.7 %   97.26 ± 4.16  9.2 kPa (8.8 %)
EF50_12_5T     121.8 ± 1.9 kPa, +9.6 %   112.0 ± 7.9 kPa, +0.8 %   111.1 ± 6.44  13.1 kPa (10.7 %)
=============  ========================  ========================  ============  ============

* Compare the **published table** with ``E_plain_mean_pa``: it is the published convention, so
  the difference measures the data, not a difference of definitions (toe compensation alone
  moves EF50 by +8.8 %, which is a change of convention, not an error of the published value).
* Use ``E_mean_pa`` (toe-compensated, the default) as the ground truth of one's own tests and
  of ``palpbayes compare``: it does not depend on where the machine started recording, on a
  tare offset or on platen seating, which differ between set-ups; quote
  ``E_window_spread_pa`` with it as the method uncertainty of a linear modulus of a non-linear
  material, and always report the window (the summary's ``rule`` column names it).
* ``skip_toe=True`` gives +3.1, +7.2 and +12.9 % against the published values, and a window of
  0-2 % with ``skip_toe=True`` -0.7, -0.5 and +5.2 %.

Standards
---------
No standard defines this slope modulus for soft silicone, and the 0-5 % window is taken from
the dataset, not from a standard.  ISO 7743 (Rubber, vulcanized or thermoplastic -
Determination of compression stress-strain properties) is the test method for rubber in
compression (test pieces, lubricated or bonded plates); ASTM D575 (Rubber properties in
compression) measures the force at a specified deflection (method A) or the deflection at a
specified force (method B), not a modulus; ASTM D3574 (flexible urethane foams) gives
force-deflection values; ISO 844 defines a compressive modulus, but for *rigid* cellular
plastics.  The only construction borrowed from a standard is the toe compensation of ASTM D638
(tensile properties of plastics), Annex A1.

Inputs
------
Finding the exports (files, folders, ground-truth manifests) is
:mod:`palpbayes.io.groundtruth_inputs`; :func:`collect_tests`, :func:`scan_inputs`,
:func:`read_groundtruth_manifest` and :func:`is_groundtruth_manifest` are re-exported here.

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
import os
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import asdict, dataclass, replace
from pathlib import Path

import numpy as np
import pandas as pd

from .errors import DataFileError, FitError, InputError
from .io.groundtruth_inputs import (
    collect_tests,
    is_groundtruth_manifest,
    read_groundtruth_manifest,
    scan_inputs,
)
from .io.instron import CompressionTest
from .units import format_pressure

__all__ = [
    "DEFAULT_STRAIN_WINDOW",
    "MIN_POINTS",
    "PER_FILE_COLUMNS",
    "SUMMARY_COLUMNS",
    "GroundTruthFit",
    "fit_modulus",
    "hac_slope_se",
    "sensitivity_windows",
    "describe_rule",
    "analyse",
    "summarise",
    "collect_tests",
    "scan_inputs",
    "is_groundtruth_manifest",
    "read_groundtruth_manifest",
]

#: Default fit window [-] in toe-compensated engineering strain (0-5 %).
DEFAULT_STRAIN_WINDOW: tuple[float, float] = (0.0, 0.05)
#: A window with fewer points than this is refused.
MIN_POINTS = 5
_MAX_ITERATIONS = 100
#: Bound on the AR(1) prewhitening coefficient and the bandwidth's autocorrelation.
_RHO_MAX = 0.97

#: Columns of the per-file table, in order.
PER_FILE_COLUMNS = ["file", "specimen", "material", "E_pa", "E_sd_pa", "strain_lo", "strain_hi",
                    "strain_toe", "r2", "n_points", "E_ols_sd_pa", "resid_acf1", "hac_lags",
                    "E_plain_pa", "E_plain_sd_pa", "E_window_spread_pa"]
#: Columns of the per-material summary, in order.
SUMMARY_COLUMNS = ["material", "n", "E_mean_pa", "E_sd_pa", "E_sem_pa", "strain_lo",
                   "strain_hi", "window_lo", "window_hi", "E_plain_mean_pa", "E_plain_sd_pa",
                   "E_window_spread_pa", "rule"]
#: Extra per-file columns :func:`analyse` adds to the :class:`GroundTruthFit` fields.
_EXTRA_COLUMNS = ("E_plain_pa", "E_plain_sd_pa", "E_window_spread_pa")


@dataclass(frozen=True)
class GroundTruthFit:
    """Modulus of one compression test.

    Attributes
    ----------
    E_pa
        [Pa] Young's modulus, the slope of the fitted line.
    E_sd_pa
        [Pa] Standard error of the slope, prewhitened Newey-West (HAC) estimate (module
        docstring): valid for autocorrelated residuals.
    strain_lo, strain_hi
        [-] Range of *measured* engineering strain covered by the fitted points.
    strain_toe
        [-] Toe offset eps0: measured strain where the fitted line reaches zero stress.
    r2
        [-] Coefficient of determination of the linear fit.
    n_points
        Number of points fitted.
    file, specimen, material
        Labels of the test.
    window_lo, window_hi
        [-] The fit window as requested (toe-compensated strain unless ``toe_compensation``
        was False).
    toe_compensation, skip_toe
        The options used.
    E_ols_sd_pa
        [Pa] The ordinary-least-squares standard error of the slope (assumes independent
        residuals; too small when they are correlated).
    resid_acf1
        [-] Lag-1 sample autocorrelation of the residuals of the fit,
        ``sum u_t u_(t-1) / sum u_t²`` (0 for independent residuals, near 1 for a smooth
        curvature).
    hac_lags
        Bandwidth L (number of lags) of the HAC estimate.
    """

    E_pa: float
    E_sd_pa: float
    strain_lo: float
    strain_hi: float
    strain_toe: float
    r2: float
    n_points: int
    file: str
    specimen: str
    material: str
    window_lo: float = DEFAULT_STRAIN_WINDOW[0]
    window_hi: float = DEFAULT_STRAIN_WINDOW[1]
    toe_compensation: bool = True
    skip_toe: bool = False
    E_ols_sd_pa: float = math.nan
    resid_acf1: float = math.nan
    hac_lags: int = 0

    def as_row(self) -> dict:
        """The per-file table row (:data:`PER_FILE_COLUMNS`; the columns :func:`analyse` adds,
        ``E_plain_pa``, ``E_plain_sd_pa`` and ``E_window_spread_pa``, are NaN here)."""
        d = asdict(self)
        return {k: d.get(k, math.nan) for k in PER_FILE_COLUMNS}


# ----------------------------------------------------------------------------- fitting


def _check_window(strain_window: Sequence[float]) -> tuple[float, float]:
    try:
        lo, hi = (float(v) for v in strain_window)
    except (TypeError, ValueError):
        raise InputError(f"strain_window must be two numbers (lo, hi), got {strain_window!r}") \
            from None
    if not (math.isfinite(lo) and math.isfinite(hi) and 0.0 <= lo < hi):
        raise InputError(f"strain_window must satisfy 0 <= lo < hi, got ({lo}, {hi})")
    if hi > 1.0:
        raise InputError(f"strain_window is a fraction of the height (0.05 = 5 %), got "
                         f"({lo}, {hi}); did you give percent?")
    return lo, hi


def _clip_rho(r: float) -> float:
    return float(min(max(r, 0.0), _RHO_MAX)) if math.isfinite(r) else 0.0


def _lag1(a: np.ndarray) -> float:
    """Lag-1 autoregression coefficient sum a_t a_(t-1) / sum a_(t-1)² (0 if undefined)."""
    den = float(a[:-1] @ a[:-1]) if a.size > 1 else 0.0
    return float(a[1:] @ a[:-1]) / den if den > 0 else 0.0


def _acf1(u: np.ndarray) -> float:
    """Lag-1 sample autocorrelation sum u_t u_(t-1) / sum u_t² of a mean-zero series."""
    u = u - u.mean()
    den = float(u @ u)
    return float(u[1:] @ u[:-1]) / den if den > 0 and u.size > 1 else math.nan


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


def _linfit(x: np.ndarray, y: np.ndarray) -> tuple[float, float, float, float, np.ndarray]:
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


def fit_modulus(
    test: CompressionTest,
    strain_window: Sequence[float] = DEFAULT_STRAIN_WINDOW,
    toe_compensation: bool = True,
    *,
    skip_toe: bool = False,
) -> GroundTruthFit:
    """Young's modulus of one compression test by the rule of the module docstring.

    Parameters
    ----------
    test
        The test (SI units, compression and load positive in compression).
    strain_window
        [-] (lo, hi) fit window as fractions of the height (default (0, 0.05) = 0-5 %), in
        toe-compensated strain when ``toe_compensation`` is True.
    toe_compensation
        Measure the window from the toe offset eps0 (default) rather than from zero.
    skip_toe
        Also drop the points below 2·eps0 of measured strain (exact for a quadratic toe).

    Returns
    -------
    GroundTruthFit

    Raises
    ------
    DataFileError
        Fewer than :data:`MIN_POINTS` points in the window, a load that does not rise with
        compression, or a test that ends before the window does.
    InputError
        An invalid window.
    """
    lo, hi = _check_window(strain_window)
    where = test.source or f"compression test {test.specimen!r}"
    eps_all, sig_all = test.strain, test.stress_pa
    k = int(np.argmax(eps_all))  # loading branch only
    eps, sig = eps_all[: k + 1], sig_all[: k + 1]
    steps = np.diff(eps)
    step = float(np.median(np.abs(steps))) if steps.size else 0.0

    eps0 = 0.0
    previous: bytes | None = None
    seen: set[bytes] = set()
    for _ in range(_MAX_ITERATIONS):
        shift = eps0 if toe_compensation else 0.0
        start = max(lo, eps0) if (toe_compensation and skip_toe) else lo
        mask = (eps - shift >= start) & (eps - shift <= hi)
        n = int(mask.sum())
        if n < MIN_POINTS:
            raise DataFileError(
                where, f"only {n} point(s) of the loading curve lie in the strain window "
                f"{_pct(shift + start)}-{_pct(shift + hi)} of measured strain (window "
                f"{_pct(lo)}-{_pct(hi)}, toe offset {_pct(eps0)}); at least {MIN_POINTS} "
                "are needed", "use a wider strain window or check the units and the geometry",
            )
        slope, intercept, se, r2, resid = _linfit(eps[mask], sig[mask])
        if not (math.isfinite(slope) and slope > 0):
            raise DataFileError(
                where, f"the load does not rise with compression between {_pct(shift + start)} "
                f"and {_pct(shift + hi)} strain (slope {format_pressure(slope, 4)})",
                "check that the file is a compression test and the load column is the load",
            )
        eps0 = -intercept / slope
        key = np.packbits(mask).tobytes()
        if not toe_compensation or key == previous or key in seen:
            break  # a fixed point (or, rarely, a cycle of point sets: keep the last fit)
        seen.add(key)
        previous = key
    else:  # pragma: no cover - the point sets are finite and cycles are detected
        raise FitError(f"{where}: the toe offset did not settle in {_MAX_ITERATIONS} iterations")

    need = (eps0 if toe_compensation else 0.0) + hi
    if eps.max() < need - step:
        raise DataFileError(
            where, f"the test reaches only {_pct(float(eps.max()))} strain but the window "
            f"{_pct(lo)}-{_pct(hi)} needs {_pct(need)} (toe offset {_pct(eps0)})",
            "use a narrower strain window",
        )
    hac_se, lags = hac_slope_se(eps[mask], resid)
    return GroundTruthFit(
        E_pa=float(slope), E_sd_pa=float(hac_se),
        strain_lo=float(eps[mask].min()), strain_hi=float(eps[mask].max()),
        strain_toe=float(eps0), r2=float(r2), n_points=n,
        file=test.source, specimen=test.specimen, material=test.material,
        window_lo=lo, window_hi=hi, toe_compensation=bool(toe_compensation),
        skip_toe=bool(skip_toe), E_ols_sd_pa=float(se), resid_acf1=_acf1(resid),
        hac_lags=int(lags),
    )


def _pct(x: float) -> str:
    return f"{100 * x:.3g} %"


# ----------------------------------------------------------------------------- tables


def _label(test: CompressionTest, mapping: Mapping[str, str] | None) -> str | None:
    if not mapping:
        return None
    src = Path(test.source) if test.source else None
    for key in (test.specimen, *((str(src), src.name, src.stem) if src else ())):
        if key in mapping:
            return str(mapping[key])
    return None


def sensitivity_windows(
    strain_window: Sequence[float] = DEFAULT_STRAIN_WINDOW,
) -> tuple[tuple[float, float], ...]:
    """The windows of the window-sensitivity figure ``E_window_spread_pa``.

    For a window [lo, hi] of width w: [lo, lo + 0.6·w] (shorter), [lo, hi] (the window) and
    [lo + 0.2·w, hi + 0.2·w] (shifted up); 0-3 %, 0-5 % and 1-6 % for the default 0-5 %.
    """
    lo, hi = _check_window(strain_window)
    w = hi - lo
    return ((lo, round(lo + 0.6 * w, 12)), (lo, hi),
            (round(lo + 0.2 * w, 12), round(hi + 0.2 * w, 12)))


def _pct_range(window: Sequence[float]) -> str:
    return f"{100 * window[0]:g}-{100 * window[1]:g} %"


def describe_rule(strain_window: Sequence[float] = DEFAULT_STRAIN_WINDOW,
                  toe_compensation: bool = True, skip_toe: bool = False) -> str:
    """One line naming the rule behind the ``E_*`` columns (written to the summary's ``rule``)."""
    window = _check_window(strain_window)
    if toe_compensation:
        origin = ("strain measured from the toe offset (zero-point construction of ASTM D638 "
                  "Annex A1)")
        if skip_toe:
            origin += ", points below twice the toe offset skipped"
    else:
        origin = "of measured strain (no toe compensation)"
    spread = ", ".join(_pct_range(w) for w in sensitivity_windows(window))
    return (f"E: least-squares slope of engineering stress on engineering strain over "
            f"{_pct_range(window)} {origin}; E_plain: the same window of measured strain, the "
            f"phantom dataset's 0-5 % convention (compare with its published table); E_sd per "
            f"test: prewhitened Newey-West HAC; window spread: range of E over {spread}")


def summarise(per_file: pd.DataFrame,
              strain_window: Sequence[float] = DEFAULT_STRAIN_WINDOW, *,
              toe_compensation: bool = True, skip_toe: bool = False) -> pd.DataFrame:
    """Per-material summary of a per-file table.

    Parameters
    ----------
    per_file
        Table with at least ``material``, ``E_pa``, ``strain_lo``, ``strain_hi``; ``E_plain_pa``
        and ``E_window_spread_pa`` when present (else the summary's columns are NaN).
    strain_window
        [-] The fit window used, written to ``window_lo`` / ``window_hi``.
    toe_compensation, skip_toe
        The options used (for the ``rule`` column).

    Returns
    -------
    pandas.DataFrame
        :data:`SUMMARY_COLUMNS`: ``n``; ``E_mean_pa``, ``E_sd_pa`` (sd over the tests, ddof = 1,
        empty when n = 1) and ``E_sem_pa`` (sd / sqrt(n)) [Pa]; ``strain_lo`` / ``strain_hi``
        the lowest and highest measured strain fitted in any test [-]; the window [-];
        ``E_plain_mean_pa`` / ``E_plain_sd_pa`` the same for the plain fits (the dataset
        authors' convention, module docstring); ``E_window_spread_pa`` the mean over the tests
        of each test's window spread [Pa]; ``rule`` (:func:`describe_rule`).  Groups are in
        order of first appearance.
    """
    lo, hi = _check_window(strain_window)
    per_file = per_file.copy()
    for col in _EXTRA_COLUMNS:
        if col not in per_file:
            per_file[col] = np.nan
    g = per_file.groupby("material", sort=False)
    n = g["E_pa"].size()
    sd = g["E_pa"].std(ddof=1)
    out = pd.DataFrame({
        "material": n.index.astype(str),
        "n": n.to_numpy(dtype=int),
        "E_mean_pa": g["E_pa"].mean().to_numpy(),
        "E_sd_pa": sd.to_numpy(),
        "E_sem_pa": (sd / np.sqrt(n)).to_numpy(),
        "strain_lo": g["strain_lo"].min().to_numpy(),
        "strain_hi": g["strain_hi"].max().to_numpy(),
        "window_lo": lo,
        "window_hi": hi,
        "E_plain_mean_pa": g["E_plain_pa"].mean().to_numpy(),
        "E_plain_sd_pa": g["E_plain_pa"].std(ddof=1).to_numpy(),
        "E_window_spread_pa": g["E_window_spread_pa"].mean().to_numpy(),
        "rule": describe_rule((lo, hi), toe_compensation, skip_toe),
    })
    return out[SUMMARY_COLUMNS]


def _variants(test: CompressionTest, fit: GroundTruthFit, window: tuple[float, float],
              toe_compensation: bool, skip_toe: bool) -> dict:
    """The plain fit and the window spread of one test (NaN where a fit is impossible)."""
    out = dict.fromkeys(_EXTRA_COLUMNS, math.nan)
    if toe_compensation:
        try:
            plain = fit_modulus(test, window, toe_compensation=False)
            out["E_plain_pa"], out["E_plain_sd_pa"] = plain.E_pa, plain.E_sd_pa
        except (InputError, FitError):  # auxiliary columns never abort the analysis
            pass
    else:
        out["E_plain_pa"], out["E_plain_sd_pa"] = fit.E_pa, fit.E_sd_pa
    values = []
    for w in sensitivity_windows(window):
        if w == window:
            values.append(fit.E_pa)
            continue
        try:
            values.append(fit_modulus(test, w, toe_compensation, skip_toe=skip_toe).E_pa)
        except (InputError, FitError):  # auxiliary columns never abort the analysis
            return out  # a window the test cannot fill: no spread
    out["E_window_spread_pa"] = float(max(values) - min(values))
    return out


def analyse(
    paths_or_tests: str | os.PathLike | CompressionTest
    | Iterable[str | os.PathLike | CompressionTest],
    *,
    strain_window: Sequence[float] = DEFAULT_STRAIN_WINDOW,
    toe_compensation: bool = True,
    skip_toe: bool = False,
    area_m2: float | None = None,
    height_m: float | None = None,
    materials: Mapping[str, str] | None = None,
    specimens: Mapping[str, str] | None = None,
) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Fit every test and summarise per material.

    Parameters
    ----------
    paths_or_tests
        Files, folders (searched recursively), ground-truth manifests or
        :class:`CompressionTest` objects (see :func:`collect_tests`).
    strain_window
        [-] Fit window, fractions (default (0, 0.05)); see :func:`fit_modulus`.
    toe_compensation, skip_toe
        See :func:`fit_modulus`.
    area_m2, height_m
        [m²], [m] Geometry for every file read, overriding manifests and headers.
    materials, specimens
        Label overrides, keyed by specimen label, file path, file name or file stem.  Default
        labels: specimen = file stem (or the manifest's), material = specimen without its
        replicate suffix (``EF10_50T_A1`` -> ``EF10_50T``, ``White_S1`` -> ``White``).

    Returns
    -------
    per_file : pandas.DataFrame
        One row per test, :data:`PER_FILE_COLUMNS` (E in [Pa], strains [-]): the fit of
        :func:`fit_modulus` plus ``E_plain_pa`` / ``E_plain_sd_pa``, the same window of
        *measured* strain (the dataset authors' convention; equal to ``E_pa`` when
        ``toe_compensation`` is False), and ``E_window_spread_pa``, max - min of E over
        :func:`sensitivity_windows` with the same options (NaN when the test does not reach
        one of them, or the plain fit is impossible).
    summary : pandas.DataFrame
        One row per material, :data:`SUMMARY_COLUMNS` (see :func:`summarise`).
    """
    window = _check_window(strain_window)
    tests = collect_tests(paths_or_tests, area_m2=area_m2, height_m=height_m)
    rows = []
    for test in tests:
        spec = _label(test, specimens)
        mat = _label(test, materials)
        if spec is not None or mat is not None:
            test = replace(test, specimen=spec if spec is not None else test.specimen,
                           material=mat if mat is not None else test.material)
        fit = fit_modulus(test, window, toe_compensation, skip_toe=skip_toe)
        rows.append({**fit.as_row(),
                     **_variants(test, fit, window, toe_compensation, skip_toe)})
    per_file = pd.DataFrame(rows, columns=PER_FILE_COLUMNS)
    per_file["n_points"] = per_file["n_points"].astype(int)
    per_file["hac_lags"] = per_file["hac_lags"].astype(int)
    return per_file, summarise(per_file, window, toe_compensation=toe_compensation,
                               skip_toe=skip_toe)
