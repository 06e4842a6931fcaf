"""The front door's :class:`Fit`: one trace's fit with its numbers, figure and folder.

:func:`palpbayes.fit` returns a :class:`Fit`; :meth:`Fit.save` writes the folder ``palpbayes
fit --out`` writes (``settings.json``, ``traces.csv``, ``posterior/<trace_id>.nc``,
``summary.csv``; not ``.partial/``, the records of an interrupted run's ``--resume``), and
:func:`load_fit` (``Fit.load``, ``pb.load_fit``) reads such a folder back into a :class:`Fit`,
whichever of the two wrote it.  The posterior comes back through
:func:`palpbayes.campaign.results.load_fit`, the reader the report uses.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from .campaign.fitjob import SUMMARY_COLUMNS, FitOutcome
from .campaign.options import FitOptions
from .campaign.results import ResultsFolder
from .errors import InputError
from .io.atomic import write_csv_atomic, write_text_atomic
from .outputs import POSTERIOR_DIR, SETTINGS, SUMMARY, TRACES, posterior_path
from .trace import IndentationTrace

__all__ = ["Fit", "load_fit"]


@dataclass
class Fit:
    """One trace's fit (:func:`palpbayes.fit`, or read back by :func:`load_fit`): its rows,
    its results and what a reader needs.

    Attributes
    ----------
    trace
        The trace fitted; None for a fit read back (a results folder keeps the fitted points,
        ``bayes.data``, not the recording).
    options
        The fit's options; None for a fit read back (``settings.json`` holds them as a
        record: :attr:`folder`).
    outcome
        Its ``summary.csv`` rows and result objects
        (:class:`~palpbayes.campaign.fitjob.FitOutcome`).
    folder
        The results folder a fit was read back from (None for a fit made here).
    """

    trace: IndentationTrace | None
    options: FitOptions | None
    outcome: FitOutcome
    folder: ResultsFolder | None = None

    @classmethod
    def load(cls, source: str | os.PathLike, trace_id: str | None = None) -> Fit:
        """:func:`load_fit`."""
        return load_fit(source, trace_id)

    @property
    def trace_id(self) -> str:
        """The trace's id (its ``summary.csv`` rows')."""
        return str(self.outcome.rows[0]["trace_id"])

    @property
    def bayes(self):
        """The Bayesian result (:class:`~palpbayes.bayes.BayesResult`), None for ``lsq``."""
        return self.outcome.bayes

    @property
    def lsq(self):
        """The paper's least squares (:class:`~palpbayes.lsq.LSQResult`), None if it failed,
        and for a fit read back without a posterior (``method="lsq"``, a failed Bayesian fit),
        whose points the folder does not keep: its row is in :meth:`summary`."""
        return self.outcome.lsq

    @property
    def methods(self) -> list[str]:
        """The methods of the rows (``["bayes"]``, ``["lsq"]`` or ``["bayes", "lsq"]``)."""
        return sorted({str(r["method"]) for r in self.outcome.rows})

    @property
    def row(self) -> dict:
        """The main ``summary.csv`` row: the Bayesian one, else the least-squares one, with
        every column (NaN where the row has none: a failed fit's)."""
        rows = {r["method"]: r for r in self.outcome.rows}
        r = rows.get("bayes", rows.get("lsq"))
        return {c: r.get(c, float("nan")) for c in SUMMARY_COLUMNS}

    @property
    def E(self) -> float:
        """[Pa] Young's modulus: the posterior median at the stated inputs (the row's ``E_pa``,
        inside :attr:`interval`, which adds the budget)."""
        return float(self.row["E_pa"])

    @property
    def interval(self) -> tuple[float, float]:
        """[Pa] E's 90 % interval (the row's full ``E_lo_pa``, ``E_hi_pa``: statistical,
        budget and, after a material misfit, the model form)."""
        return float(self.row["E_lo_pa"]), float(self.row["E_hi_pa"])

    @property
    def E_stat(self) -> tuple[float, float, float]:
        """[Pa] The statistical part alone: median and 90 % interval (``E_stat_*``); least
        squares: its E and interval."""
        r = self.row
        if r["method"] == "bayes":
            return float(r["E_stat_pa"]), float(r["E_stat_lo_pa"]), float(r["E_stat_hi_pa"])
        return float(r["E_pa"]), float(r["E_lo_pa"]), float(r["E_hi_pa"])

    @property
    def E_instron(self) -> tuple[float, float, float] | None:
        """[Pa] With a specimen: what a compression test of the block would read, median and
        90 % interval (``E_instron_*``); None otherwise."""
        r = self.row
        v = r.get("E_instron_pa")
        if v is None or not np.isfinite(v):
            return None
        return float(v), float(r["E_instron_lo_pa"]), float(r["E_instron_hi_pa"])

    def summary(self) -> pd.DataFrame:
        """The ``summary.csv`` of this fit: exactly its rows and columns
        (:data:`~palpbayes.campaign.fitjob.SUMMARY_COLUMNS`), sorted by method."""
        df = pd.DataFrame(self.outcome.rows, columns=SUMMARY_COLUMNS)
        return df.sort_values(["trace_id", "method"], kind="stable").reset_index(drop=True)

    @property
    def posterior(self):
        """The arviz ``InferenceData`` of the Bayesian fit (None for ``lsq``), made on first
        access (:attr:`BayesResult.idata <palpbayes.bayes.BayesResult.idata>`: importing
        arviz, which a fit does not)."""
        return None if self.bayes is None else self.bayes.idata

    @property
    def checks(self) -> list:
        """The model checks of the Bayesian fit (:class:`~palpbayes.checks.CheckResult`)."""
        return [] if self.bayes is None else list(self.bayes.checks)

    @property
    def notes(self) -> list[str]:
        """The main row's flags in words, one per item."""
        from .flagcodes import split_flags

        text = self.row.get("notes")
        return split_flags(text) if isinstance(text, str) else []

    def plot(self):
        """A matplotlib Figure: the data with the fit (force against depth) and the
        residuals; the paper's least squares beside it only when it was asked for
        (``method="both"``).

        Raises
        ------
        InputError
            A fit without a posterior (``method="lsq"``, or a failed Bayesian fit).
        """
        from matplotlib.figure import Figure

        from . import plots

        if self.bayes is None:
            raise InputError("plot() draws a Bayesian fit; fit with method='bayes' or 'both'")
        lsq = (self.lsq or False) if "lsq" in self.methods else False
        fig = Figure(figsize=(8.0, 6.5), layout="constrained")
        top, bottom = fig.subplots(2, 1, height_ratios=(2, 1))
        plots.plot_force_depth(self.bayes, lsq, ax=top)
        plots.plot_residuals(self.bayes, lsq, ax=bottom)
        return fig

    def save(self, out: str | os.PathLike) -> Path:
        """Write the folder ``palpbayes fit --out`` writes for this trace into ``out``
        (created): ``settings.json`` (:func:`~palpbayes.campaign.settings.settings_record`),
        ``traces.csv``, ``posterior/<trace_id>.nc`` and, last, ``summary.csv``; the folder's
        path.  :func:`load_fit`, ``palpbayes compare`` and ``report`` read it.

        Raises
        ------
        InputError
            The folder cannot be created.
        """
        from .campaign.settings import settings_record
        from .campaign.source import traces_table

        out = Path(out)
        try:
            (out / POSTERIOR_DIR).mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise InputError(f"cannot create the folder {out} ({exc.strerror or exc}); "
                             "choose another") from None
        if self.folder is None:
            settings = settings_record(self.options, None, out, 1)
            traces = traces_table([self.trace])
        else:  # read back: the record it was fitted with, its own row of traces.csv
            settings = {**self.folder.settings, "n_traces": 1}
            if settings.get("campaign_dir"):
                settings["campaign_dir_relative"] = os.path.relpath(
                    settings["campaign_dir"], out.resolve())
            table = self.folder.traces
            traces = None if table is None else table[table["trace_id"] == self.trace_id]
        write_text_atomic(json.dumps(settings, indent=2) + "\n", out / SETTINGS)
        if traces is not None:  # as campaign.run writes it
            write_csv_atomic(traces, out / TRACES, float_format="%.10g")
        if self.bayes is not None:
            self.bayes.to_netcdf(posterior_path(out, self.trace_id))
        write_csv_atomic(self.summary(), out / SUMMARY)
        return out

    def __repr__(self) -> str:
        from .units import format_pressure

        r = self.row
        lo, hi = self.interval
        state = []
        if r["method"] == "bayes":
            state.append("converged" if bool(r["converged"]) else "NOT converged")
        ok = r.get("model_ok")
        if isinstance(ok, bool | np.bool_):
            state.append("model ok" if ok else "model check failed")
        n = r.get("n_points")
        if n is not None and np.isfinite(n):
            state.append(f"{int(n)} points")
        return (f"Fit({self.trace_id!r}, {r['method']}: E {format_pressure(self.E)} "
                f"[{format_pressure(lo)}, {format_pressure(hi)}] (90 %)"
                + (f", {', '.join(state)}" if state else "") + ")")


def _python(v):
    """A table's value as :func:`palpbayes.fit`'s rows hold it (numpy scalars as Python's)."""
    return v.item() if isinstance(v, np.generic) else v


def load_fit(source: str | os.PathLike, trace_id: str | None = None) -> Fit:
    """A saved fit, read back: the folder ``palpbayes fit --out`` or :meth:`Fit.save` wrote, or
    its ``posterior/<trace_id>.nc``.

    Parameters
    ----------
    source
        The results folder, or a posterior file in its ``posterior/`` folder (its
        ``summary.csv`` next to that folder gives the rows).
    trace_id
        Which trace of a folder with several (a campaign's); None: the only one.

    Returns
    -------
    Fit
        The rows of ``summary.csv``; the Bayesian result as it was saved
        (:func:`palpbayes.campaign.results.load_fit`: draws, diagnostics, checks, budget, with
        the least squares refitted on its points); ``trace`` and ``options`` None.

    Raises
    ------
    InputError, DataFileError
        No such folder or file, no ``summary.csv``, no such trace (the message names those
        there), several traces and no ``trace_id``, or a fitted posterior missing.
    """
    from .campaign.results import load_fit as load_bayes
    from .campaign.results import load_results

    path = Path(source)
    if path.is_file() and path.suffix != ".nc":
        raise InputError(f"{path}: not a posterior (.nc) file; give the folder 'palpbayes fit "
                         "--out' (or Fit.save) wrote, or a .nc in its posterior/ folder")
    if path.suffix == ".nc":
        if not path.is_file():
            raise InputError(f"{path}: no such posterior file; give the folder 'palpbayes fit "
                             "--out' (or Fit.save) wrote, or a .nc in its posterior/ folder")
        folder = path.parent.parent
        if path.parent.name != POSTERIOR_DIR or not (folder / SUMMARY).is_file():
            raise InputError(f"{path}: not in the {POSTERIOR_DIR}/ folder of a results folder "
                             f"with its {SUMMARY}; give the folder 'palpbayes fit --out' (or "
                             "Fit.save) wrote")
        if trace_id is not None and trace_id != path.stem:
            raise InputError(f"{path} is the posterior of trace {path.stem!r}, not of "
                             f"{trace_id!r}")
        trace_id, path = path.stem, folder
    elif not path.is_dir():
        raise InputError(f"{path}: no such folder; give the folder 'palpbayes fit --out' (or "
                         "Fit.save) wrote")
    res = load_results(path)
    ids = list(dict.fromkeys(res.summary["trace_id"].astype(str)))
    some = ", ".join(ids[:5]) + (", ..." if len(ids) > 5 else "")
    if trace_id is None:
        if len(ids) != 1:
            raise InputError(f"{path} holds {len(ids)} traces ({some}); pick one with "
                             "trace_id=")
        trace_id = ids[0]
    elif str(trace_id) not in ids:
        raise InputError(f"{path}: no trace {trace_id!r} in its {SUMMARY} (it holds {some})")
    trace_id = str(trace_id)
    table = res.summary[res.summary["trace_id"].astype(str) == trace_id]
    rows = [{c: _python(v) for c, v in r.items()} for r in table.to_dict("records")]
    fitted = any(r["method"] == "bayes" and np.isfinite(r.get("E_pa", np.nan)) for r in rows)
    bayes = load_bayes(res, trace_id) if fitted else None
    outcome = FitOutcome(rows=rows, lsq=None if bayes is None else bayes.lsq, bayes=bayes,
                         posterior_path=posterior_path(path, trace_id) if fitted else None)
    return Fit(trace=None, options=None, outcome=outcome, folder=res)
