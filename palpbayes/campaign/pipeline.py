"""The fitting pipeline behind ``palpbayes report CAMPAIGN``: fit, ground truth, compare.

:func:`run_pipeline` fits a campaign folder with both methods
(:func:`palpbayes.campaign.run.fit_campaign`), analyses its compression tests when the
campaign has ``groundtruth/`` (:func:`palpbayes.compression.analyse`, written by
:func:`write_groundtruth`) and pools and compares
(:func:`palpbayes.campaign.comparison.compare`), into one results folder.
A results folder fitted before from the same campaign is reused fit by fit: a trace's fit is
kept only when its inputs are unchanged (the numbers read from its file and its manifest row,
the options, the palpbayes version: :func:`palpbayes.campaign.partial.read_partial`), every
other trace is refitted, and the ground truth, pooling, comparison and gap that follow are
computed again from the fits as they now are.  Another campaign's folder needs ``force``.
:func:`example_campaign_dir` locates the campaign shipped with a source checkout.

This module and the command line are the only writers of a results folder's ground-truth
tables; reading a results folder is :mod:`palpbayes.campaign.results`, the PDF
:mod:`palpbayes.reporting`.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from .. import __version__, outputs
from ..errors import InputError, OutputExistsError

if TYPE_CHECKING:
    import pandas as pd

    from .fitjob import FitOptions

__all__ = ["example_campaign_dir", "run_pipeline", "write_groundtruth", "check_reusable",
           "write_gap"]


def write_groundtruth(per_file: pd.DataFrame, per_group: pd.DataFrame,
                      out_dir: str | os.PathLike) -> tuple[Path, Path]:
    """Write the ground-truth tables of :func:`palpbayes.compression.analyse` into ``out_dir``.

    ``groundtruth.csv`` (one row per test) and ``groundtruth_summary.csv`` (one row per
    material), atomically, floats to 10 significant digits.  Returns the two paths.
    """
    from ..io.atomic import write_csv_atomic

    out = Path(out_dir)
    a, b = out / outputs.GROUNDTRUTH, out / outputs.GROUNDTRUTH_SUMMARY
    write_csv_atomic(per_file, a, float_format="%.10g")
    write_csv_atomic(per_group, b, float_format="%.10g")
    return a, b


def example_campaign_dir() -> Path:
    """The shipped example campaign (``data/example-campaign`` beside the package).

    Raises
    ------
    InputError
        The folder is not there (e.g. a non-editable install, which ships the package only).
    """
    import palpbayes

    p = Path(palpbayes.__file__).resolve().parents[1] / "data" / "example-campaign"
    if not (p / "manifest.csv").is_file():
        raise InputError(
            f"the shipped example campaign is not at {p} (it comes with a source checkout, "
            "not with an installed wheel); give a campaign folder, manifest or results folder, "
            "or make one with 'palpbayes simulate DIR'")
    return p


def check_reusable(out_dir: str | os.PathLike, manifest: str | os.PathLike,
                   options: FitOptions | None = None) -> str | None:
    """Whether the fits in a non-empty ``out_dir`` may be reused one by one for ``manifest``.

    Returns None when they may: ``out_dir`` holds palpbayes results (``settings.json``) of
    this campaign, read with the reader's default columns, units and signs, fitted with
    ``options`` (None: not compared) by this palpbayes version; each trace's fit is then reused
    only when its data are unchanged too (:func:`palpbayes.campaign.partial.read_partial`).
    Otherwise the reason every fit must be redone, in words ("it was fitted by palpbayes
    0.0.1, this is 0.1.0").

    Raises
    ------
    OutputExistsError
        The folder holds no palpbayes results.
    InputError
        The folder holds another campaign's results, or traces read with column, unit or sign
        options (``palpbayes fit MANIFEST --z-unit ...``).
    """
    from .settings import options_record, read_settings

    out = Path(out_dir)
    old = read_settings(out)
    if not old:
        raise OutputExistsError(f"output folder {out} is not empty and holds no palpbayes "
                                "results; choose another --out or use --force")
    if old.get("source") and Path(old["source"]).resolve() != Path(manifest).resolve():
        raise InputError(f"{out} holds results of another campaign ({old['source']}); "
                         "choose another --out or use --force to replace them")
    version = old.get("palpbayes_version")
    if version != __version__:
        return (f"it was fitted by palpbayes {version or '(an unrecorded version)'}, this is "
                f"{__version__}")
    if options is not None and old.get("options") != options_record(options)["repr"]:
        return "it was fitted with other options"
    if old.get("read_options", {}):  # 'palpbayes fit MANIFEST --z-unit mm ...': not ours
        raise InputError(f"{out} was fitted from traces read with column, unit or sign "
                         f"options ({old['read_options']}), which 'report' does not take: "
                         "choose another --out, or use --force to refit them as the files read")
    return None


def run_pipeline(manifest: str | os.PathLike, out_dir: str | os.PathLike,
                 options: FitOptions | None = None, *,
                 workers: int | None = None, force: bool = False,
                 progress: bool | None = None, scheduler: str | None = None,
                 on_plan: Callable[[list[str], list[str], str | None], None] | None = None
                 ) -> Path:
    """Fit a campaign (both methods), analyse its ground truth and compare; return out_dir.

    Steps: :func:`palpbayes.campaign.fit_campaign` (``palpbayes fit``); when the campaign folder
    has ``groundtruth/``, :func:`palpbayes.compression.analyse` written to ``groundtruth.csv``
    and ``groundtruth_summary.csv`` (``palpbayes groundtruth``); then
    :func:`palpbayes.campaign.comparison.compare` (``palpbayes compare OUT``).  A results
    folder fitted before from the same campaign is reused fit by fit (the campaign's resume):
    a trace whose file, manifest row, options and palpbayes version are unchanged keeps its
    fit, the others are refitted; with other options or by another version every trace is
    refitted (:func:`check_reusable`).  Another campaign's folder needs ``force``.

    Parameters
    ----------
    manifest
        Campaign manifest CSV.
    out_dir
        Results folder.
    options
        :class:`~palpbayes.campaign.fitjob.FitOptions` (default: both methods, package defaults).
    workers, force, progress, scheduler
        As for :func:`~palpbayes.campaign.fit_campaign`.
    on_plan
        Called before anything is fitted with the ids of the traces whose fits are reused, of
        those to fit, and the reason every trace is refitted (None when fits are reused one
        by one, or the folder is new or ``force`` is set).
    """
    from .fitjob import FitOptions
    from .run import fit_campaign

    manifest = Path(manifest).resolve()
    out = Path(out_dir)
    options = options or FitOptions(method="both")
    resume, reason = False, None
    if not force and out.is_dir() and any(out.iterdir()):
        reason = check_reusable(out, manifest, options)
        resume = reason is None
        force = reason is not None  # another version or other options: refit every trace

    def plan(reused: list[str], todo: list[str]) -> None:
        if on_plan is not None:
            on_plan(reused, todo, reason)

    fit_campaign(manifest, out, options, workers=workers, resume=resume, force=force,
                 progress=progress, scheduler=scheduler, on_plan=plan)
    gt_dir = manifest.parent / "groundtruth"
    if gt_dir.is_dir():  # for the report (compare analyses the same folder at full precision)
        from ..compression import analyse

        write_groundtruth(*analyse(gt_dir), out)
    from .comparison import compare

    # exactly `palpbayes compare OUT`: the campaign's groundtruth/ is found via settings.json
    compare(out)
    write_gap(out)
    return out


def write_gap(out_dir: str | os.PathLike) -> Path | None:
    """Write the paper's robot-vs-Instron gap, decomposed (:func:`palpbayes.gap.gap_table`),
    as ``gap.csv`` when the results hold one of the paper's materials, and beside it the same
    at finite strain (``gap_strain.csv``, copied from
    :data:`palpbayes.outputs.SHIPPED_GAP_STRAIN` when the source checkout has it); return its
    path (None otherwise, and stale tables are removed).

    The table depends on the package alone (not on the results): it is computed once per
    package (about 10 s on one core, plus ~25 s the first time to solve the blocks' twins)
    and its text kept in the twin's disk cache (:mod:`palpbayes.twin.cache`) under a digest
    of every file of the package (:func:`palpbayes.twin.cache.package_stamp`); the next
    report writes the same bytes from there."""
    import numpy as np
    import pandas as pd

    from ..io.atomic import write_text_atomic
    from ..paper import PAPER_MATERIALS
    from ..twin.cache import load_arrays, package_stamp, save_arrays

    out = Path(out_dir)
    path = out / outputs.GAP
    summary = pd.read_csv(out / outputs.SUMMARY, usecols=["material"], dtype=str)
    mats = [m for m in PAPER_MATERIALS if m in set(summary["material"].dropna())]
    if not mats:
        path.unlink(missing_ok=True)
        (out / outputs.GAP_STRAIN).unlink(missing_ok=True)
        return None
    shipped = Path(__file__).resolve().parents[2] / outputs.SHIPPED_GAP_STRAIN
    if shipped.is_file():  # minutes of finite elements, computed once and shipped
        write_text_atomic(shipped.read_text(encoding="utf-8"), out / outputs.GAP_STRAIN)
    stamp = package_stamp()
    key = {"kind": "gap", "package": stamp}
    stored = load_arrays(key) if stamp else None
    if stored is not None and stored.get("csv") is not None and stored["csv"].dtype == np.uint8:
        text = stored["csv"].tobytes().decode("utf-8")
    else:
        from ..gap import gap_table

        text = gap_table().to_csv(index=False, float_format="%.6g", lineterminator="\n")
        if stamp:
            save_arrays(key, {"csv": np.frombuffer(text.encode("utf-8"), dtype=np.uint8)})
    write_text_atomic(text, path)
    return path
