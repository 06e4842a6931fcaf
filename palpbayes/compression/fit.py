"""Young's modulus of one compression test: the toe-compensated slope of a windowed line.

Engineering quantities: strain eps = compression / initial height [-], stress sigma = load /
initial cross-section [Pa], both positive in compression.  The standard error of the slope is
:func:`~palpbayes.compression.hac.hac_slope_se`; the window is checked and described by
:mod:`palpbayes.compression.window`.

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
   ends (the simulator's toe model, :func:`palpbayes.compression.toe_compression`), so on such
   curves the slope is exact, whereas the default keeps the upper half of the toe and reads a
   slope 1-2.3 % low when the toe spans 1.3-2 % strain (the simulator's 0.2 mm slack on its
   30 / 20 mm blocks; its campaigns are analysed exactly with ``skip_toe=True``).

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
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass

import numpy as np

from ..errors import DataFileError, FitError
from ..io.instron import CompressionTest
from ..units import format_pressure
from .hac import hac_slope_se, linfit, resid_acf1
from .window import DEFAULT_STRAIN_WINDOW, check_strain_window

__all__ = ["MIN_POINTS", "PER_FILE_COLUMNS", "GroundTruthFit", "fit_modulus"]

#: A window with fewer points than this is refused.
MIN_POINTS = 5
_MAX_ITERATIONS = 100

#: Columns of the per-file table, in order.
PER_FILE_COLUMNS = ["file", "specimen", "material", "E_pa", "E_sd_pa", "strain_lo", "strain_hi",
                    "strain_toe", "r2", "n_points", "E_ols_sd_pa", "resid_acf1", "hac_lags",
                    "E_plain_pa", "E_plain_sd_pa", "E_window_spread_pa", "area_m2", "height_m"]


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
    lo, hi = check_strain_window(strain_window)
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
        slope, intercept, se, r2, resid = linfit(eps[mask], sig[mask])
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
        skip_toe=bool(skip_toe), E_ols_sd_pa=float(se), resid_acf1=resid_acf1(resid),
        hac_lags=int(lags),
    )


def _pct(x: float) -> str:
    return f"{100 * x:.3g} %"
