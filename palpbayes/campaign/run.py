"""Batch fitting of a campaign: every trace of a manifest, in parallel, resumable.

:func:`fit_campaign` runs :func:`palpbayes.campaign.fitjob.fit_trace` on every trace over a
process pool or on Dask (``scheduler``: a LocalCluster or a cluster's scheduler; each trace in
:func:`palpbayes.campaign.partial.fit_and_record`) and writes a
results folder (docs/design.md §5, §7; file names in :mod:`palpbayes.outputs`)::

    OUT_DIR/
      summary.csv               one row per trace × method, columns fitjob.SUMMARY_COLUMNS
      posterior/<trace_id>.nc   Bayesian posterior of each trace (arviz, h5netcdf)
      traces.csv                geometry and labels of every trace (manifest columns)
      settings.json             version, options, source, seed, campaign folder
      .partial/<trace_id>.json  per-trace rows, written as each trace finishes (for --resume)

Comparison tables (ground truth vs least squares vs Bayes) are made from this folder by
:func:`palpbayes.campaign.comparison.compare` (``palpbayes compare``).

Failure policy
--------------
* Every trace is read, every trace to fit passes
  :func:`palpbayes.campaign.fitjob.check_fittable` (geometry, units, contact, fit window, the
  contact model at every depth a fit evaluates) and the output folder must be creatable before
  anything is written; only then does ``force=True`` remove the previous results.  Bad input
  found there leaves the results folder as it was.  (A trace whose record is reused passed
  that check when it was fitted, with the same data, options and version: it is not checked
  again.)
* A trace whose *input* is bad (:class:`~palpbayes.errors.InputError`: unreadable file, no
  contact, missing geometry) fails the whole run with an error naming the trace — bad input is
  exit status 2, and a campaign silently missing traces would bias every table.  Finished traces
  are kept in ``.partial/``, so fixing the input and running again with ``resume=True`` only
  fits what is left.
* A :class:`~palpbayes.errors.FitError` on otherwise valid data (e.g. no finite posterior at the
  least-squares start) is recorded as a row with empty estimates, ``converged`` False and the
  error in ``flags``; the campaign goes on.  With ``method="both"`` the least-squares row is
  salvaged when only the Bayesian fit failed.  With ``options.strict`` (non-convergence is an
  error) the run raises :class:`~palpbayes.errors.FitError` *after* writing ``summary.csv``,
  listing the failed traces.

Reproducibility: each trace's seed is :func:`palpbayes.campaign.fitjob.trace_seed` (base seed,
trace id), results are read back from the per-trace JSON files and sorted by (trace_id,
method), so the summary is identical whatever the number of workers or the order of completion.
"""

from __future__ import annotations

import concurrent.futures as cf
import json
import os
import sys
import tempfile
from collections.abc import Callable, Sequence
from dataclasses import replace
from pathlib import Path

import pandas as pd

from .. import outputs
from ..errors import FitError, InputError, OutputExistsError
from ..fitdata import FitData
from ..io.atomic import write_csv_atomic, write_text_atomic
from ..procs import lifeline
from ..progress import progress_bar
from ..trace import IndentationTrace
from .fitjob import SUMMARY_COLUMNS, FitOptions, check_fittable
from .partial import fit_and_record, raise_input, read_partial
from .settings import read_settings, settings_record
from .source import load_source, traces_table

__all__ = ["fit_campaign", "progress_bar"]


def _check_out_dir(out: Path, resume: bool, force: bool) -> None:
    if resume and force:
        raise InputError("--force and --resume exclude each other: --force refits everything, "
                         "--resume keeps finished traces")
    if out.exists() and not out.is_dir():
        raise OutputExistsError(f"{out} exists and is not a folder; choose another output folder")
    for parent in out.absolute().parents:  # nearest existing ancestor must be a folder
        if parent.exists():
            if not parent.is_dir():
                raise InputError(f"cannot create output folder {out}: {parent} is a file, not a "
                                 "folder; choose another --out")
            break
    if out.is_dir() and any(out.iterdir()) and not (resume or force):
        raise OutputExistsError(
            f"output folder {out} is not empty; use --force to refit and replace its results, "
            "or --resume to keep finished traces and fit the rest")


def _clear_outputs(out: Path) -> None:
    """Remove a previous run's results (only files palpbayes writes)."""
    for name in outputs.FIT_OUTPUTS:
        (out / name).unlink(missing_ok=True)
    for sub, pattern in ((outputs.POSTERIOR_DIR, "*.nc"), (outputs.PARTIAL_DIR, "*.json")):
        for f in (out / sub).glob(pattern):
            f.unlink()


# ----------------------------------------------------------------------------- campaign


def _mp_context():
    """Process start method: fork where it is safe and fast (Linux, Python < 3.12: the workers
    inherit the imported modules), else forkserver/spawn (fork of a multi-threaded process is
    deprecated from Python 3.12)."""
    import multiprocessing as mp

    methods = mp.get_all_start_methods()
    if "fork" in methods and sys.platform.startswith("linux") and sys.version_info < (3, 12):
        return mp.get_context("fork")
    return mp.get_context("forkserver" if "forkserver" in methods else "spawn")


def _run(todo: list[IndentationTrace], options: FitOptions, out: Path, workers: int,
         on_done: Callable[[], None], prepared: dict[str, FitData]) -> None:
    if workers <= 1 or len(todo) <= 1:
        for t in todo:
            res = fit_and_record(t, options, str(out), prepared.pop(t.trace_id, None))
            if "error" in res:
                raise_input(res["error"])
            on_done()
        return
    # the workers end with this process, even when it is killed (else each waits for work
    # forever, holding its memory)
    ctx = _mp_context()
    pool = cf.ProcessPoolExecutor(max_workers=min(workers, len(todo)), mp_context=ctx,
                                  **lifeline(ctx))
    try:
        futures = [pool.submit(fit_and_record, t, options, str(out),
                               prepared.pop(t.trace_id, None)) for t in todo]
        for fut in cf.as_completed(futures):
            res = fut.result()
            if "error" in res:
                raise_input(res["error"])
            on_done()
    finally:  # on an error or Ctrl-C, drop the traces not started yet
        pool.shutdown(wait=True, cancel_futures=True)


def _run_dask(todo: list[IndentationTrace], options: FitOptions, out: Path, client,
              on_done: Callable[[], None], prepared: dict[str, FitData]) -> None:
    """:func:`fit_and_record` of every trace on a Dask ``client``
    (:func:`palpbayes.cluster.dask_client`): a few traces per worker in flight, so memory
    does not grow with the campaign; each worker writes the trace's records into ``out`` as
    the local pool does."""
    from itertools import islice

    from dask.distributed import as_completed

    n_workers = max(1, len(client.scheduler_info().get("workers", {})) or 1)
    jobs = iter(todo)
    where = str(out.resolve())  # a worker's working folder may not be ours
    opts = client.scatter(options, broadcast=True)
    pending = as_completed()
    for t in islice(jobs, 2 * n_workers):
        pending.add(client.submit(fit_and_record, t, opts, where,
                                  prepared.pop(t.trace_id, None), pure=False))
    for fut in pending:
        res = fut.result()
        fut.release()
        if "error" in res:
            raise_input(res["error"])
        on_done()
        for t in islice(jobs, 1):
            pending.add(client.submit(fit_and_record, t, opts, where,
                                      prepared.pop(t.trace_id, None), pure=False))


def _write_and_fit(traces: list[IndentationTrace], options: FitOptions, out: Path,
                   settings: dict, force: bool, done: set[str], workers: int | None, client,
                   progress: bool | None, prepared: dict[str, FitData]) -> None:
    """Create the results folder, write the settings and the traces' table, fit the traces
    not ``done`` (their records reused) on the Dask ``client`` or the local pool from their
    ``prepared`` fit data."""
    try:
        out.mkdir(parents=True, exist_ok=True)
        (out / outputs.PARTIAL_DIR).mkdir(exist_ok=True)
        (out / outputs.POSTERIOR_DIR).mkdir(exist_ok=True)
    except OSError as exc:
        raise InputError(f"cannot create output folder {out} ({exc.strerror or exc}); choose "
                         "another --out") from None
    if force:
        _clear_outputs(out)
    write_text_atomic(json.dumps(settings, indent=2) + "\n", out / outputs.SETTINGS)
    write_csv_atomic(traces_table(traces), out / outputs.TRACES, float_format="%.10g")

    todo = [t for t in traces if t.trace_id not in done]
    with progress_bar(len(traces), progress, initial=len(done)) as bar:
        if client is not None:
            _run_dask(todo, options, out, client, lambda: bar.update(1), prepared)
        elif todo:
            _run(todo, options, out, workers, lambda: bar.update(1), prepared)


# Many parameters: a campaign's source, folder and one FitOptions, plus how to run it (workers,
# resume, scheduler, progress).
def fit_campaign(
    source: str | os.PathLike | Sequence[IndentationTrace],
    out_dir: str | os.PathLike | None = None,
    options: FitOptions | None = None,
    *,
    workers: int | None = None,
    resume: bool = False,
    force: bool = False,
    progress: bool | None = None,
    read_options: dict | None = None,
    scheduler: str | None = None,
    on_plan: Callable[[list[str], list[str]], None] | None = None,
) -> pd.DataFrame:
    """Fit every trace of a campaign and write the results folder (module docstring).

    Nothing is written, and with ``force`` nothing is removed, until every trace has been read
    and has passed :func:`palpbayes.campaign.fitjob.check_fittable` (geometry, units, contact, fit
    window, the contact model over every depth a fit evaluates) and the output folder can be
    created.

    Parameters
    ----------
    source
        Campaign manifest (:mod:`palpbayes.io.manifest`) or a sequence of traces with tips.
    out_dir
        Results folder; created if needed.  None: a temporary folder, removed when the fits
        are done (only the summary table is kept: give a folder to keep the posteriors).
    options
        Fit options shared by every trace (default :class:`~palpbayes.campaign.fitjob.FitOptions`).
    workers
        Worker processes (default ``os.cpu_count()``); 1 fits in this process.  With
        ``scheduler="local"``: the LocalCluster's workers.
    scheduler
        Fit on Dask instead of a process pool: ``"local"`` (a LocalCluster on this machine,
        bound to loopback) or a scheduler address (``tcp://host:8786``), whose workers must
        see the trace files and ``out_dir`` under the same paths (each writes its trace's
        records there).  Same summary as the local run with the same seed.
    resume
        Keep traces already recorded in ``out_dir/.partial`` with the same options, by the same
        palpbayes version, from the same data (:func:`palpbayes.campaign.partial.read_partial`:
        an edited trace file or manifest row is refitted) and fit the rest (an interrupted run
        picks up where it stopped).
    force
        Replace the results of a previous run in a non-empty ``out_dir``.
    progress
        Progress bar over traces on stderr; None: only when stderr is a terminal.
    read_options
        Reader options for every trace file of a manifest (``columns``, ``units``,
        ``force_sign``, ``z_sign``; see :func:`load_source`); recorded in ``settings.json``,
        and resuming with other read options is refused.
    on_plan
        Called once the run knows what it reuses, before anything is checked or fitted, with
        the ids of the traces whose records are reused and of those to fit (e.g. to say so on
        the console).

    Returns
    -------
    pandas.DataFrame
        The summary table, as written to ``summary.csv`` (rows sorted by trace_id, method).

    Raises
    ------
    OutputExistsError
        ``out_dir`` is not empty and neither ``force`` nor ``resume`` is set.
    InputError
        Bad source or a trace with bad input (the message names the trace); resuming a folder
        fitted with other options.
    FitError
        Only with ``options.strict``: some traces failed (after ``summary.csv`` is written).
    """
    if out_dir is None:
        if resume:
            raise InputError("resume needs the results folder of the interrupted run: give "
                             "out_dir")
        if scheduler not in (None, "local"):
            raise InputError(f"the Dask cluster at {scheduler!r} writes each trace's records "
                             "into the results folder: give an out_dir its workers see")
        options = options or FitOptions()
        with tempfile.TemporaryDirectory(prefix="palpbayes-") as tmp:
            summary = fit_campaign(source, Path(tmp) / "results", replace(options, strict=False),
                                   workers=workers, progress=progress,
                                   read_options=read_options, scheduler=scheduler)
        if options.strict:
            _raise_strict(summary.to_dict("records"), "the table a run without strict returns")
        return summary
    options = options or FitOptions()
    out = Path(out_dir)
    _check_out_dir(out, resume, force)
    traces, src = load_source(source, read_options)
    if scheduler is not None and scheduler != "local" and workers is not None:
        raise InputError(f"workers = {workers!r} applies to a local run; the Dask cluster at "
                         f"{scheduler!r} has the workers it was started with")
    if workers is None and scheduler is None:
        workers = os.cpu_count() or 1
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int)
                                or workers < 1):
        raise InputError(f"workers {workers!r} must be a positive integer")
    options = options.with_progress(False)  # one bar over traces, none per fit

    settings = settings_record(options, src, out, len(traces), read_options)
    old = read_settings(out) if resume else {}
    if resume and old and old.get("options") != settings["options"]:
        raise InputError(
            f"cannot resume {out}: it was fitted with other options ({old.get('options')}); "
            "use --force to refit everything with the new options")
    if resume and old and old.get("read_options", {}) != settings["read_options"]:
        raise InputError(
            f"cannot resume {out}: its traces were read with other column/unit/sign options "
            f"({old.get('read_options', {})}); use --force to refit everything with the new ones")
    # a trace recorded with these options, by this version, from these data is reused: it is
    # neither checked nor fitted again (the check passed when it was fitted)
    done = {t.trace_id for t in traces if resume and read_partial(out, t, options) is not None}
    if on_plan is not None:
        on_plan([t.trace_id for t in traces if t.trace_id in done],
                [t.trace_id for t in traces if t.trace_id not in done])
    checking = options.with_progress(progress)  # the twin's first tables show a bar
    prepared: dict[str, FitData] = {}  # each trace prepared once: checked here, fitted below
    for t in traces:  # bad input (geometry, nu, no contact) fails before anything is written
        if t.trace_id in done:
            continue
        try:
            prepared[t.trace_id] = check_fittable(t, checking)
        except InputError as exc:
            if t.trace_id in str(exc):
                raise
            exc.args = (f"trace {t.trace_id!r}: {exc}",)  # keep the class, name the trace
            raise
    # every check passed, the cluster (if any) answers: only now create the folder and (with
    # force) remove the old results
    client = None
    if scheduler is not None:
        from ..cluster import dask_client

        client = dask_client(None if scheduler == "local" else scheduler, workers)
    try:
        _write_and_fit(traces, options, out, settings, force, done, workers, client, progress,
                       prepared)
    finally:  # on an error or Ctrl-C the cluster's queued traces go with the client
        if client is not None:
            from ..cluster import close_client

            close_client(client)
    rows = []
    for t in traces:
        recorded = read_partial(out, t, options)
        if recorded is None:  # pragma: no cover - written just above
            raise FitError(f"trace {t.trace_id!r}: its results were not recorded")
        rows += recorded
    summary = pd.DataFrame(rows, columns=SUMMARY_COLUMNS)
    summary = summary.sort_values(["trace_id", "method"], kind="stable").reset_index(drop=True)
    write_csv_atomic(summary, out / outputs.SUMMARY)
    if options.strict:
        _raise_strict(rows, str(out / outputs.SUMMARY))
    return summary


def _raise_strict(rows: list[dict], where: str) -> None:
    """The FitError of a strict run whose ``rows`` hold failed fits (see ``where``)."""
    failed = sorted({r["trace_id"] for r in rows
                     if "fit_failed" in str(r.get("flag_codes") or "").split(";")})
    if failed:
        raise FitError(f"{len(failed)} trace(s) failed in strict mode: {', '.join(failed)} "
                       f"(see {where})")
