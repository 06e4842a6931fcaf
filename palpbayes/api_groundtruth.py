"""The ground truth's front door: Young's modulus of compression tests, one path for
:func:`palpbayes.groundtruth` and ``palpbayes groundtruth`` (as :mod:`palpbayes.api` is the
trace fit's and :mod:`palpbayes.api_map` the map's).

:class:`GroundTruthOptions` holds what a user chooses and checks it
(:meth:`GroundTruthOptions.checked`); :func:`analyse_groundtruth` finds the tests, fits each
(:func:`palpbayes.compression.analyse`) and corrects for the platens into a
:class:`GroundTruth`, whose ``save`` writes the files the command writes
(``groundtruth.csv``, ``groundtruth_summary.csv``, ``groundtruth_laws.csv`` with a law);
:func:`groundtruth` is the two in one call.  Strains are fractions here; the command line's
``--strain-window`` takes percent and converts.

>>> import palpbayes as pb
>>> gt = pb.groundtruth("instron/", seed=0)              # doctest: +SKIP
>>> gt.summary(); gt.save("gt"); gt.plot()               # doctest: +SKIP

This module sits beside the package's other doors, not in :mod:`palpbayes.compression`: it
writes with :func:`palpbayes.campaign.pipeline.write_groundtruth`, and the campaign package
imports the compression package (a door inside it would close an import cycle between them).
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING

import pandas as pd

from . import outputs
from .compression import (
    DEFAULT_STRAIN_WINDOW,
    analyse,
    check_strain_window,
    correct_for_platens,
    summarise_corrected,
)
from .contact import check_nu
from .errors import InputError
from .io.groundtruth_inputs import collect_tests, scan_inputs
from .io.instron import CompressionTest

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["KEYWORDS", "FLAGS", "GroundTruthOptions", "GroundTruth", "analyse_groundtruth",
           "groundtruth"]

#: How :meth:`GroundTruthOptions.checked` names the options in its messages: by the Python
#: keywords (:func:`groundtruth`) ...
KEYWORDS: Mapping[str, str] = {"area_m2": "area_m2", "height_m": "height_m",
                               "platens": "platens", "nu": "nu",
                               "example": "platens='bonded', nu=0.3"}
#: ... or by the command line's flags (``palpbayes groundtruth``).
FLAGS: Mapping[str, str] = {"area_m2": "--area-m2", "height_m": "--height-m",
                            "platens": "--platens", "nu": "--nu",
                            "example": "--platens bonded --nu 0.3"}
_PLATENS = ("lubricated", "bonded")

#: What :func:`groundtruth` reads: one path or test, or several.
Inputs = (str | os.PathLike | CompressionTest
          | Iterable[str | os.PathLike | CompressionTest])


@dataclass(frozen=True)
class GroundTruthOptions:
    """How compression tests are analysed (the options of ``palpbayes groundtruth``).

    Parameters
    ----------
    strain_window
        [-] (lo, hi) fit window as fractions of the height (default (0, 0.05): 0-5 %),
        measured from the toe offset unless ``toe_compensation`` is False
        (:func:`palpbayes.compression.fit_modulus`).
    toe_compensation
        Measure the window from the toe offset (default) instead of from zero measured strain.
    skip_toe
        Also drop the points below twice the toe offset (exact for a quadratic toe).
    area_m2, height_m
        [m²], [m] The specimens' cross-section and height for every test, overriding the
        exports' headers and a manifest's columns (None: theirs).
    law
        ``"linear"`` (the line over the window), a hyperelastic law fitted to the whole
        loading curve (``"neo-hookean"``, ``"yeoh"`` ...) or ``"auto"`` (the laws compared
        by PSIS-LOO, each material's best kept).
    strain
        (lo, hi) compressive strains [-] (or ``"0.05,0.20"``): also each test's chord modulus
        between them under its law.
    seed
        Seed of the law fits' draws.
    platens, nu
        Correct each test's E for its platens, ``"bonded"`` or ``"lubricated"``, at the
        blocks' Poisson ratio nu [-] (the two go together; None: no correction).
    """

    strain_window: tuple[float, float] = DEFAULT_STRAIN_WINDOW
    toe_compensation: bool = True
    skip_toe: bool = False
    area_m2: float | None = None
    height_m: float | None = None
    law: str = "linear"
    strain: str | Sequence[float] | None = None
    seed: int = 0
    platens: str | None = None
    nu: float | None = None

    def checked(self, names: Mapping[str, str] = KEYWORDS) -> GroundTruthOptions:
        """These options checked, the window as two floats and nu as a float.

        ``names`` says how the messages name the options (:data:`KEYWORDS` or
        :data:`FLAGS`).  The law and the chord strains are checked by
        :func:`palpbayes.compression.analyse`, after the inputs are found.

        Raises
        ------
        InputError
            An option out of range (the message names it), or ``platens`` without ``nu``
            or ``nu`` without ``platens``.
        """
        window = check_strain_window(self.strain_window)
        for key in ("area_m2", "height_m"):
            value = getattr(self, key)
            if value is not None and not _positive(value):
                raise InputError(f"{names[key]} must be a positive number, got {value}")
        if (self.platens is None) != (self.nu is None):
            raise InputError(f"{names['platens']} and {names['nu']} go together: the platen "
                             "correction depends on the Poisson ratio (e.g. "
                             f"{names['example']})")
        if self.platens is not None and self.platens not in _PLATENS:
            raise InputError(f"{names['platens']} {self.platens!r}: use 'lubricated' or "
                             "'bonded'")
        nu = None if self.nu is None else check_nu(self.nu)
        return replace(self, strain_window=window, nu=nu)


@dataclass(frozen=True, eq=False)
class GroundTruth:
    """Young's modulus of every compression test and of every material.

    Attributes
    ----------
    tests
        One row per test (``groundtruth.csv``): ``E_pa`` and ``E_sd_pa`` [Pa], the strains
        fitted [-], the law's columns; ``E_corrected_pa`` with platens
        (docs/outputs.md, "groundtruth.csv").
    materials
        One row per material (``groundtruth_summary.csv``): ``E_mean_pa``, ``E_sd_pa`` and
        ``E_sem_pa`` [Pa] over its tests, the window and the rule.
    laws
        With a law other than ``"linear"``: the law comparison per material
        (``groundtruth_laws.csv``); else None.
    skipped
        CSV files found in the input folders that are not compression tests.
    inputs
        The inputs as given (files, folders, manifests or tests).
    options
        The options used, checked.
    """

    tests: pd.DataFrame
    materials: pd.DataFrame
    laws: pd.DataFrame | None
    skipped: list[Path]
    inputs: tuple[str | os.PathLike | CompressionTest, ...]
    options: GroundTruthOptions

    def summary(self) -> pd.DataFrame:
        """The per-material table as :meth:`save` writes it to ``groundtruth_summary.csv``
        (a copy)."""
        return self.materials.copy()

    def save(self, out: str | os.PathLike) -> Path:
        """Write what ``palpbayes groundtruth --out OUT`` writes, with its writers:
        ``groundtruth.csv`` and ``groundtruth_summary.csv``
        (:func:`palpbayes.campaign.pipeline.write_groundtruth`) and, with a law,
        ``groundtruth_laws.csv``, each atomically; the folder is made.  Returns it.

        Raises
        ------
        InputError
            ``out`` exists and is not a folder.
        """
        from .campaign.pipeline import write_groundtruth
        from .io.atomic import write_csv_atomic

        out = Path(out)
        if out.exists() and not out.is_dir():
            raise InputError(f"{out} exists and is not a folder")
        out.mkdir(parents=True, exist_ok=True)
        write_groundtruth(self.tests, self.materials, out)
        if self.laws is not None:
            write_csv_atomic(self.laws, out / outputs.GROUNDTRUTH_LAWS, float_format="%.10g")
        return out

    def plot(self) -> Figure:
        """Each test's stress-strain curve with its fitted line over the window, one panel
        per material (:func:`palpbayes.plots.compression.plot_compression_tests`; the tests
        are read again from :attr:`inputs`)."""
        from .plots.compression import plot_compression_tests

        tests = collect_tests(self.inputs, area_m2=self.options.area_m2,
                              height_m=self.options.height_m)
        return plot_compression_tests(tests, self.tests)

    def __repr__(self) -> str:
        from .units import format_pressure

        m = self.materials
        corrected = "E_corrected_mean_pa" in m
        mean, sd = (("E_corrected_mean_pa", "E_corrected_sd_pa") if corrected
                    else ("E_mean_pa", "E_sd_pa"))
        parts = []
        for _, r in m.head(3).iterrows():
            spread = f" ± {format_pressure(r[sd], 2)}" if math.isfinite(r[sd]) else ""
            parts.append(f"{r['material']} E {format_pressure(r[mean])}{spread}")
        n, k = len(self.tests), len(m)
        return (f"GroundTruth({n} test{'s' if n != 1 else ''}, {k} material"
                f"{'s' if k != 1 else ''}: " + ", ".join(parts) + (", ..." if k > 3 else "")
                + (f"; corrected for {self.options.platens} platens at nu "
                   f"{self.options.nu:g}" if corrected else "")
                + (f"; law {self.options.law}" if self.laws is not None else "") + ")")


def _positive(value) -> bool:
    try:
        v = float(value)
    except (TypeError, ValueError):
        return False
    return math.isfinite(v) and v > 0


def _as_list(inputs: Inputs) -> list:
    if isinstance(inputs, str | os.PathLike | CompressionTest):
        return [inputs]
    return list(inputs)


def analyse_groundtruth(inputs: Inputs, options: GroundTruthOptions, *,
                        progress: bool | None = None) -> GroundTruth:
    """Find the compression tests of ``inputs``, fit each and correct for the platens.

    Parameters
    ----------
    inputs
        Test files, folders (searched recursively for ``*.csv``; files that are not
        compression tests are skipped), ground-truth manifests, or
        :class:`~palpbayes.io.instron.CompressionTest` objects.
    options
        Checked options (:meth:`GroundTruthOptions.checked`).
    progress
        A progress bar over the law fits (None: when stderr is a terminal).

    Raises
    ------
    DataFileError
        An input that does not exist, no test found, or a test that cannot be fitted.
    InputError
        An unknown law or bad chord strains.
    """
    items = _as_list(inputs)
    paths = [p for p in items if not isinstance(p, CompressionTest)]
    _, _, skipped = scan_inputs(paths)
    o = options
    per_file, summary, laws = analyse(
        items, strain_window=o.strain_window, toe_compensation=o.toe_compensation,
        skip_toe=o.skip_toe, area_m2=o.area_m2, height_m=o.height_m, law=o.law,
        chord=o.strain, seed=o.seed, progress=progress, return_laws=True)
    if o.platens is not None:
        per_file = correct_for_platens(per_file, o.platens, o.nu)
        summary = summarise_corrected(per_file, summary)
    return GroundTruth(tests=per_file, materials=summary,
                       laws=laws if o.law != "linear" else None, skipped=skipped,
                       inputs=tuple(items), options=o)


# Many parameters: the options of `palpbayes groundtruth` by their Python names (GroundTruthOptions
# holds them): the door a user types.
def groundtruth(
    inputs: Inputs,
    *,
    strain_window: Sequence[float] = DEFAULT_STRAIN_WINDOW,
    toe_compensation: bool = True,
    skip_toe: bool = False,
    area_m2: float | None = None,
    height_m: float | None = None,
    law: str = "linear",
    strain: str | Sequence[float] | None = None,
    seed: int = 0,
    progress: bool | None = None,
    platens: str | None = None,
    nu: float | None = None,
) -> GroundTruth:
    """Young's modulus from compression tests, as ``palpbayes groundtruth`` finds it.

    Each test's modulus is the slope of a straight line over a window of toe-compensated
    engineering strain (:mod:`palpbayes.compression`), with a standard error that allows for
    autocorrelated residuals; the materials' means, sds and standard errors over their tests.

    Parameters
    ----------
    inputs
        Test files, folders (searched recursively; other CSV files are skipped), ground-truth
        manifests (``file, specimen, material, area_m2, height_m``), or
        :class:`~palpbayes.io.instron.CompressionTest` objects; one or several.
    strain_window
        [-] Fit window as **fractions** (default (0, 0.05), i.e. the command line's
        ``--strain-window 0 5`` in percent).
    toe_compensation, skip_toe, area_m2, height_m, law, strain, seed, platens, nu
        See :class:`GroundTruthOptions` (area [m²], height [m], strains [-]).
    progress
        A progress bar over the law fits (None: when stderr is a terminal).

    Returns
    -------
    GroundTruth
        ``.tests`` (``groundtruth.csv``), ``.summary()`` (``groundtruth_summary.csv``),
        ``.laws``, ``.save(DIR)`` (the command's files, the same bytes), ``.plot()``.

    Raises
    ------
    InputError
        A bad option (the message names it).
    DataFileError
        An input that does not exist, no compression test found, or one that cannot be
        fitted.
    """
    options = GroundTruthOptions(
        strain_window=strain_window, toe_compensation=toe_compensation, skip_toe=skip_toe,
        area_m2=area_m2, height_m=height_m, law=law, strain=strain, seed=seed,
        platens=platens, nu=nu).checked(KEYWORDS)
    return analyse_groundtruth(inputs, options, progress=progress)
