"""Ground truth: Young's modulus from uniaxial compression tests (Instron exports).

Engineering quantities: strain eps = compression / initial height [-], stress sigma = load /
initial cross-section [Pa], both positive in compression.

The rule (in the spirit of ISO 844 and ASTM D575 / D3574: the modulus is the slope of the
initial, nearly linear part of the stress-strain curve, with the strain origin corrected for the
toe region before full platen contact, the zero-point construction of ASTM D638 Annex A1)
-----------------------------------------------------------------------------------------------
1. Only the loading branch is used: samples up to the first maximum of the compression.
2. A straight line ``sigma = E·(eps - eps0)`` is fitted by ordinary least squares to the points
   whose *toe-compensated* strain ``eps - eps0`` lies in the window ``[lo, hi]``
   (default 0-5 %).  ``eps0``, the toe offset, is where the fitted line reaches zero stress;
   because the window depends on ``eps0`` the fit is iterated from ``eps0 = 0`` until the set of
   points no longer changes (a fixed point; typically 2-4 iterations).  The line's intercept
   absorbs a load offset, so neither the toe nor a tare error biases the slope the way a fit
   through the measured origin would (-13 % on the EF50 phantom).
3. ``toe_compensation=False`` applies the window to the measured strain instead (the fitted line
   still has an intercept).  ``skip_toe=True`` further drops the points below ``2·eps0`` in
   measured strain: that is where a toe that grows quadratically and joins the line tangentially
   ends (the simulator's toe model, :func:`palpbayes.simulate.toe_compression`), so on such
   curves the slope is exact, whereas the default keeps the upper half of the toe and reads a
   slope 1-2.3 % low when the toe spans 1.3-2 % strain (the simulator's 0.2 mm slack on its
   30 / 20 mm blocks; its campaigns are analysed exactly with ``skip_toe=True``).

Why the default keeps the upper toe and uses 0-5 %: the silicone phantoms stiffen with strain
(their tangent modulus grows ~2 % per 1 % strain, as a neo-Hookean solid does), so a window
that starts further from the toe reads a higher modulus; the published moduli of the shipped
phantoms were obtained from a plain 0-5 % fit that *includes* the toe.  With the default, the
shipped Instron 5900 exports give (mean ± sd of ten tests, published value in brackets)
EF10_50T 15.98 ± 0.39 kPa (15.52 ± 0.40, +3.0 %), EF30_0T 103.5 ± 4.9 kPa (97.26 ± 4.16,
+6.4 %), EF50_12_5T 121.8 ± 1.9 kPa (111.1 ± 6.44, +9.6 %); ``skip_toe=True`` gives +3.1, +7.2
and +12.9 %, and a window of 0-2 % with ``skip_toe=True`` -0.7, -0.5 and +5.2 %.  The spread
of these numbers is the real method uncertainty of a "linear modulus" of a non-linear material;
report the window with every modulus.

Inputs
------
Finding the exports (files, folders, ground-truth manifests) is
:mod:`palpbayes.io.groundtruth_inputs`; :func:`collect_tests`, :func:`scan_inputs`,
:func:`read_groundtruth_manifest` and :func:`is_groundtruth_manifest` are re-exported here.

Uncertainty
-----------
``E_sd_pa`` is the standard error of the fitted slope from the residual covariance of the
regression, ``sqrt(s² / sum((eps - mean eps)²))`` with ``s² = RSS / (n - 2)``.  It is a **lower
bound** on the real uncertainty: the residuals of a curve sampled at 10-25 Hz are correlated,
and the window choice, the non-linearity and the geometry (area, height) are not in it.  The
specimen-to-specimen scatter of a material (``E_sd_pa`` of the summary, ddof = 1) is the
number to compare with palpation estimates.
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

__all__ = [
    "DEFAULT_STRAIN_WINDOW",
    "MIN_POINTS",
    "PER_FILE_COLUMNS",
    "SUMMARY_COLUMNS",
    "GroundTruthFit",
    "fit_modulus",
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

#: Columns of the per-file table, in order.
PER_FILE_COLUMNS = ["file", "specimen", "material", "E_pa", "E_sd_pa", "strain_lo", "strain_hi",
                    "strain_toe", "r2", "n_points"]
#: Columns of the per-material summary, in order.
SUMMARY_COLUMNS = ["material", "n", "E_mean_pa", "E_sd_pa", "E_sem_pa", "strain_lo",
                   "strain_hi", "window_lo", "window_hi"]


@dataclass(frozen=True)
class GroundTruthFit:
    """Modulus of one compression test.

    Attributes
    ----------
    E_pa
        [Pa] Young's modulus, the slope of the fitted line.
    E_sd_pa
        [Pa] Standard error of the slope from the regression residuals (a lower bound on the
        real uncertainty, see the module docstring).
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

    def as_row(self) -> dict:
        """The per-file table row (:data:`PER_FILE_COLUMNS`)."""
        d = asdict(self)
        return {k: d[k] for k in PER_FILE_COLUMNS}


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


def _linfit(x: np.ndarray, y: np.ndarray) -> tuple[float, float, float, float]:
    """Slope, intercept, slope standard error and R² of an ordinary least-squares line."""
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
    return slope, float(intercept), se, r2


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
        slope, intercept, se, r2 = _linfit(eps[mask], sig[mask])
        if not (math.isfinite(slope) and slope > 0):
            raise DataFileError(
                where, f"the load does not rise with compression between {_pct(shift + start)} "
                f"and {_pct(shift + hi)} strain (slope {slope:.4g} Pa)",
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
    return GroundTruthFit(
        E_pa=float(slope), E_sd_pa=float(se),
        strain_lo=float(eps[mask].min()), strain_hi=float(eps[mask].max()),
        strain_toe=float(eps0), r2=float(r2), n_points=n,
        file=test.source, specimen=test.specimen, material=test.material,
        window_lo=lo, window_hi=hi, toe_compensation=bool(toe_compensation),
        skip_toe=bool(skip_toe),
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


def summarise(per_file: pd.DataFrame,
              strain_window: Sequence[float] = DEFAULT_STRAIN_WINDOW) -> pd.DataFrame:
    """Per-material summary of a per-file table.

    Parameters
    ----------
    per_file
        Table with at least ``material``, ``E_pa``, ``strain_lo``, ``strain_hi``.
    strain_window
        [-] The fit window used, written to ``window_lo`` / ``window_hi``.

    Returns
    -------
    pandas.DataFrame
        :data:`SUMMARY_COLUMNS`: ``n``; ``E_mean_pa``, ``E_sd_pa`` (sd over the tests, ddof = 1,
        empty when n = 1) and ``E_sem_pa`` (sd / sqrt(n)) [Pa]; ``strain_lo`` / ``strain_hi``
        the lowest and highest measured strain fitted in any test [-]; the window [-].  Groups
        are in order of first appearance.
    """
    lo, hi = _check_window(strain_window)
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
    })
    return out[SUMMARY_COLUMNS]


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
        One row per test, :data:`PER_FILE_COLUMNS` (E in [Pa], strains [-]).
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
        rows.append(fit.as_row())
    per_file = pd.DataFrame(rows, columns=PER_FILE_COLUMNS)
    per_file["n_points"] = per_file["n_points"].astype(int)
    return per_file, summarise(per_file, window)
