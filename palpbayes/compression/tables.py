"""Ground-truth tables: every test fitted (:func:`analyse`) and summarised per material.

:func:`analyse` reads the tests and fits each with
:func:`~palpbayes.compression.fit.fit_modulus` (the rule is in :mod:`palpbayes.compression.fit`);
:func:`summarise` gives one row per material.  Besides ``E_pa``, every test gets:

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

Inputs
------
Finding the exports (files, folders, ground-truth manifests) is
:mod:`palpbayes.io.groundtruth_inputs` (:func:`~palpbayes.io.groundtruth_inputs.collect_tests`,
:func:`~palpbayes.io.groundtruth_inputs.scan_inputs`).
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd

from ..errors import FitError, InputError
from ..io.groundtruth_inputs import collect_tests
from ..io.instron import CompressionTest
from ..material import LINEAR
from ..progress import progress_bar
from .finite import AUTO_LAWS
from .fit import PER_FILE_COLUMNS, GroundTruthFit, fit_modulus
from .laws import check_chord, check_law, fit_tests, law_rows, law_table, summary_columns
from .window import DEFAULT_STRAIN_WINDOW, check_strain_window, describe_rule, sensitivity_windows

__all__ = ["SUMMARY_COLUMNS", "analyse", "summarise"]

#: Columns of the per-material summary, in order.
SUMMARY_COLUMNS = ["material", "n", "E_mean_pa", "E_sd_pa", "E_sem_pa", "strain_lo",
                   "strain_hi", "window_lo", "window_hi", "E_plain_mean_pa", "E_plain_sd_pa",
                   "E_window_spread_pa", "rule"]
#: Extra per-file columns :func:`analyse` adds to the :class:`GroundTruthFit` fields.
_EXTRA_COLUMNS = ("E_plain_pa", "E_plain_sd_pa", "E_window_spread_pa")


def _label(test: CompressionTest, mapping: Mapping[str, str] | None) -> str | None:
    if not mapping:
        return None
    src = Path(test.source) if test.source else None
    for key in (test.specimen, *((str(src), src.name, src.stem) if src else ())):
        if key in mapping:
            return str(mapping[key])
    return None


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
    lo, hi = check_strain_window(strain_window)
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


# Many parameters: the ground truth's rule (window, toe, geometry overrides, law, chord strains) by
# the names of `palpbayes groundtruth`; GroundTruthOptions gathers them at the door.
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
    law: str = LINEAR,
    chord: Sequence[float] | None = None,
    seed: int = 0,
    progress: bool | None = False,
    return_laws: bool = False,
) -> tuple[pd.DataFrame, pd.DataFrame] | tuple[pd.DataFrame, pd.DataFrame, pd.DataFrame]:
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
    law
        ``"linear"`` (the line above: E0 = E), a registered hyperelastic law
        (:func:`palpbayes.material.material_law`) fitted to the whole loading curve
        (:mod:`.finite`), or ``"auto"``: each law of :data:`.finite.AUTO_LAWS`, a material's
        law the best by PSIS-LOO (:mod:`.laws`).
    chord
        (lo, hi) compressive strains [-]: add each test's chord modulus over that window under
        its law (:data:`.laws.CHORD_COLUMNS`).
    seed
        Seed of the law fits' draws.
    progress
        A progress bar over the law fits (None: when stderr is a terminal).
    return_laws
        Also return the law comparison (:func:`.laws.law_table`; one row per material for a
        single law, with elpd NaN for ``linear``).

    Returns
    -------
    per_file : pandas.DataFrame
        One row per test, :data:`PER_FILE_COLUMNS` (E in [Pa], strains [-]): the fit of
        :func:`fit_modulus` plus ``E_plain_pa`` / ``E_plain_sd_pa``, the same window of
        *measured* strain (the dataset authors' convention; equal to ``E_pa`` when
        ``toe_compensation`` is False), and ``E_window_spread_pa``, max - min of E over
        :func:`sensitivity_windows` with the same options (NaN when the test does not reach
        one of them, or the plain fit is impossible); ``area_m2`` and ``height_m``, the
        block's cross-section [m²] and height [m] used.
    summary : pandas.DataFrame
        One row per material, :data:`SUMMARY_COLUMNS` (see :func:`summarise`), then the law's
        (:func:`.laws.summary_columns`).
    laws : pandas.DataFrame
        With ``return_laws``: :data:`.laws.LAW_TABLE_COLUMNS`.
    """
    window = check_strain_window(strain_window)
    law = check_law(law)
    chord = check_chord(chord)
    tests = collect_tests(paths_or_tests, area_m2=area_m2, height_m=height_m)
    rows, labelled = [], []
    for test in tests:
        spec = _label(test, specimens)
        mat = _label(test, materials)
        if spec is not None or mat is not None:
            test = replace(test, specimen=spec if spec is not None else test.specimen,
                           material=mat if mat is not None else test.material)
        labelled.append(test)
        fit = fit_modulus(test, window, toe_compensation, skip_toe=skip_toe)
        rows.append({**fit.as_row(),
                     **_variants(test, fit, window, toe_compensation, skip_toe),
                     "area_m2": test.area_m2, "height_m": test.height_m})
    per_file = pd.DataFrame(rows, columns=PER_FILE_COLUMNS)
    per_file["n_points"] = per_file["n_points"].astype(int)
    per_file["hac_lags"] = per_file["hac_lags"].astype(int)
    laws = list(AUTO_LAWS) if law == "auto" else [law]
    with progress_bar(len(labelled) * len(laws) if law != LINEAR else 0, progress,
                      desc="hyperelastic fits", unit="fit") as bar:
        fits = fit_tests(labelled, laws, seed=seed, progress=bar.update)
    table = law_table(labelled, fits, laws)
    choice = dict(zip(table.loc[table["chosen"], "material"],
                      table.loc[table["chosen"], "law"], strict=True))
    per_file = pd.concat([per_file, pd.DataFrame(law_rows(labelled, fits, choice, chord),
                                                 index=per_file.index)], axis=1)
    summary = summarise(per_file, window, toe_compensation=toe_compensation, skip_toe=skip_toe)
    summary = summary.merge(summary_columns(per_file), on="material", how="left")
    return (per_file, summary, table) if return_laws else (per_file, summary)
